"""The motion social cost Msc as one compiled loop (numba).

:meth:`drake_social.cost.social.SocialCost.motion_cost` batches the same
computation with numpy; in the planner that batch is small (about 25 motions
of about 30 samples each) and numpy's per-operation overhead dominates. This
kernel does exactly the same arithmetic in one pass: for every motion, the
step count from the displacement bound, every person's window from the
distance bound at the motion's ends, and the threshold-aware trapezoid areas
of every (sample step, point) inside it. ``SocialCost`` uses it when numba is
importable and keeps the numpy path as the reference it is tested against.
"""

from __future__ import annotations

import math

import numpy as np

try:  # numba is a runtime dependency; the numpy path stays usable without it.
    from numba import njit

    AVAILABLE = True
except ImportError:  # pragma: no cover - exercised only where numba is missing
    AVAILABLE = False

    def njit(*args, **kwargs):
        return lambda f: f


__all__ = ["AVAILABLE", "msc_sums"]


@njit(cache=True)
def _points(q0, q1, q2, q3, l1, l2, obj, active, xs, ys):
    """Interest points ``active`` of configuration q into xs, ys (as
    ArmGeometry.interest_xy: the gripper angle by angle addition)."""
    c1, s1 = math.cos(q2), math.sin(q2)
    c2, s2 = math.cos(q3), math.sin(q3)
    c12 = c1 * c2 - s1 * s2
    s12 = s1 * c2 + c1 * s2
    ex, ey = q0 + l1 * c1, q1 + l1 * s1
    gx, gy = ex + l2 * c12, ey + l2 * s12
    for j in range(active.shape[0]):
        p = active[j]
        if p == 0:
            xs[j], ys[j] = q0, q1
        elif p == 1:
            xs[j], ys[j] = ex, ey
        elif p == 2:
            xs[j], ys[j] = gx, gy
        else:
            px, py = obj[p - 3, 0], obj[p - 3, 1]
            xs[j] = gx + c12 * px - s12 * py
            ys[j] = gy + s12 * px + c12 * py


@njit(cache=True)
def _gaussian(dx, dy, c, s, inv_front, inv_rear, inv_side):
    u = c * dx + s * dy
    v = c * dy - s * dx
    return math.exp(-(u * u * (inv_front if u > 0 else inv_rear) + v * v * inv_side))


@njit(cache=True)
def msc_sums(
    q_a, q_b, people, l1, l2, obj, active, weights, lever, resolution, reach, inv_front, inv_rear, inv_side, tau
):
    """Per motion (E,): the sum over steps of the weighted trapezoid areas
    (multiply by h = length / n for Msc) and the step count n.

    Args mirror SocialCost: people (H, 3); obj (P, 2) object interest points
    in the gripper frame; active (K,) interest-point indices with weights (K,);
    lever (c_shoulder, c_gripper); reach: the AGF's largest reach (inf for
    no culling).
    """
    e_count, h_count, k_count = q_a.shape[0], people.shape[0], active.shape[0]
    sums = np.zeros(e_count)
    steps = np.ones(e_count, dtype=np.int64)
    cos_t = np.cos(people[:, 2])
    sin_t = np.sin(people[:, 2])
    xa, ya = np.empty(k_count), np.empty(k_count)
    xb, yb = np.empty(k_count), np.empty(k_count)
    xs, ys = np.empty(k_count), np.empty(k_count)
    g_prev = np.empty(k_count)
    for e in range(e_count):
        d0, d1 = q_b[e, 0] - q_a[e, 0], q_b[e, 1] - q_a[e, 1]
        d2, d3 = q_b[e, 2] - q_a[e, 2], q_b[e, 3] - q_a[e, 3]
        span = math.hypot(d0, d1) + lever[0] * abs(d2) + lever[1] * abs(d2 + d3)
        n = max(1, int(math.ceil(span / resolution - 1e-9)))
        steps[e] = n
        if d0 == 0.0 and d1 == 0.0 and d2 == 0.0 and d3 == 0.0:
            continue
        _points(q_a[e, 0], q_a[e, 1], q_a[e, 2], q_a[e, 3], l1, l2, obj, active, xa, ya)
        _points(q_b[e, 0], q_b[e, 1], q_b[e, 2], q_b[e, 3], l1, l2, obj, active, xb, yb)
        total = 0.0
        for h in range(h_count):
            px, py, c, s = people[h, 0], people[h, 1], cos_t[h], sin_t[h]
            # The window of the motion where this person can matter.
            relevant = False
            near_a, near_b = math.inf, math.inf
            for j in range(k_count):
                da = math.hypot(xa[j] - px, ya[j] - py) - reach
                db = math.hypot(xb[j] - px, yb[j] - py) - reach
                if da + db <= span:
                    relevant = True
                near_a, near_b = min(near_a, da), min(near_b, db)
            if not relevant:
                continue
            t0, t1 = 0.0, 1.0
            if span > 0 and math.isfinite(reach):
                t0 = min(max(near_a / span, 0.0), 1.0)
                t1 = min(max(1.0 - near_b / span, 0.0), 1.0)
            k0 = int(math.floor(t0 * n))
            k1 = min(int(math.ceil(t1 * n)), n)
            k1 = max(k1, k0 + 1)
            k0 = min(k0, k1 - 1)
            for k in range(k0, k1 + 1):
                t = k / n
                _points(
                    q_a[e, 0] + t * d0, q_a[e, 1] + t * d1, q_a[e, 2] + t * d2, q_a[e, 3] + t * d3,
                    l1, l2, obj, active, xs, ys,
                )
                for j in range(k_count):
                    g = _gaussian(xs[j] - px, ys[j] - py, c, s, inv_front, inv_rear, inv_side)
                    if k > k0:
                        g0 = g_prev[j]
                        up0, up1 = g0 > tau, g > tau
                        if up0 and up1:
                            total += weights[j] * 0.5 * (g0 + g)
                        elif up0 or up1:
                            hi, lo = max(g0, g), min(g0, g)
                            total += weights[j] * 0.5 * (hi + tau) * (hi - tau) / (hi - lo)
                    g_prev[j] = g
        sums[e] = total
    return sums, steps
