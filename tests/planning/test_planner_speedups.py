"""The planner's speed-ups change nothing they promise to keep: lazy motion
costs, KD-tree neighbours, the shrinking radius (while it equals r_near),
people culling; path optimisation never raises the cost; K is bounded."""

from __future__ import annotations

import copy
import dataclasses as dc
import math
import tracemalloc

import numpy as np
import pytest

from drake_social.cost import SocialCost
from drake_social.planning import rrt_star
from drake_social.collision.planar_checker import PlanarChecker
from drake_social.collision.geometric import GeometricChecker
from drake_social.planning.optimize import optimize_path, path_cost
from drake_social.planning.rrt_star import RrtStarOptions, default_gamma
from drake_social.planning.rrt_star.reference import _Neighbors, _Tree
from drake_social.planning.space import ConfigurationSpace
from drake_social.planning.algorithms import make_planner, plan
from drake_social.scenario import ALGORITHMS, MAX_ITERATIONS, Person, ScenarioError, validate_scenario

# Each speed-up against the plain loop, every algorithm: whole plans twice over.
pytestmark = pytest.mark.slow

PI = math.pi


def same_run(a, b):
    np.testing.assert_array_equal(a.waypoints, b.waypoints)
    np.testing.assert_array_equal(a.tree_nodes, b.tree_nodes)
    np.testing.assert_array_equal(a.tree_parents, b.tree_parents)
    np.testing.assert_array_equal(a.tree_costs, b.tree_costs)
    np.testing.assert_array_equal(a.cost_history, b.cost_history)
    assert a.num_motion_checks == b.num_motion_checks and a.num_config_checks == b.num_config_checks


def solve(scenario, checker, algorithm, seed, **options):
    planner = make_planner(scenario, checker, algorithm)
    planner.options = dc.replace(planner.options, **options)
    return planner.solve(np.array(scenario.start), np.array(scenario.goal), np.random.default_rng(seed))


@pytest.fixture(scope="module")
def tiny_lambda(tiny_scenario):
    scenario = copy.deepcopy(tiny_scenario)
    scenario.social.length_weight = 0.5
    scenario.planner = dc.replace(scenario.planner, iterations=300)
    return scenario, GeometricChecker(scenario)


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_lazy_costs_give_the_eager_result_bit_for_bit(tiny_lambda, algorithm):
    scenario, checker = tiny_lambda
    eager = solve(scenario, checker, algorithm, 2, lazy_costs=False)
    dut = solve(scenario, checker, algorithm, 2, lazy_costs=True)
    same_run(eager, dut)
    if algorithm != "rrt_star":
        assert dut.num_cost_evaluations < 0.9 * eager.num_cost_evaluations  # it does skip work


@pytest.mark.parametrize("algorithm", ["rrt_star", "social_rrt_star"])
def test_kd_tree_neighbours_give_the_direct_scan_result(tiny_lambda, algorithm, monkeypatch):
    scenario, checker = tiny_lambda
    reference = solve(scenario, checker, algorithm, 4, kd_tree=False)
    monkeypatch.setattr(rrt_star.reference, "KD_TREE_MIN_NODES", 20)  # from the 20th node on
    dut = solve(scenario, checker, algorithm, 4, kd_tree=True)
    same_run(reference, dut)


def test_kd_neighbours_equal_brute_force_with_ties(rng):
    weights = np.array([1.0, 2.0, 0.5, 0.3])
    tree = _Tree()
    pts = rng.uniform(-3, 3, (3000, 4))
    pts[1500:1600] = pts[100:200]  # exact duplicates: ties for the nearest
    for q in pts:
        tree.add(q, -1 if tree.n == 0 else 0, 0.0)
    brute, dut = _Neighbors(weights, False), _Neighbors(weights, True, min_nodes=100)
    queries = np.vstack([rng.uniform(-3, 3, (200, 4)), pts[100:150], pts[150:200] + 1e-13])
    for q in queries:
        assert dut.nearest(tree, q) == brute.nearest(tree, q)
        for r in (0.3, 1.0, 2.5):
            np.testing.assert_array_equal(dut.within(tree, q, r), brute.within(tree, q, r))
        tree.add(q + 0.01, 0, 0.0)  # grow between queries: rebuilds and the direct-scan tail
    assert dut.kd is not None and dut.kd_n > 3000


