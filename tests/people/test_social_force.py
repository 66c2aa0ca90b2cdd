"""The social force terms against hand computations and PySocialForce's own formulas."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_social.people.social_force import (box_nearest, cap_speed, capsule_force, capsule_nearest,
                                              desired_velocities, goal_force, obstacle_force, pedestrian_force)

MOUSSAID = dict(lam=2.0, gamma=0.35, n=2.0, n_prime=3.0, strength=4.5)


def test_goal_force_is_the_velocity_gap_over_tau():
    desired = desired_velocities(np.array([[0.0, 0.0], [1.0, 1.0]]), np.array([[3.0, 4.0], [1.0, 1.0]]),
                                 np.array([1.5, 1.2]))
    # (3, 4) / 5 * 1.5 = (0.9, 1.2); a person standing on their goal has no direction.
    np.testing.assert_allclose(desired, [[0.9, 1.2], [0.0, 0.0]], atol=1e-12)
    force = goal_force(np.array([[0.2, 0.1], [0.5, -0.5]]), desired, 0.5)
    np.testing.assert_allclose(force, [[1.4, 2.2], [-1.0, 1.0]], atol=1e-12)


def test_head_on_pair_only_slows_down():
    # i at 0 walking +x at 1 m/s, j 2 m ahead walking -x: e = (-1, 0),
    # D = 2 * (-2, 0) + e = (-5, 0), theta = 0, B = 0.35 * 5 = 1.75.
    pos = np.array([[0.0, 0.0], [2.0, 0.0]])
    vel = np.array([[1.0, 0.0], [-1.0, 0.0]])
    f = pedestrian_force(pos, vel, pos, vel, self_index=np.arange(2), **MOUSSAID)
    along = 4.5 * math.exp(-2.0 / 1.75)
    np.testing.assert_allclose(f, [[-along, 0.0], [along, 0.0]], atol=1e-9)


def test_off_axis_pair_by_hand_turns_away():
    # i at (0, 0) walking +x at 1 m/s, j standing at (1, 1), on i's left.
    pos = np.array([[0.0, 0.0]])
    vel = np.array([[1.0, 0.0]])
    f = pedestrian_force(pos, vel, np.array([[1.0, 1.0]]), np.zeros((1, 2)), **MOUSSAID)
    s2 = math.sqrt(0.5)
    ex, ey = -s2, -s2
    dx, dy = 2.0 * (0.0 - 1.0) + ex, 2.0 * 0.0 + ey
    dn = math.hypot(dx, dy)
    tx, ty = dx / dn, dy / dn
    theta = math.atan2(ty, tx) - math.atan2(ey, ex)  # -pi + 0.2554 - (-3 pi / 4), already in [-pi, pi)
    assert -math.pi < theta < 0
    b = 0.35 * dn
    d = math.sqrt(2.0)
    along = math.exp(-d / b - (3.0 * b * theta) ** 2)
    turn = math.exp(-d / b - (2.0 * b * theta) ** 2)  # -sign(theta) = +1
    expected = 4.5 * np.array([along * tx + turn * -ty, along * ty + turn * tx])
    np.testing.assert_allclose(f[0], expected, atol=1e-9)
    assert f[0, 1] < 0  # pushed to the right, away from j


def _pysocialforce(pos, vel, lambda_importance=2.0, gamma=0.35, n=2, n_prime=3, factor=4.5):
    """PySocialForce's SocialForce._get_force (pysocialforce/forces.py), transcribed line by line."""
    def each_diff(v):
        diff = v[:, None, :] - v[None, :, :]
        return diff[~np.eye(len(v), dtype=bool), :]

    def normalize(v):
        norms = np.linalg.norm(v, axis=-1)
        out = v / norms[:, None]
        out[norms == 0] = 0
        return out, norms

    pos_diff = each_diff(pos)
    diff_direction, diff_length = normalize(pos_diff)
    vel_diff = -1.0 * each_diff(vel)
    interaction_vec = lambda_importance * vel_diff + diff_direction
    interaction_direction, interaction_length = normalize(interaction_vec)
    theta = (np.arctan2(interaction_direction[:, 1], interaction_direction[:, 0])
             - np.arctan2(diff_direction[:, 1], diff_direction[:, 0]))
    B = gamma * interaction_length
    force_velocity_amount = np.exp(-1.0 * diff_length / B - np.square(n_prime * B * theta))
    force_angle_amount = -np.sign(theta) * np.exp(-1.0 * diff_length / B - np.square(n * B * theta))
    force_velocity = force_velocity_amount.reshape(-1, 1) * interaction_direction
    left = np.fliplr(interaction_direction) * np.array([-1.0, 1.0])
    force_angle = force_angle_amount.reshape(-1, 1) * left
    force = force_velocity + force_angle
    return np.sum(force.reshape((len(pos), -1, 2)), axis=1) * factor, theta


