"""RuckigTrajectorySource: limits hold, no jumps, ends at rest at the target, base on the straight segment."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator

from drake_social.control import (
    RuckigSegment,
    RuckigTrajectorySource,
    arm_source_from_options,
    reference_source_from_options,
)
from drake_social.scenario import ExecutionOptions

DT = 1e-3  # sampling step, seconds
PERIOD = 0.01
VMAX = np.array([1.0, 0.5])
AMAX = np.array([2.0, 1.5])
JMAX = np.array([10.0, 6.0])
REL = 1e-9  # relative slack on the limits (floating point)


def _source(initial=(0.0, 0.0), **kwargs):
    args = dict(initial_position=list(initial), max_velocity=VMAX, max_acceleration=AMAX, max_jerk=JMAX,
                period=PERIOD)
    args.update(kwargs)
    return RuckigTrajectorySource(**args)


def _outputs(dut, context):
    return tuple(dut.GetOutputPort(name).Eval(context).copy()
                 for name in ("position", "velocity", "acceleration", "finished"))


def _force_update(dut, context):
    """Runs the target update at the context's time, in place."""
    scratch = context.Clone()
    dut.CalcForcedUnrestrictedUpdate(context, scratch.get_mutable_state())
    context.SetAbstractState(0, scratch.get_abstract_state(0).get_value())


def _run(dut, schedule, t_end):
    """Simulates with the target set at the given times; samples every DT.

    A target for time t is set as soon as the simulator reaches t (before the
    first step for t = 0): Drake handles the update events at t at the start
    of the next step, so the update at t sees it.

    Args:
        schedule: list of (time, target), times on the DT grid, increasing.

    Returns:
        t (K,), p, v, a (K, n), finished (K,).
    """
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    port = dut.GetInputPort("target")
    schedule = list(schedule)
    rows = []
    for k in range(int(round(t_end / DT)) + 1):
        t = k * DT
        if k > 0:
            simulator.AdvanceTo(t)
        while schedule and schedule[0][0] <= t + 1e-12:
            port.FixValue(context, np.asarray(schedule.pop(0)[1], float))
        if k == 0:
            simulator.AdvanceTo(0.0)  # handles the update at t = 0
        p, v, a, f = _outputs(dut, context)
        rows.append((t, p, v, a, f[0]))
    t = np.array([r[0] for r in rows])
    return t, np.array([r[1] for r in rows]), np.array([r[2] for r in rows]), np.array([r[3] for r in rows]), \
        np.array([r[4] for r in rows])


def _assert_within_limits(p, v, a, vmax, amax, jmax):
    assert np.all(np.isfinite(p)) and np.all(np.isfinite(v)) and np.all(np.isfinite(a))
    assert np.all(np.abs(v) <= vmax * (1 + REL) + 1e-12)
    assert np.all(np.abs(a) <= amax * (1 + REL) + 1e-12)
    # Finite differences: the jerk, and continuity of p and v (mean value theorem).
    assert np.all(np.abs(np.diff(a, axis=0)) / DT <= jmax * (1 + 1e-6) + 1e-9)
    assert np.all(np.abs(np.diff(v, axis=0)) <= amax * DT * (1 + 1e-6) + 1e-12)
    assert np.all(np.abs(np.diff(p, axis=0)) <= vmax * DT * (1 + 1e-6) + 1e-12)


def test_ports_default_context_and_no_feedthrough():
    dut = _source(initial=(0.3, -0.2))
    assert [dut.get_input_port(i).get_name() for i in range(dut.num_input_ports())] == ["target", "hold"]
    assert [dut.get_output_port(i).get_name() for i in range(dut.num_output_ports())] == [
        "position", "velocity", "acceleration", "state", "finished"]
    assert not dut.HasAnyDirectFeedthrough()
    context = dut.CreateDefaultContext()
    p, v, a, f = _outputs(dut, context)
    np.testing.assert_array_equal(dut.GetOutputPort("state").Eval(context), np.concatenate([p, v, a]))
    np.testing.assert_array_equal(p, [0.3, -0.2])
    np.testing.assert_array_equal(v, [0.0, 0.0])
    np.testing.assert_array_equal(a, [0.0, 0.0])
    assert f[0] == 1.0