def test_default_gamma_is_ompls_r_rrt(repo_root):
    """OMPL's RRTstar: r_rrt = rewire_factor (2 (1 + 1/d) mu / zeta_d)^(1/d),
    rewire factor 1.1, d = 4, zeta_4 = pi^2 / 2; by hand for the office's
    configuration box (unit weights)."""
    from drake_social.scenario import load_scenario

    space = ConfigurationSpace.from_scenario(load_scenario(repo_root / "scenarios" / "office_bar.yaml"))
    assert np.all(space.weights == 1.0)
    (w, h, a, b) = space.upper - space.lower
    mu = w * h * a * b
    assert default_gamma(space) == pytest.approx(1.1 * (2 * 1.25 * mu / (math.pi**2 / 2)) ** 0.25, rel=1e-12)


def test_shrinking_radius_changes_nothing_while_it_is_r_near(tiny_scenario):
    scenario = copy.deepcopy(tiny_scenario)
    scenario.planner = dc.replace(scenario.planner, iterations=100)
    checker = GeometricChecker(scenario)
    space = ConfigurationSpace.from_scenario(scenario)
    gamma = default_gamma(space)
    n = 101
    assert gamma * (math.log(n) / n) ** 0.25 > scenario.planner.near_radius  # the promise applies
    fixed = plan(scenario, checker, seed=3)
    scenario.planner = dc.replace(scenario.planner, near_radius_mode="shrinking")
    dut = plan(scenario, checker, seed=3)
    same_run(fixed, dut)
    assert dut.near_radius_mode == "shrinking" and dut.cost == fixed.cost


def test_shrinking_radius_is_the_rrt_star_formula(tiny_scenario):
    scenario = copy.deepcopy(tiny_scenario)
    scenario.planner = dc.replace(scenario.planner, near_radius_mode="shrinking", near_radius_gamma=3.0)
    dut = make_planner(scenario, GeometricChecker(scenario))
    r_near = scenario.planner.near_radius
    for n in (2, 10, 100, 1000, 10**5):
        assert dut.near_radius(n) == pytest.approx(min(r_near, 3.0 * (math.log(n) / n) ** 0.25), rel=1e-15)
    assert dut.near_radius(10**5) < r_near
    # The near set follows the radius.
    tree = _Tree()
    rng = np.random.default_rng(0)
    for q in dut.space.sample_uniform(rng, 500):
        tree.add(q, -1 if tree.n == 0 else 0, 0.0)
    q = dut.space.sample_uniform(rng)
    r = dut.near_radius(tree.n + 1)
    d = dut.space.distance(tree.q[: tree.n], q)
    near = dut._near(tree, q, int(np.argmin(d)))
    assert set(near.tolist()) == set(np.flatnonzero(d <= r).tolist()) | {int(np.argmin(d))}


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("algorithm", ["social_rrt_star", "rrt_star"])
def test_optimisation_never_raises_the_cost_and_keeps_every_motion_valid(tiny_scenario, seed, algorithm):
    scenario = copy.deepcopy(tiny_scenario)
    scenario.planner = dc.replace(scenario.planner, iterations=300, optimize=True)
    checker = PlanarChecker(scenario)  # plans and optimises (fast); the numpy checker verifies, independently
    dut = plan(scenario, checker, algorithm=algorithm, seed=seed)
    raw = plan(dc.replace(scenario, planner=dc.replace(scenario.planner, optimize=False)), checker,
               algorithm=algorithm, seed=seed)
    assert dut.success and dut.optimized and not raw.optimized
    assert dut.raw_cost == raw.cost == raw.raw_cost
    assert dut.cost <= raw.cost
    wp = dut.waypoints
    np.testing.assert_array_equal(wp[[0, -1]], [scenario.start, scenario.goal])
    numpy_checker = GeometricChecker(scenario)
    assert numpy_checker.are_valid(wp).all() and numpy_checker.are_motions_valid(wp[:-1], wp[1:]).all()
    planner = make_planner(scenario, checker, algorithm)
    assert dut.cost == pytest.approx(path_cost(planner.objective, wp), rel=1e-12)
    space = ConfigurationSpace.from_scenario(scenario)
    assert space.contains(wp).all()


def test_optimisation_improves_a_detour():
    """A zig-zag path in an empty room (length objective): shortcutting
    finds the straight motion."""
    from drake_social.planning.objective import PathLengthObjective
    from drake_social.scenario import Scenario, World

    scenario = Scenario(world=World(bounds=[0.0, 0.0, 10.0, 8.0]), people=[],
                        start=[1.0, 2.0, 0.0, 0.5], goal=[8.0, 2.5, 0.3, -0.5])
    validate_scenario(scenario)
    checker = GeometricChecker(scenario)
    space = ConfigurationSpace.from_scenario(scenario)
    wp = np.array([scenario.start, [3.0, 6.0, 0.5, 0.0], [5.0, 1.0, -0.5, 0.2], [6.0, 6.0, 0.0, 0.0], scenario.goal])
    objective = PathLengthObjective()
    out, cost = optimize_path(wp, objective, checker, space)
    assert cost == pytest.approx(float(objective.motion_cost(wp[0], wp[-1])[0]), rel=1e-9)
    assert cost < 0.5 * path_cost(objective, wp)


