"""Runs an execution diagram with Drake's Simulator and measures what it did.

:func:`simulate` builds the diagram (:func:`~drake_social.sim.diagram.build_diagram`),
plans at initialization (or takes the given waypoints), advances until the
sequencer reports the goal reached or ``execution.time_limit`` passes, and
returns a :class:`SimulationResult`: the logged trajectory and, after every
run, what the *executed* trajectory did: checked for collisions at the
checker's resolution (geometry only), checked against the limits of a valid
configuration (a separate finding: which joint, when, by how much), its
social cost integrated with the same cost code as the planner's, the
deviation of every body point from the planned path, the minimum clearance
and the time to goal. The people are logged at the same times as the
executed configurations (:attr:`SimulationResult.people`). When they move,
the collision check covers the obstacles and walls only (the people at t = 0
are not where the robot met them): the distances to people are measured over
time from the people log (:mod:`drake_social.experiments.metrics`), and
:attr:`ExecutionReport.collision_checked` names what was checked.

With ``replan`` (or the scenario's ``planner.replan``) the diagram's planner
replans every ``1 / planner.replan_rate`` seconds
(:class:`~drake_social.control.ReplanningPlannerSystem`): the result keeps
every replan (:attr:`SimulationResult.replans`), their summary
(:attr:`SimulationResult.replanning`, also in :meth:`SimulationResult.to_json_dict`
and logged in one line) and, as ``waypoints``, the path followed.

Example::

    from drake_social.scenario import load_scenario
    from drake_social.sim import simulate

    scenario = load_scenario("scenarios/tiny.yaml")
    run = simulate(scenario, mode="kinematic", execution="synchronized")
    print(run.summary())
"""

from __future__ import annotations

import dataclasses as dc
import logging
import math
import time
from typing import Any, Callable

import numpy as np
from pydrake.geometry import Meshcat
from pydrake.systems.analysis import ApplySimulatorConfig, InitializeParams, Simulator, SimulatorConfig

from drake_social.arguments import (
    real_array,
    require_callable,
    require_checker,
    require_instance,
    require_number,
    require_scenario,
)
from drake_social.control import replanning_summary
from drake_social.cost.social import SocialCost
from drake_social.scenario.geometry import arm_geometry, configuration_limits
from drake_social.model.plant import ACTUATED_JOINTS
from drake_social.planning.result import PlannerResult
from drake_social.collision.validity import ValidityChecker
from drake_social.people import PeopleLog, PeopleModel, people_model, without_people
from drake_social.scenario import Scenario, ScenarioError, time_limit_problem
from drake_social.sim.analysis import config_deviation, densify, point_deviation
from drake_social.sim.diagram import (
    TransportDiagram,
    build_checked,
    check_diagram_options,
    check_diagram_waypoints,
    resolve_replan,
)
from drake_social.waypoints import waypoint_array

__all__ = ["CHECKED_ROOM", "CHECKED_ROOM_AND_PEOPLE", "ExecutionReport", "LimitViolation", "SimulationResult",
           "analyze_execution", "limit_violations", "replanning_line", "scenario_simulator_config", "simulate"]

#: Simulated seconds per AdvanceTo call between checks for the goal.
_CHUNK = 0.25

_log = logging.getLogger(__name__)

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
        replanning: with replanning, the summary of ``replans``
            (:func:`~drake_social.control.replanning_summary`: count, changed,
            waits, plan times, deadline hits, rate, budget); None without.
            With replanning ``waypoints`` is the path followed: each path up
            to the waypoint it was heading for when a replan replaced it, then
            the last one.
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
    replans: tuple = ()
    replanning: dict | None = None

    @property
    def stopped_time(self) -> float:
        """Seconds the safety monitor held the robot (the stops' durations summed)."""
        return float(sum(stop["duration"] or 0.0 for stop in self.stops))

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
                 f"{summary['plan_time_p95'] * 1e3:.1f} ms, max {summary['plan_time_max'] * 1e3:.1f} ms "
                 f"(budget {summary['budget'] * 1e3:g} ms, {summary['deadline_hits']} deadline hits)")
    return line


