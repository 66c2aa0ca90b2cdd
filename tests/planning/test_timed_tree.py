"""The compiled loop's timed mode, its seeding and its deadline (issue 21).

The disabled mode is the static loop bit for bit: the equality tests against
the Python reference (test_tree_kernel.py) and the path hashes
(test_path_hashes.py) run it unchanged.
"""

from __future__ import annotations

import copy
import dataclasses as dc
import time

import numpy as np
import pytest

from drake_social.collision import people_kernel
from drake_social.collision.planar_checker import PlanarChecker
from drake_social.cost.social import SocialCost
from drake_social.kinematics import nominal_durations, nominal_path_times
from drake_social.people import without_people
from drake_social.people.prediction import Prediction
from drake_social.planning.algorithms import make_planner
from drake_social.planning.objective import SocialObjective
from drake_social.planning.rrt_star import compiled, tree_kernel
from drake_social.planning.rrt_star.compiled import timed_params

pytestmark = pytest.mark.skipif(not tree_kernel.AVAILABLE, reason="numba is not importable")


def static_prediction(scenario, t0=0.0, horizon=5.0, dt=0.1):
    """The scenario's standing people held still over the horizon."""
    h = int(round(horizon / dt)) + 1
    people = scenario.people
    p = len(people)
    xy = np.array([[person.x, person.y] for person in people], float).reshape(p, 2)
    theta = np.array([person.theta for person in people], float)
    return Prediction(t0, dt, np.repeat(xy[None], h, 0), np.repeat(theta[None], h, 0), np.ones((h, p), bool),
                      np.array([person.radius for person in people], float), np.zeros(p), np.zeros(p),
                      tuple(person.name for person in people))


def walker_prediction(x=3.2, y=2.5, t_cross=4.4, t0=0.0, horizon=12.0, dt=0.1):
    """One walker walking north at 0.4 m/s along x, at (x, y) at t_cross."""
    times = t0 + dt * np.arange(int(round(horizon / dt)) + 1)
    y = y + 0.4 * (times - t_cross)
    xy = np.stack([np.full_like(y, x), y], axis=1)[:, None, :]
    h = len(times)
    return Prediction(t0, dt, xy, np.full((h, 1), np.pi / 2), np.ones((h, 1), bool), np.array([0.25]),
                      np.array([0.4]), np.array([0.4]), ("walker",))


@pytest.fixture(scope="module")
def tiny(tiny_scenario):
    scenario = copy.deepcopy(tiny_scenario)
    scenario.planner = dc.replace(scenario.planner, iterations=300)
    return scenario, PlanarChecker(scenario)


def ends(scenario):
    return np.array(scenario.start, float), np.array(scenario.goal, float)


@pytest.mark.parametrize("length_weight", [0.0, 0.4])  # eager and lazy costs
def test_a_static_prediction_gives_the_static_tree(tiny, length_weight):
    """Standing people predicted still: the same tree as the static social
    objective (the same nodes and parents; costs to 1e-9), the people check
    relaxed (safety -1 m: the static checker has them as discs already)."""
    scenario, checker = tiny
    scenario = copy.deepcopy(scenario)
    scenario.social.length_weight = length_weight
    planner = make_planner(scenario, checker, "social_rrt_star")
    start, goal = ends(scenario)
    static = planner.solve(start, goal, np.random.default_rng(5))
    timed = timed_params(static_prediction(scenario), scenario.execution, 0.0, -1.0)
    tree = planner.solve_timed(start, goal, np.random.default_rng(5), timed)
    np.testing.assert_array_equal(tree.nodes, static.tree_nodes)
    np.testing.assert_array_equal(tree.parents, static.tree_parents)
    np.testing.assert_allclose(tree.costs, static.tree_costs, rtol=1e-9, atol=1e-12)
    assert tree.best_cost == pytest.approx(static.cost, rel=1e-9)
    np.testing.assert_array_equal(path_of(tree, tree.best_node, goal), static.waypoints)
    assert tree.iterations == 300 and not tree.deadline_hit
    # Node times: the parent's plus the nominal duration of the motion.
    child = np.flatnonzero(tree.parents >= 0)
    d = nominal_durations(tree.nodes[tree.parents[child]], tree.nodes[child], scenario.execution.max_base_speed,
                          scenario.execution.arm_max_velocity)
    np.testing.assert_allclose(tree.tnode[child], tree.tnode[tree.parents[child]] + d, rtol=0, atol=1e-12)
    assert tree.tnode[0] == 0.0


