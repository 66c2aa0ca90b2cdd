"""Small units of planning/rrt_star.py that the planner tests reach only
through whole runs: the growing tree's arrays, the path to a node, the
endpoint checks' messages and the XY length of a path to the goal
(found by the mutation run)."""

from __future__ import annotations

import copy
import dataclasses as dc
import math
import time

import numpy as np
import pytest

from drake_social.collision.geometric import GeometricChecker
from drake_social.planning.result import PlanningInputError
from drake_social.planning.rrt_star import RrtStar, RrtStarOptions, compiled_support, default_gamma
from drake_social.planning.rrt_star.reference import _Tree
from drake_social.planning.space import ConfigurationSpace
from drake_social.planning.algorithms import make_objective
from drake_social.scenario import Bar, Box, Scenario, World, validate_scenario


def room() -> Scenario:
    scenario = Scenario(world=World(bounds=[0.0, 0.0, 10.0, 6.0], obstacles=[Box(center=[5.0, 3.0], size=[1.0, 2.4])]),
                        people=[], object=Bar(length=1.0), start=[1.0, 3.0, 0.0, math.pi / 2],
                        goal=[8.2, 3.0, 0.0, math.pi / 2])
    scenario.planner = dc.replace(scenario.planner, near_radius_mode="fixed", optimize=False)  # the paper's planner
    validate_scenario(scenario)
    return scenario


def planner_for(scenario: Scenario) -> RrtStar:
    return RrtStar(ConfigurationSpace.from_scenario(scenario), GeometricChecker(scenario),
                   make_objective(scenario, "rrt_star"), RrtStarOptions.from_scenario(scenario.planner))


def test_tree_doubles_its_arrays_and_keeps_unused_parents_at_minus_one():
    tree = _Tree(2)
    assert tree.capacity == 2
    for k in range(3):
        tree.add(np.full(4, float(k)), k - 1, 1.0)
    assert tree.capacity == 4  # doubled once, not more
    assert len(tree.q) == len(tree.parent) == len(tree.cost) == len(tree.edge) == 4
    assert tree.parent.dtype == np.int64
    assert tree.parent.tolist() == [-1, 0, 1, -1]  # the unused slot stays a root marker
    assert tree.cost[:3].tolist() == [1.0, 2.0, 3.0] and tree.edge[:3].tolist() == [1.0, 1.0, 1.0]
    np.testing.assert_array_equal(tree.q[:3], [[0.0] * 4, [1.0] * 4, [2.0] * 4])
    for k in range(3, 5):
        tree.add(np.full(4, float(k)), k - 1, 0.5)
    assert tree.capacity == 8 and len(tree.parent) == len(tree.cost) == len(tree.edge) == 8
    assert tree.parent.tolist() == [-1, 0, 1, 2, 3, -1, -1, -1]
    assert tree.cost[:5].tolist() == [1.0, 2.0, 3.0, 3.5, 4.0]


def test_tree_starts_empty_and_reparents_whole_subtrees_by_hand():
    """A new tree: the capacity asked for (at least 1), no nodes, parents -1,
    float arrays. Reparenting moves the child lists, sets the edge and
    recomputes every descendant's cost as parent cost + edge; a cycle is
    refused with the nodes named."""
    for asked, capacity in ((5, 5), (0, 1), (-3, 1), (2.7, 2)):
        tree = _Tree(asked)
        assert tree.capacity == capacity and tree.n == 0 and tree.children == []
        assert tree.q.shape == (capacity, 4) and tree.q.dtype == np.float64
        assert tree.cost.shape == tree.edge.shape == (capacity,) and tree.cost.dtype == tree.edge.dtype == np.float64
        assert tree.parent.tolist() == [-1] * capacity and tree.parent.dtype == np.int64
    assert _Tree().capacity == 256
    tree = _Tree(8)
    assert tree.add(np.zeros(4), -1, 0.25) == 0 and tree.cost[0] == 0.25  # a root costs its edge
    a = tree.add(np.ones(4), 0, 1.0)
    b = tree.add(np.full(4, 2.0), a, 0.5)
    c = tree.add(np.full(4, 3.0), b, 0.125)
    d = tree.add(np.full(4, 4.0), 0, 0.5)
    assert (a, b, c, d, tree.n) == (1, 2, 3, 4, 5)
    assert tree.children == [[a, d], [b], [c], [], []]
    assert tree.cost[:5].tolist() == [0.25, 1.25, 1.75, 1.875, 0.75]
    tree.reparent(b, d, 0.375)
    assert tree.children == [[a, d], [], [c], [], [b]] and tree.parent[: tree.n].tolist() == [-1, 0, 4, 2, 0]
    assert tree.edge[b] == 0.375 and tree.cost[:5].tolist() == [0.25, 1.25, 1.125, 1.25, 0.75]
    np.testing.assert_array_equal(tree.q[b], np.full(4, 2.0))
    with pytest.raises(RuntimeError) as info:
        tree.reparent(d, c, 0.0)
    assert str(info.value) == "rewiring node 4 under its descendant 3"