#: A state beyond these is a diverged simulation, not a motion: speeds
#: (m/s, rad/s) and arm angles (rad), and the base more than the room's
#: diagonal outside the room.
_ABSURD_SPEED = 1e3
_ABSURD_ANGLE = 1e2


class SimulationDiverged(ScenarioError):
    """The simulated state became non-finite or absurd (a plant step too
    large for the scenario's dynamics).

    Attributes:
        time: simulated seconds when it was found.
        what: the state found (e.g. ``"speed 3.2e+05 of base_x"``).
    """

    def __init__(self, scenario: Scenario, mode: str, time: float, what: str):
        self.time, self.what = float(time), what
        advice = (f": execution.plant_time_step {scenario.execution.plant_time_step:g} s is too large for this "
                  "scenario's dynamics; use a smaller one" if mode == "dynamic" else "")
        super().__init__(f"the {mode} simulation diverged by t = {self.time:.2f} s ({what}){advice}")


def _divergence(q, v, lower: np.ndarray, upper: np.ndarray) -> str | None:
    """What makes the state ``q``, ``v`` (4,) a diverged one, or None."""
    q, v = np.asarray(q, float), np.asarray(v, float)
    for values, kind in ((q, "position"), (v, "speed")):
        bad = np.flatnonzero(~np.isfinite(values))
        if len(bad):
            return f"non-finite {kind} of {ACTUATED_JOINTS[bad[0]]}"
    reach = float(np.hypot(*(upper[:2] - lower[:2])))
    far = np.flatnonzero((q[:2] < lower[:2] - reach) | (q[:2] > upper[:2] + reach))
    if len(far):
        return f"{ACTUATED_JOINTS[far[0]]} = {q[far[0]]:.3g} m, more than the room's diagonal outside the room"
    spun = np.flatnonzero(np.abs(q[2:]) > _ABSURD_ANGLE)
    if len(spun):
        return f"{ACTUATED_JOINTS[2 + spun[0]]} = {q[2 + spun[0]]:.3g} rad"
    fast = np.flatnonzero(np.abs(v) > _ABSURD_SPEED)
    if len(fast):
        return f"speed {v[fast[0]]:.3g} of {ACTUATED_JOINTS[fast[0]]}"
    return None


def scenario_simulator_config(scenario: Scenario) -> SimulatorConfig:
    """The ``SimulatorConfig`` of a scenario's run.

    ``execution.integration_scheme``, ``accuracy`` and
    ``target_realtime_rate`` (by default Drake's: Runge-Kutta 3 with error
    control, accuracy 1e-4, as fast as possible), ``max_step_size`` one
    ``execution.control_period`` (seconds): the continuous base of the
    kinematic mode is integrated in steps of at most one control period.
    The rest are Drake's defaults (no publish at every step: the loggers
    sample periodically).
    """
    e = scenario.execution
    return SimulatorConfig(integration_scheme=e.integration_scheme, max_step_size=float(e.control_period),
                           accuracy=float(e.accuracy), target_realtime_rate=float(e.target_realtime_rate))


def limit_violations(scenario: Scenario, times: np.ndarray, q: np.ndarray) -> list[LimitViolation]:
    """Where the executed configurations ``q`` (T, 4) at ``times`` (T,) pass a limit.

    The configurations are compared with the limits exactly (as the
    checkers do); between two logged samples the executed trajectory is
    taken as straight, whose extremes are at the samples.

    Returns:
        One :class:`LimitViolation` per joint and bound passed, in joint
        order, lower before upper; empty when every sample is within.
    """
    lower, upper = configuration_limits(scenario)
    q = np.asarray(q, float).reshape(-1, 4)
    times = np.asarray(times, float).reshape(-1)
    found = []
    for j, joint in enumerate(ACTUATED_JOINTS):
        for bound, excess, limit in (("lower", lower[j] - q[:, j], lower[j]), ("upper", q[:, j] - upper[j], upper[j])):
            beyond = np.flatnonzero(excess > 0)
            if len(beyond):
                worst = int(np.argmax(excess))
                found.append(LimitViolation(joint=joint, bound=bound, limit=float(limit),
                                            first_time=float(times[beyond[0]]), worst_time=float(times[worst]),
                                            max_excess=float(excess[worst])))
    return found


