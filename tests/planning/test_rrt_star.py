"""The RRT* core and the paper's planners built on it (Algorithm 2)."""

from __future__ import annotations

import copy
import dataclasses as dc
import math

import numpy as np
import pytest

from drake_social.cost import SocialCost
from drake_social.kinematics import config_distance
from drake_social.scenario.geometry import arm_geometry
from drake_social.collision.planar_checker import PlanarChecker
from drake_social.collision.geometric import GeometricChecker
from drake_social.planning.objective import PathLengthObjective, SocialObjective
from drake_social.planning.result import PlanningInputError
from drake_social.planning.rrt_star import RrtStar, RrtStarOptions
from drake_social.planning.space import ConfigurationSpace
from drake_social.planning.algorithms import evaluate_path, make_objective, make_planner, plan
from drake_social.scenario import ALGORITHMS, Bar, Box, Person, Scenario, World, validate_scenario

PI = math.pi


def with_planner(scenario: Scenario, **planner) -> Scenario:
    out = copy.deepcopy(scenario)
    out.planner = dc.replace(out.planner, **planner)
    return out


@pytest.fixture(scope="module")
def tiny(tiny_scenario):
    return with_planner(tiny_scenario, iterations=400)


@pytest.fixture(scope="module")
def tiny_checker(tiny):
    return GeometricChecker(tiny)


@pytest.fixture(scope="module", params=ALGORITHMS)
def solved(request, tiny, tiny_checker):
    """(scenario, planner, result) for every algorithm on tiny.yaml."""
    planner = make_planner(tiny, tiny_checker, request.param)
    result = planner.solve(np.array(tiny.start), np.array(tiny.goal), np.random.default_rng(3))
    return tiny, planner, result


# ---- every returned path ----------------------------------------------------------------
# Slow: the module's `solved` fixture runs the Python loop of every algorithm (3-5 s each).


@pytest.mark.slow
def test_path_runs_from_start_to_exactly_the_goal(solved):
    scenario, _, dut = solved
    assert dut.success, dut.message
    np.testing.assert_array_equal(dut.waypoints[0], scenario.start)
    np.testing.assert_array_equal(dut.waypoints[-1], scenario.goal)


@pytest.mark.slow
def test_every_waypoint_and_motion_is_valid(solved, tiny_checker):
    _, _, dut = solved
    wp = dut.waypoints
    assert tiny_checker.are_valid(wp).all()
    assert tiny_checker.are_motions_valid(wp[:-1], wp[1:]).all()


@pytest.mark.slow
def test_cost_equals_the_cost_recomputed_from_the_waypoints(solved):
    scenario, planner, dut = solved
    wp = dut.waypoints
    recomputed = planner.objective.motion_cost(wp[:-1], wp[1:]).sum()
    assert dut.cost == pytest.approx(recomputed, rel=1e-9, abs=1e-12)
    parts = evaluate_path(scenario, wp, planner.objective)
    assert parts["objective"] == pytest.approx(dut.cost, rel=1e-9, abs=1e-12)


@pytest.mark.slow
def test_best_cost_never_increases(solved):
    _, _, dut = solved
    h = dut.cost_history
    assert len(h) == 400
    finite = np.isfinite(h)
    assert finite.any()
    first = np.argmax(finite)
    assert first + 1 == dut.first_solution_iteration
    assert np.all(finite[first:])  # once found, a solution is never lost
    assert np.all(np.diff(h[first:]) <= 1e-12)
    assert h[-1] == pytest.approx(dut.cost, rel=1e-12)
    # And it does improve: a planner that keeps its first solution fails here.
    assert h[-1] < 0.95 * h[first], (h[first], h[-1])


