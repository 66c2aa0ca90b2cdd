"""The results of a simulated run: what ran, what was logged, what the analysis found.

:class:`SimulationResult` is what :func:`~drake_social.sim.run.simulate`
returns: the logged trajectory, the safety stops, the replans and, after the
analysis (:func:`~drake_social.sim.execution_analysis.analyze_execution`),
an :class:`ExecutionReport` with its :class:`LimitViolation` findings.
:class:`SimulationDiverged` is the error of a run whose state became
non-finite or absurd.
"""

from __future__ import annotations

import dataclasses as dc
import math
from typing import Any

import numpy as np

from drake_social.people import PeopleLog
from drake_social.planning.result import PlannerResult
from drake_social.scenario import Scenario, ScenarioError

__all__ = ["CHECKED_ROOM", "CHECKED_ROOM_AND_PEOPLE", "ExecutionReport", "LimitViolation", "SimulationDiverged",
           "SimulationResult", "replanning_line"]

#: What the collision check of an executed trajectory covers
#: (:attr:`ExecutionReport.collision_checked`): everything when the people
#: stand still, the room alone when they move.
CHECKED_ROOM_AND_PEOPLE = ("obstacles", "walls", "people")
CHECKED_ROOM = ("obstacles", "walls")


@dc.dataclass(frozen=True)
class LimitViolation:
    """One joint of the executed trajectory beyond its limit.

    The limits are those of a valid configuration (the checkers' and the
    robot model's): the room bounds for ``base_x`` and ``base_y`` (metres),
    ``robot.joint_lower`` / ``joint_upper`` for ``psi1`` and ``psi2``
    (radians).

    Attributes:
        joint: ``base_x``, ``base_y``, ``psi1`` or ``psi2``.
        bound: ``"lower"`` or ``"upper"``.
        limit: the limit passed, metres or radians.
        first_time: first logged time beyond it, seconds.
        worst_time: time of the largest excess, seconds.
        max_excess: the largest distance beyond the limit (> 0), metres or radians.
    """

    joint: str
    bound: str
    limit: float
    first_time: float
    worst_time: float
    max_excess: float

    @property
    def kind(self) -> str:
        """What was passed: ``"a room bound"`` (base) or ``"a joint limit"`` (arm)."""
        return "a room bound" if self.joint.startswith("base") else "a joint limit"

    def __str__(self) -> str:
        unit = "m" if self.joint.startswith("base") else "rad"
        return (f"{self.joint} {self.max_excess:.3g} {unit} beyond its {self.bound} limit {self.limit:.6g} "
                f"at t = {self.worst_time:.2f} s (first at t = {self.first_time:.2f} s)")


@dc.dataclass
class ExecutionReport:
    """What the executed trajectory did, beside what was planned.

    Attributes:
        planned_social_cost: Msc summed along the planned waypoints (the
            scenario's full multi-point weights).
        executed_social_cost: the same integral along the executed trajectory,
            with the same cost function as the planner's: against the people
            at t = 0, even when they walk (the planned cost's counterpart;
            the cost among the people where they were is ``nav_agf_time_*``).
        max_point_deviation: body point name -> largest distance (metres) of
            its executed position from its planned curve, and ``"max"``.
        max_config_deviation: largest configuration-space distance of an
            executed configuration from the planned waypoint polyline.
        min_clearance: smallest signed distance (metres) of the robot to the
            environment along the executed trajectory (checked configurations;
            exact planar distances).
        collision_free: no checked configuration collides with what
            ``collision_checked`` names: a verdict on the geometry alone
            (signed distance > 0), whatever the joint limits.
        first_collision_time: time (s) of the first colliding configuration, or None.
        within_limits: no executed configuration is beyond a limit of a valid
            configuration (see :class:`LimitViolation`).
        limit_violations: one :class:`LimitViolation` per joint and bound
            passed, in joint order (empty when ``within_limits``).
        checked_configurations: how many configurations were checked (the
            executed samples, densified to the collision resolution).
        collision_resolution: largest body-point motion between checked
            configurations, metres.
        collision_checked: what the collision check and ``min_clearance``
            cover: :data:`CHECKED_ROOM_AND_PEOPLE` (the people stand still) or
            :data:`CHECKED_ROOM` (the people move; their distances over time
            are the metrics' from the people log).
    """

    planned_social_cost: float
    executed_social_cost: float
    max_point_deviation: dict[str, float]
    max_config_deviation: float
    min_clearance: float
    collision_free: bool
    first_collision_time: float | None
    checked_configurations: int
    collision_resolution: float
    within_limits: bool
    limit_violations: list[LimitViolation]
    collision_checked: list[str] = dc.field(default_factory=lambda: list(CHECKED_ROOM_AND_PEOPLE))