def crossing_setup(tiny):
    """The room without its person; a walker who meets the static plan's
    base where it crosses x = 3.5 (at the plan's nominal time there)."""
    scenario, _ = tiny
    room = without_people(scenario)
    checker = PlanarChecker(room)
    blind = make_planner(scenario, checker, "social_rrt_star").solve(*ends(scenario), np.random.default_rng(2))
    wp = blind.waypoints
    t = nominal_path_times(wp, scenario.execution.max_base_speed, scenario.execution.arm_max_velocity)
    k = int(np.flatnonzero(wp[1:, 0] >= 3.5)[0])
    u = (3.5 - wp[k, 0]) / (wp[k + 1, 0] - wp[k, 0])
    pred = walker_prediction(3.5, wp[k, 1] + u * (wp[k + 1, 1] - wp[k, 1]), t[k] + u * (t[k + 1] - t[k]))
    s = scenario.social
    social = SocialCost.from_scenario(scenario)
    social = SocialCost(social.geometry, pred.positions[0, :, :].tolist() and np.c_[pred.positions[0], [np.pi / 2]],
                        social.space, s.weights, s.resolution, scenario.planner.distance_weights)
    objective = SocialObjective(social, 0.2)
    planner = make_planner(scenario, checker, "social_rrt_star")
    safety = scenario.execution.safety_distance
    return scenario, checker, pred, objective, planner, safety


def path_of(tree, node, goal):
    path = tree.nodes[tree.path_to(node)]
    return path if np.array_equal(path[-1], goal) else np.vstack([path, goal])


def test_a_walker_crossing_never_comes_within_safety(tiny):
    """Every goal connection's path (tree path + goal) is clear of the
    walker at the nominal times when re-checked motion by motion."""
    scenario, checker, pred, objective, planner, safety = crossing_setup(tiny)
    start, goal = ends(scenario)
    timed = timed_params(pred, scenario.execution, 0.0, safety)
    tree = planner.solve_timed(start, goal, np.random.default_rng(2), timed, iterations=600, objective=objective)
    assert tree.best_node >= 0
    scene = checker.compiled_scene()
    checked = 0
    for g, e in zip(tree.goal_nodes, tree.goal_edges):
        if not np.isfinite(tree.costs[g] + e):
            continue  # a connection cut off by a later rewiring
        wp = path_of(tree, g, goal)
        t = nominal_path_times(wp, scenario.execution.max_base_speed, scenario.execution.arm_max_velocity, 0.0)
        for k in range(len(wp) - 1):
            assert people_kernel.motion_clear_of_people(
                wp[k], wp[k + 1], t[k], t[k + 1], scene.bodies, scene.robot, scene.levers, pred.positions,
                pred.present, pred.radii, pred.max_speeds, pred.t0, pred.dt, safety), (g, k)
        checked += 1
    assert checked >= 1
    # The static loop, blind to the walker, drives straight through its crossing.
    blind = planner.solve(start, goal, np.random.default_rng(2))
    t = nominal_path_times(blind.waypoints, scenario.execution.max_base_speed, scenario.execution.arm_max_velocity)
    assert not all(people_kernel.motion_clear_of_people(
        blind.waypoints[k], blind.waypoints[k + 1], t[k], t[k + 1], scene.bodies, scene.robot, scene.levers,
        pred.positions, pred.present, pred.radii, pred.max_speeds, pred.t0, pred.dt, safety)
        for k in range(len(t) - 1))


