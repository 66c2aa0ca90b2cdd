"""Holonomic P-controller and mecanum kinematics against hand computations."""

from __future__ import annotations

import numpy as np
import pytest

from drake_social.control import (
    HolonomicPController,
    MecanumDrive,
    base_velocity,
    mecanum_matrix,
    saturate_norm,
    wheel_limited_speed,
    wheel_speeds,
)
from drake_social.scenario import ExecutionOptions

R = 0.05


def _controller(**kwargs):
    args = dict(kp=1.5, max_base_speed=0.5, wheel_radius=R, max_wheel_speed=20.0)
    args.update(kwargs)
    return HolonomicPController(**args)


def _eval(dut, target, position, ff=None):
    context = dut.CreateDefaultContext()
    dut.GetInputPort("base_target").FixValue(context, target)
    dut.GetInputPort("base_position").FixValue(context, position)
    if ff is not None:
        dut.GetInputPort("base_velocity_ff").FixValue(context, ff)
    w = dut.GetOutputPort("wheel_speeds").Eval(context).copy()
    v = dut.GetOutputPort("base_velocity").Eval(context).copy()
    return w, v


def test_mecanum_matrix_is_the_papers_transposed():
    np.testing.assert_array_equal(
        mecanum_matrix(), np.array([[1, -1], [1, 1], [-1, 1], [-1, -1]], float)
    )
    # A copy: changing it changes nothing.
    m = mecanum_matrix()
    m[0, 0] = 9.0
    assert mecanum_matrix()[0, 0] == 1.0


def test_wheel_speeds_by_hand():
    # vx = 0.1, vy = 0.2, r = 0.05: w = 20 * [0.1 - 0.2, 0.1 + 0.2, -0.1 + 0.2, -0.1 - 0.2]
    np.testing.assert_allclose(wheel_speeds([0.1, 0.2], R), [-2.0, 6.0, 2.0, -6.0], rtol=0, atol=1e-12)


def test_wheel_limited_speed_by_hand():
    # r = 0.05 m, 20 rad/s: |w| = |vx +- vy| / r <= 20, so |vx| + |vy| <= 1 m/s.
    # Along x: 1 m/s; diagonal: vx = vy = s / sqrt(2), 2 s / sqrt(2) = 1 -> 0.7071;
    # along (3, -4): s (3 + 4) / 5 = 1 -> 5/7.
    dut = wheel_limited_speed([[2.0, 0.0], [0.0, -0.3], [1.0, 1.0], [3.0, -4.0], [0.0, 0.0]], R, 20.0)
    np.testing.assert_allclose(dut[:4], [1.0, 1.0, 1 / np.sqrt(2), 5 / 7], rtol=1e-15)
    assert dut[4] == np.inf
    # At that speed the largest wheel is exactly at its limit, in random directions.
    rng = np.random.default_rng(3)
    d = rng.normal(size=(100, 2))
    s = wheel_limited_speed(d, R, 20.0)
    v = d / np.linalg.norm(d, axis=1, keepdims=True) * s[:, None]
    np.testing.assert_allclose(np.max(np.abs(wheel_speeds(v, R)), axis=1), 20.0, rtol=1e-12)


def test_base_velocity_inverts_wheel_speeds_on_random_vectors():
    rng = np.random.default_rng(7)
    v = rng.normal(size=(200, 2))
    np.testing.assert_allclose(base_velocity(wheel_speeds(v, R), R), v, rtol=0, atol=1e-12)
    # Hand value: w = [1, 0, 0, 0] -> (r/4) * M[:, 0] = 0.0125 * [1, -1]
    np.testing.assert_allclose(base_velocity([1.0, 0, 0, 0], R), [0.0125, -0.0125], rtol=0, atol=1e-15)


def test_saturate_norm_keeps_direction_and_caps_the_norm():
    np.testing.assert_allclose(saturate_norm([3.0, 4.0], 1.0), [0.6, 0.8], rtol=0, atol=1e-15)
    np.testing.assert_array_equal(saturate_norm([0.3, 0.4], 1.0), [0.3, 0.4])  # within: unchanged
    np.testing.assert_array_equal(saturate_norm([0.0, 0.0], 1.0), [0.0, 0.0])
    rng = np.random.default_rng(3)
    v = rng.normal(scale=5.0, size=(100, 2))
    out = saturate_norm(v, 0.5)
    norm_in = np.linalg.norm(v, axis=1)
    norm_out = np.linalg.norm(out, axis=1)
    np.testing.assert_allclose(norm_out, np.minimum(norm_in, 0.5), rtol=1e-12)
    np.testing.assert_allclose(out / norm_out[:, None], v / norm_in[:, None], atol=1e-12)


def test_output_is_kp_times_the_error_when_within_limits():
    dut = _controller()
    # error [0.1, -0.2] -> v = 1.5 * error = [0.15, -0.3] (norm 0.335 < 0.5);
    # w = 20 * [0.15 + 0.3, 0.15 - 0.3, -0.15 - 0.3, -0.15 + 0.3] = [9, -3, -9, 3] (< 20)
    w, v = _eval(dut, [1.1, 0.8], [1.0, 1.0])
    np.testing.assert_allclose(v, [0.15, -0.3], rtol=0, atol=1e-12)
    np.testing.assert_allclose(w, [9.0, -3.0, -9.0, 3.0], rtol=0, atol=1e-12)


def test_sign_converges():
    # Target ahead in +x: the base must move in +x.
    _, v = _eval(_controller(), [2.0, 0.0], [1.9, 0.0])
    assert v[0] > 0 and v[1] == pytest.approx(0.0, abs=1e-15)


