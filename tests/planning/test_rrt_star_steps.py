"""The RRT* steps of Algorithm 2, each tested as the property it is.

Small hand-made rooms and trees; every expectation is enumerated here
independently of the planner (brute-force near sets, every candidate parent
costed and checked one by one, rewiring replayed on a copy of the tree).
"""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest

from drake_social.collision.geometric import GeometricChecker
from drake_social.planning.rrt_star import RrtStar, RrtStarOptions
from drake_social.planning.rrt_star.reference import _Counts, _Tree
from drake_social.planning.space import ConfigurationSpace
from drake_social.planning.algorithms import make_objective
from drake_social.scenario import Bar, Box, Person, Scenario, World, validate_scenario

PI = math.pi


def room(**planner) -> Scenario:
    """A 10 x 6 m room with a pillar in the middle and two people (one
    rotated by pi/4) near it, so that motion costs differ between parents
    and some near motions collide."""
    scenario = Scenario(
        world=World(bounds=[0.0, 0.0, 10.0, 6.0], obstacles=[Box(center=[5.0, 3.0], size=[1.0, 2.4])]),
        people=[Person(x=3.5, y=5.0, theta=-PI / 2), Person(x=6.8, y=1.2, theta=PI / 4)],
        object=Bar(length=1.0),
        start=[1.0, 3.0, 0.0, PI / 2],
        goal=[8.2, 3.0, 0.0, PI / 2],
    )
    # the paper's raw planner (fixed r_near, no optimisation): these tests check Algorithm 2's steps
    scenario.planner = dc.replace(scenario.planner, **{"near_radius_mode": "fixed", "optimize": False, **planner})
    validate_scenario(scenario)
    return scenario


def planner_for(scenario: Scenario, algorithm: str = "social_rrt_star") -> RrtStar:
    checker = GeometricChecker(scenario)
    objective = make_objective(scenario, algorithm)
    options = RrtStarOptions.from_scenario(scenario.planner)
    return RrtStar(ConfigurationSpace.from_scenario(scenario), checker, objective, options)


def random_tree(planner: RrtStar, rng: np.random.Generator, n: int) -> _Tree:
    """n valid configurations with random earlier parents; F from the objective."""
    space, checker, objective = planner.space, planner.checker, planner.objective
    tree = _Tree(4)
    tree.add(np.array(planner_start(planner)), -1, 0.0)
    while tree.n < n:
        q = space.sample_uniform(rng)
        if not checker.is_valid(q):
            continue
        parent = int(rng.integers(tree.n))
        tree.add(q, parent, float(objective.motion_cost(tree.q[parent], q)[0]))
    return tree


def planner_start(planner: RrtStar) -> np.ndarray:
    return np.array([1.0, 3.0, 0.0, PI / 2])


def copy_tree(tree: _Tree) -> _Tree:
    out = _Tree(4)
    for i in range(tree.n):
        out.add(tree.q[i].copy(), int(tree.parent[i]), float(tree.edge[i]))
    return out


def brute_force_near(nodes: np.ndarray, q: np.ndarray, weights: np.ndarray, r_near: float) -> list[int]:
    out = [i for i in range(len(nodes)) if math.sqrt(sum((w * (a - b)) ** 2 for w, a, b in zip(weights, nodes[i], q))) <= r_near]
    d = [math.sqrt(sum((w * (a - b)) ** 2 for w, a, b in zip(weights, nodes[i], q))) for i in range(len(nodes))]
    return out, d


def costs_from_parents(parent: np.ndarray, edge: np.ndarray) -> np.ndarray:
    """F of every node by walking to the root (independent of the tree's bookkeeping)."""
    cost = np.zeros(len(parent))
    for i in range(len(parent)):
        j, total = i, 0.0
        while parent[j] >= 0:
            total += edge[j]
            j = parent[j]
        cost[i] = total
    return cost


# ---- Steer and the near set ---------------------------------------------------------------


@pytest.mark.parametrize("planning_range, near_radius", [(1.0, 2.0), (2.0, 0.7)])
def test_near_set_is_the_nodes_within_r_near_plus_the_nearest(planning_range, near_radius):
    """Both r_near > delta and r_near < delta (where the nearest must be added
    even though it lies beyond r_near), with anisotropic distance weights."""
    scenario = room(planning_range=planning_range, near_radius=near_radius, distance_weights=[1.0, 2.0, 0.5, 0.3])
    dut = planner_for(scenario)
    rng = np.random.default_rng(7)
    tree = _Tree(4)
    for q in dut.space.sample_uniform(rng, 300):
        tree.add(q, -1 if tree.n == 0 else 0, 0.0)
    nodes = tree.q[: tree.n]
    forced = 0
    for q_rand in dut.space.sample_uniform(rng, 60):
        d_rand = [math.sqrt(sum((w * (a - b)) ** 2 for w, a, b in zip(dut.space.weights, x, q_rand))) for x in nodes]
        i_nearest = int(np.argmin(d_rand))
        # Steer: exactly delta from the nearest towards q_rand (or q_rand itself).
        expected_new = q_rand if d_rand[i_nearest] <= planning_range else (
            nodes[i_nearest] + (q_rand - nodes[i_nearest]) * planning_range / d_rand[i_nearest])
        q_new = dut.space.steer(nodes[i_nearest], q_rand, dut.options.planning_range)
        np.testing.assert_allclose(q_new, expected_new, rtol=0, atol=1e-12)
        within, d_new = brute_force_near(nodes, q_new, dut.space.weights, near_radius)
        expected = set(within) | {i_nearest}
        forced += i_nearest not in within
        near = dut._near(tree, q_new, i_nearest)
        assert sorted(near.tolist()) == sorted(expected)
        assert len(set(near.tolist())) == len(near)
    if near_radius < planning_range:
        assert forced > 5  # the case the rule is for happened
    else:
        assert forced == 0