def test_path_to_runs_from_the_root():
    tree = _Tree(4)
    tree.add(np.zeros(4), -1, 0.0)
    tree.add(np.ones(4), 0, 1.0)
    tree.add(np.ones(4) * 2, 1, 1.0)
    tree.add(np.ones(4) * 3, 0, 1.0)
    assert tree.path_to(2) == [0, 1, 2]
    assert tree.path_to(3) == [0, 3]
    assert tree.path_to(0) == [0]


@pytest.mark.parametrize("which", ["start", "goal"])
def test_endpoint_errors_name_the_endpoint(which):
    scenario = room()
    planner = planner_for(scenario)
    start, goal = np.array(scenario.start), np.array(scenario.goal)
    ends = {"start": start, "goal": goal}
    for bad, message in [(np.array([1.0, 3.0, 0.0]), "must be 4 finite numbers"),
                         (np.array([1.0, 3.0, np.inf, 0.0]), "must be 4 finite numbers"),
                         (np.array([-5.0, 3.0, 0.0, 0.0]), "is outside the configuration space"),
                         (np.array([5.0, 3.0, 0.0, 0.0]), "configuration .* is in collision")]:  # the pillar
        args = dict(ends, **{which: bad})
        with pytest.raises(PlanningInputError, match=f"^{which} .*{message}|^{which} {message}"):
            planner._check_endpoints(args["start"], args["goal"])
    planner._check_endpoints(start, goal)  # valid ends pass


def test_xy_length_sums_the_base_steps_to_the_goal():
    tree = _Tree(4)
    tree.add(np.array([0.0, 0.0, 1.0, 2.0]), -1, 0.0)
    tree.add(np.array([3.0, 4.0, -1.0, 0.0]), 0, 1.0)
    tree.add(np.array([3.0, 6.0, 0.0, 0.0]), 1, 1.0)
    goal = np.array([6.0, 10.0, 2.0, 2.0])
    assert RrtStar._xy_length(tree, 2, goal) == pytest.approx(5.0 + 2.0 + 5.0, rel=1e-15)
    assert RrtStar._xy_length(tree, 0, goal) == pytest.approx(math.hypot(6.0, 10.0), rel=1e-15)


def test_default_gamma_by_hand_with_weights():
    """OMPL's 1.1 (2 (1 + 1/d) V / zeta_d)^(1/d), d = 4, zeta_4 = pi^2 / 2,
    V the weighted box's volume (here 4 * 2 * 3 * 1 times the weights)."""
    space = ConfigurationSpace(np.array([0.0, 1.0, -1.5, -0.5]), np.array([4.0, 3.0, 1.5, 0.5]),
                               np.array([1.0, 2.0, 0.5, 3.0]))
    volume = (4.0 * 1.0) * (2.0 * 2.0) * (3.0 * 0.5) * (1.0 * 3.0)
    expected = 1.1 * (2.0 * 1.25 * volume / (math.pi**2 / 2)) ** 0.25
    assert default_gamma(space) == pytest.approx(expected, rel=1e-14)
    scenario = room()
    planner = planner_for(scenario)
    assert planner.gamma == default_gamma(planner.space)  # near_radius_gamma = 0: OMPL's
    planner.options = dc.replace(planner.options, near_radius_gamma=2.5)
    assert planner.gamma == 2.5


def run_room(iterations=150, seed=2, **options):
    scenario = room()
    planner = planner_for(scenario)
    planner.options = dc.replace(planner.options, iterations=iterations, **options)
    return planner.solve(np.array(scenario.start), np.array(scenario.goal), np.random.default_rng(seed))


@pytest.mark.slow
def test_python_loop_uses_the_kd_tree_once_large_and_finds_the_same_tree(monkeypatch):
    """The Python loop (the numpy checker) with the KD-tree from the 16th node
    on: the KD-tree does answer queries, and the tree is the direct scan's."""
    from drake_social.planning.rrt_star import reference as rrt_star

    reference = run_room(kd_tree=False)
    served = []
    original = rrt_star._Neighbors._update

    def spy(self, tree):
        used = original(self, tree)
        served.append(used)
        return used

    monkeypatch.setattr(rrt_star, "KD_TREE_MIN_NODES", 16)
    monkeypatch.setattr(rrt_star._Neighbors, "_update", spy)
    dut = run_room(kd_tree=True)
    assert reference.tree_size > 40 and sum(served) > 50  # the KD-tree served most queries
    np.testing.assert_array_equal(dut.tree_nodes, reference.tree_nodes)
    np.testing.assert_array_equal(dut.tree_parents, reference.tree_parents)
    np.testing.assert_array_equal(dut.cost_history, reference.cost_history)
    served.clear()
    run_room(kd_tree=False)
    assert served and not any(served)  # kd_tree=False: never