def _collision_free(are_valid: Callable[[np.ndarray], np.ndarray], clearance: Callable[[np.ndarray], float],
                    lower: np.ndarray, upper: np.ndarray, qs: np.ndarray) -> np.ndarray:
    """(N,) bool: each configuration's geometry is clear (signed distance > 0).

    A checker's ``are_valid`` also refuses configurations beyond the limits;
    those (found separately, :func:`limit_violations`) are judged here by
    their ``clearance`` alone.
    """
    inside = np.all((qs >= lower) & (qs <= upper), axis=1)
    free = np.zeros(len(qs), bool)
    if inside.any():
        free[inside] = np.asarray(are_valid(qs[inside]), bool)
    for i in np.flatnonzero(~inside):
        free[i] = clearance(qs[i]) > 0.0
    return free


def analyze_execution(
    scenario: Scenario,
    waypoints: np.ndarray,
    times: np.ndarray,
    q: np.ndarray,
    checker: ValidityChecker | None = None,
    *,
    people_move: bool | None = None,
) -> ExecutionReport:
    """Checks and measures an executed trajectory against its planned path.

    Two separate findings: collisions (the geometry at the checker's
    resolution) and the limits of a valid configuration
    (:func:`limit_violations`).

    Args:
        scenario: the scenario.
        waypoints: (N, 4) planned path.
        times, q: (T,), (T, 4) executed configurations over time.
        checker: the collision checker of the executed configurations;
            None = Drake's (:func:`~drake_social.collision.drake_checker.valid_configurations`:
            SceneGraphCollisionChecker answers from the shapes near the
            trajectory), independent of the planar checker that planned. The minimum
            clearance is the exact planar checker's. A given checker is used
            as given when the people stand still; when they move, a checker
            of the same kind is built for the room alone (a checker built
            with the people at t = 0 would judge the run against where they
            no longer are), and an unknown kind gives way to Drake's.
        people_move: whether the scenario's people move (None = ask its
            people model). When they do, the check and the clearance cover
            the obstacles and walls only (:data:`CHECKED_ROOM`).

    Raises:
        TypeError: an argument of the wrong kind (named).
        ScenarioError: ``waypoints`` not an (N, 4) array with 2 <= N <=
            MAX_WAYPOINTS; ``times`` and ``q`` not (T,) and (T, 4) finite.
    """
    from drake_social.collision.drake_checker import make_checker, valid_configurations

    require_scenario(scenario, "analyze_execution")
    require_checker(checker, "analyze_execution", optional=True)
    waypoints = waypoint_array(waypoints, "analyze_execution: waypoints")
    times, q = _trajectory(times, q, "analyze_execution")
    # Clearances from the exact planar checker: Drake's cylinder-box distance
    # can exceed the true one (see drake_social.collision.drake_checker).
    if people_move is None:
        people_move = not people_model(scenario).static
    room = without_people(scenario) if people_move else scenario  # what the collisions are checked against
    planar = make_checker(room, "planar")
    geometry = arm_geometry(scenario)
    social = SocialCost.from_scenario(scenario)
    wp = waypoints
    planned = float(social.motion_cost(wp[:-1], wp[1:]).sum()) if len(wp) > 1 else 0.0
    executed = float(social.motion_cost(q[:-1], q[1:]).sum()) if len(q) > 1 else 0.0

    resolution = float(scenario.planner.collision_resolution)
    # Which executed sample each densified configuration follows (for the collision time).
    dense, owner = densify(geometry, q, resolution, return_owner=True)
    lower, upper = configuration_limits(scenario)
    if people_move and checker is not None:
        checker = _room_checker(checker, room)
    if checker is None:  # Drake's, from SceneGraphs of the shapes near the trajectory (bounded memory)
        valid = _collision_free(lambda qs: valid_configurations(room, qs), planar.clearance, lower, upper, dense)
    else:
        valid = _collision_free(checker.are_valid, checker.clearance, lower, upper, dense)
    violations = limit_violations(scenario, times, q)
    clearance = float(np.min(planar.clearances(dense))) if len(dense) else math.inf
    first = None if valid.all() else float(times[owner[int(np.argmin(valid))]])
    return ExecutionReport(
        planned_social_cost=planned,
        executed_social_cost=executed,
        max_point_deviation=point_deviation(geometry, wp, q),
        max_config_deviation=config_deviation(wp, q),
        min_clearance=float(clearance),
        collision_free=bool(valid.all()),
        first_collision_time=first,
        checked_configurations=int(len(dense)),
        collision_resolution=resolution,
        within_limits=not violations,
        limit_violations=violations,
        collision_checked=list(CHECKED_ROOM if people_move else CHECKED_ROOM_AND_PEOPLE),
    )


