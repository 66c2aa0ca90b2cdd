"""Validation of a scenario's values: the rules the schema's types cannot express.

Each rule raises :class:`~drake_social.errors.ScenarioError` as
``<source>: <dotted field>: <the rule>, got <value>``: ranges (``must be >
0``), lengths, finiteness, positions inside the room, joint limits, the
choice fields' allowed names, and the rules that tie fields together (a
dynamic run's plant step, a run's length in control periods and plant steps,
the social cost's sampling of the longest motion in the room); the people's
rules (trajectories, the recorded ``people_file``, where people start) are
those of :mod:`drake_social.scenario.people_rules`.
"""

import dataclasses as dc
import math

import numpy as np

from drake_social.errors import ScenarioError
from drake_social.io.textfile import shorten
from drake_social.kinematics import displacement_bound
from drake_social.scenario.geometry import arm_geometry
from drake_social.limits import (ALGORITHMS, CONTACT_APPROXIMATIONS, INFORMED_ALGORITHMS, INTEGRATION_SCHEMES,
                                 MAX_CONTROL_STEPS, MAX_DYNAMIC_PLANT_TIME_STEP,
                                 MAX_ITERATIONS, MAX_MOTION_STEPS, MAX_OBJECT_POINTS, MAX_PLANT_STEPS,
                                 MAX_COST_WEIGHT, MAX_COURTESY_DECELERATION, MAX_COURTESY_DEVIATION,
                                 MAX_REPLAN_BUDGET, MAX_REPLAN_HORIZON,
                                 MAX_REPLAN_ITERATIONS,
                                 MAX_REPLANS_PER_CONTROL_PERIOD, MAX_REPLAY_FPS, MAX_TIME_LIMIT, MIN_CONTROL_PERIODS,
                                 SERVO_BANDWIDTH)
from drake_social.scenario.crowd_rules import crowd_problems
from drake_social.scenario.map_rules import check_map
from drake_social.scenario.people_rules import check_people
from drake_social.scenario.schema import (EXECUTIONS, INFORMED_MODES, NEAR_RADIUS_MODES, PREDICTIONS, SIM_MODES, Bar,
                                          ExecutionOptions, LShape, Scenario, interest_point_count)

__all__ = [
    "drake_config_problem",
    "period_count",
    "plant_time_step_problem",
    "replan_rate_problem",
    "time_limit_problem",
    "validate_planner_choice",
    "validate_scenario",
]


# --------------------------------------------------------------------------
# Validation. Each check names the field by its dotted path.


def _check_slow_down(c: "_Checker", e) -> None:
    """The slow-down's options (``execution.slow_down`` ... ``release_time``)."""
    if not isinstance(e.slow_down, bool):
        c.fail("execution.slow_down", f"must be true or false, got {_shown(e.slow_down)}")
    c.nonnegative("execution.stop_margin", e.stop_margin)
    c.nonnegative("execution.release_time", e.release_time)
    c.finite("execution.slow_distance", e.slow_distance)
    stop = e.safety_distance + e.stop_margin
    if not e.slow_distance > stop:
        c.fail("execution.slow_distance", f"must be > execution.safety_distance + execution.stop_margin = "
                                          f"{stop:g} m, got {e.slow_distance}")
    c.positive("execution.slow_speed", e.slow_speed)
    if e.slow_speed > e.max_base_speed:
        c.fail("execution.slow_speed", f"must be <= execution.max_base_speed {e.max_base_speed:g} m/s, "
                                       f"got {e.slow_speed}")


def _commitment(c, p) -> None:
    """What keeps a replanning robot on its route: the margin and the length, time and switching weights."""
    c.finite("planner.replan_margin", p.replan_margin)
    if not 0.0 <= p.replan_margin < 1.0:
        c.fail("planner.replan_margin", f"must be in [0, 1), got {p.replan_margin}")
    c.weight("planner.replan_length_weight", p.replan_length_weight)
    c.weight("planner.time_weight", p.time_weight)
    c.weight("planner.switch_weight", p.switch_weight)


def _courtesy(c, p) -> None:
    """The interactive prediction's courtesy bounds (``planner.courtesy_*``)."""
    for name, most, unit in (("courtesy_deceleration", MAX_COURTESY_DECELERATION, "m/s^2"),
                             ("courtesy_deviation", MAX_COURTESY_DEVIATION, "metres")):
        value = getattr(p, name)
        c.finite(f"planner.{name}", value)
        if not 0.0 < value <= most:
            c.fail(f"planner.{name}", f"must be in (0, {most:g}] {unit}, got {_shown(value)}")
    c.weight("planner.courtesy_weight", p.courtesy_weight)