def test_matches_pysocialforce_where_its_angles_need_no_wrapping():
    # Pair by pair, PySocialForce's force on i from j equals ours wherever its
    # raw angle difference is already in (-pi, pi) (elsewhere it is not
    # wrapped there, see the next test).
    rng = np.random.default_rng(7)
    pos = rng.uniform(0, 4, (6, 2))
    vel = rng.normal(0, 1, (6, 2))
    compared = 0
    for i in range(6):
        for j in range(6):
            if i == j:
                continue
            ref, theta = _pysocialforce(pos[[i, j]], vel[[i, j]])
            if abs(theta[0]) >= math.pi:
                continue
            ours = pedestrian_force(pos[[i]], vel[[i]], pos[[j]], vel[[j]], **MOUSSAID)
            np.testing.assert_allclose(ours[0], ref[0], atol=1e-9)
            compared += 1
    assert compared >= 15


def test_wrapping_the_angle_keeps_a_pair_across_the_minus_x_axis_symmetric():
    # j dead behind-left of i across the -x axis: the raw angle difference is ~2 pi
    # (atan2 jumps from +pi to -pi); wrapped it is small, and mirroring the
    # configuration in y mirrors the force.
    pos = np.array([[0.0, 0.0]])
    vel = np.array([[1.0, 0.0]])
    for dy in (1e-3, -1e-3):
        other = np.array([[1.0, dy]])
        f = pedestrian_force(pos, vel, other, np.zeros((1, 2)), **MOUSSAID)
        g = pedestrian_force(pos, vel, other * [1, -1], np.zeros((1, 2)), **MOUSSAID)
        np.testing.assert_allclose(f * [1, -1], g, atol=1e-12)
        assert np.sign(f[0, 1]) == -np.sign(dy)  # pushed away from the side j is on


def test_coincident_people_and_self_pairs_add_nothing():
    pos = np.array([[1.0, 1.0], [1.0, 1.0]])
    vel = np.zeros((2, 2))
    np.testing.assert_array_equal(pedestrian_force(pos, vel, pos, vel, **MOUSSAID), np.zeros((2, 2)))
    assert pedestrian_force(np.zeros((0, 2)), np.zeros((0, 2)), pos, vel, **MOUSSAID).shape == (0, 2)