def test_absurd_iteration_budgets_are_refused(tiny_scenario, tiny_scenario_path):
    bad = copy.deepcopy(tiny_scenario)
    bad.planner = dc.replace(bad.planner, iterations=MAX_ITERATIONS + 1)
    with pytest.raises(ScenarioError, match=r"x.yaml: planner.iterations: must be in \[1, 10000000\]"):
        validate_scenario(bad, source="x.yaml")
    with pytest.raises(ValueError, match=r"^plan: iterations must be an integer >= 1 and <= 10,000,000, got 10000000000$"):
        plan(tiny_scenario, GeometricChecker(tiny_scenario), iterations=10**10)
    with pytest.raises(ValueError, match="planner.iterations"):
        rrt_star.RrtStar(ConfigurationSpace.from_scenario(tiny_scenario), None, None,
                         RrtStarOptions(iterations=10**10))
    for field, value in (("near_radius_mode", "wide"), ("near_radius_gamma", -1.0), ("optimize", "yes")):
        wrong = copy.deepcopy(tiny_scenario)
        wrong.planner = dc.replace(wrong.planner, **{field: value})
        with pytest.raises(ScenarioError, match=f"planner.{field}"):
            validate_scenario(wrong, source="x.yaml")


class _Stop(Exception):
    pass


def test_memory_follows_the_nodes_added_not_k(tiny_scenario):
    """A K = 10^6 run stopped after 20 iterations allocates the (K,) cost
    history (8 MB) more than a K = 100 run, not a tree for K nodes (32 MB of
    configurations and 10^6 child lists more, before)."""

    def stop(k, _):
        if k == 20:
            raise _Stop

    def peak(iterations: int) -> int:
        planner = make_planner(tiny_scenario, GeometricChecker(tiny_scenario))
        planner.options = dc.replace(planner.options, iterations=iterations)
        tracemalloc.start()
        with pytest.raises(_Stop):
            planner.solve(np.array(tiny_scenario.start), np.array(tiny_scenario.goal), np.random.default_rng(0), stop)
        _, out = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        return out

    peak(100)  # warm up caches and imports
    extra = peak(10**6) - peak(100)
    assert extra < 8e6 + 2e6, extra
    tree = _Tree()
    for i in range(1000):
        tree.add(np.full(4, float(i)), i - 1, 1.0)
    assert tree.capacity == 1024 and tree.cost[999] == 1000.0 and tree.q[500, 0] == 500.0


def test_far_people_change_no_motion_cost(tiny_scenario, rng):
    """50 people far from every motion (beyond the AGF's reach plus the arm's)
    leave every motion cost unchanged bit for bit, in both backends, and the
    compiled kernel's grid culling agrees with the numpy reference."""
    base = SocialCost.from_scenario(tiny_scenario)
    far = np.column_stack([rng.uniform(30, 60, 50), rng.uniform(30, 60, 50), rng.uniform(-PI, PI, 50)])
    crowd = SocialCost(base.geometry, np.vstack([far[:25], base.people, far[25:]]), base.space,
                       resolution=base.resolution)
    space = ConfigurationSpace.from_scenario(tiny_scenario)
    q_a, q_b = space.sample_uniform(rng, 300), space.sample_uniform(rng, 300)
    for backend in ("numba", "numpy"):
        base.backend = crowd.backend = backend
        np.testing.assert_array_equal(crowd.motion_cost(q_a, q_b), base.motion_cost(q_a, q_b))


def test_grid_culling_agrees_with_the_numpy_batch(rng):
    """Many people over a large area (many grid cells), rotated, some close."""
    from drake_social.scenario.geometry import arm_geometry
    from drake_social.scenario import Scenario

    geometry = arm_geometry(Scenario())
    people = np.column_stack([rng.uniform(-20, 20, 80), rng.uniform(-20, 20, 80), rng.uniform(-PI, PI, 80)])
    dut = SocialCost(geometry, people, weights=np.array([1.0, 0.5, 2.0, 1.0, 1.5]))
    q_a = np.column_stack([rng.uniform(-20, 20, (400, 2)), rng.uniform(-PI, PI, (400, 2))])
    q_b = q_a + rng.normal(size=(400, 4)) * 1.5
    reference = copy.copy(dut)
    reference.backend = "numpy"
    expected = reference.motion_cost(q_a, q_b)
    assert np.count_nonzero(expected) > 100
    np.testing.assert_allclose(dut.motion_cost(q_a, q_b), expected, rtol=1e-12, atol=1e-14)
