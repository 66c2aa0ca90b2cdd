"""PlannerSystem: plans once at initialization, outputs exactly what plan() returns."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

import drake_social.control.planner_system as planner_system
from drake_social.control import PlannerSystem, path_parameter, waypoint_trajectory
from drake_social.collision.geometric import GeometricChecker
from drake_social.planning.result import PlanningInputError
from drake_social.planning.algorithms import plan

ITERATIONS = 150


@pytest.fixture
def counted_plan(monkeypatch):
    """Replaces the module's plan() by a wrapper that counts its calls."""
    calls = []

    def counting(*args, **kwargs):
        calls.append(kwargs)
        return plan(*args, **kwargs)

    monkeypatch.setattr(planner_system, "plan", counting)
    return calls


def _initialized(dut: PlannerSystem):
    context = dut.CreateDefaultContext()
    dut.ExecuteInitializationEvents(context)
    return context


@pytest.mark.slow
def test_outputs_equal_plan_with_the_same_seed_bit_for_bit(tiny_scenario):
    checker = GeometricChecker(tiny_scenario)
    expected = plan(tiny_scenario, checker, algorithm="social_rrt_star", iterations=ITERATIONS, seed=7)
    assert expected.success, expected.message
    dut = PlannerSystem(tiny_scenario, checker, algorithm="social_rrt_star", iterations=ITERATIONS, seed=7)
    context = _initialized(dut)

    waypoints = dut.GetOutputPort("waypoints").Eval(context)
    assert waypoints.shape == expected.waypoints.shape
    assert np.array_equal(waypoints, expected.waypoints)  # bit for bit
    result = dut.GetOutputPort("result").Eval(context)
    assert result.cost == expected.cost and result.social_cost_full == expected.social_cost_full
    assert np.array_equal(result.cost_history, expected.cost_history)

    path = dut.GetOutputPort("path").Eval(context)
    s = path_parameter(expected.waypoints)
    assert path.start_time() == 0.0
    assert path.end_time() == pytest.approx(expected.path_length, rel=1e-12)
    for s_k, q_k in zip(s, expected.waypoints):
        np.testing.assert_allclose(path.value(s_k).ravel(), q_k, rtol=0, atol=1e-12)
    # Linear between waypoints: the midpoint of segment 1 is the mean of its ends.
    mid = 0.5 * (s[1] + s[2])
    np.testing.assert_allclose(path.value(mid).ravel(), expected.waypoints[1:3].mean(0), atol=1e-12)


def test_the_default_checker_is_the_planar_one_and_gives_the_same_path_as_plan(tiny_scenario):
    from drake_social.collision.planar_checker import PlanarChecker

    dut = PlannerSystem(tiny_scenario, iterations=60, seed=3)
    assert isinstance(dut._checker, PlanarChecker)
    expected = plan(tiny_scenario, PlanarChecker(tiny_scenario), iterations=60, seed=3)
    context = _initialized(dut)
    result = dut.GetOutputPort("result").Eval(context)
    assert result.algorithm == tiny_scenario.planner.algorithm
    assert np.array_equal(dut.GetOutputPort("waypoints").Eval(context), expected.waypoints)


@pytest.mark.slow
def test_plans_once_however_often_outputs_are_evaluated_or_time_advances(tiny_scenario, counted_plan, monkeypatch):
    calc_calls = {"waypoints": 0, "path": 0}
    for name, method in (("waypoints", "_CalcWaypoints"), ("path", "_CalcPath")):
        original = getattr(PlannerSystem, method)

        def counting(self, context, output, _original=original, _name=name):
            calc_calls[_name] += 1
            _original(self, context, output)

        monkeypatch.setattr(PlannerSystem, method, counting)

    builder = DiagramBuilder()
    dut = builder.AddSystem(PlannerSystem(tiny_scenario, GeometricChecker(tiny_scenario), iterations=ITERATIONS))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    assert counted_plan == []  # nothing planned at construction
    simulator.Initialize()
    assert len(counted_plan) == 1
    context = dut.GetMyContextFromRoot(simulator.get_context())
    first = dut.GetOutputPort("waypoints").Eval(context)
    again = dut.GetOutputPort("waypoints").Eval(context)
    dut.GetOutputPort("path").Eval(context)
    simulator.AdvanceTo(2.5)
    after = dut.GetOutputPort("waypoints").Eval(context)
    dut.GetOutputPort("path").Eval(context)
    assert len(counted_plan) == 1
    assert calc_calls == {"waypoints": 1, "path": 1}  # cached across time: state is the only prerequisite
    assert np.array_equal(first, after) and np.array_equal(first, again)
    assert context.get_time() == 2.5


def test_output_before_initialization_is_a_clear_error(tiny_scenario, counted_plan):
    dut = PlannerSystem(tiny_scenario, GeometricChecker(tiny_scenario), iterations=10)
    context = dut.CreateDefaultContext()
    with pytest.raises(RuntimeError, match="planned at initialization"):
        dut.GetOutputPort("waypoints").Eval(context)
    assert counted_plan == []


def test_start_in_collision_raises_from_initialize(tiny_scenario):
    import dataclasses as dc

    scenario = dc.replace(tiny_scenario, start=[4.0, 0.6, 0.0, 1.5708])  # base inside the desk
    dut = PlannerSystem(scenario, GeometricChecker(scenario), iterations=10)
    with pytest.raises(PlanningInputError, match="start"):
        Simulator(dut).Initialize()


def test_no_path_gives_empty_outputs_and_an_unsuccessful_result(tiny_scenario):
    import dataclasses as dc

    # Too few iterations to cross 5.5 m with a 0.3 m range: no path, not an error.
    planner = dc.replace(tiny_scenario.planner, planning_range=0.3, near_radius=0.5, goal_bias=0.0)
    scenario = dc.replace(tiny_scenario, planner=planner)
    dut = PlannerSystem(scenario, GeometricChecker(scenario), iterations=5, seed=0)
    context = _initialized(dut)
    assert not dut.GetOutputPort("result").Eval(context).success
    assert dut.GetOutputPort("waypoints").Eval(context).shape == (0, 4)
    assert dut.GetOutputPort("path").Eval(context).get_number_of_segments() == 0


def test_waypoint_trajectory_drops_repeated_waypoints_and_keeps_single_configurations():
    wp = np.array([[0.0, 0, 0, 0], [3.0, 4, 0, 0], [3.0, 4, 0, 0], [3.0, 4, 0, 1.0]])
    dut = waypoint_trajectory(wp)
    np.testing.assert_allclose(dut.get_segment_times(), [0.0, 5.0, 6.0])  # 3-4-5 triangle, then 1 rad
    np.testing.assert_allclose(dut.value(5.5).ravel(), [3.0, 4.0, 0.0, 0.5])
    # Weighted distance: psi2 counts double.
    dut = waypoint_trajectory(wp, [1.0, 1.0, 1.0, 2.0])
    assert dut.end_time() == pytest.approx(7.0)
    single = waypoint_trajectory(wp[1:3])
    np.testing.assert_allclose(single.value(0.0).ravel(), wp[1])
    assert waypoint_trajectory(np.zeros((0, 4))).get_number_of_segments() == 0