def test_norm_saturation_keeps_direction_and_norm_equals_max():
    dut = _controller()
    # error [3, 4] -> Kp e = [4.5, 6] (norm 7.5) -> 0.5 * [0.6, 0.8] = [0.3, 0.4];
    # w = 20 * [-0.1, 0.7, 0.1, -0.7] = [-2, 14, 2, -14] (< 20: no wheel limit)
    w, v = _eval(dut, [3.0, 4.0], [0.0, 0.0])
    np.testing.assert_allclose(v, [0.3, 0.4], rtol=0, atol=1e-12)
    assert np.linalg.norm(v) == pytest.approx(0.5, rel=1e-12)
    np.testing.assert_allclose(w, [-2.0, 14.0, 2.0, -14.0], rtol=0, atol=1e-12)


def test_wheel_limit_scales_uniformly():
    dut = _controller(max_wheel_speed=7.0)
    # As above, w = [-2, 14, 2, -14]; max |w| 14 > 7 -> w / 2 = [-1, 7, 1, -7], v = [0.15, 0.2].
    w, v = _eval(dut, [3.0, 4.0], [0.0, 0.0])
    np.testing.assert_allclose(w, [-1.0, 7.0, 1.0, -7.0], rtol=0, atol=1e-12)
    assert np.max(np.abs(w)) == pytest.approx(7.0, rel=1e-12)
    np.testing.assert_allclose(v, [0.15, 0.2], rtol=0, atol=1e-12)


def test_wheel_limit_on_random_errors_keeps_direction():
    rng = np.random.default_rng(11)
    dut = _controller(max_base_speed=2.0, max_wheel_speed=15.0)
    for _ in range(50):
        target, position = rng.uniform(-2, 2, size=(2, 2))
        w, v = _eval(dut, target, position)
        e = target - position
        v_sat = saturate_norm(1.5 * e, 2.0)
        w_sat = wheel_speeds(v_sat, R)
        scale = min(1.0, 15.0 / np.max(np.abs(w_sat)))
        np.testing.assert_allclose(w, scale * w_sat, rtol=1e-12, atol=1e-12)
        assert np.max(np.abs(w)) <= 15.0 * (1 + 1e-12)
        # The base velocity is the one the wheels produce, parallel to the error.
        np.testing.assert_allclose(v, base_velocity(w, R), atol=1e-12)
        assert abs(v[0] * e[1] - v[1] * e[0]) <= 1e-12 * max(1.0, np.linalg.norm(e))
        assert v @ e >= 0


def test_feedforward_is_added_before_the_limits():
    dut = _controller(feedforward=True)
    assert "base_velocity_ff" in [dut.get_input_port(i).get_name() for i in range(dut.num_input_ports())]
    # v = [0.1, 0.0] + 1.5 * [0.1, 0.1] = [0.25, 0.15]
    _, v = _eval(dut, [1.1, 1.1], [1.0, 1.0], ff=[0.1, 0.0])
    np.testing.assert_allclose(v, [0.25, 0.15], rtol=0, atol=1e-12)
    # At the target, v is the feed-forward; a large one saturates: [3, 4] -> [0.3, 0.4]
    _, v = _eval(dut, [1.0, 1.0], [1.0, 1.0], ff=[3.0, 4.0])
    np.testing.assert_allclose(v, [0.3, 0.4], rtol=0, atol=1e-12)


def test_ports_and_feedthrough():
    dut = _controller()
    assert [dut.get_input_port(i).get_name() for i in range(dut.num_input_ports())] == [
        "base_target", "base_position", "hold"]
    assert [dut.get_output_port(i).get_name() for i in range(dut.num_output_ports())] == [
        "wheel_speeds", "base_velocity"]
    assert dut.HasDirectFeedthrough(1, 0)
    assert dut.num_continuous_states() == 0 and dut.num_discrete_state_groups() == 0


def test_from_options():
    options = ExecutionOptions(kp=2.0, max_base_speed=0.4, wheel_radius=0.1, max_wheel_speed=3.0)
    dut = HolonomicPController.from_options(options)
    # Kp e = [0.2, 0]; w = 10 * [0.2, 0.2, -0.2, -0.2] = 2 (< 3): v = [0.2, 0]
    w, v = _eval(dut, [0.1, 0.0], [0.0, 0.0])
    np.testing.assert_allclose(v, [0.2, 0.0], atol=1e-12)
    np.testing.assert_allclose(w, [2.0, 2.0, -2.0, -2.0], atol=1e-12)
    # Kp e = [2, 0] -> norm 0.4 -> w = 4 > 3 -> 3: v = 0.3
    w, v = _eval(dut, [1.0, 0.0], [0.0, 0.0])
    np.testing.assert_allclose(v, [0.3, 0.0], atol=1e-12)


@pytest.mark.parametrize("field", ["kp", "max_base_speed", "wheel_radius", "max_wheel_speed"])
def test_non_positive_parameters_raise(field):
    with pytest.raises(ValueError, match=field):
        _controller(**{field: -1.0})


def test_mecanum_drive_inverts_wheel_speeds():
    dut = MecanumDrive(R)
    context = dut.CreateDefaultContext()
    rng = np.random.default_rng(5)
    for v in rng.normal(size=(20, 2)):
        dut.GetInputPort("wheel_speeds").FixValue(context, wheel_speeds(v, R))
        np.testing.assert_allclose(dut.GetOutputPort("base_velocity").Eval(context), v, atol=1e-12)
    # Hand value: all wheels at +1 rad/s: M @ [1, 1, 1, 1] = [0, 0]
    dut.GetInputPort("wheel_speeds").FixValue(context, np.ones(4))
    np.testing.assert_allclose(dut.GetOutputPort("base_velocity").Eval(context), [0.0, 0.0], atol=1e-15)
    with pytest.raises(ValueError, match="wheel_radius"):
        MecanumDrive(0.0)