def test_rest_to_rest_duration_by_hand():
    # One DoF, v = 1, a = 2, j = 10, distance 3. Jerk phase a/j = 0.2 s; it reaches
    # a_max since a^2/j = 0.4 < v. Accelerating to v takes v/a + a/j = 0.7 s over
    # v * 0.7 / 2 = 0.35 m (symmetric), the same to stop; cruise (3 - 0.7) / 1 = 2.3 s.
    dut = RuckigTrajectorySource(initial_position=[0.0], max_velocity=[1.0], max_acceleration=[2.0],
                                 max_jerk=[10.0], period=PERIOD)
    context = dut.CreateDefaultContext()
    dut.GetInputPort("target").FixValue(context, [3.0])
    _force_update(dut, context)
    segment = context.get_abstract_state(0).get_value()
    assert segment.duration == pytest.approx(3.7, abs=1e-9)
    context.SetTime(1.85)  # the middle: cruising at v_max, halfway
    p, v, a, f = _outputs(dut, context)
    assert p[0] == pytest.approx(1.5, abs=1e-9) and v[0] == pytest.approx(1.0, abs=1e-9)
    assert a[0] == pytest.approx(0.0, abs=1e-9) and f[0] == 0.0
    context.SetTime(0.1)  # jerk phase: a = j t = 1, v = j t^2 / 2 = 0.05, p = j t^3 / 6
    p, v, a, _ = _outputs(dut, context)
    np.testing.assert_allclose([p[0], v[0], a[0]], [10 * 0.1**3 / 6, 0.05, 1.0], atol=1e-12)
    context.SetTime(3.7)
    p, v, a, f = _outputs(dut, context)
    assert (p[0], f[0]) == (pytest.approx(3.0, abs=1e-12), 1.0)
    context.SetTime(10.0)  # held at the end, not extrapolated
    p, v, a, _ = _outputs(dut, context)
    np.testing.assert_allclose([p[0], v[0], a[0]], [3.0, 0.0, 0.0], atol=1e-12)


@pytest.mark.slow
def test_seeded_random_targets_respect_limits_and_end_at_rest_at_the_target():
    rng = np.random.default_rng(20240607)
    dut = _source()
    for _ in range(2):
        # Targets changed at random times on the update grid, often mid-motion.
        times = np.sort(rng.choice(np.arange(0, 300), size=4, replace=False)) * PERIOD
        targets = rng.uniform(-2.0, 2.0, size=(4, 2))
        t, p, v, a, finished = _run(dut, zip(times, targets), t_end=times[-1] + 12.0)
        _assert_within_limits(p, v, a, VMAX, AMAX, JMAX)
        np.testing.assert_allclose(p[-1], targets[-1], rtol=0, atol=1e-10)
        np.testing.assert_allclose(v[-1], 0.0, atol=1e-10)
        np.testing.assert_allclose(a[-1], 0.0, atol=1e-10)
        assert finished[-1] == 1.0
        np.testing.assert_array_equal(p[0], [0.0, 0.0])  # starts at rest at the initial position
        assert not v[0].any()


def test_finished_is_zero_while_moving():
    dut = _source()
    t, p, v, a, finished = _run(dut, [(0.0, [1.0, 0.5])], t_end=4.0)
    np.testing.assert_array_equal(p[-1], [1.0, 0.5])  # exactly
    assert not v[-1].any() and not a[-1].any()
    moving = np.linalg.norm(v, axis=1) > 1e-9
    assert moving.any() and np.all(finished[moving] == 0.0)
    first_done = t[np.argmax(finished == 1.0)]
    # finished rises exactly when the reference arrives (after t = 0, it was 1 at rest).
    assert np.all(finished[(t > 0) & (t < first_done)] == 0.0)
    np.testing.assert_allclose(p[t >= first_done], np.array([[1.0, 0.5]]).repeat((t >= first_done).sum(), 0),
                               atol=1e-10)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_target_changed_mid_motion_gives_no_jump_at_the_update_time(seed):
    rng = np.random.default_rng(seed)
    dut = _source()
    context = dut.CreateDefaultContext()
    dut.GetInputPort("target").FixValue(context, rng.uniform(-2, 2, size=2))
    _force_update(dut, context)
    t_switch = float(rng.uniform(0.05, 0.3))
    context.SetTime(t_switch)
    before = _outputs(dut, context)
    # Really mid-motion, accelerating.
    assert before[3][0] == 0.0 and np.linalg.norm(before[1]) > 0 and np.linalg.norm(before[2]) > 0
    new_target = rng.uniform(-2, 2, size=2)
    dut.GetInputPort("target").FixValue(context, new_target)
    _force_update(dut, context)
    after = _outputs(dut, context)
    for x_before, x_after in zip(before[:3], after[:3]):
        np.testing.assert_allclose(x_after, x_before, rtol=0, atol=1e-12)
    segment = context.get_abstract_state(0).get_value()
    assert segment.t0 == t_switch
    np.testing.assert_array_equal(segment.target, new_target)
    # The same target again changes nothing (no recalculation).
    _force_update(dut, context)
    assert context.get_abstract_state(0).get_value() is segment