# ---- choose parent and rewire --------------------------------------------------------------


@pytest.mark.slow
def test_parent_minimises_f_plus_msc_and_rewiring_reparents_exactly_the_improved():
    scenario = room(planning_range=1.5, near_radius=2.2)
    dut = planner_for(scenario)
    space, checker, objective = dut.space, dut.checker, dut.objective
    rng = np.random.default_rng(3)
    base = random_tree(dut, rng, 80)
    cases = not_nearest = rewired = blocked = 0
    for q_rand in space.sample_uniform(rng, 80):
        tree = copy_tree(base)
        nodes = tree.q[: tree.n].copy()
        d_rand = np.sqrt((((nodes - q_rand) * space.weights) ** 2).sum(1))
        i_nearest = int(np.argmin(d_rand))
        q_new = space.steer(nodes[i_nearest], q_rand, dut.options.planning_range)
        if not checker.is_valid(q_new):
            continue
        within, _ = brute_force_near(nodes, q_new, space.weights, dut.options.near_radius)
        near = sorted(set(within) | {i_nearest})
        # Every collision-free near node, costed one by one.
        totals = {}
        for j in near:
            if checker.is_motion_valid(nodes[j], q_new):
                totals[j] = base.cost[j] + float(objective.motion_cost(nodes[j], q_new)[0])
            else:
                blocked += 1
        i_new = dut._extend(tree, q_rand, _Counts())
        if not totals:
            assert i_new == -1 and tree.n == base.n
            continue
        cases += 1
        best = min(totals, key=totals.get)
        assert i_new == base.n
        assert tree.parent[i_new] == best
        assert tree.cost[i_new] == pytest.approx(totals[best], rel=1e-12, abs=1e-12)
        not_nearest += best != i_nearest
        # Rewiring replayed on a copy (ascending near order, current costs).
        parent = np.append(base.parent[: base.n], best)
        edge = np.append(base.edge[: base.n], totals[best] - base.cost[best])
        for j in near:
            if j == best:
                continue
            cost = costs_from_parents(parent, edge)
            c = float(objective.motion_cost(q_new, nodes[j])[0])
            if cost[i_new] + c < cost[j] and checker.is_motion_valid(q_new, nodes[j]):
                parent[j], edge[j] = i_new, c
                rewired += 1
        np.testing.assert_array_equal(tree.parent[: tree.n], parent)  # nothing else changed
        np.testing.assert_array_equal(tree.q[: base.n], base.q[: base.n])
        np.testing.assert_allclose(tree.cost[: tree.n], costs_from_parents(parent, edge), rtol=1e-12, atol=1e-12)
    # The cases the properties are about did happen.
    assert cases > 30 and not_nearest > 5 and rewired > 5 and blocked > 5, (cases, not_nearest, rewired, blocked)


# ---- whole runs ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def goal_run():
    """No goal bias: the goal is reached only through goal connections."""
    scenario = room(planning_range=0.8, near_radius=2.0, goal_bias=0.0, iterations=500)
    dut = planner_for(scenario)
    result = dut.solve(np.array(scenario.start), np.array(scenario.goal), np.random.default_rng(5))
    return scenario, dut, result


@pytest.mark.slow
def test_path_ends_through_the_best_goal_connection_within_r_near(goal_run):
    scenario, dut, result = goal_run
    assert result.success
    goal = np.array(scenario.goal)
    q, cost = result.tree_nodes, result.tree_costs
    d = np.sqrt((((q - goal) * dut.space.weights) ** 2).sum(1))
    assert not np.any(d == 0)  # the goal is not a node: every path uses a goal connection
    candidates = {}
    for i in np.flatnonzero(d <= dut.options.near_radius):
        if dut.checker.is_motion_valid(q[i], goal):
            candidates[int(i)] = cost[i] + float(dut.objective.motion_cost(q[i], goal)[0])
    best = min(candidates, key=candidates.get)
    first = min(candidates)  # the first node inserted that connects
    assert candidates[first] > candidates[best] + 1e-6  # the first connection is not the best
    assert d[best] > dut.options.planning_range  # and the best lies beyond delta, within r_near
    assert result.cost == pytest.approx(candidates[best], rel=1e-12)
    np.testing.assert_array_equal(result.waypoints[-1], goal)
    np.testing.assert_array_equal(result.waypoints[-2], q[best])


@pytest.mark.slow
@pytest.mark.parametrize("planning_range, near_radius", [(0.8, 2.0), (2.0, 0.7)])
def test_every_tree_edge_is_within_the_insertion_or_rewiring_reach(planning_range, near_radius):
    """A node's parent is a near node (within r_near) or its nearest (within
    delta, which is then forced into the near set); rewiring moves only near
    nodes. So every edge is at most max(delta, r_near), and at most r_near
    when r_near >= delta."""
    scenario = room(planning_range=planning_range, near_radius=near_radius, iterations=300)
    dut = planner_for(scenario)
    result = dut.solve(np.array(scenario.start), np.array(scenario.goal), np.random.default_rng(4))
    q, parent = result.tree_nodes, result.tree_parents
    child = np.arange(1, len(q))
    length = np.sqrt((((q[child] - q[parent[child]]) * dut.space.weights) ** 2).sum(1))
    assert np.all(length <= max(planning_range, near_radius) + 1e-12)
    if near_radius < planning_range:
        assert np.any(length > near_radius)  # forced nearest parents happened