@pytest.mark.slow
def test_tree_costs_are_parent_cost_plus_edge_cost(solved):
    """After all the rewiring: F(node) = F(parent) + Msc(parent, node) for every node."""
    _, planner, dut = solved
    q, parent, cost = dut.tree_nodes, dut.tree_parents, dut.tree_costs
    assert parent[0] == -1 and cost[0] == 0.0
    child = np.arange(1, len(q))
    assert np.all(parent[child] >= 0) and np.all(parent[child] < len(q))
    edge = planner.objective.motion_cost(q[parent[child]], q[child])
    np.testing.assert_allclose(cost[child], cost[parent[child]] + edge, rtol=1e-9, atol=1e-9)
    # Rewiring happened: only a re-parented node can have a parent inserted
    # after it (a planner that never rewires fails here).
    assert np.sum(parent[child] > child) >= 5
    # No cycles: following parents from any node reaches the root.
    depth = np.zeros(len(q), int)
    for i in child:
        j, steps = i, 0
        while j != 0:
            j, steps = parent[j], steps + 1
            assert steps <= len(q)
        depth[i] = steps


@pytest.mark.slow
def test_result_reports_its_counts_and_parts(solved):
    scenario, planner, dut = solved
    assert dut.tree_size == len(dut.tree_nodes) <= 401
    # One configuration check per sample, except goal samples once the goal is a node.
    assert 400 * (1 - 2 * planner.options.goal_bias) <= dut.num_config_checks <= 400
    assert np.sum(np.all(dut.tree_nodes == scenario.goal, axis=1)) <= 1  # the goal enters the tree once
    assert dut.num_motion_checks >= dut.tree_size - 1  # every inserted node checked its parent motion
    assert dut.num_cost_evaluations >= dut.tree_size - 1
    assert dut.wall_time > 0


# ---- determinism ------------------------------------------------------------------------


@pytest.mark.slow
def test_same_seed_gives_the_identical_result(tiny, tiny_checker):
    a = plan(tiny, tiny_checker, seed=11)
    b = plan(tiny, tiny_checker, seed=11)
    np.testing.assert_array_equal(a.waypoints, b.waypoints)
    np.testing.assert_array_equal(a.tree_nodes, b.tree_nodes)
    np.testing.assert_array_equal(a.cost_history, b.cost_history)
    assert a.cost == b.cost


@pytest.mark.slow
def test_different_seeds_give_different_trees(tiny, tiny_checker):
    a = plan(tiny, tiny_checker, seed=1)
    b = plan(tiny, tiny_checker, seed=2)
    n = min(len(a.tree_nodes), len(b.tree_nodes))
    assert not np.array_equal(a.tree_nodes[:n], b.tree_nodes[:n])


@pytest.mark.slow
def test_scenario_seed_is_the_default(tiny, tiny_checker):
    a = plan(tiny, tiny_checker)
    b = plan(tiny, tiny_checker, seed=tiny.random_seed)
    assert a.seed == tiny.random_seed
    np.testing.assert_array_equal(a.waypoints, b.waypoints)


# ---- the social planners do what the paper says ---------------------------------------------


def corridor_scenario() -> Scenario:
    """A 14 x 8 m hall. A wall (y 3.2..4.8, x 4..10) splits it into the
    direct south corridor (y 0..3.2) and a north detour (y 4.8..8). A person
    stands in the south corridor facing across it; the detour is free. A
    2.2 m bar."""
    scenario = Scenario(
        description="corridor with a person and a free detour",
        world=World(bounds=[0.0, 0.0, 14.0, 8.0], obstacles=[Box(center=[7.0, 4.0], size=[6.0, 1.6])]),
        people=[Person(x=7.0, y=0.5, theta=PI / 2, radius=0.25, name="in corridor")],
        object=Bar(length=2.2),
        start=[1.5, 2.0, 0.0, PI / 2],
        goal=[12.0, 2.0, 0.0, PI / 2],
    )
    scenario.planner = dc.replace(scenario.planner, iterations=700, near_radius_mode="fixed", optimize=False)
    validate_scenario(scenario)
    return scenario


@pytest.fixture(scope="module")
def corridor():
    scenario = corridor_scenario()
    return scenario, PlanarChecker(scenario)  # exact and sound like the numpy one, and compiled: these runs are long


def _median_social(scenario, checker, algorithm, seeds):
    results = [plan(scenario, checker, algorithm=algorithm, seed=s) for s in seeds]
    assert all(r.success for r in results), [r.message for r in results]
    return results, float(np.median([r.social_cost_full for r in results]))