def test_no_jump_across_a_switch_in_the_simulator():
    dut = _source()
    t, p, v, a, _ = _run(dut, [(0.0, [2.0, 1.0]), (0.8, [-1.0, 1.5])], t_end=6.0)
    k = int(round(0.8 / DT))
    # Over the one update at 0.8 s, the changes are bounded by the limits times DT.
    assert np.all(np.abs(p[k + 1] - p[k]) <= VMAX * DT + 1e-12)
    assert np.all(np.abs(v[k + 1] - v[k]) <= AMAX * DT + 1e-12)
    assert np.all(np.abs(a[k + 1] - a[k]) <= JMAX * DT + 1e-12)
    _assert_within_limits(p, v, a, VMAX, AMAX, JMAX)
    np.testing.assert_allclose(p[-1], [-1.0, 1.5], atol=1e-10)


def _distance_from_line(points, start, end):
    d = (end - start) / np.linalg.norm(end - start)
    rel = points - start
    return np.linalg.norm(rel - np.outer(rel @ d, d), axis=1)


def test_reference_base_speed_by_hand():
    # Base (0, 0) -> (3, 4): along the segment, v = 0.5, a = 1, j = 5 on the norm.
    # a/j = 0.2 s, a^2/j = 0.2 < 0.5: t_acc = 0.5 + 0.2 = 0.7 s over 0.175 m each
    # way; cruise (5 - 0.35) / 0.5 = 9.3 s; T = 10.7 s (the arm's move is shorter).
    options = ExecutionOptions()
    dut = reference_source_from_options(options, [0.0, 0.0, 0.0, 0.0])
    context = dut.CreateDefaultContext()
    dut.GetInputPort("target").FixValue(context, [3.0, 4.0, 0.2, -0.1])
    _force_update(dut, context)
    assert context.get_abstract_state(0).get_value().duration == pytest.approx(10.7, abs=1e-9)
    context.SetTime(5.35)
    p, v, a, _ = _outputs(dut, context)
    np.testing.assert_array_equal(dut.GetOutputPort("state").Eval(context), np.concatenate([p, v, a]))
    np.testing.assert_allclose(v[:2], [0.3, 0.4], atol=1e-9)  # norm 0.5, along (3, 4)
    np.testing.assert_allclose(p, [1.5, 2.0, 0.1, -0.05], atol=1e-9)  # halfway, all DoFs