def test_python_loop_history_is_float_and_inf_before_the_first_solution():
    dut = run_room()
    assert dut.success and dut.cost_history.dtype == np.float64 and dut.cost_history.shape == (150,)
    k = dut.first_solution_iteration
    assert np.all(np.isinf(dut.cost_history[: k - 1])) and np.isfinite(dut.cost_history[k - 1])
    assert dut.cost_history[-1] == dut.cost and np.all(np.diff(dut.cost_history[k - 1 :]) <= 0)
    assert dut.informed_diameters.shape == (0,)
    assert dut.informed_diameters.dtype == np.float64


def room_planner(start, goal, iterations):
    scenario = room()
    scenario.start, scenario.goal = list(start), list(goal)
    planner = planner_for(scenario)
    planner.options = dc.replace(planner.options, iterations=iterations, goal_bias=0.0)
    return planner, np.array(start, float), np.array(goal, float)


@pytest.mark.parametrize("distance", [2.5, 1.0])
def test_the_start_connects_to_a_goal_within_the_near_radius_inclusive(distance):
    """Start and goal on a free line, exactly ``distance`` apart (r_near =
    2.5 m is included): the root's own goal connection is found before any
    sample, so the best path is the straight motion, of length ``distance``
    (any path through other nodes is longer)."""
    planner, start, goal = room_planner([1.0, 1.0, 0.0, math.pi / 2], [1.0 + distance, 1.0, 0.0, math.pi / 2], 30)
    assert planner.options.near_radius == 2.5 and planner.space.distance(start, goal) == distance
    assert planner.checker.is_motion_valid(start, goal)
    dut = planner.solve(start, goal, np.random.default_rng(0))
    assert dut.success and dut.cost == distance
    np.testing.assert_array_equal(dut.waypoints, [start, goal])


def test_integer_ends_give_the_float_ends_result(tiny_scenario):
    """Start and goal given as integer arrays are planned as floats: the
    compiled loop (the planar checker) and the Python loop (the numpy
    checker) return the trees of the float ends."""
    from drake_social.collision.planar_checker import PlanarChecker
    from drake_social.planning.rrt_star import tree_kernel
    from drake_social.planning.algorithms import make_planner

    scenario = copy.deepcopy(tiny_scenario)
    scenario.planner = dc.replace(scenario.planner, iterations=60)
    start, goal = np.array([1, 2, 0, 1]), np.array([6, 2, 0, 1])
    checkers = [GeometricChecker(scenario)] + ([PlanarChecker(scenario)] if tree_kernel.AVAILABLE else [])
    for checker in checkers:
        planner = make_planner(scenario, checker, "rrt_star")
        assert checker.is_valid(start.astype(float)) and checker.is_valid(goal.astype(float))
        expected = planner.solve(start.astype(float), goal.astype(float), np.random.default_rng(3))
        dut = planner.solve(start, goal, np.random.default_rng(3))
        assert dut.success and dut.waypoints.dtype == np.float64
        np.testing.assert_array_equal(dut.tree_nodes, expected.tree_nodes)
        np.testing.assert_array_equal(dut.waypoints, expected.waypoints)


def test_a_node_on_the_goal_costs_nothing_more():
    """planning_range 2 > r_near 0.5: the start, 1.5 m from the goal, has no
    goal connection of its own, but a goal sample is steered onto the goal
    exactly; that node's path is the path (cost 1.5 m, no extra motion)."""
    planner, start, goal = room_planner([1.0, 1.0, 0.0, math.pi / 2], [2.5, 1.0, 0.0, math.pi / 2], 5)
    planner.options = dc.replace(planner.options, planning_range=2.0, near_radius=0.5, goal_bias=0.5)
    assert np.random.default_rng(2).random() < 0.5  # the first sample is the goal
    dut = planner.solve(start, goal, np.random.default_rng(2))
    assert dut.success and dut.cost == 1.5
    np.testing.assert_array_equal(dut.waypoints, [start, goal])
    assert any(np.array_equal(q, goal) for q in dut.tree_nodes)


@pytest.mark.slow
def test_lazy_path_length_costs_count_like_the_eager_loop():
    """For a length objective the lazy loop takes the motion costs as the
    length bounds it computes anyway: the same tree and the same counts as
    the eager reference (every near motion costed once per extension)."""
    eager = run_room(lazy_costs=False)
    lazy = run_room(lazy_costs=True)
    np.testing.assert_array_equal(lazy.tree_nodes, eager.tree_nodes)
    np.testing.assert_array_equal(lazy.tree_parents, eager.tree_parents)
    assert (lazy.num_cost_evaluations, lazy.num_motion_checks, lazy.num_config_checks) == (
        eager.num_cost_evaluations, eager.num_motion_checks, eager.num_config_checks)
    assert lazy.num_cost_evaluations > lazy.tree_size  # several near motions per extension