@pytest.mark.slow
def test_social_rrt_star_ends_with_lower_social_cost_than_rrt_star(corridor):
    scenario, checker = corridor
    _, rrt = _median_social(scenario, checker, "rrt_star", range(3))
    _, social = _median_social(scenario, checker, "social_rrt_star", range(3))
    assert social < 0.5 * rrt, (social, rrt)


def _closest_object_approach(scenario, waypoints, person) -> float:
    """Smallest distance (metres) from an object interest point to the person,
    over the path sampled 40 times per segment."""
    geometry = arm_geometry(scenario)
    wp = np.asarray(waypoints)
    t = np.linspace(0.0, 1.0, 40)[None, :, None]
    q = (wp[:-1, None, :] + t * (wp[1:] - wp[:-1])[:, None, :]).reshape(-1, 4)
    p = geometry.interest_points(q)[:, 3:]
    return float(np.hypot(p[..., 0] - person.x, p[..., 1] - person.y).min())


@pytest.mark.slow
def test_multi_point_keeps_the_object_farther_from_people_than_base_only(corridor):
    """Base-only cost is blind to the bar, so its arm swings the bar wherever
    the tree happens to; the multi-point cost keeps the bar away from the
    person. With the detour closed both planners must pass the person."""
    scenario, _ = corridor
    closed = copy.deepcopy(scenario)
    closed.world.obstacles.append(Box(center=[7.0, 6.4], size=[6.0, 3.2]))
    checker = PlanarChecker(closed)
    seeds = range(4)
    base, _ = _median_social(closed, checker, "base_rrt_star", seeds)
    multi, _ = _median_social(closed, checker, "social_rrt_star", seeds)
    person = closed.people[0]
    base_gap = np.median([_closest_object_approach(closed, r.waypoints, person) for r in base])
    multi_gap = np.median([_closest_object_approach(closed, r.waypoints, person) for r in multi])
    # Measured: 0.71 m (base-only) against 1.6 m (multi-point).
    assert multi_gap > base_gap + 0.4, (multi_gap, base_gap)


# ---- informed sampling -------------------------------------------------------------------


@pytest.mark.slow
def test_informed_planner_samples_only_inside_its_ellipse(tiny, tiny_checker, monkeypatch):
    from drake_social.planning import sampling

    drawn = []
    original = sampling.EllipseSampler.sample

    def recording(self, rng, c):
        q = original(self, rng, c)
        drawn.append((q, c, self))
        return q

    monkeypatch.setattr(sampling.EllipseSampler, "sample", recording)
    dut = plan(tiny, tiny_checker, algorithm="informed_social_rrt_star", seed=5)
    assert dut.success
    after = [(q, c, s) for q, c, s in drawn if np.isfinite(c)]
    assert len(after) > 50
    for q, c, s in after:
        assert s.contains(q[:2], c)
    # Paper mode: the diameter in force is the best path's base length, which
    # may grow when a longer path becomes socially cheaper.
    assert dut.informed_diameters[-1] == pytest.approx(dut.base_length, rel=1e-9)


def empty_room(length_weight: float) -> Scenario:
    scenario = Scenario(
        world=World(bounds=[0.0, 0.0, 10.0, 8.0]),
        people=[Person(x=5.0, y=7.5, theta=PI / 2)],  # faces the wall, far from the route
        start=[1.0, 2.0, 0.0, 0.5],
        goal=[8.0, 2.5, 0.3, -0.5],
    )
    scenario.social.length_weight = length_weight
    scenario.planner = dc.replace(scenario.planner, iterations=500, informed_mode="admissible",
                                  near_radius_mode="fixed", optimize=False)
    validate_scenario(scenario)
    return scenario