@dc.dataclass
class SimulationResult:
    """A simulated execution.

    Attributes:
        mode, execution: how it ran.
        reached: the sequencer reported the goal reached before the time limit.
        message: one line on the outcome.
        time_to_goal: simulated seconds until the goal was reached (None if not).
        sim_time: simulated seconds.
        wall_time: seconds spent in ``Simulator.AdvanceTo`` (planning excluded).
        realtime_factor: ``sim_time / wall_time``.
        waypoints: (N, 4) the path followed.
        times: (T,) log times, seconds.
        q: (T, 4) configurations; v: (T, 4) their velocities (m/s, rad/s).
        wheel_speeds: (T, 4) commanded wheel speeds, rad/s.
        target: (T, 4) the sequencer's target; reference: (T, 4) what was tracked.
        target_index: (T,) the sequencer's index.
        planner: the PlannerResult when the diagram planned, else None.
        report: the :class:`ExecutionReport`, or None when not analysed or no path.
        people: the people at ``times`` (a :class:`~drake_social.people.PeopleLog`;
            the crowd as it reacted to the robot), or None when the scenario
            has no people or nothing ran.
        stopped: (T,) True at the sample times t_k the safety monitor holds
            the robot from (its decision at t_k: ``start <= t_k < end`` of a
            stop), all False without people. (The ``stop`` logger, published
            before the updates, shows the decision of t_{k-1} at t_k.)
        waiting: (T,) True at the sample times t_k the replanner holds the
            robot from (its latest decision at or before t_k found no safe
            path: status ``"wait"``), all False without replanning.
        speed_limit: (T,) the slow-down's limit on the fastest point's speed
            at the sample times (m/s; +inf where nothing limits, all +inf
            without the slow-down; the logger publishes before the updates,
            so sample k shows the limit decided at t_{k-1}).
        slow_stops: one dict per stop of the slow-down (its limit 0), as
            ``stops`` (the person that bound the limit, the part nearest to
            them and its distance at the start).
        slow_stopped: (T,) True at the sample times the slow-down's limit
            holds the robot at 0 from (as ``stopped``), all False without it.
        stops: one dict per stop by the safety monitor, in order: ``start``
            and ``end`` (the times of the updates that stopped and released
            the robot, seconds; ``end`` None when still stopped at the end),
            ``duration`` (seconds, until the end of the run when still
            stopped), ``person`` (nearest person's name, or index), ``part``
            (``base``, ``arm`` or ``object``) and ``distance`` (that part's
            surface distance at the start, metres).
        replans: with replanning, every
            :class:`~drake_social.planning.replan.ReplanResult` of the run in
            order (the first plan's first; the replans after the goal was
            reached are left out); empty without.
        predicted: with replanning, what the replans that changed the path
            or began a wait predicted
            (:class:`~drake_social.people.predicted.PredictedPeople`, each
            naming its replan's index in ``replans``; at most
            :data:`~drake_social.control.replanner_system.MAX_PREDICTED_REPLANS`);
            empty without.
        replanning: with replanning, the summary of ``replans``
            (:func:`~drake_social.control.replanning_summary`: count, changed,
            waits, plan times (median, p95, p99, max), deadline hits, rate,
            budget); None without.
            With replanning ``waypoints`` is the path followed: each path up
            to the waypoint it was heading for when a replan replaced it, then
            the last one.
        judged: the polyline the deviation is measured from: ``waypoints``,
            or with replanning each replaced path up to and including the
            waypoint it was heading for (:class:`~drake_social.control.ReplanState`'s
            ``judged``).
    """

    mode: str
    execution: str
    reached: bool
    message: str
    time_to_goal: float | None
    sim_time: float
    wall_time: float
    realtime_factor: float
    waypoints: np.ndarray
    times: np.ndarray
    q: np.ndarray
    v: np.ndarray
    wheel_speeds: np.ndarray
    target: np.ndarray
    reference: np.ndarray
    target_index: np.ndarray
    planner: PlannerResult | None = None
    report: ExecutionReport | None = None
    people: PeopleLog | None = None
    stopped: np.ndarray = dc.field(default_factory=lambda: np.zeros(0, bool))
    waiting: np.ndarray = dc.field(default_factory=lambda: np.zeros(0, bool))
    stops: list[dict] = dc.field(default_factory=list)
    speed_limit: np.ndarray = dc.field(default_factory=lambda: np.zeros(0))
    slow_stops: list[dict] = dc.field(default_factory=list)
    slow_stopped: np.ndarray = dc.field(default_factory=lambda: np.zeros(0, bool))
    replans: tuple = ()
    replanning: dict | None = None
    judged: np.ndarray | None = None
    predicted: tuple = ()

    @property
    def stopped_time(self) -> float:
        """Seconds the safety monitor held the robot (the stops' durations summed)."""
        return float(sum(stop["duration"] or 0.0 for stop in self.stops))

    @property
    def slow_stopped_time(self) -> float:
        """Seconds the slow-down's limit held the robot at 0 (its stops' durations summed)."""
        return float(sum(stop["duration"] or 0.0 for stop in self.slow_stops))

    def summary(self) -> str:
        """One line for the terminal."""
        line = f"{self.mode}/{self.execution}: {self.message}"
        if self.report is not None:
            r = self.report
            line += (f"; social cost planned {r.planned_social_cost:.4g}, executed {r.executed_social_cost:.4g}; "
                     f"max point deviation {r.max_point_deviation['max']:.3g} m; "
                     f"min clearance {r.min_clearance:.3g} m; "
                     f"{'collision-free' if r.collision_free else 'COLLIDES'}"
                     f"{'' if 'people' in r.collision_checked else ' (obstacles and walls; the people move)'}; "
                     + ("within the joint limits and room bounds" if r.within_limits else
                        "BEYOND A LIMIT: " + "; ".join(str(v) for v in r.limit_violations)))
        if self.slow_stops:
            n = len(self.slow_stops)
            line += f"; {n} slow-down stop{'s' if n > 1 else ''} ({self.slow_stopped_time:.2f} s)"
        if self.stops:
            line += f"; {len(self.stops)} safety stop{'s' if len(self.stops) > 1 else ''} ({self.stopped_time:.2f} s)"
        if self.replanning is not None:
            line += f"; {replanning_line(self.replanning)}"
        if self.sim_time > 0 and math.isfinite(self.realtime_factor):  # nothing simulated: no factor to show
            line += f"; {self.realtime_factor:.0f}x realtime"
        return line

    def to_json_dict(self) -> dict[str, Any]:
        """JSON-ready summary (the logged arrays are left out)."""

        def num(x):
            return None if x is None or not np.isfinite(x) else float(x)

        out: dict[str, Any] = {
            "mode": self.mode,
            "execution": self.execution,
            "reached": self.reached,
            "message": self.message,
            "time_to_goal": num(self.time_to_goal),
            "sim_time": self.sim_time,
            "wall_time": self.wall_time,
            "realtime_factor": num(self.realtime_factor),
            "num_waypoints": int(len(self.waypoints)),
            "num_samples": int(len(self.times)),
            "stops": [dict(stop) for stop in self.stops],
            "stopped_time": self.stopped_time,
            "slow_stops": [dict(stop) for stop in self.slow_stops],
            "slow_stopped_time": self.slow_stopped_time,
        }
        if self.report is not None:
            r = dc.asdict(self.report)
            r["first_collision_time"] = num(r["first_collision_time"])
            r["min_clearance"] = num(r["min_clearance"])
            out.update(r)
        if self.planner is not None:
            out["planner"] = {k: v for k, v in self.planner.to_record().items() if k != "cost_history"}
        if self.replanning is not None:
            out["replanning"] = dict(self.replanning)
        return out