def test_a_goal_drawn_again_adds_nothing_and_counts_like_the_compiled_loop():
    """Goal bias 0.5 near the goal: once the goal is a node, drawing it again
    adds no node and checks nothing; the Python loop's counts equal the
    compiled loop's (a second implementation) on the planar checker."""
    from drake_social.collision.planar_checker import PlanarChecker
    from drake_social.planning.rrt_star import tree_kernel

    if not tree_kernel.AVAILABLE:
        pytest.skip("numba is not importable")
    scenario = room()
    scenario.start, scenario.goal = [1.0, 1.0, 0.0, math.pi / 2], [2.5, 1.0, 0.0, math.pi / 2]
    checker = PlanarChecker(scenario)
    runs = []
    for compiled in (False, True):
        planner = RrtStar(ConfigurationSpace.from_scenario(scenario), checker, make_objective(scenario, "rrt_star"),
                          dc.replace(RrtStarOptions.from_scenario(scenario.planner), iterations=40, goal_bias=0.5,
                                     compiled=compiled))
        assert compiled_support(planner.checker, planner.objective, RrtStarOptions())[0]
        runs.append(planner.solve(np.array(scenario.start), np.array(scenario.goal), np.random.default_rng(4)))
    python, compiled = runs
    assert sum(np.array_equal(q, scenario.goal) for q in python.tree_nodes) == 1  # the goal, once
    np.testing.assert_array_equal(python.tree_nodes, compiled.tree_nodes)
    assert (python.num_cost_evaluations, python.num_motion_checks, python.num_config_checks) == (
        compiled.num_cost_evaluations, compiled.num_motion_checks, compiled.num_config_checks)


@pytest.mark.parametrize("case", ["found", "found, optimised", "not found"])
def test_compiled_and_python_loops_fill_the_result_alike(case):
    """The compiled loop's result (built from its arrays) against the Python
    loop's on the same tree: the counts and sizes as ints, the first solution
    None when there is none, the raw cost before optimisation and a positive
    wall time measured from the start of solve."""
    from drake_social.collision.planar_checker import PlanarChecker
    from drake_social.planning.rrt_star import tree_kernel

    if not tree_kernel.AVAILABLE:
        pytest.skip("numba is not importable")
    scenario = room()
    options = dict(iterations=150, optimize=case == "found, optimised")
    if case == "not found":  # 8 iterations of 0.5 m steps cannot cross the 7.2 m room
        options.update(iterations=8, planning_range=0.5, near_radius=0.5)
    runs = []
    for compiled in (False, True):
        planner = RrtStar(ConfigurationSpace.from_scenario(scenario), PlanarChecker(scenario),
                          make_objective(scenario, "rrt_star"),
                          dc.replace(RrtStarOptions.from_scenario(scenario.planner), compiled=compiled, **options))
        assert compiled_support(planner.checker, planner.objective, RrtStarOptions())[0]
        before = time.perf_counter()
        runs.append(planner.solve(np.array(scenario.start), np.array(scenario.goal), np.random.default_rng(2)))
        spent = time.perf_counter() - before
        assert 0 < runs[-1].wall_time <= spent
    python, compiled = runs
    goal, weights = np.array(scenario.goal), np.array(planner.space.weights)
    for dut in runs:
        assert type(dut.tree_size) is int and dut.tree_size == len(dut.tree_nodes) == len(dut.tree_parents) > 1
        for name in ("num_config_checks", "num_motion_checks", "num_cost_evaluations"):
            assert type(getattr(dut, name)) is int and getattr(dut, name) > 0, name
        by_hand = min(math.sqrt(sum((w * (a - b)) ** 2 for w, a, b in zip(weights, q, goal))) for q in dut.tree_nodes)
        assert dut.closest_distance_to_goal == pytest.approx(by_hand, rel=1e-12)
        assert dut.algorithm == "rrt_star" and dut.cost_history.shape == (options["iterations"],)
        assert dut.near_radius_mode == "fixed" and dut.optimized == (case == "found, optimised")
        if case == "not found":
            assert dut.success is False and dut.first_solution_iteration is None and dut.raw_cost == np.inf
            assert dut.cost == np.inf and dut.waypoints.shape == (0, 4)
            assert dut.message == (f"no collision-free connection to the goal after 8 iterations; tree of "
                                   f"{dut.tree_size} nodes, closest node {by_hand:.3g} from the goal (near radius 0.5)")
        else:
            assert dut.success is True and dut.message == "path found"
            assert type(dut.first_solution_iteration) is int and dut.first_solution_iteration >= 1
            assert dut.raw_cost == dut.cost_history[-1]
            if dut.optimized:  # the optimiser shortens this path (10.14 -> 8.0): the result takes it
                assert dut.cost < dut.raw_cost
            else:
                assert dut.cost == dut.raw_cost
    for name in ("success", "tree_size", "first_solution_iteration", "raw_cost", "cost", "num_config_checks",
                 "num_motion_checks", "num_cost_evaluations"):
        assert getattr(compiled, name) == getattr(python, name), name
    np.testing.assert_array_equal(compiled.tree_nodes, python.tree_nodes)


