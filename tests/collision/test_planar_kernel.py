"""The compiled planar kernel alone (no Drake): exact distances, the displacement bound, advancement."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_social.kinematics import displacement_bound
from drake_social.collision import planar_kernel as dut
from drake_social.collision.broadphase import build_grid


def golden_min(f, n_iter: int = 120):
    """min over t in [0, 1] of a convex f (vectorised): golden-section search
    plus both ends; an independent numerical method, not the kernel's closed form."""
    lo, hi = 0.0, 1.0
    g = (math.sqrt(5) - 1) / 2
    lo = np.zeros_like(f(0.0))
    hi = np.ones_like(lo)
    for _ in range(n_iter):
        a, b = hi - g * (hi - lo), lo + g * (hi - lo)
        left = f(a) < f(b)
        hi = np.where(left, b, hi)
        lo = np.where(left, lo, a)
    return np.minimum(np.minimum(f(0.0), f(1.0)), f(0.5 * (lo + hi)))


def box_sdf(px, py, cx, cy, yaw, hx, hy):
    c, s = np.cos(yaw), np.sin(yaw)
    u, v = c * (px - cx) + s * (py - cy), -s * (px - cx) + c * (py - cy)
    ux, uy = np.abs(u) - hx, np.abs(v) - hy
    return np.hypot(np.maximum(ux, 0), np.maximum(uy, 0)) + np.minimum(np.maximum(ux, uy), 0)


