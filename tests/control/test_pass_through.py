"""Waypoints where the path goes straight on: the robot carries its speed through them, on the segments."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from drake_social.control import WaypointSequencer, reference_source_from_options
from drake_social.control.sequencer import PASS_THROUGH_TOLERANCE, next_rest
from drake_social.scenario import ExecutionOptions, load_scenario
from drake_social.sim import simulate

OPTS = ExecutionOptions()
LINE = np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [2.0, 0.0, 0.0, 0.0], [3.0, 0.0, 0.0, 0.0],
                 [3.0, 1.0, 0.0, 0.0]])


def _off(offset, weights=None):
    """LINE with its waypoint 1 moved ``offset`` off the line (along y) and the rest computed from 0."""
    wp = LINE.copy()
    wp[1, 1] = offset
    return next_rest(wp, 0, weights)


def test_next_rest_goes_through_straight_waypoints_to_the_turn():
    assert next_rest(LINE, 0) == 3 and next_rest(LINE, 1) == 3 and next_rest(LINE, 3) == 4
    assert next_rest(LINE, 4) == 4  # the last waypoint
    assert next_rest(LINE[:2], 0) == 1


@pytest.mark.parametrize("offset, rest", [
    (PASS_THROUGH_TOLERANCE, 3),                 # at the tolerance: gone through
    (PASS_THROUGH_TOLERANCE * (1 - 1e-6), 3),    # just within
    (PASS_THROUGH_TOLERANCE * (1 + 1e-6), 1),    # just beyond: a turn, the robot rests there
])
def test_the_pass_through_tolerance_at_its_value_and_either_side(offset, rest):
    # Waypoint 1 off the segment 0 -> 2 by ``offset`` (|y| at x = 1 of the segment from (0, 0) to (2, 0)).
    assert _off(offset) == rest


def test_the_tolerance_is_in_the_planners_weighted_distance():
    # Off by 0.6e-9 in y: within 1e-9 with weight 1, beyond with weight 2 on y.
    assert _off(0.6e-9, np.ones(4)) == 3
    assert _off(0.6e-9, np.array([1.0, 2.0, 1.0, 1.0])) == 1


def test_a_path_that_goes_back_on_its_line_rests_where_it_turns_back():
    # 0 -> 2 -> 1 -> 3 along x: every waypoint lies on the segment 0 -> 3, but the path reverses at 2.
    wp = np.array([[0.0, 0, 0, 0], [2.0, 0, 0, 0], [1.0, 0, 0, 0], [3.0, 0, 0, 0]])
    assert next_rest(wp, 0) == 1 and next_rest(wp, 1) == 2 and next_rest(wp, 2) == 3


def test_the_sequencer_heads_for_the_turns_and_outputs_the_waypoints_between():
    dut = WaypointSequencer(LINE, base_tolerance=0.05, joint_tolerance=0.05, period=0.01, pass_through=True)
    context = dut.CreateDefaultContext()
    seen = []
    for q in (LINE[0], LINE[3], LINE[4]):
        dut.GetInputPort("q").FixValue(context, q)
        update = dut.AllocateDiscreteVariables()
        dut.CalcForcedDiscreteVariableUpdate(context, update)
        context.SetDiscreteState(update)
        seen.append((int(dut.GetOutputPort("index").Eval(context)[0]),
                     dut.GetOutputPort("via").Eval(context).tolist()))
    assert seen == [(3, LINE[1:3].tolist()), (4, []), (4, [])]
    assert dut.GetOutputPort("done").Eval(context)[0] == 1.0


def test_the_reference_carries_its_speed_through_waypoints_on_a_straight_run():
    dut = reference_source_from_options(OPTS, LINE[0])
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    dut.GetInputPort("target").FixValue(context, LINE[3])
    dut.GetInputPort("via").FixValue(context, LINE[1:3])
    dt = 0.001
    times = np.arange(0.0, 10.0, dt)
    p, v = [], []
    for t in times:
        simulator.AdvanceTo(t)
        p.append(dut.GetOutputPort("position").Eval(context).copy())
        v.append(dut.GetOutputPort("velocity").Eval(context).copy())
    p, v = np.array(p), np.array(v)
    speed = np.linalg.norm(v, axis=1)
    for x in (1.0, 2.0):  # at the interior waypoints: the cruise speed, not rest
        k = int(np.argmin(np.abs(p[:, 0] - x)))
        assert abs(p[k, 0] - x) <= OPTS.max_base_speed * dt
        assert speed[k] == pytest.approx(OPTS.max_base_speed, rel=1e-12)
    moving = np.flatnonzero(speed > 0)
    assert np.all(speed[moving[0]:moving[-1] + 1] > 0)  # no rest between the start and the end
    np.testing.assert_array_equal(p[-1], LINE[3])
    assert np.abs(p[:, 1:]).max() == 0.0  # on the line


def test_a_run_through_collinear_waypoints_keeps_its_speed_and_stays_on_the_segments():
    scenario = load_scenario("scenarios/tiny.yaml")
    start, goal = np.array(scenario.start), np.array(scenario.goal)
    waypoints = np.array([start + f * (goal - start) for f in (0.0, 0.2, 0.45, 0.7, 1.0)])
    run = simulate(scenario, waypoints=waypoints, mode="kinematic")
    assert run.reached and run.report.collision_free
    assert run.report.max_point_deviation["max"] <= 1e-9
    speed = np.hypot(run.v[:, 0], run.v[:, 1])
    for w in waypoints[1:-1]:
        k = int(np.argmin(np.abs(run.q[:, 0] - w[0])))
        assert speed[k] == pytest.approx(scenario.execution.max_base_speed, rel=1e-9)
    moving = np.flatnonzero(speed > 0)
    assert np.all(speed[moving[0]:moving[-1] + 1] > 0)
    # One rest-to-rest motion of 5.5 m at 0.5 m/s (1 m/s^2, 5 m/s^3): 11 s + 0.5 s + 0.2 s, by hand.
    assert run.time_to_goal == pytest.approx(5.5 / 0.5 + 0.5 / 1.0 + 1.0 / 5.0, abs=0.02)