def test_options_from_scenario_copy_every_planner_field():
    """Every RrtStarOptions field that the scenario's planner section
    provides lands in its own option (distinct values, none a default); the
    loop switches stay on."""
    from drake_social.scenario import PlannerOptions

    p = PlannerOptions(iterations=77, planning_range=0.7, near_radius=1.9, goal_bias=0.11, informed_mode="admissible",
                       near_radius_mode="shrinking", near_radius_gamma=3.3, optimize=True)
    for informed in (False, True):
        dut = RrtStarOptions.from_scenario(p, informed=informed)
        assert dc.astuple(dut) == (77, 0.7, 1.9, 0.11, informed, "admissible", "shrinking", 3.3, True, True, True,
                                   True)
    assert RrtStarOptions.from_scenario(p).informed is False


def rrt_star_with(**options):
    scenario = room()
    return RrtStar(ConfigurationSpace.from_scenario(scenario), GeometricChecker(scenario),
                   make_objective(scenario, "rrt_star"), dc.replace(RrtStarOptions(), **options), name="named")


@pytest.mark.parametrize("options, error, message", [
    (dict(iterations=0), ValueError, "planner.iterations must be in [1, 10000000], got 0"),
    (dict(iterations=10_000_001), ValueError, "planner.iterations must be in [1, 10000000], got 10000001"),
    (dict(near_radius_mode="fix"), ValueError, "unknown near_radius_mode 'fix'; allowed: fixed, shrinking"),
    (dict(near_radius_gamma=-0.5), ValueError, "near_radius_gamma must be >= 0, got -0.5"),
    (dict(near_radius_gamma=math.nan), ValueError, "near_radius_gamma must be >= 0, got nan"),
    (dict(near_radius_gamma=math.inf), ValueError, "near_radius_gamma must be >= 0, got inf"),
    (dict(planning_range=0.0), ValueError, "planning_range and near_radius must be > 0"),
    (dict(near_radius=0.0), ValueError, "planning_range and near_radius must be > 0"),
    (dict(near_radius=math.nan), ValueError, "planning_range and near_radius must be > 0"),
    (dict(goal_bias=1.0), ValueError, "goal_bias must be in [0, 1), got 1.0"),
    (dict(goal_bias=-0.01), ValueError, "goal_bias must be in [0, 1), got -0.01"),
    (dict(informed=True, informed_mode="papers"), ValueError,
     "unknown informed mode 'papers'; allowed: paper, admissible"),
])
def test_planner_options_are_refused_with_the_field_and_the_allowed_values(options, error, message):
    with pytest.raises(error) as info:
        rrt_star_with(**options)
    assert str(info.value) == message


def test_planner_accepts_the_edges_of_its_option_ranges_and_keeps_its_parts():
    for options in (dict(iterations=1), dict(iterations=10_000_000), dict(near_radius_gamma=0.0),
                    dict(goal_bias=0.0), dict(near_radius_mode="shrinking"), dict(planning_range=0.5),
                    dict(near_radius=0.5),
                    dict(informed=True, informed_mode="admissible"), dict(informed=True, informed_mode="paper")):
        dut = rrt_star_with(**options)
        assert dut.name == "named" and dut.options == dc.replace(RrtStarOptions(), **options)
    scenario = room()
    space, checker, objective = (ConfigurationSpace.from_scenario(scenario), GeometricChecker(scenario),
                                 make_objective(scenario, "rrt_star"))
    dut = RrtStar(space, checker, objective)
    assert (dut.space, dut.checker, dut.objective, dut.name) == (space, checker, objective, "rrt_star")
    assert dut.options == RrtStarOptions()
    scenario.social.length_weight = 0.0  # a social objective with no length term bounds no path length
    with pytest.raises(PlanningInputError) as info:
        RrtStar(space, checker, make_objective(scenario, "social_rrt_star"),
                RrtStarOptions(informed=True, informed_mode="admissible"))
    assert str(info.value) == ("informed_mode 'admissible' needs an objective that bounds the path length "
                               "(social.length_weight > 0); without it the ellipse would never shrink")
    RrtStar(space, checker, make_objective(scenario, "social_rrt_star"), RrtStarOptions(informed=True))  # paper: fine


