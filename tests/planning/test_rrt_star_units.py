"""Small units of planning/rrt_star.py that the planner tests reach only
through whole runs: the growing tree's arrays, the path to a node, the
endpoint checks' messages and the XY length of a path to the goal
(found by the mutation run)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_social.planning.geometric import GeometricChecker
from drake_social.planning.result import PlanningInputError
from drake_social.planning.rrt_star import RrtStar, RrtStarOptions, _Tree
from drake_social.planning.space import ConfigurationSpace
from drake_social.planning.variants import make_objective
from drake_social.scenario import Bar, Box, Scenario, World, validate_scenario


def room() -> Scenario:
    scenario = Scenario(world=World(bounds=[0.0, 0.0, 10.0, 6.0], obstacles=[Box(center=[5.0, 3.0], size=[1.0, 2.4])]),
                        people=[], object=Bar(length=1.0), start=[1.0, 3.0, 0.0, math.pi / 2],
                        goal=[8.2, 3.0, 0.0, math.pi / 2])
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