def test_a_safety_horizon_before_the_crossing_lets_the_tree_through_it(tiny):
    """The walker crosses the blind plan's line after the safety horizon: the
    tree's check (``_people_ok``) considers the horizon's samples only
    (``safety_slots``, counted by hand) and accepts the motion through the
    crossing that the full prediction's check refuses; every goal connection
    of a tree grown so is clear over the horizon."""
    scenario, checker, pred, objective, planner, safety = crossing_setup(tiny)
    start, goal = ends(scenario)
    assert timed_params(pred, scenario.execution, 0.0, safety).safety_slots == pred.samples
    horizon = 0.5
    timed = timed_params(pred, scenario.execution, 0.0, safety, safety_horizon=horizon)
    assert timed.safety_slots == int(np.ceil(horizon / pred.dt - 1e-9)) + 1 == pred.until(horizon).samples
    full = timed_params(pred, scenario.execution, 0.0, safety)
    scene = checker.compiled_scene()
    blind = planner.solve(start, goal, np.random.default_rng(2)).waypoints
    t = nominal_path_times(blind, scenario.execution.max_base_speed, scenario.execution.arm_max_velocity, 0.0)
    refused = [k for k in range(len(blind) - 1)
               if not tree_kernel._people_ok(blind[k], blind[k + 1], t[k], t[k + 1], scene, full)]
    assert refused and t[refused[0]] > horizon  # the crossing comes after the horizon
    assert all(tree_kernel._people_ok(blind[k], blind[k + 1], t[k], t[k + 1], scene, timed) for k in refused)
    tree = planner.solve_timed(start, goal, np.random.default_rng(2), timed, iterations=600, objective=objective)
    short = pred.until(horizon)
    for g, e in zip(tree.goal_nodes, tree.goal_edges):
        if not np.isfinite(tree.costs[g] + e):
            continue
        wp = path_of(tree, g, goal)
        tw = nominal_path_times(wp, scenario.execution.max_base_speed, scenario.execution.arm_max_velocity, 0.0)
        assert all(people_kernel.motion_clear_of_people(
            wp[k], wp[k + 1], tw[k], tw[k + 1], scene.bodies, scene.robot, scene.levers, short.positions,
            short.present, short.radii, short.max_speeds, short.t0, short.dt, safety) for k in range(len(wp) - 1))


