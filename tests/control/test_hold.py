"""The safety hold of the Ruckig reference, the base controller and the sequencer."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from drake_social.control import (
    HolonomicPController,
    WaypointSequencer,
    arm_source_from_options,
    reference_source_from_options,
)
from drake_social.scenario import ExecutionOptions

OPTS = ExecutionOptions()
DT = OPTS.control_period
START = np.array([0.0, 0.0, 0.0, 0.0])
TARGET = np.array([2.0, 1.0, 0.5, -0.3])


def _source(kind):
    if kind == "reference":
        return reference_source_from_options(OPTS, START), START, TARGET
    return arm_source_from_options(OPTS, START[2:]), START[2:], TARGET[2:]


def _run(dut, target, t_end, hold=None):
    """Samples position, velocity, finished every DT; ``hold``: list of (time, value) set when reached
    (None: the port stays unconnected)."""
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    dut.GetInputPort("target").FixValue(context, target)
    changes = dict(hold or [])
    rows = []
    for k in range(int(round(t_end / DT)) + 1):
        t = k * DT
        simulator.AdvanceTo(t)
        for when, value in changes.items():
            if abs(when - t) < 1e-9:
                dut.GetInputPort("hold").FixValue(context, [value])
        rows.append((t, dut.GetOutputPort("position").Eval(context).copy(),
                     dut.GetOutputPort("velocity").Eval(context).copy(),
                     dut.GetOutputPort("finished").Eval(context)[0]))
    return (np.array([r[0] for r in rows]), np.array([r[1] for r in rows]), np.array([r[2] for r in rows]),
            np.array([r[3] for r in rows]))


@pytest.mark.parametrize("kind", ["reference", "arm"])
def test_hold_zero_is_the_reference_without_the_port_bit_for_bit(kind):
    dut, _, target = _source(kind)
    free = _run(dut, target, 4.0)
    zero = _run(dut, target, 4.0, hold=[(0.0, 0.0)])
    for a, b in zip(free, zero):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("kind", ["reference", "arm"])
def test_hold_freezes_the_reference_and_release_goes_on_continuously(kind):
    dut, start, target = _source(kind)
    t1, t2, t_end = 0.8, 1.5, 8.0
    t, p_free, _, _ = _run(dut, target, t_end)
    t, p, v, finished = _run(dut, target, t_end, hold=[(0.0, 0.0), (t1, 1.0), (t2, 0.0)])
    k1, k2 = int(round(t1 / DT)), int(round(t2 / DT))
    # Identical until the hold; from the update at t1 on, at rest where it was at t1.
    np.testing.assert_array_equal(p[:k1 + 1], p_free[:k1 + 1])
    assert np.linalg.norm(p_free[k1] - start) > 0.1 and np.linalg.norm(p_free[k1] - target) > 0.1  # mid-motion
    np.testing.assert_array_equal(p[k1:k2 + 1], np.broadcast_to(p_free[k1], p[k1:k2 + 1].shape))
    np.testing.assert_array_equal(v[k1 + 1:k2 + 1], 0.0)
    assert not finished[k1 + 1:k2 + 1].any()
    # Released: continuous in position (no step beyond the speed limits), at the target in the end.
    vmax = np.array([OPTS.max_base_speed] * 2 + list(OPTS.arm_max_velocity))[-len(start):]
    assert np.all(np.abs(np.diff(p, axis=0)) <= vmax * DT * (1 + 1e-9))
    assert np.linalg.norm(p[k2 + 20] - p_free[k1]) > 1e-3  # it moves again
    np.testing.assert_array_equal(p[-1], target)
    assert finished[-1] == 1.0
    if kind == "reference":
        # The synchronized reference stays on the straight segment start -> target.
        u = (target - start) / np.linalg.norm(target - start)
        off = (p - start) - ((p - start) @ u)[:, None] * u
        assert np.abs(off).max() < 1e-12


def test_controller_commands_zero_while_held():
    dut = HolonomicPController.from_options(OPTS, feedforward=True)
    context = dut.CreateDefaultContext()
    dut.GetInputPort("base_target").FixValue(context, [1.0, 0.5])
    dut.GetInputPort("base_position").FixValue(context, [0.0, 0.0])
    dut.GetInputPort("base_velocity_ff").FixValue(context, [0.2, 0.1])
    free = dut.GetOutputPort("wheel_speeds").Eval(context).copy()
    assert np.abs(free).max() > 1.0
    dut.GetInputPort("hold").FixValue(context, [0.0])
    np.testing.assert_array_equal(dut.GetOutputPort("wheel_speeds").Eval(context), free)
    dut.GetInputPort("hold").FixValue(context, [1.0])
    np.testing.assert_array_equal(dut.GetOutputPort("wheel_speeds").Eval(context), np.zeros(4))
    np.testing.assert_array_equal(dut.GetOutputPort("base_velocity").Eval(context), np.zeros(2))


@pytest.mark.parametrize("hold, index", [(None, 1.0), (0.0, 1.0), (1.0, 0.0)])
def test_sequencer_does_not_advance_while_held(hold, index):
    waypoints = np.array([[0, 0, 0, 0], [1, 0, 0.5, 0], [1, 1, 0.5, 0.2]], float)
    dut = WaypointSequencer(waypoints, base_tolerance=0.05, joint_tolerance=0.05, period=DT)
    context = dut.CreateDefaultContext()
    dut.GetInputPort("q").FixValue(context, [0.01, 0.0, 0.0, 0.0])  # at waypoint 0
    if hold is not None:
        dut.GetInputPort("hold").FixValue(context, [hold])
    update = dut.AllocateDiscreteVariables()
    dut.CalcForcedDiscreteVariableUpdate(context, update)
    context.SetDiscreteState(update)
    assert dut.GetOutputPort("index").Eval(context)[0] == index