def plain_distances(q_nodes, w, x):
    """Weighted distances from x, one node at a time in plain Python."""
    return [math.sqrt(sum((wi * (a - b)) ** 2 for wi, a, b in zip(w, q, x))) for q in q_nodes]


def test_neighbours_through_the_kd_tree_equal_a_plain_scan_ties_included():
    """_Neighbors with the KD-tree on from 8 nodes against a plainly written
    scan: nodes on a lattice (many exact ties, some nodes exactly at the
    radius) plus random ones and four lattice nodes again, queried at
    lattice points, midpoints, random points and nodes; and the rebuild
    rule (more than max(256, n / 16) nodes added since the last build)."""
    from drake_social.planning.rrt_star.reference import _Neighbors

    rng = np.random.default_rng(3)
    w = np.array([1.0, 2.0, 0.5, 0.25])
    lattice = np.array([[i, j, 2 * k, 4 * m] for i in range(3) for j in range(2) for k in range(2) for m in range(2)],
                       float) * 0.5
    nodes = np.vstack([lattice, rng.uniform(-1, 2, (36, 4)), lattice[:4]])  # the last four: duplicates
    tree = _Tree(8)
    for q in nodes:
        tree.add(q, -1 if tree.n == 0 else 0, 0.0)
    dut = _Neighbors(w, True, min_nodes=8)
    scan = _Neighbors(w, False)
    queries = np.vstack([lattice[:10], (lattice[:-1] + lattice[1:]) / 2, rng.uniform(-1, 2, (30, 4)), nodes[30:40]])
    ties = 0
    for x in queries:
        i, d = dut.nearest(tree, x)
        plain = plain_distances(tree.q[: tree.n], w, x)
        assert (i, d) == scan.nearest(tree, x) and i == plain.index(min(plain))  # the lowest index on ties
        assert d == pytest.approx(min(plain), rel=1e-12)
        ties += int(plain.count(min(plain)) > 1)
        for r in (0.5, 0.75, 1.0):
            expected = [k for k, v in enumerate(plain) if v <= r]
            np.testing.assert_array_equal(dut.within(tree, x, r), expected)
            np.testing.assert_array_equal(scan.within(tree, x, r), expected)
    assert ties >= 5 and dut.kd is not None and dut.kd_n == tree.n
    # Rebuilds: not before max(256, kd_n / 16) nodes more, then at once.
    built = dut.kd
    for _ in range(256):
        tree.add(rng.uniform(-1, 2, 4), 0, 0.0)
    assert dut._update(tree) and dut.kd is built and dut.kd_n == 64
    tree.add(rng.uniform(-1, 2, 4), 0, 0.0)
    assert dut._update(tree) and dut.kd is not built and dut.kd_n == tree.n == 321
    x = rng.uniform(-1, 2, 4)
    assert dut.nearest(tree, x) == scan.nearest(tree, x)
    assert not _Neighbors(w, True, min_nodes=tree.n + 1)._update(tree)  # too few nodes
    assert not _Neighbors(w, False, min_nodes=1)._update(tree)  # off
    small = _Neighbors(w, True, min_nodes=tree.n)
    assert small._update(tree) and small.kd_n == tree.n
    # A large tree waits for a sixteenth more: built at 4,800 nodes, not rebuilt at 5,100, rebuilt at 5,101.
    big = _Tree(8192)
    for k, q in enumerate(rng.uniform(-1, 2, (4800, 4))):
        big.add(q, -1 if k == 0 else 0, 0.0)
    many = _Neighbors(w, True, min_nodes=8)
    assert many._update(big) and many.kd_n == 4800
    for q in rng.uniform(-1, 2, (300, 4)):
        big.add(q, 0, 0.0)
    assert many._update(big) and many.kd_n == 4800
    big.add(rng.uniform(-1, 2, 4), 0, 0.0)
    assert many._update(big) and many.kd_n == 5101
    # A radius below a millimetre: a node exactly at it (2^-13 along x) is within, through the KD-tree too.
    tiny_tree = _Tree(16)
    x0 = np.array([0.5, 0.5, 0.5, 0.5])
    for k in range(12):
        tiny_tree.add(x0 + np.array([2.0 ** -13, 0.0, 0.0, 0.0]) * k, -1 if k == 0 else 0, 0.0)
    near = _Neighbors(np.ones(4), True, min_nodes=8)
    np.testing.assert_array_equal(near.within(tiny_tree, x0, 2.0 ** -13), [0, 1])
    np.testing.assert_array_equal(near.within(tiny_tree, x0 + np.array([2.0 ** -12, 0, 0, 0]), 2.0 ** -13), [1, 2, 3])
    # ... and a nearest tie below a millimetre: nodes 0 and 1 both 2^-14 from the query, the lower index wins.
    assert near.nearest(tiny_tree, x0 + np.array([2.0 ** -14, 0, 0, 0])) == (0, 2.0 ** -14)


