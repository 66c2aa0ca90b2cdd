"""The one check of a path to execute (drake_social.waypoints), through every
door: ``simulate --path``, ``simulate`` and ``build_diagram``; and the
arguments of the public functions (drake_social.arguments).

Each refusal is asserted by its exact message (source, waypoint, field, what
is allowed); the verdicts on collisions are confirmed by the pure-numpy
reference checker, independent of the planar checker the run uses.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from drake_social.cli import main
from drake_social.limits import MAX_WAYPOINTS
from drake_social.collision.geometric import GeometricChecker
from drake_social.planning.result import PlanningInputError
from drake_social.scenario import ScenarioError, validate_scenario
from drake_social.sim.diagram import build_diagram
from drake_social.sim.execution_analysis import analyze_execution
from drake_social.sim.run import simulate

H = math.pi / 2
#: A path of tiny.yaml whose waypoints are all free but whose second segment
#: drives the base through the desk (confirmed below by the numpy checker).
THROUGH_THE_DESK = [[1.0, 2.5, 0.0, 1.5708], [2.5, 0.6, H, 0.0], [5.5, 0.6, H, 0.0], [6.5, 2.5, 0.0, 1.5708]]


@pytest.fixture(scope="module")
def path(tiny_scenario):
    """A straight two-waypoint path of tiny.yaml, start to goal (free, checked below)."""
    return np.array([tiny_scenario.start, tiny_scenario.goal], float)


def test_the_fixtures_are_what_the_tests_assume(tiny_scenario, path):
    reference = GeometricChecker(tiny_scenario)
    assert reference.are_valid(path).all() and reference.are_motions_valid(path[:1], path[1:]).all()
    desk = np.array(THROUGH_THE_DESK)
    assert reference.are_valid(desk).all()
    assert reference.are_motions_valid(desk[:-1], desk[1:]).tolist() == [True, False, True]


# ---- the API: simulate and build_diagram ------------------------------------------------

SHAPE = "must be an (N, 4) array of rows [x, y, psi1, psi2] with 2 <= N <= 10,000"


@pytest.mark.parametrize("waypoints, message", [
    (np.zeros(3), f"waypoints: {SHAPE}, got shape (3,)"),
    (np.zeros((3, 5)), f"waypoints: {SHAPE}, got shape (3, 5)"),
    (np.zeros((4, 3)), f"waypoints: {SHAPE}, got shape (4, 3)"),
    (np.zeros((2, 2, 4)), f"waypoints: {SHAPE}, got shape (2, 2, 4)"),
    (np.zeros((0, 4)), f"waypoints: {SHAPE} (the start, ..., the goal; limits.MAX_WAYPOINTS), got 0 waypoints"),
    ([[1.0, 2.5, 0.0, 1.5708]], f"waypoints: {SHAPE} (the start, ..., the goal; limits.MAX_WAYPOINTS), "
                                "got 1 waypoint"),
    (np.zeros((MAX_WAYPOINTS + 1, 4)), f"waypoints: {SHAPE} (the start, ..., the goal; limits.MAX_WAYPOINTS), "
                                       "got 10,001 waypoints"),
])
@pytest.mark.parametrize("door", ["simulate", "build_diagram"])
def test_a_wrong_shape_is_refused_never_reshaped(tiny_scenario, door, waypoints, message):
    run = {"simulate": simulate, "build_diagram": build_diagram}[door]
    with pytest.raises(ScenarioError) as info:
        run(tiny_scenario, waypoints=waypoints)
    assert str(info.value) == f"{door}: {message}"


@pytest.mark.parametrize("waypoints, kind", [
    ("1,2,3,4", "str"), ([["1", "2", "3", "4"]] * 2, "<U1"), ([[1, 2, 3, None]] * 2, "values of type NoneType"),
    ([[True, False, True, False]] * 2, "bool"), ([[1j, 0, 0, 0]] * 2, "complex128"),
    (np.array([[1.0, 2.5, 0.0, True]] * 2, dtype=object), "values of type bool"),
    (np.array([[1.0, 2.5, 0.0, 1j]] * 2, dtype=object), "values of type complex"),
    (np.ma.masked_array(np.zeros((2, 4)), mask=[[0, 0, 0, 1], [0] * 4]), "a masked array"),
])
def test_values_that_are_not_real_numbers_are_a_type_error(tiny_scenario, waypoints, kind):
    with pytest.raises(TypeError, match=r"^simulate: waypoints: must be an \(N, 4\) array") as info:
        simulate(tiny_scenario, waypoints=waypoints)
    assert kind in str(info.value)


def test_ragged_rows_are_refused(tiny_scenario):
    with pytest.raises(ScenarioError, match=r"^build_diagram: waypoints: .*its rows differ in length"):
        build_diagram(tiny_scenario, waypoints=[[1.0, 2.5, 0.0, 1.5708], [6.5, 2.5]])


def _with(path, row, values):
    """``path`` with a waypoint inserted before ``row``."""
    return np.insert(np.asarray(path, float), row, values, axis=0)


@pytest.mark.parametrize("make, message", [
    (lambda p: _with(p, 1, [100.0, 2.5, 0.0, 1.5708]),
     "waypoint 1: x: 100.0 is outside the room [0.0, 8.0] (world.bounds)"),
    (lambda p: _with(p, 1, [3.0, -0.5, 0.0, 1.5708]),
     "waypoint 1: y: -0.5 is outside the room [0.0, 5.0] (world.bounds)"),
    (lambda p: _with(p, 1, [3.0, 2.5, 10.0, 1.5708]),
     f"waypoint 1: psi1: 10.0 is outside the joint range [{-math.pi!r}, {math.pi!r}] "
     "(robot.joint_lower/joint_upper)"),
    (lambda p: _with(p, 1, [3.0, 2.5, 0.0, -4.0]),
     f"waypoint 1: psi2: -4.0 is outside the joint range [{-math.pi!r}, {math.pi!r}] "
     "(robot.joint_lower/joint_upper)"),
    (lambda p: _with(p, 1, [3.0, 2.5, np.nan, 0.0]), "waypoint 1: psi1: must be a finite number, got nan"),
    (lambda p: _with(p, 1, [np.inf, 2.5, 0.0, 0.0]), "waypoint 1: x: must be a finite number, got inf"),
    (lambda p: p[:1], None),  # [start] alone: see the shape test
    (lambda p: _with(p, 0, [2.0, 2.5, 0.0, 1.5708]),
     "waypoint 0: the first waypoint [2.0, 2.5, 0.0, 1.5708] is not the scenario's start [1.0, 2.5, 0.0, 1.5708] "
     "(to within 1e-09 per coordinate): a path runs from the scenario's start to its goal; make this row the start, "
     "or set the scenario's start to it (e.g. --set \"start: [2.0, 2.5, 0.0, 1.5708]\")"),
    (lambda p: _with(p, 2, [6.0, 2.5, 0.0, 1.5708]),
     "waypoint 2: the last waypoint [6.0, 2.5, 0.0, 1.5708] is not the scenario's goal [6.5, 2.5, 0.0, 1.5708] "
     "(to within 1e-09 per coordinate): a path runs from the scenario's start to its goal; make this row the goal, "
     "or set the scenario's goal to it (e.g. --set \"goal: [6.0, 2.5, 0.0, 1.5708]\")"),
    (lambda p: p + [0.0, 0.0, 0.0, 2e-9], "waypoint 0: the first waypoint"),
    (lambda p: _with(p, 1, [4.0, 3.8, 0.0, 1.5708]),
     "waypoint 1: configuration [4.0, 3.8, 0.0, 1.5708] is in collision (PlanarChecker): base with person[0] "
     "'standing'"),
    (lambda p: np.array(THROUGH_THE_DESK),
     "waypoint 1: the straight motion to waypoint 2 collides (PlanarChecker, checked continuously); every segment "
     "must be collision-free"),
])
def test_simulate_refuses_a_path_it_must_not_execute(tiny_scenario, path, make, message):
    if message is None:
        message = "must be an (N, 4) array"
    with pytest.raises(ScenarioError) as info:
        simulate(tiny_scenario, waypoints=make(path), analyze=False)
    assert str(info.value).startswith(f"simulate: waypoints: {message}"), str(info.value)


def test_a_collision_is_also_the_reference_checkers_verdict(tiny_scenario, path):
    person = _with(path, 1, [4.0, 3.8, 0.0, 1.5708])
    assert GeometricChecker(tiny_scenario).are_valid(person).tolist() == [True, False, True]


@pytest.mark.slow
def test_endpoints_within_the_tolerance_are_accepted_and_run(tiny_scenario, path):
    nearly = path + [[1e-10, 0.0, 0.0, -1e-10], [0.0, 0.0, 0.0, 0.0]]
    dut = simulate(tiny_scenario, waypoints=nearly, analyze=False)
    assert dut.reached and dut.time_to_goal > 5.5 / tiny_scenario.execution.max_base_speed - 1.0
    np.testing.assert_array_equal(dut.waypoints, nearly)


def test_a_given_checker_decides(tiny_scenario):
    """The checker passed is the one that checks (here one that refuses everything)."""

    class Refuses(GeometricChecker):
        def are_valid(self, qs):
            return np.zeros(len(qs), bool)

    with pytest.raises(ScenarioError, match=r"^build_diagram: waypoints: waypoint 0: configuration .* is in "
                                            r"collision \(Refuses\)"):
        build_diagram(tiny_scenario, waypoints=[tiny_scenario.start, tiny_scenario.goal],
                      checker=Refuses(tiny_scenario))


# ---- simulate --path ------------------------------------------------------------------------


def _csv(tmp_path, rows, extra: str = "") -> str:
    file = tmp_path / "path.csv"
    file.write_text("x,y,psi1,psi2\n" + "".join(",".join(repr(float(v)) for v in r) + "\n" for r in rows) + extra)
    return str(file)


@pytest.mark.parametrize("rows, message", [
    ([[1.0, 2.5, 0.0, 1.5708], [100.0, 2.5, 0.0, 1.5708], [6.5, 2.5, 0.0, 1.5708]],
     "line 3 (waypoint 1): x: 100.0 is outside the room [0.0, 8.0] (world.bounds)"),
    ([[1.0, 2.5, 0.0, 1.5708], [3.0, 2.5, 10.0, 1.5708], [6.5, 2.5, 0.0, 1.5708]],
     "line 3 (waypoint 1): psi1: 10.0 is outside the joint range"),
    ([[1.0, 2.5, 0.0, 1.5708], [4.0, 3.8, 0.0, 1.5708], [6.5, 2.5, 0.0, 1.5708]],
     "line 3 (waypoint 1): configuration [4.0, 3.8, 0.0, 1.5708] is in collision (PlanarChecker): base with "
     "person[0] 'standing'"),
    (THROUGH_THE_DESK, "line 3 (waypoint 1): the straight motion to line 4 collides (PlanarChecker"),
    ([[1.0, 2.5, 0.0, 1.5708], [6.0, 2.5, 0.0, 1.5708]],
     "line 3 (waypoint 1): the last waypoint [6.0, 2.5, 0.0, 1.5708] is not the scenario's goal"),
])
def test_path_file_is_checked_like_any_path(tmp_path, tiny_scenario_path, capsys, rows, message):
    file = _csv(tmp_path, rows)
    assert main(["simulate", str(tiny_scenario_path), "--path", file, "--no-replay", "--out",
                 str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"drake-social: error: {file} (--path): {message}"), err
    assert not (tmp_path / "out").exists()


def test_path_file_longer_than_the_limit_is_refused_at_the_first_row_too_many(tmp_path, tiny_scenario_path,
                                                                                 capsys):
    t = np.linspace(0.0, 1.0, MAX_WAYPOINTS + 1)[:, None]
    rows = np.array([1.0, 2.5, 0.0, 1.5708]) + t * [5.5, 0.0, 0.0, 0.0]
    # A line that is not a row after the limit: refused for the limit, so it was never read.
    file = _csv(tmp_path, rows, extra="not,a,row\n")
    assert main(["simulate", str(tiny_scenario_path), "--path", file, "--no-replay", "--out",
                 str(tmp_path / "out")]) == 2
    assert capsys.readouterr().err == (
        f"drake-social: error: {file}: line {MAX_WAYPOINTS + 2}: more than 10,000 waypoints; a path may have at most "
        "10,000 (drake_social.limits.MAX_WAYPOINTS) (--path)\n")


def test_planning_options_with_path_are_refused(tmp_path, tiny_scenario_path, capsys):
    file = _csv(tmp_path, [[1.0, 2.5, 0.0, 1.5708], [6.5, 2.5, 0.0, 1.5708]])
    out = tmp_path / "out"
    for options, named in ((["--iterations", "500", "--algorithm", "rrt_star", "--seed", "7"],
                            "--algorithm, --iterations and --seed"), (["--seed", "0"], "--seed")):
        assert main(["simulate", str(tiny_scenario_path), "--path", file, *options, "--no-replay",
                     "--out", str(out)]) == 2
        pronoun = "it" if named == "--seed" else "them"
        assert capsys.readouterr().err == (
            f"drake-social: error: {named}: only for planning; with --path {file} nothing is planned (the path is "
            f"executed as given): leave {pronoun} out, or leave out --path to plan\n")
    assert not out.exists()


# ---- start equal to goal: one behaviour -----------------------------------------------------

SAME = "goal: [1.0, 2.5, 0.0, 1.5708]"


@pytest.mark.parametrize("command", ["plan", "simulate"])
def test_start_equal_to_goal_is_refused_by_plan_and_simulate_alike(tmp_path, tiny_scenario_path, capsys, command):
    assert main([command, str(tiny_scenario_path), "--set", SAME, "--out", str(tmp_path / "out")]) == 2
    assert capsys.readouterr().err == (
        f"drake-social: error: {tiny_scenario_path} (--set {SAME!r}): goal: must differ from start (both are "
        "[1.0, 2.5, 0.0, 1.5708]): a transport from a configuration to itself has nothing to plan or execute\n")
    assert not (tmp_path / "out").exists()


def test_the_planner_refuses_start_equal_to_goal(tiny_scenario):
    from drake_social.planning.algorithms import make_planner

    planner = make_planner(tiny_scenario, GeometricChecker(tiny_scenario))
    q = np.asarray(tiny_scenario.start, float)
    with pytest.raises(PlanningInputError, match=r"^start and goal are the same configuration \[1.0, 2.5, 0.0, "
                                                 r"1.5708\]: nothing to plan"):
        planner.solve(q, q.copy(), np.random.default_rng(0))


# ---- contradictory execution options ------------------------------------------------------


@pytest.mark.parametrize("execution, field, message", [
    ({"control_period": 10.0, "time_limit": 5.0}, "execution.control_period",
     "must be <= execution.time_limit / 10 = 0.5 s (a run lasts at least 10 control periods: the sequencer "
     "decides once per period), got 10.0"),
    ({"control_period": 5.0, "time_limit": 5.0}, "execution.control_period",
     "must be <= execution.time_limit / 10 = 0.5 s"),
    ({"control_period": 4.99, "time_limit": 5.0, "kp": 0.1}, "execution.control_period",
     "must be <= execution.time_limit / 10 = 0.5 s"),
    ({"control_period": 0.01, "time_limit": 0.0999}, "execution.control_period",
     "must be <= execution.time_limit / 10 = 0.00999 s"),
    ({"kp": 200.0}, "execution.kp",
     "execution.kp * execution.control_period must be < 2 (the base's sampled P-controller multiplies its error "
     "by 1 - kp * control_period each period and converges only then), got 200.0 * 0.01 = 2"),
    ({"plant_time_step": 0.02}, "execution.plant_time_step", "must be <= execution.control_period 0.01, got 0.02"),
])
def test_contradictory_execution_options_are_refused_with_the_rule(tiny_scenario, execution, field, message):
    import dataclasses as dc

    bad = copy.deepcopy(tiny_scenario)
    bad.execution = dc.replace(bad.execution, **execution)
    with pytest.raises(ScenarioError) as info:
        validate_scenario(bad, source="x.yaml")
    assert str(info.value).startswith(f"x.yaml: {field}: {message}"), str(info.value)


@pytest.mark.parametrize("inside, outside, field", [
    ({"control_period": 0.5, "time_limit": 5.0, "kp": 3.9, "plant_time_step": 0.5},
     {"kp": 4.0}, "execution.kp"),
    ({"control_period": 0.5, "time_limit": 5.0, "kp": 3.9, "plant_time_step": 0.5},
     {"time_limit": 4.99}, "execution.control_period"),
    ({"control_period": 0.01, "kp": 199.9, "plant_time_step": 0.002},
     {"kp": 200.0}, "execution.kp"),
    ({"control_period": 0.01, "kp": 1.5, "plant_time_step": 0.01},
     {"plant_time_step": 0.0101}, "execution.plant_time_step"),
])
def test_execution_options_just_inside_the_rules_are_accepted_and_just_outside_refused(tiny_scenario, inside,
                                                                                        outside, field):
    import dataclasses as dc

    dut = copy.deepcopy(tiny_scenario)
    dut.execution = dc.replace(dut.execution, **inside)
    validate_scenario(dut)  # raises if refused
    dut.execution = dc.replace(dut.execution, **outside)
    with pytest.raises(ScenarioError, match=f"^x.yaml: {field}: "):
        validate_scenario(dut, source="x.yaml")


def test_control_period_against_time_limit_from_the_command_line(tmp_path, tiny_scenario_path, capsys):
    for setting, period in (("execution: {control_period: 10, time_limit: 5}", 10.0),
                            ("execution: {kp: 0.1, control_period: 4.99, time_limit: 5}", 4.99),
                            ("execution: {control_period: 0.5000001, plant_time_step: 0.5, time_limit: 5}", 0.5000001)):
        assert main(["simulate", str(tiny_scenario_path), "--set", setting, "--no-replay",
                     "--out", str(tmp_path / "out")]) == 2
        assert (f"execution.control_period: must be <= execution.time_limit / 10 = 0.5 s (a run lasts at least 10 "
                f"control periods: the sequencer decides once per period), got {period}\n") in capsys.readouterr().err
        assert not (tmp_path / "out").exists()


# ---- the public functions' arguments ----------------------------------------------------------

CHECKER = "must be a validity checker object"


def _cases(s):
    from drake_social.control import (
        HolonomicPController,
        PlannerSystem,
        WaypointSequencer,
        arm_source_from_options,
        reference_source_from_options,
    )
    from drake_social.collision.drake_checker import make_checker
    from drake_social.planning.rrt_star import RrtStar
    from drake_social.planning.space import ConfigurationSpace
    from drake_social.planning.algorithms import make_objective, make_planner, plan

    space, objective = ConfigurationSpace.from_scenario(s), make_objective(s, "rrt_star")
    wp = np.array([s.start, s.goal], float)
    return [
        (lambda: simulate("scenarios/tiny.yaml"), TypeError,
         "simulate: scenario must be a drake_social.scenario.Scenario, got str 'scenarios/tiny.yaml' (load the file "
         "first: drake_social.scenario.load_scenario(path))"),
        (lambda: simulate(None), TypeError,
         "simulate: scenario must be a drake_social.scenario.Scenario, got NoneType None"),
        (lambda: build_diagram(42), TypeError, "build_diagram: scenario must be a drake_social.scenario.Scenario"),
        (lambda: simulate(s, checker="planar"), TypeError, f"simulate: checker {CHECKER}"),
        (lambda: simulate(s, mode=5), TypeError, "simulate: mode must be one of kinematic, dynamic or None, got int 5"),
        (lambda: simulate(s, execution="fast"), ValueError,
         "simulate: unknown execution 'fast'; allowed: synchronized, paper"),
        (lambda: simulate(s, waypoints=wp, time_limit="5"), TypeError,
         "simulate: time_limit must be a finite number of seconds or None, got str '5'"),
        (lambda: simulate(s, waypoints=wp, time_limit=-1.0), ValueError,
         "simulate: time_limit must be in (0, 600] seconds, got -1.0"),
        (lambda: simulate(s, waypoints=wp, time_limit=0), ValueError,
         "simulate: time_limit must be in (0, 600] seconds, got 0"),
        (lambda: simulate(s, waypoints=wp, time_limit=math.nan), ValueError,
         "simulate: time_limit must be a finite number of seconds, got nan"),
        (lambda: simulate(s, waypoints=wp, time_limit=601), ValueError,
         "simulate: time_limit must be in (0, 600] seconds, got 601"),
        (lambda: simulate(s, waypoints=wp, time_limit=0.010000001), ValueError,
         "simulate: time_limit must be >= 10 * execution.control_period 0.01 = 0.1 s (a run lasts at least 10 "
         "control periods: the sequencer decides once per period), got 0.010000001"),
        (lambda: simulate(s, waypoints=wp, time_limit=0.0999), ValueError,
         "simulate: time_limit must be >= 10 * execution.control_period 0.01 = 0.1 s"),
        (lambda: simulate(s, waypoints=wp, analysis_checker="drake"), TypeError,
         f"simulate: analysis_checker {CHECKER}"),
        (lambda: simulate(s, waypoints=wp, progress=3), TypeError, "simulate: progress must be a callable or None"),
        (lambda: simulate(s, waypoints=wp, meshcat="http://localhost"), TypeError,
         "simulate: meshcat must be a pydrake.geometry.Meshcat or None"),
        (lambda: plan(s, "planar"), TypeError,
         f"plan: checker {CHECKER} (drake_social.collision.drake_checker.make_checker(scenario, kind), with is_valid, "
         "are_valid, is_motion_valid, are_motions_valid and clearance), got str 'planar' (a checker's name: build "
         "the checker with make_checker(scenario, 'planar'))"),
        (lambda: plan("x.yaml", GeometricChecker(s)), TypeError, "plan: scenario must be a drake_social.scenario"),
        (lambda: plan(s, GeometricChecker(s), algorithm="rrt"), ValueError,
         "plan: unknown algorithm 'rrt'; allowed: rrt_star"),
        (lambda: plan(s, GeometricChecker(s), seed=-1), ValueError, "plan: seed must be an integer >= 0, got -1"),
        (lambda: plan(s, GeometricChecker(s), iterations=2.5), TypeError, "plan: iterations must be an integer"),
        (lambda: make_planner(s, None), TypeError, f"make_planner: checker {CHECKER}"),
        (lambda: RrtStar(space, "planar", objective), TypeError, f"RrtStar: checker {CHECKER}"),
        (lambda: RrtStar(space, GeometricChecker(s), "length"), TypeError, "RrtStar: objective must be an Objective"),
        (lambda: RrtStar(space, GeometricChecker(s), objective).solve(s.start, s.goal, 0), TypeError,
         "RrtStar.solve: rng must be a numpy.random.Generator"),
        (lambda: make_checker("x", "planar"), TypeError, "make_checker: scenario must be a drake_social.scenario"),
        (lambda: GeometricChecker(None), TypeError, "GeometricChecker: scenario must be a drake_social.scenario"),
        (lambda: make_objective("x", "rrt_star"), TypeError, "make_objective: scenario must be a drake_social"),
        (lambda: make_objective(s, None), TypeError, "make_objective: algorithm must be one of rrt_star"),
        (lambda: ConfigurationSpace.from_scenario({}), TypeError,
         "ConfigurationSpace.from_scenario: scenario must be a drake_social.scenario.Scenario, got dict {}"),
        (lambda: __import__("drake_social.cost.social", fromlist=["SocialCost"]).SocialCost.from_scenario("x"),
         TypeError, "SocialCost.from_scenario: scenario must be a drake_social.scenario.Scenario"),
        (lambda: make_checker(s, "plnar"), ValueError, "make_checker: unknown kind 'plnar'; allowed: planar"),
        (lambda: PlannerSystem("x"), TypeError, "PlannerSystem: scenario must be a drake_social.scenario.Scenario"),
        (lambda: PlannerSystem(s, "planar"), TypeError, f"PlannerSystem: checker {CHECKER}"),
        (lambda: PlannerSystem(s, iterations=0), ValueError, "PlannerSystem: iterations must be an integer >= 1"),
        (lambda: WaypointSequencer.from_options(s), TypeError,
         "WaypointSequencer.from_options: execution_options must be a drake_social.scenario.ExecutionOptions"),
        (lambda: HolonomicPController.from_options(None), TypeError,
         "HolonomicPController.from_options: execution_options must be"),
        (lambda: arm_source_from_options(s.execution, [0.0, 0.0, 0.0]), ValueError,
         "arm_source_from_options: initial_arm: must be a (2,) array of [psi1, psi2], got shape (3,)"),
        (lambda: reference_source_from_options(s.execution, np.zeros((2, 2))), ValueError,
         "reference_source_from_options: initial_q: must be a (4,) array of [x, y, psi1, psi2], got shape (2, 2)"),
        (lambda: reference_source_from_options(s.execution, [0.0, 0.0, 0.0, 1j]), TypeError,
         "reference_source_from_options: initial_q: must be a (4,) array of real numbers ([x, y, psi1, psi2]), "
         "got an array of complex128"),
        (lambda: reference_source_from_options(s.execution, [0.0, 0.0, 0.0, np.inf]), ValueError,
         "reference_source_from_options: initial_q: must hold finite numbers only, got inf at index 3"),
        (lambda: RrtStar(space, GeometricChecker(s), objective).solve(np.ones(4, bool), s.goal,
                                                                       np.random.default_rng(0)),
         TypeError, "RrtStar.solve: start: must be a (4,) array of real numbers ([x, y, psi1, psi2]), got an array "
                    "of bool"),
        (lambda: RrtStar(space, GeometricChecker(s), objective).solve(np.array(s.start) + 0j, s.goal,
                                                                       np.random.default_rng(0)),
         TypeError, "RrtStar.solve: start: must be a (4,) array of real numbers ([x, y, psi1, psi2]), got an array "
                    "of complex128"),
        (lambda: RrtStar(space, GeometricChecker(s), objective).solve(s.start, [1.0, 2.0], np.random.default_rng(0)),
         PlanningInputError, "RrtStar.solve: goal: must be a (4,) array of [x, y, psi1, psi2], got shape (2,)"),
        (lambda: plan(s, GeometricChecker(s), seed=1.0), TypeError, "plan: seed must be an integer >= 0 or None"),
        (lambda: plan(s, GeometricChecker(s), iterations="20"), TypeError, "plan: iterations must be an integer"),
        (lambda: plan(s, GeometricChecker(s), iterations=0), ValueError,
         "plan: iterations must be an integer >= 1 and <= 10,000,000, got 0"),
        (lambda: PlannerSystem(s, iterations="20"), TypeError, "PlannerSystem: iterations must be an integer"),
        (lambda: __import__("drake_social.planning.algorithms", fromlist=["x"]).evaluate_path(s, np.zeros(3)),
         ValueError, "evaluate_path: waypoints: must be an (N, 4) array of rows [x, y, psi1, psi2] with N >= 1, "
                     "got shape "
                     "(3,)"),
        (lambda: __import__("drake_social.planning.algorithms", fromlist=["x"]).evaluate_path(s, [[1, 2, 3, "4"]]),
         TypeError, "evaluate_path: waypoints: must be an (N, 4) array"),
        (lambda: analyze_execution("x", wp, np.zeros(2), np.zeros((2, 4))), TypeError,
         "analyze_execution: scenario must be a drake_social.scenario.Scenario"),
        (lambda: analyze_execution(s, wp, np.zeros(3), np.zeros((3, 5))), ScenarioError,
         "analyze_execution: q: must be an (N, 4) array of rows [x, y, psi1, psi2] with N >= 1, got shape (3, 5)"),
        (lambda: analyze_execution(s, wp, np.zeros(0), np.zeros((0, 4))), ScenarioError,
         "analyze_execution: times: must be an (N,) array of seconds with N >= 1, got 0 samples"),
        (lambda: analyze_execution(s, wp, np.ma.masked_array(np.zeros(2)), np.zeros((2, 4))), TypeError,
         "analyze_execution: times: must be an (N,) array of real numbers (seconds) with N >= 1, got a masked array"),
        (lambda: analyze_execution(s, wp, np.zeros(2), np.zeros((3, 4))), ScenarioError,
         "analyze_execution: times and q must have the same T rows, got 2 and 3"),
        (lambda: analyze_execution(s, np.zeros(3), np.zeros(2), np.zeros((2, 4))), ScenarioError,
         "analyze_execution: waypoints: must be an (N, 4) array"),
        (lambda: analyze_execution(s, wp, np.zeros(2), np.zeros((2, 4)), checker="drake"), TypeError,
         f"analyze_execution: checker {CHECKER}"),
    ]


def test_public_functions_check_their_arguments_at_the_door(tiny_scenario):
    for k, (call, kind, message) in enumerate(_cases(tiny_scenario)):
        with pytest.raises(kind) as info:
            call()
        assert str(info.value).startswith(message), (k, str(info.value))


def test_simulate_validates_a_scenario_changed_in_code(tiny_scenario):
    import dataclasses as dc

    changed = copy.deepcopy(tiny_scenario)
    changed.execution = dc.replace(changed.execution, control_period=10.0, time_limit=5.0)
    with pytest.raises(ScenarioError, match=r"^simulate: scenario: execution.control_period: must be <= "
                                            r"execution.time_limit / 10 = 0.5 s"):
        simulate(changed, waypoints=[changed.start, changed.goal])


# ---- each check once, the cheap ones first ----------------------------------------------------


def _counting(monkeypatch, owner, name):
    """Counts the calls of ``owner.name`` (a function or method)."""
    calls = []
    original = getattr(owner, name)

    def counted(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(owner, name, counted)
    return calls


@pytest.mark.slow
def test_a_path_file_and_the_scenario_are_checked_once(tmp_path, tiny_scenario_path, capsys, monkeypatch):
    import drake_social.scenario
    import drake_social.scenario.load
    import drake_social.sim.checks
    from drake_social.collision.planar_checker import PlanarChecker

    motions = _counting(monkeypatch, PlanarChecker, "are_motions_valid")
    validations = [_counting(monkeypatch, module, "validate_scenario")  # every name a caller reaches it by
                   for module in (drake_social.scenario, drake_social.scenario.load, drake_social.sim.checks)]
    file = _csv(tmp_path, [[1.0, 2.5, 0.0, 1.5708], [6.5, 2.5, 0.0, 1.5708]])
    code = main(["simulate", str(tiny_scenario_path), "--path", file, "--no-replay", "--mode", "kinematic",
                 "--out", str(tmp_path / "out")])
    assert code == 0, capsys.readouterr().err
    assert len(motions) == 1  # the path's segments: the analysis checks configurations only
    assert sum(len(v) for v in validations) == 1


@pytest.mark.parametrize("arguments, kind, message", [
    ({"time_limit": "5"}, TypeError, "simulate: time_limit must be a finite number of seconds or None, got str '5'"),
    ({"analyze": "yes"}, TypeError, "simulate: analyze must be True or False, got str 'yes'"),
    ({"progress": 3}, TypeError, "simulate: progress must be a callable or None"),
    ({"analysis_checker": "drake"}, TypeError, "simulate: analysis_checker must be a validity checker object"),
    ({"mode": "fast"}, ValueError, "simulate: unknown mode 'fast'"),
    ({"time_limit": 1200.0}, ValueError, "simulate: time_limit must be in (0, 600] seconds, got 1200.0"),
])
def test_simulate_checks_cheap_arguments_before_the_waypoints_collisions(tiny_scenario, path, monkeypatch,
                                                                         arguments, kind, message):
    from drake_social.collision.planar_checker import PlanarChecker

    motions = _counting(monkeypatch, PlanarChecker, "are_motions_valid")
    configurations = _counting(monkeypatch, PlanarChecker, "are_valid")
    with pytest.raises(kind) as info:
        simulate(tiny_scenario, waypoints=path, **arguments)
    assert str(info.value).startswith(message), str(info.value)
    assert (motions, configurations) == ([], [])


def test_object_arrays_of_real_numbers_are_converted_exactly(tiny_scenario, path):
    from decimal import Decimal
    from fractions import Fraction

    from drake_social.waypoints import waypoint_array

    for convert in (float, np.float64, np.float32, Fraction, Decimal, lambda v: np.int64(v) if v == int(v) else v):
        values = [[convert(v) for v in row] for row in path.tolist()]
        dut = waypoint_array(np.array(values, dtype=object), "x")
        np.testing.assert_array_equal(dut, np.array([[float(v) for v in row] for row in values]))
        assert dut.dtype == float
    # Python floats as Fractions (exact) come back bit for bit.
    exact = [[Fraction(v) for v in row] for row in path.tolist()]
    np.testing.assert_array_equal(waypoint_array(exact, "x"), path)


def test_the_segment_message_says_how_the_checker_checks_motions(tiny_scenario):
    with pytest.raises(ScenarioError) as info:
        simulate(tiny_scenario, waypoints=THROUGH_THE_DESK, checker=GeometricChecker(tiny_scenario, resolution=0.02))
    assert str(info.value) == (
        "simulate: waypoints: waypoint 1: the straight motion to waypoint 2 collides (GeometricChecker, sampled every "
        "0.02 m of body-point motion (planner.collision_resolution)); every segment must be collision-free")


def test_a_checker_of_another_scenario_is_refused(tiny_scenario):
    import dataclasses as dc

    from drake_social.collision.drake_checker import make_checker

    empty = copy.deepcopy(tiny_scenario)
    empty.world = dc.replace(empty.world, obstacles=[])
    for checker in (make_checker(empty, "planar"), GeometricChecker(empty)):
        with pytest.raises(ScenarioError, match=rf"^simulate: waypoints: the checker {type(checker).__name__} was "
                                                r"made for another scenario \(its room, people, robot or object "
                                                r"differ\)"):
            simulate(tiny_scenario, waypoints=THROUGH_THE_DESK, checker=checker)
    # A copy of the same scenario is the same room: its checker is accepted.
    same = make_checker(copy.deepcopy(tiny_scenario), "planar")
    with pytest.raises(ScenarioError, match="the straight motion to waypoint 2 collides"):
        simulate(tiny_scenario, waypoints=THROUGH_THE_DESK, checker=same)


@pytest.mark.parametrize("method, answer, expected", [
    ("are_valid", lambda n: np.ones(n + 1, bool), "GeometricChecker.are_valid must return (2,) booleans (one per "
                                                  "configuration), got an array of bool of shape (3,)"),
    ("are_valid", lambda n: np.ones((n, 1), bool), "GeometricChecker.are_valid must return (2,) booleans"),
    ("are_valid", lambda n: np.full(n, 0.5), "GeometricChecker.are_valid must return (2,) booleans (one per "
                                             "configuration), got an array of float64 of shape (2,)"),
    ("are_motions_valid", lambda n: np.ones(3, bool), "GeometricChecker.are_motions_valid must return (1,) booleans "
                                                      "(one per motion), got an array of bool of shape (3,)"),
])
def test_a_checker_answering_the_wrong_shape_is_named(tiny_scenario, path, method, answer, expected):
    checker = GeometricChecker(tiny_scenario)
    setattr(checker, method, lambda *qs: answer(len(qs[0])))
    with pytest.raises(TypeError) as info:
        simulate(tiny_scenario, waypoints=path, checker=checker)
    assert str(info.value).startswith(expected), str(info.value)


def test_simulate_takes_numpy_booleans_for_analyze(tiny_scenario, path):
    dut = simulate(tiny_scenario, waypoints=path, analyze=np.False_, time_limit=1.0)
    assert dut.report is None