@pytest.mark.slow
@pytest.mark.parametrize("seed", [5, 6, 7])
def test_reference_rest_to_rest_stays_on_the_segment_with_the_speed_norm_limited(seed):
    rng = np.random.default_rng(seed)
    options = ExecutionOptions()
    start = np.array([1.0, 1.0, 0.0, 0.0])
    dut = reference_source_from_options(options, start)
    # Random segments, plus the awkward ones: a zero base component, no base motion, no arm motion.
    targets = [start + rng.uniform(-1.5, 1.5, size=4) for _ in range(2)]
    targets.append(targets[-1] + [0.0, 0.7, 0.3, 0.0])
    targets.append(targets[-1] + [0.0, 0.0, -0.5, 0.4])
    targets.append(targets[-1] + [-0.4, 0.3, 0.0, 0.0])
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    vmax = np.array([options.max_base_speed] * 2 + options.arm_max_velocity)
    amax = np.array([options.max_base_acceleration] * 2 + options.arm_max_acceleration)
    jmax = np.array([options.max_base_jerk] * 2 + options.arm_max_jerk)
    t = 0.0
    previous = start
    for target in targets:
        dut.GetInputPort("target").FixValue(context, target)
        rows = [_outputs(dut, context)[:3]]
        # Rest to rest: the next target only once this one is reached.
        while True:
            t += DT
            simulator.AdvanceTo(t)
            p, v, a, f = _outputs(dut, context)
            rows.append((p, v, a))
            heading = context.get_abstract_state(0).get_value().target
            if f[0] == 1.0 and heading is not None and np.array_equal(heading, target):
                break
        p, v, a = (np.array([r[i] for r in rows]) for i in range(3))
        _assert_within_limits(p, v, a, vmax, amax, jmax)
        assert np.max(_distance_from_line(p, previous, target)) < 1e-9
        assert np.max(np.linalg.norm(v[:, :2], axis=1)) <= options.max_base_speed * (1 + REL)
        assert np.max(np.linalg.norm(a[:, :2], axis=1)) <= options.max_base_acceleration * (1 + REL)
        np.testing.assert_allclose(p[-1], target, rtol=0, atol=1e-10)
        np.testing.assert_allclose(v[-1], 0.0, atol=1e-10)
        previous = target


@pytest.mark.slow
def test_reference_retargeted_mid_motion_in_a_new_direction_stays_within_per_axis_limits():
    # Moving along +x at full speed, then told to go along +y: the x limit must
    # still allow braking (a share of the x limits that is not ~0).
    options = ExecutionOptions()
    dut = reference_source_from_options(options, [0.0, 0.0, 0.0, 0.0])
    t, p, v, a, _ = _run(dut, [(0.0, [3.0, 0.0, 0.0, 0.0]), (2.0, [1.0, 2.0, 0.5, 0.0])], t_end=14.0)
    k = int(round(2.0 / DT))
    assert v[k, 0] == pytest.approx(options.max_base_speed, rel=1e-9)  # cruising when switched
    vmax = np.array([options.max_base_speed] * 2 + options.arm_max_velocity)
    amax = np.array([options.max_base_acceleration] * 2 + options.arm_max_acceleration)
    jmax = np.array([options.max_base_jerk] * 2 + options.arm_max_jerk)
    _assert_within_limits(p, v, a, vmax, amax, jmax)
    np.testing.assert_allclose(p[-1], [1.0, 2.0, 0.5, 0.0], atol=1e-10)


def test_arm_source_from_options_uses_the_arm_limits():
    options = ExecutionOptions(arm_max_velocity=[0.5, 2.0], arm_max_acceleration=[1.0, 4.0],
                               arm_max_jerk=[5.0, 20.0], control_period=0.02)
    dut = arm_source_from_options(options, [0.1, -0.1])
    np.testing.assert_array_equal(dut.GetOutputPort("position").Eval(dut.CreateDefaultContext()), [0.1, -0.1])
    t, p, v, a, _ = _run(dut, [(0.0, [1.6, -1.6])], t_end=5.0)
    # Time synchronization: both joints arrive together; joint 1 (slower) sets the pace,
    # so joint 2 never needs its own larger limits: bounded by those of joint 1.
    _assert_within_limits(p, v, a, np.array([0.5, 2.0]), np.array([1.0, 4.0]), np.array([5.0, 20.0]))
    assert np.max(np.abs(v[:, 0])) == pytest.approx(0.5, rel=1e-6)
    np.testing.assert_allclose(p[-1], [1.6, -1.6], atol=1e-10)
    # The hand duration of joint 1: 1.5 rad at v 0.5, a 1, j 5: t_acc = 0.5 + 0.2 = 0.7 s
    # over 0.175 rad each way, cruise (1.5 - 0.35) / 0.5 = 2.3 s: T = 3.7 s.
    moving = np.nonzero(np.linalg.norm(v, axis=1) > 1e-9)[0]
    assert t[moving[-1]] == pytest.approx(3.7, abs=DT + 1e-9)