def _room_checker(checker: ValidityChecker, room: Scenario) -> ValidityChecker | None:
    """A checker of ``checker``'s kind for ``room`` (the scenario without its
    people), or None (Drake's) for a kind this module does not know."""
    from drake_social.collision.drake_checker import GeometricChecker, PlanarChecker, SceneGraphChecker, make_checker

    for cls, kind in ((PlanarChecker, "planar"), (GeometricChecker, "numpy"), (SceneGraphChecker, "drake")):
        if isinstance(checker, cls):
            return make_checker(room, kind, parallelism=1) if kind == "drake" else make_checker(room, kind)
    _log.info("analyze_execution: a %s checker of the people at t = 0 replaced by Drake's of the room alone",
              type(checker).__name__)
    return None


def _trajectory(times, q, who: str) -> tuple[np.ndarray, np.ndarray]:
    """``times`` (T,) and ``q`` (T, 4), T >= 1, as finite float arrays, or the error naming them."""
    times = real_array(times, who, "times", (None,), layout="seconds", rows=(1, None), row_name="sample",
                       error=ScenarioError)
    q = real_array(q, who, "q", (None, 4), layout="rows [x, y, psi1, psi2]", rows=(1, None), row_name="sample",
                   error=ScenarioError)
    if len(times) != len(q):
        raise ScenarioError(f"{who}: times and q must have the same T rows, got {len(times)} and {len(q)}")
    return times, q


