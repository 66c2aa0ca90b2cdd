"""The time-series reductions behind run_metrics, on hand-written samples."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_social.evaluation.time_series import (
    derivative_magnitudes,
    episodes,
    held_time,
    motion_profile,
    motion_stats,
    trapezoid_mean,
)

_T = np.array([0.0, 1.0, 3.0, 4.0, 7.0])


def test_held_time_holds_each_sample_until_the_next_and_the_last_for_nothing():
    assert held_time([True, False, True, False, False], _T) == 1.0 + 1.0
    assert held_time([False, False, False, False, True], _T) == 0.0
    assert held_time([True] * 5, _T) == 7.0


@pytest.mark.parametrize("mask, count, seconds", [
    ([True, True, False, True, True], 2, 3.0 + 3.0),  # a run at the start counts; the last run holds 3 s
    ([False, False, False, False, True], 1, 0.0),     # the last sample alone: an episode of no time
    ([False] * 5, 0, 0.0),
    ([True] * 5, 1, 7.0),
])
def test_episodes_count_runs_where_they_start(mask, count, seconds):
    assert episodes(np.array(mask), _T) == (count, seconds)


def test_trapezoid_mean_leaves_out_steps_with_an_infinite_end():
    values = np.array([1.0, 3.0, np.inf, 2.0, 4.0])
    # Steps [0, 1] (mean 2, 1 s) and [4, 7] (mean 3, 3 s): (2 + 9) / 4.
    assert trapezoid_mean(values, _T) == pytest.approx(11.0 / 4.0, rel=1e-15)
    assert math.isnan(trapezoid_mean(np.full(5, np.inf), _T)) and math.isnan(trapezoid_mean([1.0], [0.0]))


def test_divided_differences_are_exact_for_a_quadratic_in_two_dimensions():
    t = np.array([0.0, 0.3, 0.4, 1.1, 2.0])
    xy = np.column_stack([3.0 * t**2, -4.0 * t**2 + 1.0])  # |a| = 2 * 5 = 10 everywhere
    np.testing.assert_allclose(derivative_magnitudes(t, xy, 2), 10.0, rtol=1e-12)
    np.testing.assert_allclose(derivative_magnitudes(t, xy, 3), 0.0, atol=1e-9)
    # |v| over [t_k, t_k+1] of a quadratic is the speed at the step's midpoint: 10 (t_k + t_k+1) / 2.
    np.testing.assert_allclose(derivative_magnitudes(t, xy, 1), 5.0 * (t[:-1] + t[1:]), rtol=1e-12)


def test_motion_stats_pool_tracks_and_are_nan_when_too_short():
    t = np.array([0.0, 1.0, 2.0, 3.0])
    tracks = np.stack([np.column_stack([t, 0 * t]), np.column_stack([3 * t, 0 * t])], axis=1)  # (T, 2, 2)
    dut = motion_stats(t, tracks)
    assert dut["speed_mean"] == pytest.approx(2.0) and dut["speed_max"] == pytest.approx(3.0)
    assert dut["accel_max"] == 0.0 and dut["jerk_max"] == 0.0
    short = motion_stats(t[:2], tracks[:2, 0])
    assert short["speed_max"] == 1.0 and math.isnan(short["accel_mean"]) and math.isnan(short["jerk_max"])


def test_jerk_p95_is_the_95th_percentile_of_the_windows():
    # Positions 0 except 1 at sample 10 of 41 at 1 s spacing: the third differences are 1, -3, 3, -1
    # in the four windows around it (|j| = 1, 3, 3, 1 m/s^3), 0 in the other 34.
    t = np.arange(41.0)
    x = np.zeros(41)
    x[10] = 1.0
    dut = motion_stats(t, np.column_stack([x, 0 * x]))
    # The 95th percentile of the 38: at rank 0.95 x 37 = 35.15 of the sorted values (1 and 3): 1.3.
    assert dut["jerk_max"] == pytest.approx(3.0)
    assert dut["jerk_p95"] == pytest.approx(1.3)
    assert math.isnan(motion_stats(t[:3], np.zeros((3, 2)))["jerk_p95"])


def test_motion_profile_is_the_fastest_track_at_mid_window():
    t = np.array([0.0, 1.0, 2.0, 4.0])
    tracks = np.stack([np.column_stack([t, 0 * t]), np.column_stack([0 * t, t**2])], axis=1)  # (T, 2, 2)
    dut = motion_profile(t, tracks)
    times, speed = dut["speed"]
    np.testing.assert_allclose(times, [0.5, 1.5, 3.0])
    np.testing.assert_allclose(speed, [1.0, 3.0, 6.0])  # track 1 (t^2) is the faster from the second step
    np.testing.assert_allclose(dut["accel"][1], [2.0, 2.0])
    np.testing.assert_allclose(dut["jerk"][0], [2.0])
    assert len(motion_profile(t[:1], tracks[:1])["speed"][1]) == 0