def test_set_initial_position_and_context_clone():
    dut = _source()
    context = dut.CreateDefaultContext()
    dut.SetInitialPosition(context, [0.5, 0.25])
    p, v, a, f = _outputs(dut, context)
    np.testing.assert_array_equal(p, [0.5, 0.25])
    assert f[0] == 1.0
    dut.GetInputPort("target").FixValue(context, [0.5, 1.25])
    _force_update(dut, context)
    context.SetTime(0.5)
    clone = context.Clone()  # the segment (holding a ruckig.Trajectory) is shared, not deep-copied
    for x, y in zip(_outputs(dut, context), _outputs(dut, clone)):
        np.testing.assert_array_equal(x, y)
    segment = context.get_abstract_state(0).get_value()
    assert copy.deepcopy(segment) is segment and copy.copy(segment) is segment
    assert AbstractValue.Make(segment).Clone().get_value() is segment
    with pytest.raises(AttributeError):
        segment.t0 = 1.0
    with pytest.raises(ValueError):
        segment.rest[0] = 1.0
    with pytest.raises(ValueError, match="3 finite numbers"):
        RuckigTrajectorySource(initial_position=[0, 0, 0], max_velocity=[1] * 3, max_acceleration=[1] * 3,
                               max_jerk=[1] * 3, period=PERIOD).SetInitialPosition(context, [0, 0])


def test_segment_at_rest_and_clamped():
    segment = RuckigSegment(1.0, None, [1.0, 2.0], None)
    p, v, a = segment.at(5.0)
    np.testing.assert_array_equal(p, [1.0, 2.0])
    assert segment.duration == 0.0 and not v.any() and not a.any()


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(max_velocity=[1.0]), "max_velocity must hold 2"),
        (dict(max_acceleration=[1.0, 0.0]), "max_acceleration"),
        (dict(max_jerk=[1.0, np.inf]), "max_jerk"),
        (dict(period=0.0), "period"),
        (dict(synchronization="sometimes"), "synchronization must be one of"),
        (dict(xy_norm_dofs=(0, 2)), "xy_norm_dofs"),
        (dict(xy_norm_dofs=(0, 0)), "xy_norm_dofs"),
        (dict(initial=(0.0, np.nan)), "initial_position"),
    ],
)
def test_bad_parameters_raise(kwargs, message):
    with pytest.raises(ValueError, match=message):
        _source(**kwargs)


def test_non_finite_target_raises_naming_the_system():
    dut = _source()
    dut.set_name("arm_source")
    context = dut.CreateDefaultContext()
    dut.GetInputPort("target").FixValue(context, [np.nan, 0.0])
    with pytest.raises(RuntimeError, match="arm_source.*finite"):
        _force_update(dut, context)


# ---- position limits -------------------------------------------------------------

_ARM = dict(max_velocity=[1.0, 1.0], max_acceleration=[2.0, 2.0], max_jerk=[10.0, 10.0], period=PERIOD)
_PI_BOX = ([-np.pi, -np.pi], [np.pi, np.pi])