def test_box_nearest_outside_corner_and_inside_by_hand():
    c = math.cos(math.pi / 4)
    centers = np.array([[0.0, 0.0], [0.0, 0.0]])
    halves = np.array([[1.0, 1.0], [1.0, 1.0]])
    cos, sin = np.array([1.0, c]), np.array([0.0, c])
    d, n = box_nearest(np.array([[2.0, 0.5], [0.5, 0.2], [2.0, 0.0]]), centers, halves, cos, sin)
    # Axis-aligned box: (2, 0.5) is 1 m from the +x face; (0.5, 0.2) is inside,
    # 0.5 m from the +x face (0.8 from +y); (2, 0) is 1 m from the +x face.
    np.testing.assert_allclose(d[:, 0], [1.0, -0.5, 1.0], atol=1e-12)
    np.testing.assert_allclose(n[:, 0], [[1, 0], [1, 0], [1, 0]], atol=1e-12)
    # The box turned by 45 degrees has a corner at (sqrt 2, 0): (2, 0) is
    # 2 - sqrt 2 from it, along +x; (0.5, 0.2) is inside, nearest its
    # +x face in its own frame: distance |local x| - 1, normal (cos, sin).
    assert d[2, 1] == pytest.approx(2 - math.sqrt(2), abs=1e-12)
    np.testing.assert_allclose(n[2, 1], [1.0, 0.0], atol=1e-12)
    lx, ly = c * 0.5 + c * 0.2, -c * 0.5 + c * 0.2
    assert abs(lx) > abs(ly)
    assert d[1, 1] == pytest.approx(lx - 1.0, abs=1e-12)
    np.testing.assert_allclose(n[1, 1], [c, c], atol=1e-12)


def test_obstacle_force_is_exponential_in_the_surface_distance():
    centers, halves = np.array([[0.0, 0.0], [5.0, 0.0]]), np.array([[1.0, 1.0], [0.5, 2.0]])
    cos, sin = np.ones(2), np.zeros(2)
    f = obstacle_force(np.array([[2.0, 0.5]]), np.array([0.25]), centers, halves, cos, sin,
                       strength=10.0, range_=0.2)
    # Box 0: face x = 1, distance 1 - 0.25 = 0.75, pushes +x; box 1: face x = 4.5,
    # distance 2.5 - 0.25 = 2.25, pushes -x.
    expected = 10.0 * (math.exp(-0.75 / 0.2) - math.exp(-2.25 / 0.2))
    np.testing.assert_allclose(f, [[expected, 0.0]], atol=1e-9)
    assert obstacle_force(np.ones((3, 2)), np.ones(3), np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0),
                          np.zeros(0), strength=10.0, range_=0.2).shape == (3, 2)


def test_capsule_force_side_end_and_disc_by_hand():
    ends = np.array([[[0.0, 0.0], [2.0, 0.0]], [[5.0, 5.0], [5.0, 5.0]]])  # a link, then a disc
    radii = np.array([0.04, 0.35])
    pts = np.array([[1.0, 0.5], [3.0, 0.0], [5.0, 6.0]])
    d, n = capsule_nearest(pts, ends, radii)
    np.testing.assert_allclose(d[:, 0], [0.46, 0.96, math.hypot(3.0, 6.0) - 0.04], atol=1e-12)
    np.testing.assert_allclose(n[0, 0], [0, 1], atol=1e-12)
    np.testing.assert_allclose(n[1, 0], [1, 0], atol=1e-12)
    assert d[2, 1] == pytest.approx(1.0 - 0.35, abs=1e-12)
    np.testing.assert_allclose(n[2, 1], [0, 1], atol=1e-12)
    f = capsule_force(pts[:1], np.array([0.25]), ends, radii, strength=10.0, range_=0.2)
    d_disc = math.hypot(4.0, 4.5) - 0.35 - 0.25
    expected = (10.0 * math.exp(-(0.46 - 0.25) / 0.2) * np.array([0.0, 1.0])
                + 10.0 * math.exp(-d_disc / 0.2) * np.array([-4.0, -4.5]) / math.hypot(4.0, 4.5))
    np.testing.assert_allclose(f[0], expected, atol=1e-9)


def test_cap_speed_scales_down_only_the_fast():
    v = cap_speed(np.array([[3.0, 4.0], [0.3, 0.4], [0.0, 0.0]]), np.array([2.5, 2.5, 1.0]))
    np.testing.assert_allclose(v, [[1.5, 2.0], [0.3, 0.4], [0.0, 0.0]], atol=1e-12)