def simulate(
    scenario: Scenario,
    *,
    mode: str | None = None,
    execution: str | None = None,
    waypoints: np.ndarray | None = None,
    checker: ValidityChecker | None = None,
    meshcat: Meshcat | None = None,
    time_limit: float | None = None,
    analyze: bool = True,
    analysis_checker: ValidityChecker | None = None,
    progress: Callable[[float], None] | None = None,
    simulator_config: SimulatorConfig | None = None,
    people: PeopleModel | None = None,
    replan: bool | None = None,
) -> SimulationResult:
    """Plans (unless ``waypoints`` are given), executes and measures a transport.

    Args:
        scenario: a validated scenario.
        mode, execution, waypoints, checker, meshcat: see
            :func:`~drake_social.sim.diagram.build_diagram`. With ``meshcat``
            the run is recorded (``execution.replay_fps``); publish or export
            it afterwards (:mod:`drake_social.sim.replay`).
        time_limit: simulated seconds before giving up, in (0, MAX_TIME_LIMIT],
            at least MIN_CONTROL_PERIODS and at most MAX_CONTROL_STEPS control
            periods and at most MAX_PLANT_STEPS plant steps (the scenario's
            rules, :func:`~drake_social.scenario.time_limit_problem`); None =
            ``scenario.execution.time_limit``.
        analyze: check and measure the executed trajectory (:func:`analyze_execution`).
        analysis_checker: the checker of that analysis (None = Drake's).
        progress: optional ``progress(t)`` callback with the simulated time,
            called every quarter of a simulated second.
        simulator_config: Drake's ``SimulatorConfig`` of the run (integration
            scheme, accuracy, maximum step, target realtime rate); None =
            :func:`scenario_simulator_config`.
        people: the people model of the diagram (see
            :func:`~drake_social.sim.diagram.build_diagram`); None = the scenario's.
        replan: replan while executing (see
            :func:`~drake_social.sim.diagram.build_diagram`); None =
            ``scenario.planner.replan`` when planning.

    Returns:
        The :class:`SimulationResult`; ``reached`` is False when no path was
        found or the goal was not reached in time (``message`` says which).

    Raises:
        TypeError: an argument of the wrong kind (named).
        ValueError: an unknown mode or execution, a time limit outside the
            rules of a run's length.
        ScenarioError: an invalid scenario (e.g. contradictory execution
            options), or ``waypoints`` that must not be executed
            (:func:`~drake_social.waypoints.check_waypoints`: shape, limits,
            start and goal, collisions).
        PlanningInputError: the start or goal is unusable (from the planner).
    """
    # The cheap checks first, the waypoints' collision check last.
    require_scenario(scenario, "simulate")
    require_number(time_limit, "simulate", "time_limit", optional=True, unit="of seconds")  # its range: below
    require_instance(analyze, (bool, np.bool_), "simulate", "analyze", "True or False")
    require_checker(analysis_checker, "simulate", "analysis_checker", optional=True)
    require_callable(progress, "simulate", "progress")
    require_instance(simulator_config, SimulatorConfig, "simulate", "simulator_config",
                     "a pydrake.systems.analysis.SimulatorConfig", optional=True)
    require_instance(people, PeopleModel, "simulate", "people", "a drake_social.people.PeopleModel", optional=True)
    mode, execution = check_diagram_options(scenario, mode=mode, execution=execution, checker=checker,
                                            meshcat=meshcat, who="simulate")
    if time_limit is not None:  # the scenario's own was checked with it (validate_scenario)
        problem = time_limit_problem(time_limit, scenario.execution, "time_limit")
        if problem:
            raise ValueError(f"simulate: {problem[0]} {problem[1]}")
    limit = float(scenario.execution.time_limit if time_limit is None else time_limit)
    replan = resolve_replan(scenario, replan, waypoints is not None, True, "simulate")
    if waypoints is not None:
        waypoints = check_diagram_waypoints(scenario, waypoints, checker, "simulate")
    return run_checked(scenario, mode, execution, waypoints, checker, meshcat, limit, bool(analyze),
                       analysis_checker, progress, simulator_config=simulator_config, people=people, replan=replan)


