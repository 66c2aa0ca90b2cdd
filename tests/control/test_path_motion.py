"""Motions along a polyline: on its segments, through its corners, capped, stopped, never past its end."""

from __future__ import annotations

import numpy as np
import pytest

from drake_social.control.path_motion import SMALLEST_CAP, PathProfile, Polyline

LIMITS = (0.5, 1.0, 5.0)  # s', s'', s''' limits of the path parameter


def test_a_polyline_drops_repeated_points_and_keeps_its_last_point_exactly():
    dut = Polyline(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [1.0, 2.0]]))
    np.testing.assert_array_equal(dut.points, [[0.0, 0.0], [1.0, 0.0], [1.0, 2.0]])
    np.testing.assert_array_equal(dut.starts, [0.0, 1.0, 3.0])
    assert dut.at(1.5, 0.2, -0.1) == ([1.0, 0.5], [0.0, 0.2], [-0.0, -0.1])
    assert dut.at(0.25)[0] == [0.25, 0.0]
    with pytest.raises(ValueError, match="two distinct points"):
        Polyline(np.array([[1.0, 1.0], [1.0, 1.0]]))


def test_a_profile_ends_at_rest_exactly_at_the_last_point():
    path = Polyline(np.array([[0.0, 0.0], [0.3, 0.4], [0.6, 0.8]]))
    dut = PathProfile.plan(path, LIMITS, 1.0)  # a cap above the limit: the limit
    assert dut.cap == 0.5 and dut.arrives and dut.end == [0.6, 0.8]
    assert dut.at_time(dut.duration + 1.0) == ([0.6, 0.8], [0.0, 0.0], [0.0, 0.0])
    # Through the corner-free middle point at the cruise speed.
    t = np.linspace(0.0, dut.duration, 2001)
    s = np.array([dut.state(x)[0] for x in t])
    k = int(np.argmin(np.abs(s - 0.5)))
    assert dut.state(t[k])[1] == pytest.approx(0.5, rel=1e-12)


@pytest.mark.parametrize("cap", [0.0, SMALLEST_CAP * 0.999])
def test_a_cap_of_zero_or_below_the_smallest_stops_on_the_path(cap):
    path = Polyline(np.array([[0.0, 0.0], [2.0, 0.0]]))
    moving = PathProfile.plan(path, LIMITS, 0.5)
    s, sd, sdd = moving.state(1.5)
    assert sd > 0.2
    dut = PathProfile.plan(path, LIMITS, cap, s, sd, sdd)
    assert dut.cap == 0.0 and not dut.arrives
    # The shortest stop from there: at rest short of the end, on the segment, the jerk within its limit.
    assert s < dut.end_s < 2.0 and dut.end == [dut.end_s, 0.0]
    t = np.arange(0.0, dut.duration, 1e-3)
    acc = np.array([dut.state(x)[2] for x in t])
    assert np.abs(np.diff(acc) / 1e-3).max() <= LIMITS[2] * (1 + 1e-6)


def test_a_cap_just_above_the_smallest_still_moves():
    path = Polyline(np.array([[0.0, 0.0], [2.0, 0.0]]))
    assert PathProfile.plan(path, LIMITS, SMALLEST_CAP * 1.001).cap == pytest.approx(SMALLEST_CAP * 1.001)


def test_re_planned_in_its_last_braking_the_motion_never_passes_the_end():
    # A cap re-planned every 10 ms from late in the approach, falling by up to 30 % or rising by 2 %
    # each time (a seeded chain in which Ruckig's profile, within its precision, runs 9e-9 past the end
    # before its last sample): the position stays on the segment.
    path = Polyline(np.array([[0.0, 0.0], [1.0, 0.0]]))
    rng = np.random.default_rng(249)
    dut = PathProfile.plan(path, LIMITS, 0.5)
    t0, t = 0.0, dut.duration * rng.uniform(0.5, 0.98)
    cap, passed, raw = 0.5, [], []
    for _ in range(300):
        if dut.trajectory is None:
            break
        for x in np.linspace(t - t0, t - t0 + 0.01, 21):
            passed.append(dut.at_time(x)[0][0])
            if x < dut.duration:
                raw.append(dut.trajectory.at_time(x)[0][0])
        s, sd, sdd = dut.state(t - t0)
        cap *= rng.uniform(0.7, 1.02)
        dut = PathProfile.plan(path, LIMITS, cap, s, sd, sdd)
        t0, t = t, t + 0.01
    assert max(raw) > 1.0 + 5e-9  # Ruckig's profile goes past the end ...
    assert max(passed) <= 1.0  # ... the motion does not