@pytest.mark.slow
def test_admissible_ellipse_never_excludes_the_optimum():
    """With lambda > 0 and a far person the optimum is the straight motion
    (its social cost is 0 and its length minimal). Every ellipse used must
    contain its base path, and also the path the planner ended with (whose
    cost is below every earlier best)."""
    scenario = empty_room(length_weight=1.0)
    checker = GeometricChecker(scenario)
    start, goal = np.array(scenario.start), np.array(scenario.goal)
    objective = make_planner(scenario, checker, "informed_social_rrt_star").objective
    assert objective.motion_cost(start, goal)[0] == pytest.approx(config_distance(start, goal))
    dut = plan(scenario, checker, algorithm="informed_social_rrt_star", seed=0)
    assert dut.success
    d = dut.informed_diameters[np.isfinite(dut.informed_diameters)]
    assert len(d) > 0
    optimum_xy = np.linspace(start[:2], goal[:2], 50)
    final_xy = dut.waypoints[:, :2]
    for c in d:
        foci = np.hypot(*(optimum_xy - start[:2]).T) + np.hypot(*(optimum_xy - goal[:2]).T)
        assert np.all(foci <= c + 1e-9)
        foci = np.hypot(*(final_xy - start[:2]).T) + np.hypot(*(final_xy - goal[:2]).T)
        assert np.all(foci <= c + 1e-9)
    # The diameters shrink as the best cost does (admissible: cost / lambda).
    assert np.all(np.diff(d) <= 1e-9)
    np.testing.assert_allclose(d[-1], dut.cost, rtol=1e-12)
    # And the planner came close to the optimum's cost.
    assert dut.cost <= 1.1 * config_distance(start, goal)


def test_admissible_mode_needs_a_length_weight(tiny):
    bad = with_planner(tiny, algorithm="informed_social_rrt_star", informed_mode="admissible")
    validate_scenario(bad)  # with the default tie-break (length_weight 0.001)
    bad.social = dc.replace(bad.social, length_weight=0.0)
    from drake_social.scenario import ScenarioError

    with pytest.raises(ScenarioError, match="planner.informed_mode"):
        validate_scenario(bad, source="x.yaml")


# ---- no path, bad endpoints ----------------------------------------------------------------


def walled_goal_scenario() -> Scenario:
    scenario = Scenario(
        world=World(
            bounds=[0.0, 0.0, 12.0, 6.0],
            obstacles=[Box(center=[8.0, 3.0], size=[0.2, 6.0])],  # a full-height wall at x = 8
        ),
        object=Bar(length=1.0),
        start=[2.0, 3.0, 0.0, PI / 2],
        goal=[10.5, 3.0, 0.0, PI / 2],
    )
    scenario.planner = dc.replace(scenario.planner, iterations=300, near_radius_mode="fixed", optimize=False)
    validate_scenario(scenario)
    return scenario


@pytest.mark.slow
@pytest.mark.parametrize("algorithm", ["rrt_star", "informed_social_rrt_star"])
def test_walled_off_goal_returns_a_clear_no_path_result(algorithm):
    scenario = walled_goal_scenario()
    checker = GeometricChecker(scenario)
    dut = plan(scenario, checker, algorithm=algorithm, seed=0)
    assert not dut.success
    assert "no collision-free connection to the goal" in dut.message
    assert dut.waypoints.shape == (0, 4) and dut.cost == math.inf
    assert dut.first_solution_iteration is None
    assert np.all(np.isinf(dut.cost_history))
    # The best partial information: the tree stayed west of the wall.
    assert dut.tree_size > 50 and np.all(dut.tree_nodes[:, 0] < 8.0)
    assert dut.closest_distance_to_goal > 10.5 - 8.0 - 0.1
    assert "no path" in dut.summary()
    with pytest.raises(RuntimeError):
        dut.raise_if_failed()


@pytest.mark.parametrize("which", ["start", "goal"])
def test_start_or_goal_in_collision_raises_a_clear_error(tiny, tiny_checker, which):
    bad = copy.deepcopy(tiny)
    setattr(bad, which, [4.0, 3.8, 0.0, 0.0])  # the base on the person
    with pytest.raises(PlanningInputError, match=f"{which} configuration .* is in collision"):
        plan(bad, tiny_checker)


