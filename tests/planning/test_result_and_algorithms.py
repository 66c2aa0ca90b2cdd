"""planning/result.py and planning/variants.py: the result's summary, JSON
and failure, the objectives and planners the algorithm names make, the cost
parts of a path and what ``plan`` overrides (found by the mutation run; the
whole-planner runs of test_rrt_star.py are not in its selection)."""

from __future__ import annotations

import copy
import dataclasses as dc
import math

import numpy as np
import pytest

from drake_social.cost import SocialCost
from drake_social.kinematics import config_distance
from drake_social.planning import algorithms as variants
from drake_social.collision.geometric import GeometricChecker
from drake_social.planning.objective import PathLengthObjective, SocialObjective
from drake_social.planning.result import NoPathError, PlannerResult
from drake_social.planning.algorithms import base_only_weights, evaluate_path, make_objective, make_planner, plan
from drake_social.scenario import ALGORITHMS, MAX_ITERATIONS

# ---- result.py ---------------------------------------------------------------


def a_result(**changes) -> PlannerResult:
    fields = dict(
        algorithm="social_rrt_star", success=True, message="path found",
        waypoints=np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 2.0, 0.5, -0.5]]), cost=3.25,
        social_cost_full=1.5, social_cost_planner=1.25, path_length=2.5, base_length=2.0,
        first_solution_iteration=7, cost_history=np.array([np.inf, 4.0, 3.25]), tree_size=12,
        num_config_checks=20, num_motion_checks=30, num_cost_evaluations=40, wall_time=0.125, seed=5,
        closest_distance_to_goal=0.0, optimized=True, raw_cost=3.5, near_radius_mode="shrinking",
        optimize_time=0.25,
    )
    fields.update(changes)
    return PlannerResult(**fields)


def test_summary_of_a_success_and_of_a_failure():
    assert a_result(cost=3.14159, social_cost_full=0.123456, base_length=2.0 / 3).summary() == (
        "social_rrt_star: 2 waypoints, cost 3.142 (raw 3.5), social (full weights) 0.1235, base path 0.67 m, "
        "first solution at iteration 7, tree 12 nodes, 0.125 s + 0.250 s optimising")
    assert a_result(optimized=False, raw_cost=3.25).summary() == (
        "social_rrt_star: 2 waypoints, cost 3.25, social (full weights) 1.5, base path 2.00 m, "
        "first solution at iteration 7, tree 12 nodes, 0.125 s")
    failed = a_result(success=False, message="tree too small", waypoints=np.zeros((0, 4)), cost=np.inf)
    assert failed.summary() == "social_rrt_star: no path (tree too small)"


def test_raise_if_failed_raises_the_message_only_on_failure():
    ok = a_result()
    assert ok.raise_if_failed() is ok
    with pytest.raises(NoPathError, match=r"^tree too small$"):
        a_result(success=False, message="tree too small").raise_if_failed()


def test_record_has_every_planner_field_and_none_for_non_finite_numbers():
    got = a_result().to_record()
    assert got == {
        "algorithm": "social_rrt_star", "success": True, "message": "path found", "seed": 5, "planning_time": 0.125,
        "optimize_time": 0.25,
        "cost": 3.25, "raw_cost": 3.5, "optimized": True, "near_radius_mode": "shrinking",
        "first_solution_iteration": 7, "tree_size": 12, "num_config_checks": 20, "num_motion_checks": 30,
        "num_cost_evaluations": 40, "num_waypoints": 2, "closest_distance_to_goal": 0.0,
        "waypoints": [[0.0, 0.0, 0.0, 0.0], [1.0, 2.0, 0.5, -0.5]], "cost_history": [None, 4.0, 3.25],
    }
    assert all(type(got[k]) is float for k in ("cost", "raw_cost", "planning_time", "closest_distance_to_goal"))
    failed = a_result(success=False, cost=np.inf, raw_cost=np.inf, closest_distance_to_goal=float("nan"),
                      first_solution_iteration=None, seed=None, cost_history=np.full(2, np.inf)).to_record()
    assert [failed[k] for k in ("cost", "raw_cost", "closest_distance_to_goal", "first_solution_iteration",
                                "seed", "cost_history")] == [None, None, None, None, None, [None, None]]
    assert failed["tree_size"] == 12 and failed["success"] is False


# ---- variants.py -------------------------------------------------------------