def test_same_generator_same_tree_bit_for_bit(tiny):
    scenario, checker, pred, objective, planner, safety = crossing_setup(tiny)
    start, goal = ends(scenario)
    timed = timed_params(pred, scenario.execution, 0.0, safety)
    a = planner.solve_timed(start, goal, np.random.default_rng(9), timed, iterations=300, objective=objective)
    b = planner.solve_timed(start, goal, np.random.default_rng(9), timed, iterations=300, objective=objective)
    for field in ("nodes", "parents", "costs", "tnode", "history", "goal_nodes", "goal_edges"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    assert (a.best_node, a.best_cost, a.counts) == (b.best_node, b.best_cost, b.counts)


def test_the_seed_path_is_in_the_tree_and_bounds_the_best(tiny):
    """A seed from the start to the goal: its chain is nodes 0 .. M-1 with
    their exact costs and times, and the best cost never exceeds it."""
    scenario, checker, pred, objective, planner, safety = crossing_setup(tiny)
    start, goal = ends(scenario)
    timed = timed_params(pred, scenario.execution, 0.0, safety)
    found = planner.solve_timed(start, goal, np.random.default_rng(3), timed, iterations=600, objective=objective)
    seed = path_of(found, found.best_node, goal)
    tree = planner.solve_timed(start, goal, np.random.default_rng(4), timed, iterations=1, seed_path=seed,
                               objective=objective)
    m = len(seed)
    np.testing.assert_array_equal(tree.nodes[:m], seed)
    np.testing.assert_array_equal(tree.parents[:m], np.arange(-1, m - 1))
    t = nominal_path_times(seed, scenario.execution.max_base_speed, scenario.execution.arm_max_velocity, 0.0)
    np.testing.assert_allclose(tree.tnode[:m], t, rtol=0, atol=1e-12)
    # The chain's cost: the timed objective motion by motion, independently (one motion per call).
    from drake_social.planning.rrt_star.tree_kernel import _motion_costs

    params = compiled.grow_params(planner.space, checker, objective, planner.options, planner.gamma, start, goal,
                                  timed)
    edges = [_motion_costs(seed[k:k + 1], seed[k + 1:k + 2], t[k:k + 1], t[k + 1:k + 2], params.objective, timed)[0]
             for k in range(m - 1)]
    np.testing.assert_allclose(np.diff(tree.costs[:m]), edges, rtol=1e-9, atol=1e-12)
    assert m - 1 in tree.goal_nodes  # the seed ends at the goal: connected at cost 0
    assert tree.best_cost <= tree.costs[m - 1] + 1e-12
    # With a full search the seed still bounds the best.
    full = planner.solve_timed(start, goal, np.random.default_rng(4), timed, iterations=400, seed_path=seed,
                               objective=objective)
    assert full.best_cost <= tree.costs[m - 1] * (1 + 1e-12)


def test_a_seed_stops_at_its_first_invalid_motion(tiny):
    """A straight seed that a walker crosses at x = 3.5 when the robot would
    be there: the chain keeps the waypoints before the crossing only."""
    scenario, checker, _, objective, planner, safety = crossing_setup(tiny)
    start, goal = ends(scenario)
    seed = np.linspace(start, goal, 12)  # 0.5 m steps along y = 2.5
    speed = scenario.execution.max_base_speed
    pred = walker_prediction(3.5, 2.5, (3.5 - start[0]) / speed)
    timed = timed_params(pred, scenario.execution, 0.0, safety)
    tree = planner.solve_timed(start, goal, np.random.default_rng(0), timed, iterations=1, seed_path=seed,
                               objective=objective)
    m = 1
    while m < len(tree.nodes) and m < len(seed) and np.array_equal(tree.nodes[m], seed[m]) \
            and tree.parents[m] == m - 1:
        m += 1
    assert 2 <= m < len(seed)  # some of the chain, not all of it
    assert seed[m - 1, 0] < 3.5 and not np.any(tree.goal_nodes < m)
    with pytest.raises(ValueError, match="seed_path must start at the start"):
        planner.solve_timed(start, goal, np.random.default_rng(0), timed, iterations=1, seed_path=seed[1:],
                            objective=objective)


def test_a_deadline_stops_early_with_the_best_so_far(tiny):
    scenario, checker, pred, objective, planner, safety = crossing_setup(tiny)
    start, goal = ends(scenario)
    timed = timed_params(pred, scenario.execution, 0.0, safety)
    k = 20000
    tree = planner.solve_timed(start, goal, np.random.default_rng(1), timed, iterations=k,
                               deadline=time.perf_counter() + 0.05, objective=objective)
    assert tree.deadline_hit and 0 < tree.iterations < k
    # The first chunk: DEADLINE_CHUNK calls, the start's goal connection (iteration -1) among them.
    assert tree.iterations >= compiled.DEADLINE_CHUNK - 1 and len(tree.history) == tree.iterations
    assert tree.best_cost == tree.history[-1]
    # The same samples without a deadline: the same tree (the deadline only cuts).
    again = planner.solve_timed(start, goal, np.random.default_rng(1), timed, iterations=tree.iterations,
                                objective=objective)
    assert not again.deadline_hit
    np.testing.assert_array_equal(again.nodes, tree.nodes)
    np.testing.assert_array_equal(again.parents, tree.parents)
    assert again.best_cost == tree.best_cost


def test_timed_params_name_their_errors(tiny):
    scenario, *_ = tiny
    with pytest.raises(ValueError, match="t_root"):
        timed_params(walker_prediction(), scenario.execution, float("nan"), 0.05)
    with pytest.raises(ValueError, match="safety"):
        timed_params(walker_prediction(), scenario.execution, 0.0, float("inf"))