def test_start_outside_the_space_raises(tiny, tiny_checker):
    planner = make_planner(tiny, tiny_checker)
    with pytest.raises(PlanningInputError, match="outside the configuration space"):
        planner.solve(np.array([-1.0, 2.5, 0.0, 0.0]), np.array(tiny.goal), np.random.default_rng(0))
    with pytest.raises(PlanningInputError, match=r"^RrtStar.solve: start: must hold finite numbers only, got nan at index 0$"):
        planner.solve(np.array([np.nan, 2.5, 0.0, 0.0]), np.array(tiny.goal), np.random.default_rng(0))


def test_start_equal_to_goal_is_refused(tiny, tiny_checker):
    """Nothing to plan: refused like the scenario check refuses it (a one-row
    path would be no path that simulate can execute)."""
    same = copy.deepcopy(tiny)
    same.goal = list(same.start)
    with pytest.raises(PlanningInputError, match=r"^start and goal are the same configuration"):
        plan(same, tiny_checker, iterations=5)


# ---- configuration, not copies ---------------------------------------------------------------


def test_variants_are_configurations_of_one_core(tiny, tiny_checker):
    objectives = {a: make_planner(tiny, tiny_checker, a).objective for a in ALGORITHMS}
    assert isinstance(objectives["rrt_star"], PathLengthObjective)
    for a in ALGORITHMS[1:]:
        assert isinstance(objectives[a], SocialObjective)
    np.testing.assert_array_equal(objectives["base_rrt_star"].social.weights, [1, 0, 0, 0, 0])
    np.testing.assert_array_equal(objectives["social_rrt_star"].social.weights, [1, 1, 1, 1, 1])
    assert make_planner(tiny, tiny_checker, "informed_base_rrt_star").options.informed
    assert not make_planner(tiny, tiny_checker, "base_rrt_star").options.informed


def test_length_weight_adds_lambda_times_length(tiny, rng):
    scenario = copy.deepcopy(tiny)
    scenario.social.length_weight = 0.0
    plain = make_objective(scenario, "social_rrt_star")
    scenario.social.length_weight = 0.7
    dut = make_objective(scenario, "social_rrt_star")
    space = ConfigurationSpace.from_scenario(scenario)
    a, b = space.sample_uniform(rng, 30), space.sample_uniform(rng, 30)
    np.testing.assert_allclose(dut.motion_cost(a, b), plain.motion_cost(a, b) + 0.7 * config_distance(a, b))


def test_bad_options_are_refused(tiny, tiny_checker):
    space = ConfigurationSpace.from_scenario(tiny)
    objective = PathLengthObjective()
    with pytest.raises(ValueError, match="iterations"):
        RrtStar(space, tiny_checker, objective, RrtStarOptions(iterations=0))
    with pytest.raises(ValueError, match="goal_bias"):
        RrtStar(space, tiny_checker, objective, RrtStarOptions(goal_bias=1.0))
    with pytest.raises(ValueError, match="informed mode"):
        RrtStar(space, tiny_checker, objective, RrtStarOptions(informed=True, informed_mode="wild"))


# ---- the tree's bookkeeping -------------------------------------------------------------------


def test_tree_costs_are_recomputed_so_descendants_never_undercut_ancestors():
    """Shifting a subtree by a cost difference can leave a child one ulp below
    its ancestor; with zero-cost motions the strict rewiring test then picked
    that ancestor and the tree grew a cycle. Costs are recomputed instead."""
    from drake_social.planning.rrt_star.reference import _Tree

    dut = _Tree(8)
    dut.add(np.zeros(4), -1, 0.0)
    a = dut.add(np.ones(4), 0, 0.1)
    b = dut.add(np.ones(4), a, 0.2)
    c = dut.add(np.ones(4), b, 0.0)  # a free motion, as far from people
    d = dut.add(np.ones(4), 0, 6.8478872835105875 - 0.1)
    dut.reparent(b, d, 0.7)
    assert dut.cost[c] == dut.cost[b] == dut.cost[d] + 0.7
    for node in (a, b, c, d):
        assert dut.cost[node] >= dut.cost[dut.parent[node]]
    with pytest.raises(RuntimeError, match="descendant"):
        dut.reparent(d, c, 0.0)


