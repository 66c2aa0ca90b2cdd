"""WaypointSequencer: advances exactly when base and arm are within tolerance, one step per update."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from drake_social.control import WaypointSequencer
from drake_social.scenario import ExecutionOptions

BASE_TOL = 0.05
JOINT_TOL = 0.02
WAYPOINTS = np.array([
    [0.0, 0.0, 0.0, 0.0],
    [1.0, 0.0, 0.5, -0.3],
    [1.0, 2.0, 0.5, 0.2],
])


def _make(waypoints=WAYPOINTS, **kwargs):
    return WaypointSequencer(waypoints, base_tolerance=BASE_TOL, joint_tolerance=JOINT_TOL, period=0.01, **kwargs)


def _step(dut, context, q, reference_done=None):
    """Fixes q (and reference_done), runs one forced update, returns (index, done, target)."""
    dut.GetInputPort("q").FixValue(context, np.asarray(q, float))
    if reference_done is not None:
        dut.GetInputPort("reference_done").FixValue(context, [reference_done])
    update = dut.AllocateDiscreteVariables()
    dut.CalcForcedDiscreteVariableUpdate(context, update)
    context.SetDiscreteState(update)
    index = dut.GetOutputPort("index").Eval(context)[0]
    done = dut.GetOutputPort("done").Eval(context)[0]
    return index, done, dut.GetOutputPort("target").Eval(context).copy()


def _offset(target, dx=0.0, dy=0.0, d1=0.0, d2=0.0):
    return np.asarray(target, float) + [dx, dy, d1, d2]


def test_initial_outputs_are_the_first_waypoint():
    dut = _make()
    context = dut.CreateDefaultContext()
    np.testing.assert_array_equal(dut.GetOutputPort("target").Eval(context), WAYPOINTS[0])
    assert dut.GetOutputPort("index").Eval(context)[0] == 0.0
    assert dut.GetOutputPort("done").Eval(context)[0] == 0.0
    assert [dut.get_input_port(i).get_name() for i in range(dut.num_input_ports())] == ["q", "hold"]
    assert [dut.get_output_port(i).get_name() for i in range(dut.num_output_ports())] == ["target", "done", "index"]


def test_base_distance_is_euclidean_just_inside_advances_just_outside_does_not():
    # 3-4-5 triangle: |(0.03, 0.04) * s| = 0.05 s; each axis alone is within 0.05.
    dut = _make()
    context = dut.CreateDefaultContext()
    outside = _offset(WAYPOINTS[0], 0.03 * 1.001, 0.04 * 1.001)  # 0.05005 m
    assert _step(dut, context, outside)[0] == 0.0
    inside = _offset(WAYPOINTS[0], 0.03 * 0.999, -0.04 * 0.999)  # 0.04995 m
    index, done, target = _step(dut, context, inside)
    assert (index, done) == (1.0, 0.0)
    np.testing.assert_array_equal(target, WAYPOINTS[1])


@pytest.mark.parametrize("joint", [2, 3])
def test_one_joint_just_outside_blocks_the_advance(joint):
    dut = _make()
    context = dut.CreateDefaultContext()
    _step(dut, context, WAYPOINTS[0])  # at waypoint 0 -> heads for 1
    q = WAYPOINTS[1].copy()
    q[joint] += JOINT_TOL * 1.01
    assert _step(dut, context, q)[0] == 1.0
    q[joint] = WAYPOINTS[1][joint] - JOINT_TOL * 1.01
    assert _step(dut, context, q)[0] == 1.0
    q[joint] = WAYPOINTS[1][joint] - JOINT_TOL * 0.99
    assert _step(dut, context, q)[0] == 2.0


def test_one_step_per_update_even_when_q_is_within_tolerance_of_later_waypoints():
    same = np.array([[0.0, 0.0, 0.0, 0.0]] * 4)
    dut = _make(same)
    context = dut.CreateDefaultContext()
    history = [_step(dut, context, same[0])[:2] for _ in range(6)]
    assert history == [(1.0, 0.0), (2.0, 0.0), (3.0, 0.0), (3.0, 1.0), (3.0, 1.0), (3.0, 1.0)]


def test_done_latches_at_the_last_waypoint():
    dut = _make()
    context = dut.CreateDefaultContext()
    for k in range(3):
        _step(dut, context, WAYPOINTS[k])
    assert dut.GetOutputPort("done").Eval(context)[0] == 1.0
    # Moving away afterwards does not clear done nor change the target.
    index, done, target = _step(dut, context, [5.0, 5.0, 1.0, 1.0])
    assert (index, done) == (2.0, 1.0)
    np.testing.assert_array_equal(target, WAYPOINTS[2])


def test_single_waypoint_sets_done_when_reached():
    dut = _make(WAYPOINTS[:1])
    context = dut.CreateDefaultContext()
    assert _step(dut, context, _offset(WAYPOINTS[0], 0.06))[:2] == (0.0, 0.0)
    assert _step(dut, context, _offset(WAYPOINTS[0], 0.049))[:2] == (0.0, 1.0)


def test_reference_done_gates_the_advance():
    dut = _make(wait_for_reference=True)
    context = dut.CreateDefaultContext()
    assert _step(dut, context, WAYPOINTS[0], reference_done=0.0)[0] == 0.0
    assert _step(dut, context, WAYPOINTS[0], reference_done=0.4)[0] == 0.0
    assert _step(dut, context, WAYPOINTS[0], reference_done=1.0)[0] == 1.0
    # Reference arrived but the robot has not: no advance either.
    assert _step(dut, context, _offset(WAYPOINTS[1], 0.1), reference_done=1.0)[0] == 1.0


def test_abstract_waypoints_input_and_no_feedthrough_from_q():
    dut = WaypointSequencer(base_tolerance=BASE_TOL, joint_tolerance=JOINT_TOL, period=0.01)
    names = [dut.get_input_port(i).get_name() for i in range(dut.num_input_ports())]
    assert names == ["waypoints", "q", "hold"]
    q_index = dut.GetInputPort("q").get_index()
    for k in range(dut.num_output_ports()):
        assert not dut.HasDirectFeedthrough(q_index, k)
    context = dut.CreateDefaultContext()
    dut.GetInputPort("waypoints").FixValue(context, AbstractValue.Make(WAYPOINTS.copy()))
    np.testing.assert_array_equal(dut.GetOutputPort("target").Eval(context), WAYPOINTS[0])
    index, _, target = _step(dut, context, _offset(WAYPOINTS[0], 0.01, -0.01, 0.01, -0.01))
    assert index == 1.0
    np.testing.assert_array_equal(target, WAYPOINTS[1])


def test_abstract_input_with_an_empty_path_raises_naming_the_system():
    dut = WaypointSequencer(base_tolerance=BASE_TOL, joint_tolerance=JOINT_TOL, period=0.01)
    dut.set_name("sequencer")
    context = dut.CreateDefaultContext()
    dut.GetInputPort("waypoints").FixValue(context, AbstractValue.Make(np.zeros((0, 4))))
    dut.GetInputPort("q").FixValue(context, np.zeros(4))
    with pytest.raises(RuntimeError, match="sequencer.*no waypoints"):
        dut.GetOutputPort("target").Eval(context)
    with pytest.raises(RuntimeError, match="sequencer.*no waypoints"):
        dut.CalcForcedDiscreteVariableUpdate(context, dut.AllocateDiscreteVariables())


def test_abstract_input_with_a_malformed_array_raises():
    dut = WaypointSequencer(base_tolerance=BASE_TOL, joint_tolerance=JOINT_TOL, period=0.01)
    context = dut.CreateDefaultContext()
    dut.GetInputPort("waypoints").FixValue(context, AbstractValue.Make(np.zeros((3, 2))))
    with pytest.raises(RuntimeError, match=r"\(N, 4\).*\(3, 2\)"):
        dut.GetOutputPort("target").Eval(context)


@pytest.mark.parametrize(
    "waypoints, message",
    [
        (np.zeros((0, 4)), "no waypoints"),
        (np.zeros((3, 3)), r"\(N, 4\).*\(3, 3\)"),
        (np.zeros(4), r"\(N, 4\).*\(4,\)"),
        (np.array([[0, 0, 0, 0], [np.nan, 0, 0, 0], [0, 0, np.inf, 0]]), r"finite; rows \[1, 2\]"),
    ],
)
def test_bad_fixed_waypoints_raise_at_construction(waypoints, message):
    with pytest.raises(ValueError, match=message):
        _make(waypoints)


@pytest.mark.parametrize("field", ["base_tolerance", "joint_tolerance", "period"])
def test_non_positive_parameters_raise(field):
    kwargs = dict(base_tolerance=BASE_TOL, joint_tolerance=JOINT_TOL, period=0.01)
    kwargs[field] = 0.0
    with pytest.raises(ValueError, match=field):
        WaypointSequencer(WAYPOINTS, **kwargs)


def test_from_options_takes_tolerances_and_period_and_runs_periodically():
    options = ExecutionOptions(base_tolerance=0.1, joint_tolerance=0.03, control_period=0.02)
    dut = WaypointSequencer.from_options(options, WAYPOINTS)
    attribute = dut.GetUniquePeriodicDiscreteUpdateAttribute()
    assert (attribute.period_sec(), attribute.offset_sec()) == (pytest.approx(0.02), 0.0)
    builder = DiagramBuilder()
    builder.AddNamedSystem("sequencer", dut)
    # Within the scenario's tolerances of waypoint 0 (0.09 m, 0.029 rad; the
    # test's own 0.05 / 0.02 would not accept it), 1.0 m from waypoint 1.
    q = builder.AddSystem(ConstantVectorSource(_offset(WAYPOINTS[0], 0.09, 0.0, 0.029, -0.029)))
    builder.Connect(q.get_output_port(), dut.GetInputPort("q"))
    simulator = Simulator(builder.Build())
    simulator.AdvanceTo(0.1)
    context = dut.GetMyContextFromRoot(simulator.get_context())
    assert dut.GetOutputPort("index").Eval(context)[0] == 1.0
    np.testing.assert_array_equal(dut.GetOutputPort("target").Eval(context), WAYPOINTS[1])


def test_closes_a_loop_with_the_controller_and_the_drive_without_an_algebraic_loop():
    # Sequencer -> P controller -> mecanum drive -> integrator -> q (arm held at the
    # waypoints' joint values). Kp = 1.5 and 0.5 m/s: 1 m then 2 m take a few seconds.
    from pydrake.systems.primitives import Demultiplexer, Integrator, Multiplexer

    from drake_social.control import HolonomicPController, MecanumDrive

    waypoints = np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [1.0, 2.0, 0.0, 0.0]])
    builder = DiagramBuilder()
    dut = builder.AddNamedSystem("sequencer", _make(waypoints))
    controller = builder.AddSystem(
        HolonomicPController(kp=1.5, max_base_speed=0.5, wheel_radius=0.05, max_wheel_speed=20.0))
    drive = builder.AddSystem(MecanumDrive(0.05))
    base = builder.AddSystem(Integrator(2))
    split = builder.AddSystem(Demultiplexer([2, 2]))
    arm = builder.AddSystem(ConstantVectorSource([0.0, 0.0]))
    q = builder.AddSystem(Multiplexer([2, 2]))
    builder.Connect(dut.GetOutputPort("target"), split.get_input_port())
    builder.Connect(split.get_output_port(0), controller.GetInputPort("base_target"))
    builder.Connect(base.get_output_port(), controller.GetInputPort("base_position"))
    builder.Connect(controller.GetOutputPort("wheel_speeds"), drive.GetInputPort("wheel_speeds"))
    builder.Connect(drive.GetOutputPort("base_velocity"), base.get_input_port())
    builder.Connect(base.get_output_port(), q.get_input_port(0))
    builder.Connect(arm.get_output_port(), q.get_input_port(1))
    builder.Connect(q.get_output_port(), dut.GetInputPort("q"))
    simulator = Simulator(builder.Build())
    simulator.AdvanceTo(15.0)
    context = dut.GetMyContextFromRoot(simulator.get_context())
    assert dut.GetOutputPort("done").Eval(context)[0] == 1.0
    position = base.get_output_port().Eval(base.GetMyContextFromRoot(simulator.get_context()))
    # Within the tolerance of the goal when done was latched, closer still since.
    assert np.linalg.norm(position - [1.0, 2.0]) <= BASE_TOL