def test_the_compiled_loop_applies_to_the_planar_checker_and_known_objectives_only(tiny_scenario):
    """Compiled: the planar checker with the path length or the numba social
    objective. The Python loop: the numpy checker, the numpy social backend,
    any other objective class (even a subclass)."""
    from drake_social.collision.planar_checker import PlanarChecker
    from drake_social.planning.rrt_star import tree_kernel
    from drake_social.planning.objective import PathLengthObjective, SocialObjective

    if not tree_kernel.AVAILABLE:
        pytest.skip("numba is not importable")
    scenario = tiny_scenario
    space, planar, numpy_checker = (ConfigurationSpace.from_scenario(scenario), PlanarChecker(scenario),
                                    GeometricChecker(scenario))
    social = make_objective(scenario, "social_rrt_star")
    assert type(social) is SocialObjective and social.social.backend == "numba"

    class Longer(PathLengthObjective):  # other costs: the compiled loop would not run them
        def motion_cost(self, q_a, q_b):
            return 2.0 * super().motion_cost(q_a, q_b)

    class Named(PathLengthObjective):  # the same costs: keeps the declared compiled form
        name = "named"

    slow = copy.deepcopy(social)
    slow.social.backend = "numpy"
    for objective, checker, applies in ((make_objective(scenario, "rrt_star"), planar, True), (social, planar, True),
                                        (social, numpy_checker, False), (slow, planar, False),
                                        (Longer(), planar, False), (Named(), planar, True)):
        planner = RrtStar(space, checker, objective)
        assert compiled_support(checker, objective, planner.options)[0] is applies


def test_near_radius_by_hand():
    """Fixed: r_near for any tree. Shrinking: min(r_near, gamma (ln n / n)^(1/4)),
    r_near itself for a single node."""
    fixed = rrt_star_with(near_radius=2.0)
    assert [fixed.near_radius(n) for n in (1, 2, 50, 10**6)] == [2.0] * 4
    dut = rrt_star_with(near_radius=2.0, near_radius_mode="shrinking", near_radius_gamma=3.0)
    assert dut.near_radius(1) == 2.0
    for n in (2, 3, 50, 5000, 10**6):
        by_hand = min(2.0, 3.0 * (math.log(n) / n) ** 0.25)
        assert dut.near_radius(n) == pytest.approx(by_hand, rel=1e-15)
    assert dut.near_radius(2) == 2.0 and dut.near_radius(5000) < 1.0  # 3 (ln 2 / 2)^0.25 > 2, then smaller
    small = rrt_star_with(near_radius=2.0, near_radius_mode="shrinking", near_radius_gamma=1.0)
    assert small.near_radius(2) == pytest.approx((math.log(2) / 2) ** 0.25)  # shrinks from the second node on
    default = rrt_star_with(near_radius=9.0, near_radius_mode="shrinking")  # gamma 0: OMPL's default
    assert default.near_radius(100) == pytest.approx(default_gamma(default.space) * (math.log(100) / 100) ** 0.25)


def test_near_set_is_the_nodes_within_the_radius_of_the_grown_tree_then_the_nearest():
    """_near: the ascending indices within near_radius(n + 1) (the tree with
    the new node), inclusive, then the nearest node when it is not among
    them; with or without a neighbour structure."""
    from drake_social.planning.rrt_star.reference import _Neighbors

    dut = rrt_star_with(near_radius=1.0)
    tree = _Tree(4)
    for x in (0.0, 3.0, 1.5, 2.5, 6.0):  # along x, weights 1
        tree.add(np.array([1.0 + x, 1.0, 0.0, 0.0]), -1 if tree.n == 0 else 0, 0.0)
    q_new = np.array([3.5, 1.0, 0.0, 0.0])  # 2.5 from node 0, 0.5 from 1, 1.0 from 2, 0.0 from 3, 3.5 from 4
    for neighbors in (None, _Neighbors(dut.space.weights, False), _Neighbors(dut.space.weights, True, 2)):
        np.testing.assert_array_equal(dut._near(tree, q_new, 1, neighbors), [1, 2, 3])
        np.testing.assert_array_equal(dut._near(tree, q_new, 4, neighbors), [1, 2, 3, 4])  # the nearest, appended
    far = np.array([8.0, 1.0, 0.0, 0.0])  # exactly 1.0 from node 4 (x = 7.0), the others farther
    np.testing.assert_array_equal(dut._near(tree, far, 4), [4])
    np.testing.assert_array_equal(dut._near(tree, far, 0), [4, 0])
    # Shrinking: the radius of the tree with the new node, n + 1 = 5 here, min(1, gamma (ln 5 / 5)^(1/4)) =
    # 0.995 for this gamma: nodes 0.5 and 0.99 away are in, the one 1.0 away is out (r(4) would take it in,
    # r(6) = 0.977 would leave the 0.99 one out).
    tree = _Tree(4)
    for x in (1.0, 4.0, 4.49, 4.5):
        tree.add(np.array([x, 1.0, 0.0, 0.0]), -1 if tree.n == 0 else 0, 0.0)
    gamma = 0.995 / (math.log(5) / 5) ** 0.25
    shrink = rrt_star_with(near_radius=1.0, near_radius_mode="shrinking", near_radius_gamma=gamma)
    assert shrink.near_radius(5) == pytest.approx(0.995) and shrink.near_radius(4) == 1.0
    assert shrink.near_radius(6) < 0.98
    np.testing.assert_array_equal(shrink._near(tree, q_new, 1), [1, 2])


