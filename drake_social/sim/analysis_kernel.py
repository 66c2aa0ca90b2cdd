"""The compiled inner loops of :func:`drake_social.sim.analysis.point_deviation` (numba).

Two loops over the executed points of one body point, each the same
arithmetic as the numpy formulation it replaces, point by point, so that the
figures agree to rounding:

* :func:`nearest_segments`: among the polyline segments next to a point's
  nearest vertices (found by a KD-tree), the one nearest the point.
* :func:`step_distances`: the distance from a point to the true curve that
  the body point traces along the densified planned path, over the dense
  step of that segment and the steps either side: each step's ends and
  Newton's iterates of the nearest point from the chord's projection (the
  numpy formulation searches each step by golden sections; both give the
  distance to a point of the curve, the same to ~1e-9 m).

Without numba both run as plain Python (slow, but the same figures).
"""

from __future__ import annotations

import math

import numpy as np

from drake_social.cost.kernel import AVAILABLE, njit

__all__ = ["AVAILABLE", "nearest_segments", "step_distances"]


@njit(cache=True)
def nearest_segments(points, curve, nearest):
    """Index (T,) of the segment of the polyline ``curve`` (M >= 2, 2) nearest
    each point (T, 2) among the segments ``i -> i + 1`` for ``i`` one of the
    point's candidate vertices ``nearest`` (T, k) or the one before it
    (clipped to the segments); ties keep the first found, vertices before
    their predecessors."""
    t_count, k = nearest.shape
    last = curve.shape[0] - 2
    out = np.zeros(t_count, np.int64)
    for t in range(t_count):
        px, py = points[t, 0], points[t, 1]
        best = np.inf
        best_i = 0
        for shift in range(2):
            found = np.inf
            found_i = 0
            for c in range(k):
                i = nearest[t, c] - shift
                i = 0 if i < 0 else (last if i > last else i)
                ax, ay = curve[i, 0], curve[i, 1]
                dx, dy = curve[i + 1, 0] - ax, curve[i + 1, 1] - ay
                dd = dx * dx + dy * dy
                u = 0.0
                if dd > 0:
                    u = ((px - ax) * dx + (py - ay) * dy) / dd
                    u = 0.0 if u < 0.0 else (1.0 if u > 1.0 else u)
                ex, ey = px - (ax + u * dx), py - (ay + u * dy)
                dist = math.sqrt(ex * ex + ey * ey)
                if dist < found:
                    found, found_i = dist, i
            if found < best:
                best, best_i = found, found_i
        out[t] = best_i
    return out


@njit(cache=True)
def _point(dense, i, f, kind, l1, l2, gx, gy):
    """The body point at fraction ``f`` of the dense step ``i`` (linear in q),
    with its first and second derivatives in ``f``: ``kind`` 0 the base
    centre, 1 the elbow, 2 the point (gx, gy) of the gripper frame."""
    d0, d1 = dense[i + 1, 0] - dense[i, 0], dense[i + 1, 1] - dense[i, 1]
    x, y = dense[i, 0] + f * d0, dense[i, 1] + f * d1
    dx, dy, ddx, ddy = d0, d1, 0.0, 0.0
    if kind >= 1:
        d2 = dense[i + 1, 2] - dense[i, 2]
        q2 = dense[i, 2] + f * d2
        c1, s1 = l1 * math.cos(q2), l1 * math.sin(q2)
        x += c1
        y += s1
        dx -= s1 * d2
        dy += c1 * d2
        ddx -= c1 * d2 * d2
        ddy -= s1 * d2 * d2
        if kind == 2:
            d3 = d2 + dense[i + 1, 3] - dense[i, 3]
            q3 = q2 + dense[i, 3] + f * (dense[i + 1, 3] - dense[i, 3])
            c, s = math.cos(q3), math.sin(q3)
            tx, ty = c * (l2 + gx) - s * gy, s * (l2 + gx) + c * gy
            x += tx
            y += ty
            dx -= ty * d3
            dy += tx * d3
            ddx -= tx * d3 * d3
            ddy -= ty * d3 * d3
    return x, y, dx, dy, ddx, ddy


@njit(cache=True)
def _step_distance(dense, i, kind, l1, l2, gx, gy, px, py, iterations):
    """Smallest distance from (px, py) found on the body point's curve along
    the dense step ``i``: its two ends and the Newton iterates of the
    stationary point of the squared distance, from the chord's projection.
    Every figure is the distance to a point of the curve (an upper bound of
    the true one); on a step whose curve bends little (the dense steps are a
    few millimetres), Newton's iterates converge to the nearest point."""
    x0, y0, _, _, _, _ = _point(dense, i, 0.0, kind, l1, l2, gx, gy)
    x1, y1, _, _, _, _ = _point(dense, i, 1.0, kind, l1, l2, gx, gy)
    best = min(math.hypot(x0 - px, y0 - py), math.hypot(x1 - px, y1 - py))
    cx, cy = x1 - x0, y1 - y0
    cc = cx * cx + cy * cy
    f = 0.0
    if cc > 0:
        f = ((px - x0) * cx + (py - y0) * cy) / cc
        f = 0.0 if f < 0.0 else (1.0 if f > 1.0 else f)
    for _ in range(iterations):
        x, y, dx, dy, ddx, ddy = _point(dense, i, f, kind, l1, l2, gx, gy)
        ex, ey = x - px, y - py
        best = min(best, math.hypot(ex, ey))
        g = ex * dx + ey * dy
        h = dx * dx + dy * dy + ex * ddx + ey * ddy
        if not h > 0.0:
            break
        new = f - g / h
        new = 0.0 if new < 0.0 else (1.0 if new > 1.0 else new)
        if new == f:
            break
        f = new
    else:
        x, y, _, _, _, _ = _point(dense, i, f, kind, l1, l2, gx, gy)
        best = min(best, math.hypot(x - px, y - py))
    return best


@njit(cache=True)
def step_distances(dense, points, steps, kind, l1, l2, gx, gy, iterations):
    """Smallest distance (T,) of each point (T, 2) from the body point's curve
    along the dense steps ``steps[t] - 1``, ``steps[t]``, ``steps[t] + 1``
    (clipped) of ``dense`` (M >= 2, 4), each step searched on its own
    (:func:`_step_distance`, at most ``iterations`` Newton steps)."""
    last = dense.shape[0] - 1
    out = np.empty(points.shape[0])
    for t in range(points.shape[0]):
        found = np.inf
        for offset in range(-1, 2):
            step = steps[t] + offset
            step = 0 if step < 0 else (last - 1 if step > last - 1 else step)
            found = min(found, _step_distance(dense, step, kind, l1, l2, gx, gy, points[t, 0], points[t, 1],
                                              iterations))
        out[t] = found
    return out