class _Checker:
    def __init__(self, source: str):
        self.source = source

    def fail(self, field: str, message: str):
        raise ScenarioError(f"{self.source}: {field}: {message}")

    def finite(self, field: str, value) -> None:
        arr = np.asarray(value, dtype=float)
        if not np.all(np.isfinite(arr)):
            self.fail(field, f"must be finite numbers, got {_shown(value)}")

    def positive(self, field: str, value) -> None:
        self.finite(field, value)
        if not np.all(np.asarray(value, dtype=float) > 0):
            self.fail(field, f"must be > 0, got {_shown(value)}")

    def nonnegative(self, field: str, value) -> None:
        self.finite(field, value)
        if not np.all(np.asarray(value, dtype=float) >= 0):
            self.fail(field, f"must be >= 0, got {_shown(value)}")

    def weight(self, field: str, value) -> None:
        """A weight of an objective: in [0, MAX_COST_WEIGHT]."""
        self.finite(field, value)
        arr = np.asarray(value, dtype=float)
        if not np.all((arr >= 0) & (arr <= MAX_COST_WEIGHT)):
            self.fail(field, f"must be in [0, {MAX_COST_WEIGHT:g}], got {_shown(value)}")

    def length(self, field: str, value, n: int) -> None:
        if len(value) != n:
            self.fail(field, f"must have {n} values, got {len(value)}: {_shown(value)}")

    def points(self, field: str, value, min_count: int) -> None:
        if len(value) < min_count:
            self.fail(field, f"needs at least {min_count} points [x, y], got {len(value)}")
        for i, p in enumerate(value):
            self.length(f"{field}[{i}]", p, 2)
            self.finite(f"{field}[{i}]", p)


def _shown(value) -> str:
    """A value of the scenario as an error message repeats it (:func:`~drake_social.io.textfile.shorten`)."""
    return shorten(repr(value) if isinstance(value, str) else str(value))


def period_count(duration: float, period: float) -> int:
    """How many periods of ``period`` seconds a run of ``duration`` seconds
    takes (the ratio rounded up; a ratio within 1e-9 of an integer counts as
    that integer, so 270 s / 0.0045 s is 60,000 periods although it computes
    to 60000.00000000001)."""
    ratio = duration / period
    nearest = round(ratio)
    return int(nearest) if abs(ratio - nearest) <= 1e-9 * max(1.0, ratio) else math.ceil(ratio)



def _longest_motion_bound(scenario: Scenario) -> float:
    """The largest displacement bound of any motion in the scenario's
    configuration space (metres): :func:`~drake_social.kinematics.displacement_bound`
    with every interest point's lever, the room's extent and both joints'
    full turns (the social cost's own bound never exceeds it)."""
    x_min, y_min, x_max, y_max = scenario.world.bounds
    lower, upper = scenario.robot.joint_lower, scenario.robot.joint_upper
    extent = np.array([x_max - x_min, y_max - y_min, upper[0] - lower[0], upper[1] - lower[1]])
    return float(displacement_bound(extent, arm_geometry(scenario).lever()))


def plant_time_step_problem(execution: ExecutionOptions, mode: str) -> tuple[str, str] | None:
    """What is wrong with ``execution.plant_time_step`` for a run in ``mode``
    (a dynamic run's servo is stable only up to
    :data:`MAX_DYNAMIC_PLANT_TIME_STEP`), or None.

    Returns:
        (the field at fault, what is allowed and what was given), or None.
    """
    step = execution.plant_time_step
    if mode == "dynamic" and step > MAX_DYNAMIC_PLANT_TIME_STEP:
        return "execution.plant_time_step", (
            f"must be <= {MAX_DYNAMIC_PLANT_TIME_STEP:.6g} s in dynamic mode (the servo's damping gain "
            f"{2 * SERVO_BANDWIDTH:g} /s times the step must be <= 1 for the plant to stay stable), got {step}")
    return None