@pytest.mark.slow
def test_segment_box_distance_equals_an_independent_minimisation(rng):
    """30,000 random (segment, rotated box) pairs: disjoint ones exact to 1e-9,
    crossing ones negative and never below the least box signed distance along the axis."""
    n = 30_000
    a, b = rng.uniform(-3, 3, (n, 2)), rng.uniform(-3, 3, (n, 2))
    b[: n // 10] = a[: n // 10]  # discs
    c, yaw = rng.uniform(-1, 1, (n, 2)), rng.uniform(-math.pi, math.pi, n)
    h = rng.uniform(0.05, 1.5, (n, 2))
    got = np.array([dut.segment_box_distance(*a[i], *b[i], *c[i], math.cos(yaw[i]), math.sin(yaw[i]), *h[i])
                    for i in range(n)])
    ref = golden_min(lambda t: box_sdf(a[:, 0] + t * (b[:, 0] - a[:, 0]), a[:, 1] + t * (b[:, 1] - a[:, 1]),
                                       c[:, 0], c[:, 1], yaw, h[:, 0], h[:, 1]))
    apart = ref > 1e-12
    assert 0.3 < apart.mean() < 0.9  # both cases exercised
    np.testing.assert_allclose(got[apart], ref[apart], atol=1e-9, rtol=0)
    assert np.all(got[~apart] <= 1e-12) and np.all(got[~apart] >= ref[~apart] - 1e-12)


def test_segment_disc_distance_equals_an_independent_minimisation(rng):
    """10,000 random (segment, disc) pairs, exact to 1e-9 whether apart or not."""
    n = 10_000
    a, b, c = rng.uniform(-2, 2, (n, 2)), rng.uniform(-2, 2, (n, 2)), rng.uniform(-2, 2, (n, 2))
    r = rng.uniform(0.0, 0.5, n)
    got = np.array([dut.segment_disc_distance(*a[i], *b[i], *c[i], r[i]) for i in range(n)])
    ref = golden_min(lambda t: np.hypot(a[:, 0] + t * (b[:, 0] - a[:, 0]) - c[:, 0],
                                        a[:, 1] + t * (b[:, 1] - a[:, 1]) - c[:, 1]) - r)
    np.testing.assert_allclose(got, ref, atol=1e-9, rtol=0)


def test_displacement_is_the_kinematics_bound(rng):
    dq = rng.normal(size=(500, 4))
    lever = np.array([0.7, 2.3])
    np.testing.assert_allclose([dut.displacement(d, lever) for d in dq], displacement_bound(dq, lever), rtol=1e-15)


# ---- a hand-made scene: base disc r = 0.3, one link of 2 m (capsule r = 0.05) on psi1.


def _scene(obstacles):
    bodies = np.array([[-1, 0, 0, 1, 0, -1], [0, 0, 0, 1, 0, 2], [1, 2.0, 0, 1, 0, 3]], float)
    robot = np.array([[0, 0, 0, 0, 0, 0.3], [1, 0, 0, 2.0, 0, 0.05]], float)
    env = np.array([[dut.BOX, cx, cy, math.cos(yaw), math.sin(yaw), hx, hy, math.hypot(hx, hy)]
                    for cx, cy, yaw, hx, hy in obstacles], float).reshape(-1, 8)
    lever = np.array([[0.0, 0.0], [2.05, 0.0]])  # per capsule: the base disc, the link
    lower, upper = np.array([-10, -10, -math.pi, -math.pi]), np.array([10, 10, math.pi, math.pi])
    return bodies, robot, env, lever, lower, upper


def test_clearance_of_the_hand_made_scene():
    bodies, robot, env, *_ = _scene([(3.0, 0.0, math.pi / 4, 0.1, 0.1)])  # a diamond, corner at x = 3 - 0.1 sqrt 2
    q = np.array([0.0, 0.0, 0.0, 0.0])
    assert dut.clearance(q, bodies, robot, env, build_grid(env)) == pytest.approx(3 - 0.1 * math.sqrt(2) - 2.05, abs=1e-12)
    q = np.array([0.0, 0.0, math.pi / 2, 0.0])  # the link points up: the base is nearest
    assert dut.clearance(q, bodies, robot, env, build_grid(env)) == pytest.approx(3 - 0.1 * math.sqrt(2) - 0.3, abs=1e-12)
    assert dut.clearance(q, bodies, robot, env[:0], build_grid(env[:0])) == math.inf  # an empty room


def test_a_thin_wall_swept_by_the_link_tip_is_caught_at_any_speed():
    # Link tip at radius 2.05 sweeps psi1 from -0.5 to 0.5 past a 2 cm wall at x = 1.95..2.0 (radially).
    bodies, robot, env, lever, lower, upper = _scene([(1.975, 0.0, 0.0, 0.01, 0.1)])
    q_a, q_b = np.array([0.0, 0.0, -0.5, 0.0]), np.array([0.0, 0.0, 0.5, 0.0])
    assert dut.clearance(q_a, bodies, robot, env, build_grid(env)) > 0.0 and dut.clearance(q_b, bodies, robot, env, build_grid(env)) > 0.0
    assert not dut.motion_valid(q_a, q_b, lower, upper, bodies, robot, env, build_grid(env), lever)
    assert not dut.motion_valid(q_b, q_a, lower, upper, bodies, robot, env, build_grid(env), lever)
    # Turning the other way round the wall (through pi) is free.
    q_c = np.array([0.0, 0.0, math.pi - 0.01, 0.0])
    assert dut.motion_valid(q_b, q_c, lower, upper, bodies, robot, env, build_grid(env), lever)
    # Limits: an end outside them rejects the motion.
    assert not dut.motion_valid(q_b, np.array([0.0, 0.0, 4.0, 0.0]), lower, upper, bodies, robot, env, build_grid(env), lever)


def test_zero_length_and_grazing_motions(rng):
    bodies, robot, env, lever, lower, upper = _scene([(0.0, 1.0, 0.0, 1.0, 0.2)])  # a slab above, y 0.8..1.2
    q = np.array([0.0, 0.5 - 1e-10, -math.pi / 2, 0.0])  # base 1e-10 below the slab
    assert dut.valid(q[None], lower, upper, bodies, robot, env, build_grid(env))[0]
    assert not dut.motion_valid(q, q, lower, upper, bodies, robot, env, build_grid(env), lever)  # within TOLERANCE
    q = np.array([0.0, 0.4, -math.pi / 2, 0.0])
    assert dut.motion_valid(q, q, lower, upper, bodies, robot, env, build_grid(env), lever)
    # Passing under the slab 1 mm clear (valid) or 1 mm into it (invalid), both ends clear of it.
    for y, free in ((0.499, True), (0.501, False)):
        q_a, q_b = np.array([-3.0, y, -math.pi / 2, 0.0]), np.array([3.0, y, -math.pi / 2, 0.0])
        assert dut.clearance(q_a, bodies, robot, env, build_grid(env)) > 0.5 and dut.clearance(q_b, bodies, robot, env, build_grid(env)) > 0.5
        assert dut.motion_valid(q_a, q_b, lower, upper, bodies, robot, env, build_grid(env), lever) == free


def test_batched_calls_equal_single_calls(rng):
    bodies, robot, env, lever, lower, upper = _scene([(2.0, 1.0, 0.3, 0.4, 0.2), (-1.0, -2.0, 1.0, 0.3, 0.6)])
    q_a = rng.uniform([-4, -4, -3, -3], [4, 4, 3, 3], (400, 4))
    q_b = q_a + rng.normal(scale=0.7, size=q_a.shape)
    np.testing.assert_array_equal(dut.motions_valid(q_a, q_b, lower, upper, bodies, robot, env, build_grid(env), lever),
                                  [dut.motion_valid(a, b, lower, upper, bodies, robot, env, build_grid(env), lever)
                                   for a, b in zip(q_a, q_b)])
    np.testing.assert_array_equal(dut.clearances(q_a, bodies, robot, env, build_grid(env)),
                                  [dut.clearance(q, bodies, robot, env, build_grid(env)) for q in q_a])


def test_the_advancement_queue_is_first_in_first_out_through_its_growth():
    """queue_start / queue_pop / queue_split (the planar and the people's
    motion checks' search) against a deque: random queries clear random
    steps; the queue holds more than its first 64 slots, doubles in order and
    splits each interval into what the query leaves, empty parts dropped."""
    from collections import deque

    rng = np.random.default_rng(5)
    buffer, ends = dut.queue_start(0.0, 1.0)
    model = deque([(0.0, 1.0)])
    largest = 0
    for _ in range(3000):
        if not model:
            break
        a, b = dut.queue_pop(buffer, ends)
        assert (a, b) == model.popleft()
        t = 0.5 * (a + b)
        # Mostly tiny steps (the queue grows), sometimes one that clears the interval.
        tau = (b - a) * (0.6 if rng.random() < 0.05 else 1e-3 * rng.random())
        buffer = dut.queue_split(buffer, ends, a, b, t, tau)
        model.extend(iv for iv in ((a, t - tau), (t + tau, b)) if iv[0] <= iv[1])
        assert ends[1] - ends[0] == len(model)
        largest = max(largest, len(model))
    assert largest > 64 and buffer.shape[0] >= largest  # it grew
    remaining = []
    while ends[0] != ends[1]:
        remaining.append(dut.queue_pop(buffer, ends))
    assert remaining == list(model)