@pytest.mark.parametrize("checker_kind", ["numpy (Python loop)", "planar (compiled loop)"])
def test_the_starts_own_goal_connection_is_reported_even_when_no_node_is_added(checker_kind):
    """Start and goal 1 m apart on a free line: the start's goal connection,
    made before the first sample, is the solution from iteration 1 on, even
    though the first sample adds no node (a review found both loops waiting
    for a node to be added before reporting it: success=False at K = 1)."""
    from drake_social.collision.planar_checker import PlanarChecker
    from drake_social.planning.rrt_star import tree_kernel

    if checker_kind.startswith("planar") and not tree_kernel.AVAILABLE:
        pytest.skip("numba is not importable")
    planner, start, goal = room_planner([1.0, 3.0, 0.0, math.pi / 2], [2.0, 3.0, 0.0, math.pi / 2], 1)
    planner.options = dc.replace(planner.options, planning_range=20.0)  # a sample anywhere: often no node
    if checker_kind.startswith("planar"):
        planner.checker = PlanarChecker(room())
        assert compiled_support(planner.checker, planner.objective, RrtStarOptions())[0]
    for iterations in (1, 2, 5):
        planner.options = dc.replace(planner.options, iterations=iterations)
        dut = planner.solve(start, goal, np.random.default_rng(0))
        assert dut.success and dut.cost == 1.0 and dut.first_solution_iteration == 1
        np.testing.assert_array_equal(dut.cost_history, np.ones(iterations))
        np.testing.assert_array_equal(dut.waypoints, [start, goal])
        if iterations <= 2:
            assert dut.tree_size == 1  # the first two samples of seed 0 add no node


def test_a_checker_without_the_compiled_capability_runs_the_python_loop_and_the_log_says_why(monkeypatch, caplog):
    """The numpy checker declares no compiled scene: the compiled loop is never
    prepared, the Python loop plans (its tree equals the reference run's),
    and one INFO line names the planner and the reason."""
    import logging

    from drake_social.planning.rrt_star import compiled

    reference = run_room(iterations=60, compiled=False)

    def refuse(*args, **kwargs):
        raise AssertionError("the compiled loop was prepared")

    monkeypatch.setattr(compiled, "prepare", refuse)
    with caplog.at_level(logging.INFO, logger="drake_social.planning.rrt_star"):
        dut = run_room(iterations=60)
    np.testing.assert_array_equal(dut.tree_nodes, reference.tree_nodes)
    assert dut.tree_size > 10
    assert [r.getMessage() for r in caplog.records] == [
        "rrt_star plans with the Python loop: the checker GeometricChecker declares no compiled_scene() "
        "(the validity protocol's CompiledSceneChecker capability)"]


def test_compiled_support_names_each_missing_capability(tiny_scenario):
    """Each reason of compiled_support, from declared capabilities only."""
    from drake_social.collision.validity import PlanarScene
    from drake_social.planning.objective import Objective, SocialObjective

    class SceneChecker(GeometricChecker):  # declares the capability: that is all it takes
        def compiled_scene(self) -> PlanarScene:
            raise NotImplementedError

    checker = SceneChecker(tiny_scenario)
    social = make_objective(tiny_scenario, "social_rrt_star")
    assert compiled_support(checker, social, RrtStarOptions()) == (True, "")
    assert compiled_support(checker, make_objective(tiny_scenario, "rrt_star"), RrtStarOptions()) == (True, "")
    assert compiled_support(checker, social, RrtStarOptions(compiled=False)) == (
        False, "RrtStarOptions.compiled is False (the Python reference loop was asked for)")
    assert compiled_support(checker, Objective(), RrtStarOptions()) == (
        False, "the objective Objective declares no compiled form (compiled_form = None)")
    slow = copy.deepcopy(social)
    slow.social.backend = "numpy"
    assert compiled_support(checker, slow, RrtStarOptions()) == (
        False, "the social cost's backend is 'numpy', not 'numba'")

    class Doubled(SocialObjective):
        def motion_cost(self, q_a, q_b):
            return 2.0 * super().motion_cost(q_a, q_b)

    assert Doubled.compiled_form is None and SocialObjective.compiled_form == "social"