def run_checked(
    scenario: Scenario,
    mode: str,
    execution: str,
    waypoints: np.ndarray | None,
    checker: ValidityChecker | None,
    meshcat: Meshcat | None,
    time_limit: float,
    analyze: bool,
    analysis_checker: ValidityChecker | None,
    progress: Callable[[float], None] | None,
    *,
    simulator_config: SimulatorConfig | None = None,
    people: PeopleModel | None = None,
    replan: bool = False,
    replanner=None,
) -> SimulationResult:
    """:func:`simulate` with its arguments already checked (the scenario
    validated, ``waypoints`` checked with ``checker`` by
    :func:`~drake_social.waypoints.check_waypoints`, ``mode``, ``execution``
    and ``time_limit`` the ones in force and allowed). For drake_social's own
    callers that checked them once (``drake-social simulate``). ``replan``:
    whether to replan (resolved); ``replanner``: the replanner object of
    :func:`~drake_social.sim.diagram.build_diagram` (None = the scenario's)."""
    limit = time_limit
    built = build_checked(scenario, mode, execution, waypoints, checker, meshcat, people=people, replan=replan,
                          replanner=replanner)
    root = built.diagram.CreateDefaultContext()
    if built.visualizer is not None:
        from drake_social.sim.replay import start_recording

        start_recording(built.meshcat, float(scenario.execution.replay_fps))
    # The initialization events (the planner plans) run first on their own, so
    # that a failed plan is reported before anything evaluates the sequencer;
    # Initialize() below then does not repeat them.
    built.diagram.ExecuteInitializationEvents(root)
    planner_result = None
    path = built.waypoints
    if built.replanning:  # a first plan that waits is no failure: the robot waits for a safe path
        path = np.asarray(built.subsystem("planner").GetOutputPort("waypoints").Eval(
            built.subsystem("planner").GetMyContextFromRoot(root)), float).reshape(-1, 4)
    elif path is None:
        planner = built.subsystem("planner")
        planner_result = planner.GetOutputPort("result").Eval(planner.GetMyContextFromRoot(root))
        path = np.asarray(planner_result.waypoints, float).reshape(-1, 4)
        if not planner_result.success:
            return _empty_result(built, path, planner_result, f"no path to execute ({planner_result.message})")
    simulator = Simulator(built.diagram, root)
    ApplySimulatorConfig(scenario_simulator_config(scenario) if simulator_config is None else simulator_config,
                         simulator)
    simulator.Initialize(InitializeParams(suppress_initialization_events=True))

    # Advance in chunks and stop at the first chunk after the goal: a Python
    # monitor called after every step would cost more than the whole kinematic
    # simulation. The time to goal comes from the logged done flag.
    sequencer = built.subsystem("sequencer")
    sequencer_context = sequencer.GetMyContextFromRoot(root)
    done_port = sequencer.GetOutputPort("done")
    chunk = max(_CHUNK, float(scenario.execution.control_period))
    q_port = built.loggers["q"].get_input_port()
    v_port = built.loggers["v"].get_input_port()
    q_context = built.loggers["q"].GetMyContextFromRoot(root)
    v_context = built.loggers["v"].GetMyContextFromRoot(root)
    bounds = configuration_limits(scenario)

    def check_divergence(cause: BaseException | None = None) -> None:
        what = _divergence(q_port.Eval(q_context), v_port.Eval(v_context), *bounds)
        if what is not None:
            raise SimulationDiverged(scenario, built.mode, root.get_time(), what) from cause

    t0 = time.perf_counter()
    while root.get_time() < limit:
        try:
            simulator.AdvanceTo(min(limit, root.get_time() + chunk))
        except RuntimeError as e:  # Drake refuses a state gone non-finite: say why
            check_divergence(e)
            raise
        check_divergence()
        if progress is not None:
            progress(root.get_time())
        if done_port.Eval(sequencer_context)[0] > 0.5:
            break
    wall = time.perf_counter() - t0
    if built.visualizer is not None:
        from drake_social.sim.replay import finish_recording

        finish_recording(built.meshcat)

    logs = {name: logger.FindLog(root) for name, logger in built.loggers.items()}
    times = logs["q"].sample_times().copy()
    data = {name: log.data().T.copy() for name, log in logs.items()}
    sim_time = root.get_time()
    # The sequencer decides in its update at t_k from q(t_k); a log sample at
    # t_k is published before that update, so done shows from t_k + period on.
    # The time to goal is t_k; the samples after the first done one (the
    # chunk's remainder) are dropped.
    done = np.flatnonzero(data["done"][:, 0] > 0.5)
    reached = len(done) > 0
    if reached:
        keep = int(done[0]) + 1
        times = times[:keep]
        data = {name: values[:keep] for name, values in data.items()}
    reached_at = [float(times[max(len(times) - 2, 0)])] if reached else []
    replans, replanning = (), None
    if built.replanning:
        planner = built.subsystem("planner")
        planner_context = planner.GetMyContextFromRoot(root)
        end = float(times[-1]) if len(times) else 0.0
        replans = tuple(r for r in planner.replans(planner_context) if r.t <= end + 1e-9)
        path = planner.followed(planner_context)
        replanning = replanning_summary(replans, planner.rate, float(scenario.planner.replan_budget))
    message = (f"goal reached at t = {reached_at[0]:.2f} s" if reached
               else f"goal not reached within the time limit of {limit:g} s "
                    + (f"(the last replan: {replans[-1].status})" if replans else
                       f"(at waypoint {int(data['index'][-1, 0]) if len(times) else 0} of {len(path) - 1})"))
    result = SimulationResult(
        mode=built.mode, execution=built.execution, reached=reached, message=message,
        time_to_goal=reached_at[0] if reached else None, sim_time=sim_time, wall_time=wall,
        realtime_factor=sim_time / wall if wall > 0 else math.inf, waypoints=path, times=times,
        q=data["q"], v=data["v"], wheel_speeds=data["wheel_speeds"], target=data["target"],
        reference=data["reference"], target_index=data["index"][:, 0].astype(int), planner=planner_result,
        stops=_stops(built, root, float(times[-1]) if len(times) else 0.0), replans=replans, replanning=replanning,
    )
    result.stopped = _stopped(times, result.stops)
    result.waiting = _waiting(times, replans)
    source = built.subsystem("people")
    if source.model.count and len(times):  # the open-loop people sampled; a crowd from its logged state
        result.people = source.people_log(times, data.get("crowd_state"))
    _log.info("%s", result.summary())
    if replanning is not None:
        _log.info("replanning: %s", replanning_line(replanning))
    for stop in result.stops:
        _log.info("safety stop at t = %.3f s (%s of the robot %.3f m from %s) %s", stop["start"], stop["part"],
                  stop["distance"], stop["person"],
                  "until the end" if stop["end"] is None else f"until t = {stop['end']:.3f} s")
    if analyze:
        result.report = analyze_execution(scenario, path, times, result.q, analysis_checker,
                                          people_move=not source.model.static)
    return result


