"""Runs an execution diagram with Drake's Simulator and measures what it did.

:func:`simulate` builds the diagram (:func:`~drake_social.sim.diagram.build_diagram`),
plans at initialization (or takes the given waypoints), advances until the
sequencer reports the goal reached or ``execution.time_limit`` passes, and
returns a :class:`~drake_social.sim.results.SimulationResult`: the logged
trajectory, the people at the same times, the safety stops and, after every
run, what the *executed* trajectory did
(:func:`~drake_social.sim.execution_analysis.analyze_execution`: collisions,
limits, social cost, deviation from the plan, clearance). It reads the
systems it needs from the diagram's records (the autonomy's sequencer,
planner and safety monitor, the station's people source), never by a
subsystem's name.

With ``replan`` (or the scenario's ``planner.replan``) the diagram's planner
replans every ``1 / planner.replan_rate`` seconds
(:class:`~drake_social.control.ReplanningPlannerSystem`): the result keeps
every replan (``SimulationResult.replans``), their summary
(``SimulationResult.replanning``, also in ``SimulationResult.to_json_dict``
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
from typing import Callable

import numpy as np
from pydrake.geometry import Meshcat
from pydrake.systems.analysis import ApplySimulatorConfig, InitializeParams, Simulator, SimulatorConfig

from drake_social.arguments import require_callable, require_checker, require_instance, require_number, require_scenario
from drake_social.collision.validity import ValidityChecker
from drake_social.control import replanning_summary
from drake_social.scenario.geometry import configuration_limits
from drake_social.model.plant import ACTUATED_JOINTS
from drake_social.people import PeopleModel
from drake_social.planning.result import PlannerResult
from drake_social.scenario import Scenario, time_limit_problem
from drake_social.sim.autonomy import path_source
from drake_social.sim.checks import check_diagram_options, check_diagram_waypoints, resolve_replan
from drake_social.sim.diagram import TransportDiagram, build_checked
from drake_social.sim.execution_analysis import analyze_execution
from drake_social.sim.results import SimulationDiverged, SimulationResult, replanning_line

__all__ = ["scenario_simulator_config", "simulate"]

#: Simulated seconds per AdvanceTo call between checks for the goal.
_CHUNK = 0.25

_log = logging.getLogger(__name__)

#: A state beyond these is a diverged simulation, not a motion: speeds
#: (m/s, rad/s) and arm angles (rad), and the base more than the room's
#: diagonal outside the room.
_ABSURD_SPEED = 1e3
_ABSURD_ANGLE = 1e2


#: The start of Drake's message when a discrete plant's step fails.
_SOLVER_FAILED = "discrete update solver failed to converge"


def _contact_solver_failed(scenario: Scenario, time: float) -> SimulationDiverged:
    """The error of a dynamic run whose plant step failed at ``time`` (s).

    TAMSI, the default contact approximation, can fail to converge in a hard
    contact (a body pushed into a wall by the base's servo, as the paper's
    execution may do when it leaves the checked segments); SAP (``lagged``,
    ``similar``) solves it, at about three times the cost of a step.
    """
    approximation = scenario.execution.contact_approximation
    advice = ("a hard contact; execution.contact_approximation: lagged or similar (SAP) solves it, "
              "as may a smaller execution.plant_time_step" if approximation == "tamsi" else
              f"execution.plant_time_step {scenario.execution.plant_time_step:g} s is too large for this "
              "contact; use a smaller one")
    return SimulationDiverged(scenario, "dynamic", time,
                              f"the plant's {approximation} contact solver did not converge", advice)


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
    built = build_checked(scenario, mode, execution, path_source(waypoints, replan, replanner), checker, meshcat,
                          people=people)
    root = built.diagram.CreateDefaultContext()
    if built.visualizer is not None:
        from drake_social.sim.replay import start_recording

        start_recording(built.meshcat, float(scenario.execution.replay_fps))
    # The initialization events (the planner plans) run first on their own, so
    # that a failed plan is reported before anything evaluates the sequencer;
    # Initialize() below then does not repeat them.
    built.diagram.ExecuteInitializationEvents(root)
    path, planner_result = _first_path(built, root)
    if planner_result is not None and not planner_result.success:
        return _empty_result(built, path, planner_result, f"no path to execute ({planner_result.message})")
    simulator = Simulator(built.diagram, root)  # owns root: alive until the logs are read
    ApplySimulatorConfig(scenario_simulator_config(scenario) if simulator_config is None else simulator_config,
                         simulator)
    simulator.Initialize(InitializeParams(suppress_initialization_events=True))
    wall = _advance(simulator, built, time_limit, progress)
    if built.visualizer is not None:
        from drake_social.sim.replay import finish_recording

        finish_recording(built.meshcat)
    result = _result(built, root, path, planner_result, time_limit, wall)
    _log_result(result)
    if analyze:
        result.report = analyze_execution(scenario, result.waypoints, result.times, result.q, analysis_checker,
                                          people_move=not built.station.people.model.static,
                                          judged=result.judged)
    return result


def _first_path(built: TransportDiagram, root) -> tuple[np.ndarray, PlannerResult | None]:
    """The path to execute after the initialization events, and the planner's
    result when it planned once (None: given waypoints, or the replanner's
    first plan, which may wait without failing: the robot waits for a safe path)."""
    planner = built.autonomy.planner
    if built.replanning:
        path = planner.GetOutputPort("waypoints").Eval(planner.GetMyContextFromRoot(root))
        return np.asarray(path, float).reshape(-1, 4), None
    if built.waypoints is not None:
        return built.waypoints, None
    result = planner.GetOutputPort("result").Eval(planner.GetMyContextFromRoot(root))
    return np.asarray(result.waypoints, float).reshape(-1, 4), result


def _advance(simulator: Simulator, built: TransportDiagram, limit: float,
             progress: Callable[[float], None] | None) -> float:
    """Advances until the sequencer's goal flag or ``limit`` (s), checking for
    divergence; returns the wall-clock seconds spent in ``AdvanceTo``.

    Advance in chunks and stop at the first chunk after the goal: a Python
    monitor called after every step would cost more than the whole kinematic
    simulation. The time to goal comes from the logged done flag.
    """
    root = simulator.get_context()
    sequencer = built.autonomy.sequencer
    sequencer_context = sequencer.GetMyContextFromRoot(root)
    done_port = sequencer.GetOutputPort("done")
    chunk = max(_CHUNK, float(built.scenario.execution.control_period))
    q_port, v_port = built.loggers["q"].get_input_port(), built.loggers["v"].get_input_port()
    q_context, v_context = (built.loggers[name].GetMyContextFromRoot(root) for name in ("q", "v"))
    bounds = configuration_limits(built.scenario)

    def check_divergence(cause: BaseException | None = None) -> None:
        what = _divergence(q_port.Eval(q_context), v_port.Eval(v_context), *bounds)
        if what is not None:
            raise SimulationDiverged(built.scenario, built.mode, root.get_time(), what) from cause

    t0 = time.perf_counter()
    while root.get_time() < limit:
        try:
            simulator.AdvanceTo(min(limit, root.get_time() + chunk))
        except RuntimeError as e:  # Drake refuses a state gone non-finite: say why
            check_divergence(e)
            if _SOLVER_FAILED in str(e):
                raise _contact_solver_failed(built.scenario, root.get_time()) from e
            raise
        check_divergence()
        if progress is not None:
            progress(root.get_time())
        if done_port.Eval(sequencer_context)[0] > 0.5:
            break
    return time.perf_counter() - t0


def _logs(built: TransportDiagram, root) -> tuple[np.ndarray, dict[str, np.ndarray], bool]:
    """The log times, each logger's samples (T, n) and whether the goal was reached.

    The sequencer decides in its update at t_k from q(t_k); a log sample at
    t_k is published before that update, so done shows from t_k + period on.
    The time to goal is t_k; the samples after the first done one (the
    chunk's remainder) are dropped.
    """
    logs = {name: logger.FindLog(root) for name, logger in built.loggers.items()}
    times = logs["q"].sample_times().copy()
    data = {name: log.data().T.copy() for name, log in logs.items()}
    done = np.flatnonzero(data["done"][:, 0] > 0.5)
    if len(done):
        keep = int(done[0]) + 1
        times = times[:keep]
        data = {name: values[:keep] for name, values in data.items()}
    return times, data, len(done) > 0


def _result(built: TransportDiagram, root, path: np.ndarray, planner_result: PlannerResult | None, limit: float,
            wall: float) -> SimulationResult:
    """The :class:`~drake_social.sim.results.SimulationResult` of a finished run (not yet analysed)."""
    times, data, reached = _logs(built, root)
    reached_at = [float(times[max(len(times) - 2, 0)])] if reached else []
    end = float(times[-1]) if len(times) else 0.0
    replans, replanning, judged, predicted = (), None, path, ()
    if built.replanning:
        planner = built.autonomy.planner
        planner_context = planner.GetMyContextFromRoot(root)
        replans = tuple(r for r in planner.replans(planner_context) if r.t <= end + 1e-9)
        predicted = tuple(p for p in planner.predictions(planner_context) if p.replan < len(replans))
        path, judged = planner.followed(planner_context), planner.judged(planner_context)
        replanning = replanning_summary(replans, planner.rate, float(built.scenario.planner.replan_budget))
    message = (f"goal reached at t = {reached_at[0]:.2f} s" if reached
               else f"goal not reached within the time limit of {limit:g} s "
                    + (f"(the last replan: {replans[-1].status})" if replans else
                       f"(at waypoint {int(data['index'][-1, 0]) if len(times) else 0} of {len(path) - 1})"))
    sim_time = root.get_time()
    result = SimulationResult(
        mode=built.mode, execution=built.execution, reached=reached, message=message,
        time_to_goal=reached_at[0] if reached else None, sim_time=sim_time, wall_time=wall,
        realtime_factor=sim_time / wall if wall > 0 else math.inf, waypoints=path, times=times,
        q=data["q"], v=data["v"], wheel_speeds=data["wheel_speeds"], target=data["target"],
        reference=data["reference"], target_index=data["index"][:, 0].astype(int), planner=planner_result,
        stops=_stops(built.autonomy.safety, root, end), replans=replans, replanning=replanning, predicted=predicted,
        speed_limit=data["speed_limit"][:, 0] if "speed_limit" in data else np.full(len(times), np.inf),
        slow_stops=_stops(built.autonomy.speed_limit, root, end), judged=judged,
    )
    result.stopped = _stopped(times, result.stops)
    result.slow_stopped = _stopped(times, result.slow_stops)
    result.waiting = _waiting(times, replans)
    source = built.station.people
    if source.model.count and len(times):  # the open-loop people sampled; a crowd from its logged state
        result.people = source.people_log(times, data.get("crowd_state"))
    return result


def _log_result(result: SimulationResult) -> None:
    _log.info("%s", result.summary())
    if result.replanning is not None:
        _log.info("replanning: %s", replanning_line(result.replanning))
    for stop in result.stops:
        _log.info("safety stop at t = %.3f s (%s of the robot %.3f m from %s) %s", stop["start"], stop["part"],
                  stop["distance"], stop["person"],
                  "until the end" if stop["end"] is None else f"until t = {stop['end']:.3f} s")


def _stops(monitor, root, end_time: float) -> list[dict]:
    """The stops of ``monitor`` (the safety monitor, the slow-down's limiter or None) up to
    ``end_time`` (the last kept sample), as dicts (:attr:`SimulationResult.stops`); a stop
    released after ``end_time`` is still on at the end."""
    if monitor is None:
        return []
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