def drake_config_problem(execution: ExecutionOptions) -> tuple[str, str] | None:
    """What is wrong with the Drake settings of a scenario's ``execution``
    section, or None: ``contact_approximation`` (one of
    :data:`CONTACT_APPROXIMATIONS`), ``integration_scheme`` (one of
    :data:`INTEGRATION_SCHEMES`), ``accuracy`` (> 0, finite) and
    ``target_realtime_rate`` (>= 0, finite).

    Returns:
        (the field at fault, what is allowed and what was given), or None.
    """
    e = execution
    if e.contact_approximation not in CONTACT_APPROXIMATIONS:
        return "execution.contact_approximation", (f"unknown approximation {_shown(e.contact_approximation)}; "
                                                   f"allowed: {', '.join(CONTACT_APPROXIMATIONS)}")
    if e.integration_scheme not in INTEGRATION_SCHEMES:
        return "execution.integration_scheme", (f"unknown scheme {_shown(e.integration_scheme)}; "
                                                f"allowed: {', '.join(INTEGRATION_SCHEMES)}")
    for name in ("accuracy", "target_realtime_rate"):
        value = getattr(e, name)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            return f"execution.{name}", f"must be a finite number, got {_shown(value)}"
    if not e.accuracy > 0:
        return "execution.accuracy", f"must be > 0, got {e.accuracy!r}"
    if e.target_realtime_rate < 0:
        return "execution.target_realtime_rate", (f"must be >= 0 (0 = as fast as possible), "
                                                  f"got {e.target_realtime_rate!r}")
    return None


def time_limit_problem(time_limit: float, execution: ExecutionOptions, argument: str | None = None
                       ) -> tuple[str, str] | None:
    """What is wrong with a run of ``time_limit`` seconds under ``execution``
    (the rules of a run's length), or None.

    The rules: ``0 < time_limit <= MAX_TIME_LIMIT``, at least
    :data:`MIN_CONTROL_PERIODS` and at most :data:`MAX_CONTROL_STEPS` control
    periods, at most :data:`MAX_PLANT_STEPS` plant steps. Both
    :func:`validate_scenario` (``execution.time_limit``) and
    :func:`drake_social.sim.run.simulate` (its ``time_limit`` argument) use them.

    Args:
        time_limit: seconds.
        execution: the periods and steps of the run.
        argument: the name of a function's argument giving ``time_limit``;
            None = the scenario's own ``execution.time_limit``.

    Returns:
        (the field at fault, what is allowed and what was given), or None.
    """
    e = execution
    limit = float(time_limit)
    if not 0 < limit <= MAX_TIME_LIMIT:
        return argument or "execution.time_limit", f"must be in (0, {MAX_TIME_LIMIT:g}] seconds, got {time_limit}"
    # (periods or steps, their length, its field, the fewest, the most, why)
    rules = ((e.control_period, "execution.control_period", MIN_CONTROL_PERIODS, None,
              f"a run lasts at least {MIN_CONTROL_PERIODS} control periods: the sequencer decides once per period"),
             (e.control_period, "execution.control_period", None, MAX_CONTROL_STEPS,
              f"a run may take at most {MAX_CONTROL_STEPS:,} control periods"),
             (e.plant_time_step, "execution.plant_time_step", None, MAX_PLANT_STEPS,
              f"a run may take at most {MAX_PLANT_STEPS:,} plant steps"))
    for length, field, fewest, most, why in rules:
        if fewest is not None and limit < fewest * length * (1 - 1e-9):  # whole periods, up to rounding
            if argument:
                return argument, (f"must be >= {fewest} * {field} {length} = {fewest * length:.6g} s ({why}), "
                                  f"got {time_limit}")
            return field, f"must be <= execution.time_limit / {fewest} = {limit / fewest:.6g} s ({why}), got {length}"
        if most is not None and period_count(limit, length) > most:
            if argument:
                return argument, (f"must be <= {most:,} * {field} {length} = {most * length:.6g} s ({why}), "
                                  f"got {time_limit}")
            return field, f"must be >= execution.time_limit / {most:,} = {limit / most:.3g} s ({why}), got {length}"
    return None


def replan_rate_problem(rate: float, execution: ExecutionOptions) -> str | None:
    """What is wrong with replanning ``rate`` times a second (> 0) under
    ``execution`` (at most :data:`MAX_REPLANS_PER_CONTROL_PERIOD` replan per
    control period: the period ``1 / rate`` at least ``control_period``), or None.

    A rule of a run that replans: :func:`validate_scenario` applies it with
    ``planner.replan`` on, and whatever turns replanning on for a scenario
    without it (``simulate --replan``, ``simulate(..., replan=True)``) applies it then.
    """
    period = execution.control_period / MAX_REPLANS_PER_CONTROL_PERIOD
    if 1.0 / rate < period:
        return (f"must be <= 1 / execution.control_period = {1.0 / period:g} Hz (at most one replan per control "
                f"period: the sequencer takes a new path once per period), got {rate}")
    return None