def replanning_line(summary: dict) -> str:
    """A run's replanning summary (:func:`~drake_social.control.replanning_summary`) in words."""
    line = (f"{summary['count']} replans at {summary['rate']:g} Hz: {summary['changed']} changed the path, "
            f"{summary['waits']} waited")
    if summary["count"]:
        line += (f"; plan time median {summary['plan_time_median'] * 1e3:.1f} ms, p95 "
                 f"{summary['plan_time_p95'] * 1e3:.1f} ms, p99 {summary['plan_time_p99'] * 1e3:.1f} ms, "
                 f"max {summary['plan_time_max'] * 1e3:.1f} ms "
                 f"(budget {summary['budget'] * 1e3:g} ms, {summary['deadline_hits']} deadline hits)")
    return line


class SimulationDiverged(ScenarioError):
    """The simulated state became non-finite or absurd (a plant step too
    large for the scenario's dynamics).

    Attributes:
        time: simulated seconds when it was found.
        what: the state found (e.g. ``"speed 3.2e+05 of base_x"``) or the
            step that failed (the plant's contact solver).
    """

    def __init__(self, scenario: Scenario, mode: str, time: float, what: str, advice: str | None = None):
        self.time, self.what = float(time), what
        if advice is None:
            advice = (f"execution.plant_time_step {scenario.execution.plant_time_step:g} s is too large for this "
                      "scenario's dynamics; use a smaller one" if mode == "dynamic" else "")
        advice = f": {advice}" if advice else ""
        super().__init__(f"the {mode} simulation diverged by t = {self.time:.2f} s ({what}){advice}")