def _plain_ruckig_maximum(p, v, a, target):
    """The largest position of each DoF on plain Ruckig's segment from (p, v, a) to target (time sync)."""
    import ruckig

    inp = ruckig.InputParameter(2)
    inp.current_position, inp.current_velocity, inp.current_acceleration = list(p), list(v), list(a)
    inp.target_position, inp.target_velocity, inp.target_acceleration = list(target), [0.0, 0.0], [0.0, 0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [1.0, 1.0], [2.0, 2.0], [10.0, 10.0]
    trajectory = ruckig.Trajectory(2)
    ruckig.Ruckig(2).calculate(inp, trajectory)
    return np.array([e.max for e in trajectory.position_extrema])


def _sampled_positions(dut, context, t_from, t_to):
    out = []
    for t in np.arange(t_from, t_to + DT / 2, DT):
        context.SetTime(float(t))
        out.append(dut.GetOutputPort("position").Eval(context).copy())
    return np.array(out)


def test_a_retarget_that_would_pass_a_limit_waits_for_rest_and_the_reference_never_passes_it():
    # psi1 heads for its upper limit pi; 1.26 s into that segment (still
    # moving) the target changes to one with psi1 also at pi. Plain Ruckig's
    # new segment from that state passes pi (by 2.7e-9 rad): the source
    # keeps its current segment, and heads for the new target once at rest.
    a, b, c = [2.46, 0.54], [np.pi, 1.3], [np.pi, 1.22]
    dut = RuckigTrajectorySource(initial_position=a, position_limits=_PI_BOX, **_ARM)
    context = dut.CreateDefaultContext()
    port = dut.GetInputPort("target")
    port.FixValue(context, b)
    _force_update(dut, context)
    first = context.get_abstract_state(0).get_value()
    context.SetTime(1.26)
    p, v, acc, _ = _outputs(dut, context)
    assert np.max(np.abs(v)) > 1e-3  # moving
    assert _plain_ruckig_maximum(p, v, acc, c)[0] > np.pi + 1e-12  # the witness: plain Ruckig passes pi
    port.FixValue(context, c)
    _force_update(dut, context)
    assert context.get_abstract_state(0).get_value() is first  # not started while moving
    context.SetTime(first.duration)
    _force_update(dut, context)  # at rest at b: now heads for c
    second = context.get_abstract_state(0).get_value()
    assert second is not first and np.array_equal(second.target, c)
    before = dut.CreateDefaultContext()
    before.SetAbstractState(0, first)
    positions = np.concatenate([_sampled_positions(dut, before, 0.0, first.duration),
                                _sampled_positions(dut, context, first.duration, first.duration + second.duration)])
    assert np.all(positions <= np.pi) and np.all(positions >= -np.pi)
    np.testing.assert_array_equal(positions[-1], c)


def test_a_segment_ending_at_a_limit_never_passes_it_by_rounding():
    # Rest to rest onto both upper limits: Ruckig's own extrema pass pi by
    # rounding (~4e-16); the outputs are clipped to the limits.
    dut = RuckigTrajectorySource(initial_position=[0.3, -2.0], position_limits=_PI_BOX, **_ARM)
    t, p, _, _, _ = _run(dut, [(0.0, [np.pi, np.pi])], t_end=6.0)
    assert np.max(p) <= np.pi
    np.testing.assert_array_equal(p[-1], [np.pi, np.pi])


def test_a_target_outside_the_position_limits_is_an_error_naming_it():
    dut = RuckigTrajectorySource(initial_position=[0.0, 0.0], position_limits=_PI_BOX, **_ARM)
    dut.set_name("arm")
    context = dut.CreateDefaultContext()
    dut.GetInputPort("target").FixValue(context, [3.2, 0.0])
    with pytest.raises(RuntimeError, match=r"arm: the target \[3.2, 0.0\] at t = 0.0 s is outside the position limits"):
        _force_update(dut, context)
    with pytest.raises(ValueError, match="initial_position .* is outside position_limits"):
        RuckigTrajectorySource(initial_position=[0.0, -3.5], position_limits=_PI_BOX, **_ARM)
    with pytest.raises(ValueError, match="SetInitialPosition: .* is outside the position limits"):
        dut.SetInitialPosition(context, [0.0, 4.0])
    with pytest.raises(ValueError, match=r"position_limits must be \(lower, upper\) of 2 finite numbers"):
        RuckigTrajectorySource(initial_position=[0.0, 0.0], position_limits=([1.0, 0.0], [0.0, 1.0]), **_ARM)


# ---- the wheels' limit on the base ---------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("direction, expected", [
    # wheel limit r * w_max = 0.05 * 20 = 1 m/s on |vx| + |vy|; speed s along u: s (|ux| + |uy|) <= 1.
    ([4.0, 0.0], 1.0),                    # along x: |ux| + |uy| = 1
    ([0.0, -4.0], 1.0),                   # along y
    ([3.0, 3.0], 1.0 / np.sqrt(2.0)),     # diagonal: 2 / sqrt(2)
    ([3.0, -4.0], 5.0 / 7.0),             # (3/5 + 4/5) = 7/5
])
def test_reference_base_speed_is_the_wheels_limit_when_max_base_speed_exceeds_it(direction, expected):
    options = ExecutionOptions(max_base_speed=2.0, max_base_acceleration=1.0, max_base_jerk=5.0)
    dut = reference_source_from_options(options, [0.0, 0.0, 0.0, 0.0])
    t, p, v, a, _ = _run(dut, [(0.0, [*direction, 0.0, 0.0])], t_end=8.0)
    speed = np.hypot(v[:, 0], v[:, 1])
    # Cruises at it (4-5 m segments); a DoF that does not move keeps a share
    # of 1e-6 of the limits (_SHARE_FLOOR), counted in the sum: 1e-6 slower.
    assert np.max(speed) == pytest.approx(expected, rel=2e-6)
    assert np.max(speed) <= expected * (1 + 1e-12)
    wheels = (np.abs(v[:, 0]) + np.abs(v[:, 1])) / options.wheel_radius  # the largest |w_i|, by hand
    assert np.max(wheels) <= options.max_wheel_speed * (1 + 1e-9)
    assert np.max(_distance_from_line(p[:, :2], np.zeros(2), np.array(direction))) < 1e-9