def _stops(built: TransportDiagram, root, end_time: float) -> list[dict]:
    """The safety monitor's stops up to ``end_time`` (the last kept sample), as dicts
    (:attr:`SimulationResult.stops`); a stop released after ``end_time`` is still on at the end."""
    if "stop" not in built.loggers:
        return []
    monitor = built.subsystem("safety")
    out = []
    for stop in monitor.stops(monitor.GetMyContextFromRoot(root)):
        if stop.start > end_time:
            break
        if stop.end is not None and stop.end > end_time:
            stop = dc.replace(stop, end=None)
        out.append(stop.to_dict(end_time))
    return out


def _stopped(times: np.ndarray, stops: list[dict]) -> np.ndarray:
    """(T,) True where a stop holds the robot: start <= t < end (end None: to the end)."""
    held = np.zeros(len(times), bool)
    for stop in stops:
        held |= (times >= stop["start"]) & (True if stop["end"] is None else times < stop["end"])
    return held


def _waiting(times: np.ndarray, replans) -> np.ndarray:
    """(T,) True where the latest replan at or before t_k (within 1e-9 s: the
    replan period and the log period are summed apart) found no safe path."""
    if not replans:
        return np.zeros(len(times), bool)
    at = np.array([r.t for r in replans], float)
    wait = np.array([r.status == "wait" for r in replans], bool)
    latest = np.searchsorted(at, np.asarray(times, float) + 1e-9, side="right") - 1
    return (latest >= 0) & wait[np.maximum(latest, 0)]


def _empty_result(built: TransportDiagram, path: np.ndarray, planner: PlannerResult, message: str) -> SimulationResult:
    empty = np.zeros((0, 4))
    return SimulationResult(
        mode=built.mode, execution=built.execution, reached=False, message=message, time_to_goal=None,
        sim_time=0.0, wall_time=0.0, realtime_factor=math.nan, waypoints=path, times=np.zeros(0), q=empty,
        v=empty, wheel_speeds=empty, target=empty, reference=empty, target_index=np.zeros(0, int),
        planner=planner,
    )