def validate_planner_choice(scenario: Scenario, algorithm: str, iterations: int | None = None,
                            source: str = "<scenario>") -> None:
    """Checks ``scenario`` as a run that plans with ``algorithm`` (and
    ``iterations``) in place of its ``planner.algorithm`` (and
    ``planner.iterations``) does: a study's or a benchmark's runs choose the
    planner themselves, and a rule such as ``planner.informed_mode:
    admissible`` (which needs ``social.length_weight > 0`` for the informed
    planners) depends on it.

    Args:
        scenario: a scenario (valid with its own planner).
        algorithm: the planner of the run (one of :data:`ALGORITHMS`).
        iterations: K of the run; None = the scenario's.
        source: how errors name the scenario and the choice.

    Raises:
        ScenarioError: as :func:`validate_scenario`, naming ``source``.
    """
    planner = dc.replace(scenario.planner, algorithm=algorithm,
                         iterations=scenario.planner.iterations if iterations is None else int(iterations))
    validate_scenario(dc.replace(scenario, planner=planner), source=source)


def validate_scenario(scenario: Scenario, source: str = "<scenario>") -> None:
    """Checks values that the schema's types cannot express.

    Raises:
        ScenarioError: naming ``source``, the dotted field and what is allowed.
    """
    c = _Checker(source)
    w = scenario.world
    c.length("world.bounds", w.bounds, 4)
    c.finite("world.bounds", w.bounds)
    x_min, y_min, x_max, y_max = w.bounds
    if not (x_max > x_min and y_max > y_min):
        c.fail("world.bounds", f"must be [x_min, y_min, x_max, y_max] with max > min, got {w.bounds}")
    c.positive("world.wall_thickness", w.wall_thickness)
    for i, box in enumerate(w.obstacles):
        c.length(f"world.obstacles[{i}].center", box.center, 2)
        c.finite(f"world.obstacles[{i}].center", box.center)
        c.length(f"world.obstacles[{i}].size", box.size, 2)
        c.positive(f"world.obstacles[{i}].size", box.size)
        c.finite(f"world.obstacles[{i}].yaw", box.yaw)

    def inside(field: str, x: float, y: float) -> None:
        if not (x_min <= x <= x_max and y_min <= y <= y_max):
            c.fail(field, f"position ({x}, {y}) is outside world.bounds {w.bounds}")

    for i, p in enumerate(scenario.people):
        c.finite(f"people[{i}]", [p.x, p.y, p.theta])
        c.positive(f"people[{i}].radius", p.radius)
        if p.trajectory is None:  # a trajectory's every segment is checked in check_people
            inside(f"people[{i}]", p.x, p.y)

    r = scenario.robot
    c.positive("robot.base_radius", r.base_radius)
    c.length("robot.link_lengths", r.link_lengths, 2)
    c.positive("robot.link_lengths", r.link_lengths)
    c.positive("robot.link_width", r.link_width)
    c.length("robot.joint_lower", r.joint_lower, 2)
    c.finite("robot.joint_lower", r.joint_lower)
    c.length("robot.joint_upper", r.joint_upper, 2)
    c.finite("robot.joint_upper", r.joint_upper)
    if not all(u > lo for lo, u in zip(r.joint_lower, r.joint_upper)):
        c.fail("robot.joint_upper", f"must exceed robot.joint_lower {r.joint_lower}, got {r.joint_upper}")
    # A part as wide as the room's smaller side touches a wall in every
    # configuration (and Drake's distance queries stall on parts ~10^6 m wide).
    side = min(x_max - x_min, y_max - y_min)
    for field, width, what in (("robot.base_radius", 2 * r.base_radius, "the base's diameter"),
                               ("robot.link_width", r.link_width, "the links' width")):
        if not width < side:
            limit = side / 2 if field == "robot.base_radius" else side
            c.fail(field, f"must be < {limit:.6g} m in this room ({what} must be less than its smaller side, "
                          f"{side:.6g} m, or the robot touches a wall everywhere), got {getattr(r, field[6:])}")

    o = scenario.object
    if isinstance(o, Bar):
        c.positive("object.length", o.length)
    elif isinstance(o, LShape):
        c.length("object.lengths", o.lengths, 2)
        c.positive("object.lengths", o.lengths)
    else:
        c.points("object.points", o.points, 2)
        if len(o.points) > MAX_OBJECT_POINTS:
            c.fail("object.points", f"at most {MAX_OBJECT_POINTS} vertices (each is a collision shape of the model, "
                                    f"checked at every step of a motion), got {len(o.points)}; a polyline through "
                                    f"fewer of its vertices approximates a smooth curve")
    c.positive("object.thickness", o.thickness)
    if not o.thickness < side:
        c.fail("object.thickness", f"must be < {side:.6g} m in this room (the object's thickness must be less than "
                                   f"its smaller side, or the object touches a wall everywhere), got {o.thickness}")
    if o.interest_points is not None:
        c.points("object.interest_points", o.interest_points, 1)

    for name in ("start", "goal"):
        q = getattr(scenario, name)
        c.length(name, q, 4)
        c.finite(name, q)
        inside(name, q[0], q[1])
        for j in range(2):
            if not (r.joint_lower[j] <= q[2 + j] <= r.joint_upper[j]):
                c.fail(
                    f"{name}[{2 + j}]",
                    f"psi{j + 1} = {q[2 + j]} is outside the joint range "
                    f"[{r.joint_lower[j]}, {r.joint_upper[j]}]",
                )
    if np.array_equal(np.asarray(scenario.start, float), np.asarray(scenario.goal, float)):
        c.fail("goal", f"must differ from start (both are {list(scenario.goal)}): a transport from a "
                       "configuration to itself has nothing to plan or execute")
    # The map: readable, the base of start and goal in free cells.
    check_map(scenario, c.fail)
    # Trajectories, the recorded file and where people start (against the robot at start).
    check_people(scenario, c.fail)

    s = scenario.social
    c.positive("social.sigma_h", s.sigma_h)
    c.positive("social.side_ratio", s.side_ratio)
    c.positive("social.rear_ratio", s.rear_ratio)
    c.finite("social.threshold", s.threshold)
    if not 0.0 <= s.threshold < 1.0:
        c.fail("social.threshold", f"must be in [0, 1), got {s.threshold}")
    n_points = 3 + interest_point_count(o)
    if s.weights is not None:
        c.length("social.weights", s.weights, n_points)
        c.weight("social.weights", s.weights)
    c.weight("social.length_weight", s.length_weight)
    c.positive("social.resolution", s.resolution)
    # The longest motion in the room must be sampleable in at most
    # MAX_MOTION_STEPS steps (the object and robot are checked above).
    longest = _longest_motion_bound(scenario)
    if longest > MAX_MOTION_STEPS * s.resolution:
        c.fail("social.resolution", f"must be >= {longest / MAX_MOTION_STEPS:.3g} m for this world and robot "
                                    f"(a motion may move a point {longest:.4g} m, sampled in at most "
                                    f"{MAX_MOTION_STEPS:,} steps), got {s.resolution}")

    p = scenario.planner
    if p.algorithm not in ALGORITHMS:
        c.fail("planner.algorithm", f"unknown algorithm {_shown(p.algorithm)}; allowed: {', '.join(ALGORITHMS)}")
    if not 1 <= p.iterations <= MAX_ITERATIONS:
        c.fail("planner.iterations", f"must be in [1, {MAX_ITERATIONS}], got {p.iterations}")
    if p.near_radius_mode not in NEAR_RADIUS_MODES:
        c.fail("planner.near_radius_mode",
               f"unknown mode {_shown(p.near_radius_mode)}; allowed: {', '.join(NEAR_RADIUS_MODES)}")
    c.finite("planner.near_radius_gamma", p.near_radius_gamma)
    if p.near_radius_gamma < 0:
        c.fail("planner.near_radius_gamma", f"must be >= 0 (0: computed from the space), got {p.near_radius_gamma}")
    if not isinstance(p.optimize, bool):
        c.fail("planner.optimize", f"must be true or false, got {_shown(p.optimize)}")
    c.positive("planner.planning_range", p.planning_range)
    c.positive("planner.near_radius", p.near_radius)
    c.finite("planner.goal_bias", p.goal_bias)
    if not 0.0 <= p.goal_bias < 1.0:
        c.fail("planner.goal_bias", f"must be in [0, 1), got {p.goal_bias}")
    if p.informed_mode not in INFORMED_MODES:
        c.fail("planner.informed_mode", f"unknown mode {_shown(p.informed_mode)}; allowed: {', '.join(INFORMED_MODES)}")
    if p.informed_mode == "admissible" and p.algorithm in INFORMED_ALGORITHMS and s.length_weight <= 0:
        c.fail("planner.informed_mode", "'admissible' needs social.length_weight > 0")
    c.length("planner.distance_weights", p.distance_weights, 4)
    c.positive("planner.distance_weights", p.distance_weights)
    c.positive("planner.collision_resolution", p.collision_resolution)
    if not isinstance(p.replan, bool):
        c.fail("planner.replan", f"must be true or false, got {_shown(p.replan)}")
    for name in ("replan_rate", "replan_budget", "replan_horizon", "safety_horizon"):
        c.positive(f"planner.{name}", getattr(p, name))
    if not 1 / p.replan_rate < math.inf:  # a period of 1e-320 Hz overflows
        c.fail("planner.replan_rate", f"must have a finite period 1 / replan_rate, got {p.replan_rate}")
    for name, most in (("replan_budget", MAX_REPLAN_BUDGET), ("replan_horizon", MAX_REPLAN_HORIZON),
                       ("safety_horizon", MAX_REPLAN_HORIZON)):
        if getattr(p, name) > most:
            c.fail(f"planner.{name}", f"must be in (0, {most:g}] seconds, got {getattr(p, name)}")
    if not 1 <= p.replan_iterations <= MAX_REPLAN_ITERATIONS:
        c.fail("planner.replan_iterations", f"must be in [1, {MAX_REPLAN_ITERATIONS:,}] (samples of one replan's "
                                            f"search), got {p.replan_iterations}")
    _commitment(c, p)
    c.finite("planner.replan_search_period", p.replan_search_period)
    if not p.replan_search_period >= 0.0:
        c.fail("planner.replan_search_period", f"must be >= 0 seconds, got {p.replan_search_period}")
    if p.prediction not in PREDICTIONS:
        c.fail("planner.prediction", f"unknown prediction {_shown(p.prediction)}; allowed: {', '.join(PREDICTIONS)}")
    _courtesy(c, p)
    e = scenario.execution
    if e.mode not in SIM_MODES:
        c.fail("execution.mode", f"unknown mode {_shown(e.mode)}; allowed: {', '.join(SIM_MODES)}")
    if e.execution not in EXECUTIONS:
        c.fail("execution.execution", f"unknown execution {_shown(e.execution)}; allowed: {', '.join(EXECUTIONS)}")
    for name in ("kp", "max_base_speed", "max_base_acceleration", "max_base_jerk", "wheel_radius",
                 "max_wheel_speed", "base_tolerance", "joint_tolerance", "control_period",
                 "plant_time_step", "time_limit", "replay_fps"):
        c.positive(f"execution.{name}", getattr(e, name))
    c.nonnegative("execution.safety_distance", e.safety_distance)  # 0 = stop on contact only
    _check_slow_down(c, e)
    for name in ("arm_max_velocity", "arm_max_acceleration", "arm_max_jerk"):
        c.length(f"execution.{name}", getattr(e, name), 2)
        c.positive(f"execution.{name}", getattr(e, name))
    if e.plant_time_step > e.control_period:
        c.fail("execution.plant_time_step",
               f"must be <= execution.control_period {e.control_period}, got {e.plant_time_step}")
    problem = time_limit_problem(e.time_limit, e)
    if problem:
        c.fail(*problem)
    problem = plant_time_step_problem(e, e.mode)
    if problem:
        c.fail(*problem)
    problem = drake_config_problem(e)
    if problem:
        c.fail(*problem)
    if e.kp * e.control_period >= 2.0:
        c.fail("execution.kp",
               f"execution.kp * execution.control_period must be < 2 (the base's sampled P-controller "
               f"multiplies its error by 1 - kp * control_period each period and converges only then), got "
               f"{e.kp} * {e.control_period} = {e.kp * e.control_period:.6g}")
    if e.replay_fps > MAX_REPLAY_FPS:
        c.fail("execution.replay_fps", f"must be <= {MAX_REPLAY_FPS:g} frames per second, got {e.replay_fps}")
    problem = replan_rate_problem(p.replan_rate, e) if p.replan else None  # --replan checks it when it turns it on
    if problem:
        c.fail("planner.replan_rate", problem)
    if scenario.random_seed < 0:
        c.fail("random_seed", f"must be >= 0, got {scenario.random_seed}")
    for field, message in crowd_problems(scenario):
        c.fail(field, message)
