"""Every system of drake_social.control keeps its run in the context, not on itself.

For each system: a run from a reset context (the initial one set back, then
Simulator.Initialize again) repeats the first run number for number, and two
contexts of the same system advanced in turns give each the run it gives alone
(nothing of one context's run leaks into the other through the system).
"""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from drake_social.collision.drake_checker import make_checker
from drake_social.control import (
    HolonomicPController,
    PeopleSource,
    PlannerSystem,
    RuckigTrajectorySource,
    WaypointSequencer,
    people_vector,
    reference_source_from_options,
)
from drake_social.people import PeopleState, people_model
from drake_social.scenario import ExecutionOptions

PERIOD = 0.01
TIMES = np.arange(0.0, 6.0 + 1e-9, 0.05)


def _values(ports, root) -> np.ndarray:
    """The ports' values, concatenated, in the root context ``root``."""
    return np.concatenate([np.asarray(p.Eval(p.get_system().GetMyContextFromRoot(root)), float) for p in ports])


def _record(simulator: Simulator, ports) -> np.ndarray:
    """The ports' values at TIMES, advancing ``simulator``."""
    rows = []
    for t in TIMES:
        simulator.AdvanceTo(float(t))
        rows.append(_values(ports, simulator.get_context()))
    return np.array(rows)


def _tracking_loop():
    """Sequencer -> synchronized Ruckig reference -> its position fed back as q (perfect tracking)."""
    waypoints = np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 0.5, 0.3, -0.2], [1.5, 1.5, 0.0, 0.4]])
    options = ExecutionOptions()
    builder = DiagramBuilder()
    sequencer = builder.AddNamedSystem(
        "sequencer", WaypointSequencer.from_options(options, waypoints=waypoints, wait_for_reference=True))
    reference = builder.AddNamedSystem("reference", reference_source_from_options(options, waypoints[0]))
    builder.Connect(sequencer.GetOutputPort("target"), reference.GetInputPort("target"))
    builder.Connect(reference.GetOutputPort("finished"), sequencer.GetInputPort("reference_done"))
    builder.Connect(reference.GetOutputPort("position"), sequencer.GetInputPort("q"))
    diagram = builder.Build()
    ports = [reference.GetOutputPort("state"), sequencer.GetOutputPort("index"), sequencer.GetOutputPort("done")]
    return diagram, ports


def test_sequencer_and_reference_rerun_the_same_from_a_reset_context():
    diagram, ports = _tracking_loop()
    simulator = Simulator(diagram)
    initial = simulator.get_context().Clone()
    simulator.Initialize()
    first = _record(simulator, ports)
    # The run does something: the sequencer reaches the last waypoint and latches done.
    assert first[-1, -1] == 1.0 and first[-1, -2] == 2.0
    np.testing.assert_allclose(first[-1, :4], [1.5, 1.5, 0.0, 0.4], atol=1e-12)
    simulator.get_mutable_context().SetTimeStateAndParametersFrom(initial)
    simulator.Initialize()
    np.testing.assert_array_equal(_record(simulator, ports), first)


def test_two_contexts_of_one_diagram_run_independently():
    """Two simulators on one diagram, advanced in turns, one of them started
    half a period later: each gives the run it gives alone."""
    diagram, ports = _tracking_loop()
    alone = Simulator(diagram)
    alone.Initialize()
    expected = _record(alone, ports)

    a, b = Simulator(diagram), Simulator(diagram)
    b.get_mutable_context().SetTime(-PERIOD / 2)  # a different run on the same system
    a.Initialize()
    b.Initialize()
    rows = []
    for t in TIMES:
        b.AdvanceTo(float(t) - PERIOD / 2)
        a.AdvanceTo(float(t))
        rows.append(_values(ports, a.get_context()))
    np.testing.assert_array_equal(np.array(rows), expected)


def test_ruckig_contexts_with_different_targets_do_not_share_their_instant():
    """Two contexts at the same time with different segments: each output is
    its own segment's value (the per-instant cache lives in the context)."""
    dut = RuckigTrajectorySource(initial_position=[0.0, 0.0], max_velocity=[1.0, 1.0],
                                 max_acceleration=[2.0, 2.0], max_jerk=[10.0, 10.0], period=PERIOD)
    sims = []
    for target in ([1.0, -0.5], [-2.0, 0.25]):
        simulator = Simulator(dut)
        dut.GetInputPort("target").FixValue(simulator.get_mutable_context(), target)
        simulator.Initialize()
        sims.append(simulator)
    position = dut.GetOutputPort("position")
    for t in np.arange(0.1, 3.0, 0.1):
        for simulator in sims:
            simulator.AdvanceTo(float(t))
        values = [position.Eval(s.get_context()).copy() for s in sims]
        # Alone, from its own segment: the same numbers.
        for simulator, value in zip(sims, values):
            segment = simulator.get_context().get_abstract_state(0).get_value()
            np.testing.assert_array_equal(value, segment.at(float(t))[0])
        assert not np.array_equal(values[0], values[1])
    np.testing.assert_allclose(position.Eval(sims[0].get_context()), [1.0, -0.5], atol=1e-12)
    np.testing.assert_allclose(position.Eval(sims[1].get_context()), [-2.0, 0.25], atol=1e-12)