@pytest.mark.slow
def test_zero_cost_motions_never_rewire_into_a_cycle():
    """A social objective with nobody around: every motion costs exactly 0, the
    situation in which the shifted costs used to loop forever."""
    scenario = empty_room(length_weight=0.0)
    scenario.people = []
    checker = GeometricChecker(scenario)
    dut = plan(scenario, checker, algorithm="social_rrt_star", iterations=400, seed=0)
    assert dut.success and dut.cost == 0.0
    assert np.all(dut.tree_costs == 0.0)


# ---- every scenario file, with Drake's checker ---------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("name", ["office_bar", "generic_L", "tiny"])
def test_every_scenario_plans_a_valid_path_with_drake(name, repo_root):
    """A short run per shipped scenario with the SceneGraph checker (clearance
    advancement for motions); its path is re-checked by Drake's discrete
    edge check and by the independent numpy checker."""
    from drake_social.collision.drake_checker import SceneGraphChecker
    from drake_social.scenario import load_scenario

    # The raw tree path: an optimised one hugs the walls, where Drake's motion
    # check and the numpy checker's can disagree (generic_L, seed 0).
    scenario = load_scenario(repo_root / "scenarios" / f"{name}.yaml", "planner: {optimize: false}")
    dut = plan(scenario, SceneGraphChecker(scenario, parallelism=1), iterations=800, seed=0)
    assert dut.success, dut.message
    wp = dut.waypoints
    np.testing.assert_array_equal(wp[[0, -1]], [scenario.start, scenario.goal])
    drake = SceneGraphChecker(scenario, parallelism=1)
    assert drake.are_valid(wp).all() and drake.are_motions_valid(wp[:-1], wp[1:]).all()
    numpy_ = GeometricChecker(scenario)
    assert numpy_.are_valid(wp).all() and numpy_.are_motions_valid(wp[:-1], wp[1:]).all()


def test_admissible_mode_without_a_length_weight_is_refused(tiny, tiny_checker):
    bad = with_planner(tiny, informed_mode="admissible")  # the file's algorithm is not informed: passes validation
    bad.social = dc.replace(bad.social, length_weight=0.0)
    validate_scenario(bad)
    with pytest.raises(PlanningInputError, match="admissible.*length_weight"):
        make_planner(bad, tiny_checker, "informed_social_rrt_star")


def test_paper_ellipse_can_shut_out_a_cheaper_detour_the_admissible_one_keeps():
    """The corridor: the straight route past the person is short and costly,
    the north detour long and cheap. After the straight route is found, the
    paper's ellipse (its XY length) excludes the detour; the admissible one
    (its cost / lambda) contains the whole detour, since the detour costs less."""
    from drake_social.planning.sampling import EllipseSampler, transverse_diameter

    scenario = corridor_scenario()
    scenario.social.length_weight = 0.5
    objective = make_objective(scenario, "informed_social_rrt_star")
    start, goal = np.array(scenario.start), np.array(scenario.goal)
    straight = np.array([start, goal])
    detour = np.array([start, [3.0, 6.4, 0.0, PI / 2], [10.5, 6.4, 0.0, PI / 2], goal])
    cost = {name: objective.motion_cost(p[:-1], p[1:]).sum() for name, p in (("straight", straight), ("detour", detour))}
    assert cost["detour"] < cost["straight"]
    xy_length = float(np.hypot(*np.diff(straight[:, :2], axis=0).T).sum())
    ellipse = EllipseSampler(ConfigurationSpace.from_scenario(scenario), start[:2], goal[:2])
    t = np.linspace(0, 1, 50)[:, None]
    detour_xy = np.vstack([a[:2] + t * (b[:2] - a[:2]) for a, b in zip(detour[:-1], detour[1:])])
    paper = transverse_diameter("paper", cost["straight"], xy_length, objective)
    admissible = transverse_diameter("admissible", cost["straight"], xy_length, objective)
    assert not ellipse.contains(detour_xy, paper).all()
    assert ellipse.contains(detour_xy, admissible).all()
