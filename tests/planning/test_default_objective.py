"""The default objective breaks ties by length (``social.length_weight``
0.001): where nobody is, every route's social cost is 0, and the default
path is the shortest one; the paper's pure social integral (0) has no
preference among them."""

from __future__ import annotations

import dataclasses as dc

import numpy as np
import pytest

from drake_social.collision.geometric import GeometricChecker
from drake_social.kinematics import config_distance
from drake_social.planning.algorithms import make_objective, plan
from drake_social.scenario import Box, Scenario, SocialCostOptions, World, validate_scenario


def test_the_default_length_weight_is_a_tie_break():
    assert SocialCostOptions().length_weight == 0.001
    scenario = Scenario()
    validate_scenario(scenario)
    dut = make_objective(scenario, "social_rrt_star")
    assert dut.length_weight == 0.001
    a, b = np.array([1.0, 1.0, 0.0, 0.0]), np.array([4.0, 5.0, 0.5, -0.5])
    # nobody in the default scenario: the cost is the tie-break alone
    assert dut.motion_cost(a, b)[0] == pytest.approx(0.001 * config_distance(a, b), rel=1e-14)


def empty_room(length_weight: float | None = None) -> Scenario:
    """10 x 8 m, nobody, no obstacle: every motion's social cost is 0."""
    scenario = Scenario(world=World(bounds=[0.0, 0.0, 10.0, 8.0]), people=[],
                        start=[1.0, 2.0, 0.0, 0.5], goal=[8.0, 6.5, 0.3, -0.5])
    if length_weight is not None:
        scenario.social = dc.replace(scenario.social, length_weight=length_weight)
    scenario.planner = dc.replace(scenario.planner, iterations=300)
    validate_scenario(scenario)
    return scenario


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_an_empty_room_gives_the_straight_motion_by_default(seed):
    """With the defaults (social_rrt_star, optimised, the tie-break) the path
    is the straight motion from start to goal: its length is the distance
    between them. The paper's pure social integral plans a path of cost 0
    too, but of any length: here at least 10 % longer."""
    scenario = empty_room()
    checker = GeometricChecker(scenario)
    start, goal = np.array(scenario.start), np.array(scenario.goal)
    straight = float(config_distance(start, goal))
    dut = plan(scenario, checker, seed=seed)
    assert dut.success and dut.social_cost_full == 0.0
    assert dut.path_length == pytest.approx(straight, rel=1e-12)
    np.testing.assert_array_equal(dut.waypoints, [start, goal])
    pure = plan(empty_room(length_weight=0.0), checker, seed=seed)
    assert pure.success and pure.cost == 0.0
    assert pure.path_length > 1.1 * straight


def test_around_a_wall_the_default_is_as_short_as_the_length_planner():
    """A wall between start and goal and nobody in the room: the default
    objective's path is within 5 % of the length-optimal planner's
    (``rrt_star``, same seed, same samples), the pure social integral's is
    not."""
    scenario = empty_room()
    scenario.world = dc.replace(scenario.world, obstacles=[Box(center=[5.0, 3.0], size=[0.3, 6.0])])
    scenario.planner = dc.replace(scenario.planner, iterations=600)
    validate_scenario(scenario)
    checker = GeometricChecker(scenario)
    shortest = plan(scenario, checker, algorithm="rrt_star", seed=0)
    dut = plan(scenario, checker, seed=0)
    pure = plan(dc.replace(scenario, social=dc.replace(scenario.social, length_weight=0.0)), checker, seed=0)
    assert shortest.success and dut.success and pure.success
    assert dut.path_length <= 1.05 * shortest.path_length
    assert pure.path_length > 1.15 * shortest.path_length