def test_planner_plans_into_its_own_context(tiny_scenario):
    dut = PlannerSystem(tiny_scenario, make_checker(tiny_scenario, "planar"), iterations=300)
    planned, fresh = dut.CreateDefaultContext(), dut.CreateDefaultContext()
    dut.ExecuteInitializationEvents(planned)
    waypoints = dut.GetOutputPort("waypoints").Eval(planned)
    assert len(waypoints) >= 2
    np.testing.assert_array_equal(waypoints[0], tiny_scenario.start)
    # The other context has not planned: its outputs say so.
    with pytest.raises(RuntimeError, match="planned at initialization"):
        dut.GetOutputPort("waypoints").Eval(fresh)
    # A clone carries the plan; planning again in another context gives the same path (seeded).
    np.testing.assert_array_equal(dut.GetOutputPort("waypoints").Eval(planned.Clone()), waypoints)
    dut.ExecuteInitializationEvents(fresh)
    np.testing.assert_array_equal(dut.GetOutputPort("waypoints").Eval(fresh), waypoints)


def test_controller_is_a_function_of_its_inputs():
    dut = HolonomicPController(kp=2.0, max_base_speed=10.0, wheel_radius=0.05, max_wheel_speed=1e3)
    context = dut.CreateDefaultContext()
    dut.GetInputPort("base_target").FixValue(context, [1.0, 2.0])
    dut.GetInputPort("base_position").FixValue(context, [0.5, 0.0])
    clone = context.Clone()
    dut.GetInputPort("base_position").FixValue(clone, [1.0, 2.0])
    # v = kp (target - position) = [1, 4] m/s; w = (1/r) [vx - vy, vx + vy, vy - vx, -vx - vy].
    np.testing.assert_allclose(dut.GetOutputPort("wheel_speeds").Eval(context), [-60.0, 100.0, 60.0, -100.0])
    np.testing.assert_array_equal(dut.GetOutputPort("wheel_speeds").Eval(clone), np.zeros(4))
    np.testing.assert_allclose(dut.GetOutputPort("wheel_speeds").Eval(context), [-60.0, 100.0, 60.0, -100.0])


class _Walking:
    """A people model whose one person walks along +x at 0.5 m/s from x = 1."""

    count, static = 1, False

    def state_at(self, t):
        return PeopleState(t=t, positions=[[1.0 + 0.5 * t, 2.0]], headings=[0.0], velocities=[[0.5, 0.0]],
                           radii=[0.3], names=("walker",))


def test_people_source_answers_at_each_context_time(tiny_scenario):
    dut = PeopleSource(_Walking())
    early, late = dut.CreateDefaultContext(), dut.CreateDefaultContext()
    late.SetTime(4.0)
    np.testing.assert_array_equal(dut.GetOutputPort("people_vector").Eval(late), [3.0, 2.0, 0.0, 0.5, 0.0, 0.3])
    np.testing.assert_array_equal(dut.GetOutputPort("people_vector").Eval(early), [1.0, 2.0, 0.0, 0.5, 0.0, 0.3])
    state = dut.GetOutputPort("people_state").Eval(late)
    assert state.t == 4.0 and state.names == ("walker",)
    clone = late.Clone()
    clone.SetTime(2.0)
    np.testing.assert_array_equal(dut.GetOutputPort("people_vector").Eval(clone)[:2], [2.0, 2.0])
    np.testing.assert_array_equal(dut.GetOutputPort("people_vector").Eval(late)[:2], [3.0, 2.0])
    # The scenario's people: one row [x, y, theta, 0, 0, radius] per person, in order.
    source = PeopleSource(people_model(tiny_scenario))
    rows = source.GetOutputPort("people_vector").Eval(source.CreateDefaultContext()).reshape(-1, 6)
    expected = [[p.x, p.y, p.theta, 0.0, 0.0, p.radius] for p in tiny_scenario.people]
    np.testing.assert_array_equal(rows, expected)
    assert len(rows) == len(tiny_scenario.people) >= 1
    np.testing.assert_array_equal(people_vector(people_model(tiny_scenario).state_at(7.0)), rows.reshape(-1))


def test_people_source_refuses_what_is_not_a_people_model():
    with pytest.raises(TypeError, match="PeopleModel"):
        PeopleSource([[1.0, 2.0, 0.0]])
