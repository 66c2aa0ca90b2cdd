"""PeopleSource with a crowd: a discrete-time system fed back the robot.

A test-double crowd (its step a known function of the state, the time, the
open-loop people and the robot's configuration) is stepped by hand and
compared with the source simulated in a diagram whose robot moves on a
known line; a reset or cloned context repeats its run.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput, TrajectorySource
from pydrake.trajectories import PiecewisePolynomial

from drake_social.control import PeopleSource, people_vector
from drake_social.people import PeopleState, ScenarioPeople, StaticPeople
from drake_social.people.compose import concat_states

DT = 0.1
Q0, Q1, T_END = np.array([0.0, 1.0, 0.2, -0.1]), np.array([5.0, 2.0, 0.4, 0.3]), 10.0


class Crowd:
    """Two people; each step moves them by a function of everything step receives."""

    count, time_step = 2, DT

    def initial_state(self):
        return np.array([1.0, 1.0, 3.0, 2.0])

    def step(self, state, t, others, robot_q):
        pos = np.asarray(state, float).reshape(2, 2)
        lead = others.positions[0] if others.count else np.array([4.0, 4.0])
        # Towards the open-loop person, away from the robot's base, drifting with time.
        away = pos - np.asarray(robot_q[:2], float)
        moved = pos + 0.1 * (lead - pos) + 0.05 * away / np.linalg.norm(away, axis=1)[:, None] + [0.01 * t, 0.0]
        return moved.reshape(-1)

    def people_state(self, state, t):
        pos = np.asarray(state, float).reshape(2, 2)
        return PeopleState(t=t, positions=pos, headings=np.arctan2(pos[:, 1], pos[:, 0]), velocities=np.zeros((2, 2)),
                           radii=[0.2, 0.3], names=("c0", "c1"))


class Walker:
    """One open-loop person walking along +x at 0.4 m/s from (2, 3)."""

    count, static = 1, False

    def state_at(self, t):
        return PeopleState(t=t, positions=[[2.0 + 0.4 * t, 3.0]], headings=[0.0], velocities=[[0.4, 0.0]],
                           radii=[0.25], names=("walker",))


def robot_q(t: float) -> np.ndarray:
    return Q0 + (Q1 - Q0) * t / T_END


def by_hand(model: ScenarioPeople, crowd: Crowd, t: float) -> PeopleState:
    """The people at ``t``: the crowd stepped k = floor(t / DT) times from t = 0, with the robot at q(t_j)."""
    x = crowd.initial_state()
    for j in range(int(math.floor(t / DT + 1e-9))):
        x = crowd.step(x, j * DT, model.open_loop_state(j * DT), robot_q(j * DT))
    return concat_states([model.open_loop_state(t), crowd.people_state(x, t)], t)


def diagram(model):
    builder = DiagramBuilder()
    source = builder.AddNamedSystem("people", PeopleSource(model))
    q = builder.AddSystem(TrajectorySource(PiecewisePolynomial.FirstOrderHold([0.0, T_END], np.column_stack([Q0, Q1]))))
    builder.Connect(q.get_output_port(), source.GetInputPort("robot_q"))
    logger = LogVectorOutput(source.GetOutputPort("crowd_state"), builder, publish_period=0.05)
    return builder.Build(), source, logger


TIMES = np.round(np.arange(0.0, 2.0 + 1e-9, 0.05), 10)  # on and between the crowd's steps


@pytest.mark.parametrize("open_loop", [[Walker()], []], ids=["with a walker", "crowd alone"])
def test_the_simulated_source_equals_the_crowd_stepped_by_hand(open_loop):
    crowd = Crowd()
    model = ScenarioPeople(open_loop, crowd)
    built, source, logger = diagram(model)
    assert source.crowd is crowd and source.GetInputPort("robot_q").size() == 4
    simulator = Simulator(built)
    context = simulator.get_mutable_context()
    port = source.GetOutputPort("people_vector")
    seen = []
    for t in TIMES:
        simulator.AdvanceTo(float(t))
        got = port.Eval(source.GetMyContextFromRoot(context))
        expected = people_vector(by_hand(model, crowd, float(t)))
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12, err_msg=f"t = {t}")
        seen.append(got)
    state = source.GetOutputPort("people_state").Eval(source.GetMyContextFromRoot(context))
    assert state.names == ("walker",) * len(open_loop) + ("c0", "c1") and state.t == pytest.approx(TIMES[-1])
    # The robot matters: the crowd stepped with the robot elsewhere ends elsewhere.
    x = crowd.initial_state()
    for j in range(20):
        x = crowd.step(x, j * DT, model.open_loop_state(j * DT), robot_q(j * DT) + [3.0, -2.0, 0.0, 0.0])
    assert np.abs(x.reshape(2, 2) - seen[-1].reshape(-1, 6)[-2:, :2]).max() > 0.05
    # The logged crowd state rebuilds the people at the log's times (what a run's people log is).
    log = logger.FindLog(context)
    rebuilt = source.people_log(log.sample_times(), log.data().T)
    np.testing.assert_allclose(log.sample_times(), TIMES, rtol=0, atol=1e-12)
    for k, t in enumerate(TIMES):
        np.testing.assert_allclose(rebuilt.positions[k], by_hand(model, crowd, float(t)).positions, atol=1e-12)
    # Without the robot nearby the same source agrees with the model's own open-loop crowd at t = 0.
    np.testing.assert_array_equal(rebuilt.positions[0], model.state_at(0.0).positions)


def test_the_outputs_depend_on_state_and_time_only():
    # No algebraic loop: robot_q feeds the update only, no output reads it at the same instant.
    model = ScenarioPeople([Walker()], Crowd())
    source = PeopleSource(model)
    context = source.CreateDefaultContext()
    source.GetInputPort("robot_q").FixValue(context, Q0)
    assert not source.HasDirectFeedthrough(0, 0) and not source.HasDirectFeedthrough(0, 1)
    # The initial state: x_0 in force from t = 0.
    np.testing.assert_array_equal(context.get_discrete_state_vector().value(),
                                  np.concatenate([[-DT], Crowd().initial_state(), Crowd().initial_state()]))


def _run(simulator, source, times):
    rows = []
    for t in times:
        simulator.AdvanceTo(float(t))
        rows.append(source.GetOutputPort("people_vector").Eval(source.GetMyContextFromRoot(simulator.get_context())))
    return np.array(rows)


def test_a_reset_or_cloned_context_repeats_the_run():
    model = ScenarioPeople([Walker()], Crowd())
    built, source, _ = diagram(model)
    simulator = Simulator(built)
    initial = simulator.get_context().Clone()
    first = _run(simulator, source, TIMES)
    # Reset: the initial context set back.
    simulator.get_mutable_context().SetTimeStateAndParametersFrom(initial)
    simulator.Initialize()
    np.testing.assert_array_equal(_run(simulator, source, TIMES), first)
    # Two contexts in turns: each gives the run it gives alone.
    a, b = Simulator(built, initial.Clone()), Simulator(built, initial.Clone())
    rows_a, rows_b = [], []
    for t in TIMES:
        rows_a.append(_run(a, source, [t])[0])
        rows_b.append(_run(b, source, [t])[0])
    np.testing.assert_array_equal(rows_a, first)
    np.testing.assert_array_equal(rows_b, first)


def test_without_a_crowd_there_is_no_state_and_no_robot_input():
    model = ScenarioPeople([StaticPeople([[1.0, 2.0, 0.5]], [0.3], ["ann"])])
    source = PeopleSource(model)
    assert source.crowd is None and source.num_input_ports() == 0
    assert source.CreateDefaultContext().num_discrete_state_groups() == 0
    assert [source.get_output_port(i).get_name() for i in range(source.num_output_ports())] == \
        ["people_state", "people_vector"]
    log = source.people_log([0.0, 0.5])
    np.testing.assert_array_equal(log.positions, [[[1.0, 2.0]], [[1.0, 2.0]]])


def test_a_crowd_that_is_not_a_crowd_model_is_refused():
    class Odd(ScenarioPeople):
        @property
        def crowd(self):
            return "a crowd"

    with pytest.raises(TypeError, match="CrowdModel"):
        PeopleSource(Odd([Walker()]))