def test_base_only_weights():
    np.testing.assert_array_equal(base_only_weights(5), [1.0, 0.0, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(base_only_weights(1), [1.0])


def weighted(tiny_scenario, length_weight=0.3, distance_weights=(1.0, 2.0, 0.5, 0.25)):
    scenario = copy.deepcopy(tiny_scenario)
    scenario.social.length_weight = length_weight
    scenario.planner = dc.replace(scenario.planner, distance_weights=list(distance_weights))
    return scenario


def test_make_objective_for_each_algorithm(tiny_scenario):
    scenario = weighted(tiny_scenario)
    with pytest.raises(ValueError, match=r"^make_objective: unknown algorithm 'rrt'; allowed: " + ", ".join(ALGORITHMS) + "$"):
        make_objective(scenario, "rrt")
    length = make_objective(scenario, "rrt_star")
    assert type(length) is PathLengthObjective
    np.testing.assert_array_equal(length.distance_weights, [1.0, 2.0, 0.5, 0.25])
    full = SocialCost.from_scenario(scenario)
    for algorithm in ALGORITHMS[1:]:
        dut = make_objective(scenario, algorithm)
        assert type(dut) is SocialObjective and dut.length_weight == 0.3
        base_only = algorithm in ("base_rrt_star", "informed_base_rrt_star")
        expected = base_only_weights(full.geometry.num_interest_points) if base_only else full.weights
        np.testing.assert_array_equal(dut.social.weights, expected)
        np.testing.assert_array_equal(dut.social.distance_weights, [1.0, 2.0, 0.5, 0.25])
    assert ALGORITHMS[2] == "base_rrt_star" and full.weights[1:].any()  # the base-only weights differ from the full ones


def test_make_planner_takes_the_scenarios_options(tiny_scenario):
    scenario = weighted(tiny_scenario)
    scenario.planner = dc.replace(scenario.planner, algorithm="informed_base_rrt_star", iterations=123,
                                  planning_range=1.25, near_radius=2.75, goal_bias=0.125)
    checker = GeometricChecker(scenario)
    dut = make_planner(scenario, checker)  # the scenario's algorithm
    assert dut.name == "informed_base_rrt_star" and dut.checker is checker
    assert dut.options.informed and (dut.options.iterations, dut.options.planning_range, dut.options.near_radius,
                                     dut.options.goal_bias) == (123, 1.25, 2.75, 0.125)
    np.testing.assert_array_equal(dut.objective.social.weights, base_only_weights(len(dut.objective.social.weights)))
    r = scenario.robot.base_radius
    np.testing.assert_array_equal(dut.space.lower, [r, r, *scenario.robot.joint_lower])
    np.testing.assert_array_equal(dut.space.upper, [8.0 - r, 5.0 - r, *scenario.robot.joint_upper])
    np.testing.assert_array_equal(dut.space.weights, [1.0, 2.0, 0.5, 0.25])
    other = make_planner(scenario, checker, "social_rrt_star")
    assert other.name == "social_rrt_star" and not other.options.informed
    assert type(make_planner(scenario, checker, "rrt_star").objective) is PathLengthObjective


PATH = np.array([[1.0, 2.5, 0.0, 1.5], [2.0, 2.5, 0.3, 1.5], [2.0, 3.5, 0.3, 1.0], [5.0, 3.5, 0.3, 1.0]])


def test_evaluate_path_parts_by_hand(tiny_scenario):
    scenario = weighted(tiny_scenario, length_weight=0.5)
    # Plain norms of the three steps and the base's XY steps, by hand.
    length = math.sqrt(1 + 0.09) + math.sqrt(1 + 0.25) + 3.0
    full = SocialCost.from_scenario(scenario)
    base = full.with_weights(base_only_weights(full.geometry.num_interest_points))
    steps_full = [float(full.motion_cost(PATH[i : i + 1], PATH[i + 1 : i + 2])[0]) for i in range(3)]
    steps_base = [float(base.motion_cost(PATH[i : i + 1], PATH[i + 1 : i + 2])[0]) for i in range(3)]
    assert min(steps_full) > 0 and sum(steps_base) < sum(steps_full)  # the person is in reach: not a vacuous test
    plain = evaluate_path(scenario, PATH)
    assert set(plain) == {"social_cost_full", "social_cost_planner", "path_length", "base_length"}
    assert plain["path_length"] == pytest.approx(length, rel=1e-14)
    assert plain["base_length"] == pytest.approx(5.0, rel=1e-15)
    assert plain["social_cost_full"] == pytest.approx(sum(steps_full), rel=1e-12)
    assert plain["social_cost_planner"] == plain["social_cost_full"]  # no objective: the full weights
    informed_base = evaluate_path(scenario, PATH, make_objective(scenario, "informed_base_rrt_star"))
    assert informed_base["social_cost_planner"] == pytest.approx(sum(steps_base), rel=1e-12)
    assert informed_base["social_cost_full"] == plain["social_cost_full"]
    # Msc plus lambda times the weighted length (weights 1, 2, 0.5, 0.25).
    weighted_length = math.hypot(1, 0.15) + math.hypot(2, 0.125) + 3.0
    assert informed_base["objective"] == pytest.approx(sum(steps_base) + 0.5 * weighted_length, rel=1e-12)
    length_only = evaluate_path(scenario, PATH, make_objective(scenario, "rrt_star"))
    assert length_only["objective"] == pytest.approx(weighted_length, rel=1e-14)
    assert length_only["social_cost_planner"] == plain["social_cost_full"]  # not social: the full weights


def test_evaluate_path_of_one_waypoint_is_zero(tiny_scenario):
    scenario = weighted(tiny_scenario)
    dut = evaluate_path(scenario, PATH[:1].tolist(), make_objective(scenario, "social_rrt_star"))
    assert dut == {"social_cost_full": 0.0, "path_length": 0.0, "base_length": 0.0, "social_cost_planner": 0.0,
                   "objective": 0.0}
    assert all(type(v) is float for v in dut.values())


def solve(scenario, algorithm, seed):
    """The planner's own run, for comparison with ``plan``."""
    planner = make_planner(scenario, GeometricChecker(scenario), algorithm)
    return planner, planner.solve(np.array(scenario.start), np.array(scenario.goal), np.random.default_rng(seed))


@pytest.fixture(scope="module")
def short(tiny_scenario):
    scenario = copy.deepcopy(tiny_scenario)
    scenario.planner = dc.replace(scenario.planner, iterations=60)
    return scenario


def test_plan_overrides_iterations_on_a_copy_and_fills_the_parts(short):
    dut = plan(short, GeometricChecker(short), algorithm="base_rrt_star", iterations=40, seed=3)
    assert short.planner.iterations == 60  # the caller's scenario is untouched
    fewer = copy.deepcopy(short)
    fewer.planner.iterations = 40
    planner, expected = solve(fewer, "base_rrt_star", 3)
    assert dut.success and dut.algorithm == "base_rrt_star" and dut.seed == 3 and len(dut.cost_history) == 40
    np.testing.assert_array_equal(dut.tree_nodes, expected.tree_nodes)
    np.testing.assert_array_equal(dut.waypoints, expected.waypoints)
    assert dut.cost == expected.cost
    parts = evaluate_path(fewer, expected.waypoints, planner.objective)
    assert (dut.social_cost_full, dut.social_cost_planner, dut.path_length, dut.base_length) == (
        parts["social_cost_full"], parts["social_cost_planner"], parts["path_length"], parts["base_length"])
    assert dut.social_cost_planner < dut.social_cost_full  # base-only weights: the planner's part differs


@pytest.mark.slow
def test_plan_defaults_to_the_scenarios_seed_algorithm_and_iterations(short):
    dut = plan(short, GeometricChecker(short), seed=None)
    _, expected = solve(short, None, short.random_seed)
    assert dut.seed == short.random_seed == 1 and dut.algorithm == short.planner.algorithm
    assert len(dut.cost_history) == 60
    np.testing.assert_array_equal(dut.tree_nodes, expected.tree_nodes)
    np.testing.assert_array_equal(dut.waypoints, expected.waypoints)


def test_plan_leaves_the_parts_unset_without_a_path(short):
    dut = plan(short, GeometricChecker(short), iterations=1, seed=0)
    assert not dut.success and dut.seed == 0
    assert all(math.isnan(v) for v in (dut.social_cost_full, dut.social_cost_planner, dut.path_length,
                                       dut.base_length))


def test_plan_accepts_exactly_the_allowed_iterations(short, monkeypatch):
    seen = []

    def fake_make_planner(scenario, checker, algorithm):
        seen.append(scenario.planner.iterations)
        raise RuntimeError("stop here")

    monkeypatch.setattr(variants, "make_planner", fake_make_planner)
    checker = GeometricChecker(short)
    for n in (1, MAX_ITERATIONS, np.int64(17)):
        with pytest.raises(RuntimeError, match="stop here"):
            plan(short, checker, iterations=n)
    assert seen == [1, MAX_ITERATIONS, 17]
    # One rule for every integer argument (require_int): integers only, not their text nor floats.
    for n in ("17", 17.0, True):
        with pytest.raises(TypeError, match=r"^plan: iterations must be an integer >= 1 and <= 10,000,000 or None, "):
            plan(short, checker, iterations=n)
    for n in (0, MAX_ITERATIONS + 1):
        with pytest.raises(ValueError, match=rf"^plan: iterations must be an integer >= 1 and <= 10,000,000, got {n}$"):
            plan(short, checker, iterations=n)
    assert len(seen) == 3


def test_plan_passes_the_progress_callback(short):
    calls = []
    dut = plan(short, GeometricChecker(short), iterations=30, seed=2, progress=lambda k, c: calls.append((k, c)))
    assert [k for k, _ in calls] == list(range(1, 31))
    np.testing.assert_array_equal([c for _, c in calls], dut.cost_history)


# ---- the table of algorithm specs --------------------------------------------


def test_the_spec_table_names_exactly_the_scenarios_algorithms_in_order():
    from drake_social.limits import INFORMED_ALGORITHMS

    assert tuple(variants.ALGORITHM_SPECS) == ALGORITHMS
    assert all(name == spec.name for name, spec in variants.ALGORITHM_SPECS.items())
    assert INFORMED_ALGORITHMS == tuple(n for n, s in variants.ALGORITHM_SPECS.items() if s.sampler == "informed")
    # The paper's five planners, written out: objective, weights, sampler.
    assert {n: (s.objective, s.weights, s.sampler) for n, s in variants.ALGORITHM_SPECS.items()} == {
        "rrt_star": ("length", "all_points", "uniform"),
        "social_rrt_star": ("social", "all_points", "uniform"),
        "base_rrt_star": ("social", "base_only", "uniform"),
        "informed_social_rrt_star": ("social", "all_points", "informed"),
        "informed_base_rrt_star": ("social", "base_only", "informed"),
    }
    with pytest.raises(TypeError):
        variants.ALGORITHM_SPECS["x"] = variants.ALGORITHM_SPECS["rrt_star"]  # read-only


def test_an_unknown_name_lists_the_known_ones():
    message = r"^plan: unknown algorithm 'informed_rrt_star'; allowed: " + ", ".join(ALGORITHMS) + "$"
    with pytest.raises(ValueError, match=message):
        variants.algorithm_spec("informed_rrt_star", "plan")
    with pytest.raises(TypeError, match=r"^algorithm_spec: algorithm must be one of rrt_star, "):
        variants.algorithm_spec(3)


def test_a_spec_field_outside_its_values_is_refused_by_name():
    with pytest.raises(ValueError, match=r"^AlgorithmSpec 'x': unknown sampler 'ellipse'; allowed: uniform, informed$"):
        variants.AlgorithmSpec("x", "social", "all_points", "ellipse", "")
    with pytest.raises(ValueError, match=r"^AlgorithmSpec 'x': the length objective has no social weights"):
        variants.AlgorithmSpec("x", "length", "base_only", "uniform", "")


def test_new_names_are_configured_by_their_spec_not_by_their_letters(tiny_scenario):
    """A name starting with "informed" or containing "base" means nothing by itself:
    an informed length planner and a multi-point planner called "baseline" get
    what their specs say."""
    scenario = weighted(tiny_scenario)
    informed_length = variants.AlgorithmSpec("informed_rrt_star", "length", "all_points", "informed", "")
    baseline = variants.AlgorithmSpec("baseline_social", "social", "all_points", "uniform", "")
    table = {**variants.ALGORITHM_SPECS, informed_length.name: informed_length, baseline.name: baseline}
    checker = GeometricChecker(scenario)
    full = SocialCost.from_scenario(scenario)
    dut = make_planner(scenario, checker, variants.algorithm_spec("informed_rrt_star", specs=table))
    assert type(dut.objective) is PathLengthObjective and dut.options.informed and dut.name == "informed_rrt_star"
    np.testing.assert_array_equal(dut.objective.distance_weights, [1.0, 2.0, 0.5, 0.25])
    dut = make_planner(scenario, checker, variants.algorithm_spec("baseline_social", specs=table))
    assert type(dut.objective) is SocialObjective and not dut.options.informed
    np.testing.assert_array_equal(dut.objective.social.weights, full.weights)
    assert full.weights[1:].any()  # differs from the base-only weights
    result = plan(scenario, checker, algorithm=informed_length, iterations=40, seed=1)
    assert result.algorithm == "informed_rrt_star" and len(result.informed_diameters) == 40
    # A spec is not a name of the shipped table.
    with pytest.raises(ValueError, match=r"^make_planner: unknown algorithm 'baseline_social'"):
        make_planner(scenario, checker, "baseline_social")