def test_reference_base_speed_below_the_wheels_limit_is_unchanged():
    # max_base_speed 0.5 < 1/sqrt(2): the diagonal cruise is still 0.5 m/s.
    dut = reference_source_from_options(ExecutionOptions(), [0.0, 0.0, 0.0, 0.0])
    _, _, v, _, _ = _run(dut, [(0.0, [3.0, 3.0, 0.0, 0.0])], t_end=3.0)
    assert np.max(np.hypot(v[:, 0], v[:, 1])) == pytest.approx(0.5, rel=1e-9)


def _braked_run(brake_at: float | None, release_at: float | None, t_end: float = 4.0, connect: bool = True):
    """A 2-DoF synchronized reference along (0, 0) -> (2, 1) with its ``brake``
    input switched on at ``brake_at`` and off at ``release_at`` (None: never)."""
    dut = _source(synchronization="phase", via=True, point_speed=lambda u: 1.0)
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    dut.GetInputPort("target").FixValue(context, np.array([2.0, 1.0]))
    if connect:
        dut.GetInputPort("brake").FixValue(context, [0.0])
    simulator.AdvanceTo(0.0)
    rows = []
    for k in range(int(round(t_end / DT)) + 1):
        t = k * DT
        if k > 0:
            simulator.AdvanceTo(t)
        if brake_at is not None and abs(t - brake_at) < 1e-12:
            dut.GetInputPort("brake").FixValue(context, [1.0])
        if release_at is not None and abs(t - release_at) < 1e-12:
            dut.GetInputPort("brake").FixValue(context, [0.0])
        p, v, a, _ = _outputs(dut, context)
        rows.append((t, p, v, a))
    return (np.array([r[0] for r in rows]),) + tuple(np.array([r[i] for r in rows]) for i in (1, 2, 3))


def test_brake_stops_on_the_path_jerk_limited_and_goes_on_when_released():
    """The brake input (a replanner's wait): the reference brakes to rest on
    its straight segment within the acceleration and jerk limits (no jump,
    unlike the hold), stays at rest while braked, and goes on along the same
    segment to the target when released."""
    t, p, v, a = _braked_run(brake_at=0.8, release_at=2.5, t_end=7.0)
    _assert_within_limits(p, v, a, VMAX, AMAX, JMAX)
    direction = np.array([2.0, 1.0]) / np.sqrt(5.0)
    off_line = p[:, 0] * direction[1] - p[:, 1] * direction[0]
    assert np.max(np.abs(off_line)) <= 1e-9  # on the segment throughout
    along = p @ direction
    assert np.all(np.diff(along) >= -1e-12)  # never back
    braked = (t >= 0.8 + PERIOD) & (t < 2.5)
    moving_at_brake = np.abs(v[np.searchsorted(t, 0.8)]).max()
    assert moving_at_brake > 0.1
    rest = braked & (np.abs(v).max(axis=1) == 0.0)
    assert rest.any()  # at rest exactly (the reference's velocity is 0: a replanner sees it at rest)
    first_rest = np.flatnonzero(rest)[0]
    assert np.all(rest[first_rest:np.flatnonzero(braked)[-1] + 1])  # and stays at rest while braked
    np.testing.assert_array_equal(p[first_rest], p[np.flatnonzero(braked)[-1]])
    np.testing.assert_allclose(p[-1], [2.0, 1.0], atol=1e-12)  # released: on to the target


def test_a_brake_input_at_zero_is_the_reference_without_it():
    """Connected and off, the brake changes nothing: the same reference, bit
    for bit, as with the input left unconnected (and it does move)."""
    t, p, v, a = _braked_run(brake_at=None, release_at=None)
    _, p2, v2, _ = _braked_run(brake_at=None, release_at=None, connect=False)
    np.testing.assert_array_equal(p, p2)
    np.testing.assert_array_equal(v, v2)
    assert np.abs(v).max() > 0.1
