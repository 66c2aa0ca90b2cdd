"""Exact planar signed distances and a sound motion check, compiled (numba).

The scene is planar by construction (every collision shape is a vertical
extrusion over the same slab, see :mod:`drake_social.model.plant`), so the
distance between two shapes is the 2-D distance between their footprints.
This module works on footprints only, in plain arrays; the Drake adapter
:class:`drake_social.model.planar_checker.PlanarChecker` reads them from the
SceneGraph. No pydrake here.

Footprints (metres, radians):

* **robot**: capsules, one row ``[body, ax, ay, bx, by, r]`` each: the axis
  ``a -> b`` in the frame of body ``body`` and the radius ``r``. A disc is a
  capsule with ``a == b``; a Drake *stadium* (box + two end cylinders) is one
  capsule.
* **bodies**: a planar chain, one row ``[parent, ox, oy, oc, os, joint]`` per
  body, parents first. The pose of the root (``parent = -1``) is ``(x, y)``
  = ``(q[0] + ox, q[1] + oy)`` with rotation ``(oc, os)`` (cos, sin); a child
  is ``X_WC = X_WP X_PC R(q[joint])`` with ``X_PC`` = translation ``(ox, oy)``
  and rotation ``(oc, os)``, and no joint rotation when ``joint = -1`` (a
  weld). Body poses are ``[x, y, c, s]``.
* **environment**: one row ``[kind, cx, cy, c, s, hx, hy, rho]`` per shape:
  kind 0 is a box of half sizes ``(hx, hy)`` at ``(cx, cy)`` rotated by
  ``(c, s)``; kind 1 a disc of radius ``hx``. ``rho`` bounds the distance of
  any of its points from ``(cx, cy)``.

Distances. Signed distances are **exact when positive**:

* capsule to disc: point-to-segment distance minus both radii (exact, also
  when negative);
* capsule to box: the axis is clipped against the box (Liang-Barsky in the
  box frame). Disjoint: the distance of two disjoint convex polygons is
  attained at a vertex of one of them, so it is the least of the axis ends'
  distances to the box and the four corners' distances to the axis, minus
  ``r``. Crossing: the box's signed-distance function at the axis ends and
  the midpoint of the clipped part, all <= 0, minus ``r``: negative, and
  never below minus the penetration depth (only the sign is meaningful).

The clearance of a configuration is the least signed distance over all
(capsule, shape) pairs. A broad phase skips pairs whose bounding circles are
already further apart than the best value found (``|m - c| - rho_a - rho_b``
is a lower bound of their distance), which never changes the result.

Motions: :func:`motion_valid` by conservative advancement, see there.
"""

from __future__ import annotations

import math

import numpy as np

try:  # numba is a runtime dependency; without it these run (slowly) as Python.
    from numba import njit

    AVAILABLE = True
except ImportError:  # pragma: no cover - exercised only where numba is missing
    AVAILABLE = False

    def njit(*args, **kwargs):
        return lambda f: f


__all__ = [
    "AVAILABLE",
    "BOX",
    "DISC",
    "MAX_STEPS",
    "STEP_MARGIN",
    "TOLERANCE",
    "body_poses",
    "clearance",
    "clearances",
    "displacement",
    "motion_valid",
    "motions_valid",
    "pair_distances",
    "segment_box_distance",
    "segment_disc_distance",
    "valid",
    "world_capsules",
]

#: Environment shape kinds (column 0 of the environment rows).
BOX, DISC = 0, 1
#: A motion is rejected where a reached configuration is within this of
#: contact, metres (it keeps the advancement steps from shrinking to zero).
TOLERANCE = 1e-9
#: Each advancement step is shortened by this distance, metres, so that the
#: rounding of distances and poses (~1e-14 m) cannot make a step too long.
STEP_MARGIN = 1e-10
#: A motion needing more clearance queries than this is rejected
#: (conservative: it grazes an obstacle for a long stretch).
MAX_STEPS = 100_000


@njit(cache=True)
def _point_segment(px, py, ax, ay, bx, by):
    """Distance from point p to segment [a, b]."""
    dx, dy = bx - ax, by - ay
    wx, wy = px - ax, py - ay
    den = dx * dx + dy * dy
    t = 0.0
    if den > 0.0:
        t = (wx * dx + wy * dy) / den
        t = min(max(t, 0.0), 1.0)
    ex, ey = wx - t * dx, wy - t * dy
    return math.sqrt(ex * ex + ey * ey)


@njit(cache=True)
def _box_sdf(u, v, hx, hy):
    """Signed distance of point (u, v), in the box frame, to the box."""
    ux, uy = abs(u) - hx, abs(v) - hy
    mx, my = max(ux, 0.0), max(uy, 0.0)
    return math.sqrt(mx * mx + my * my) + min(max(ux, uy), 0.0)


@njit(cache=True)
def segment_disc_distance(ax, ay, bx, by, cx, cy, radius):
    """Signed distance of segment [a, b] to the disc (c, radius), metres."""
    return _point_segment(cx, cy, ax, ay, bx, by) - radius


@njit(cache=True)
def segment_box_distance(ax, ay, bx, by, cx, cy, c, s, hx, hy):
    """Signed distance of segment [a, b] to the box (centre c, rotation (c, s),
    half sizes hx, hy): exact when they are disjoint, <= 0 when they meet."""
    # Into the box frame.
    au, av = c * (ax - cx) + s * (ay - cy), c * (ay - cy) - s * (ax - cx)
    bu, bv = c * (bx - cx) + s * (by - cy), c * (by - cy) - s * (bx - cx)
    du, dv = bu - au, bv - av
    # Liang-Barsky: the parameter interval [t0, t1] of the axis inside the box.
    t0, t1 = 0.0, 1.0
    meets = True
    for k in range(2):
        p0, d, h = (au, du, hx) if k == 0 else (av, dv, hy)
        if d == 0.0:
            if abs(p0) > h:
                meets = False
        else:
            ta, tb = (-h - p0) / d, (h - p0) / d
            if ta > tb:
                ta, tb = tb, ta
            t0, t1 = max(t0, ta), min(t1, tb)
            if t0 > t1:
                meets = False
    if meets:
        tm = 0.5 * (t0 + t1)
        inner = _box_sdf(au + tm * du, av + tm * dv, hx, hy)
        return min(min(inner, 0.0), min(_box_sdf(au, av, hx, hy), _box_sdf(bu, bv, hx, hy)))
    best = min(_box_sdf(au, av, hx, hy), _box_sdf(bu, bv, hx, hy))
    for k in range(4):
        qu = hx if k < 2 else -hx
        qv = hy if k % 2 == 0 else -hy
        best = min(best, _point_segment(qu, qv, au, av, bu, bv))
    return best


@njit(cache=True)
def body_poses(q, bodies):
    """World poses (B, 4) ``[x, y, cos, sin]`` of the chain ``bodies`` at q (4,)."""
    n = bodies.shape[0]
    out = np.empty((n, 4))
    for i in range(n):
        parent, ox, oy, oc, os_ = int(bodies[i, 0]), bodies[i, 1], bodies[i, 2], bodies[i, 3], bodies[i, 4]
        joint = int(bodies[i, 5])
        if parent < 0:
            x, y, c, s = q[0] + ox, q[1] + oy, oc, os_
        else:
            px, py, pc, ps = out[parent, 0], out[parent, 1], out[parent, 2], out[parent, 3]
            x, y = px + pc * ox - ps * oy, py + ps * ox + pc * oy
            c, s = pc * oc - ps * os_, ps * oc + pc * os_
        if joint >= 0:
            jc, js = math.cos(q[joint]), math.sin(q[joint])
            c, s = c * jc - s * js, s * jc + c * js
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = x, y, c, s
    return out


@njit(cache=True)
def world_capsules(q, bodies, robot):
    """The robot's capsules (S, 5) ``[ax, ay, bx, by, r]`` in the world at q."""
    poses = body_poses(q, bodies)
    n = robot.shape[0]
    out = np.empty((n, 5))
    for j in range(n):
        b = int(robot[j, 0])
        x, y, c, s = poses[b, 0], poses[b, 1], poses[b, 2], poses[b, 3]
        out[j, 0] = x + c * robot[j, 1] - s * robot[j, 2]
        out[j, 1] = y + s * robot[j, 1] + c * robot[j, 2]
        out[j, 2] = x + c * robot[j, 3] - s * robot[j, 4]
        out[j, 3] = y + s * robot[j, 3] + c * robot[j, 4]
        out[j, 4] = robot[j, 5]
    return out


@njit(cache=True)
def _pair(cap, j, env, k):
    """Signed distance between world capsule j and environment shape k."""
    ax, ay, bx, by, r = cap[j, 0], cap[j, 1], cap[j, 2], cap[j, 3], cap[j, 4]
    if env[k, 0] == DISC:
        return segment_disc_distance(ax, ay, bx, by, env[k, 1], env[k, 2], env[k, 5]) - r
    return segment_box_distance(ax, ay, bx, by, env[k, 1], env[k, 2], env[k, 3], env[k, 4], env[k, 5], env[k, 6]) - r


@njit(cache=True)
def _clearance(q, bodies, robot, env):
    cap = world_capsules(q, bodies, robot)
    best = np.inf
    for j in range(cap.shape[0]):
        mx, my = 0.5 * (cap[j, 0] + cap[j, 2]), 0.5 * (cap[j, 1] + cap[j, 3])
        rho = 0.5 * math.hypot(cap[j, 2] - cap[j, 0], cap[j, 3] - cap[j, 1]) + cap[j, 4]
        for k in range(env.shape[0]):
            # Broad phase: a lower bound of the pair's distance (bounding circles).
            if math.hypot(mx - env[k, 1], my - env[k, 2]) - rho - env[k, 7] >= best:
                continue
            best = min(best, _pair(cap, j, env, k))
    return best


@njit(cache=True)
def clearance(q, bodies, robot, env):
    """The least signed distance (metres) from the robot to the environment
    at q (4,); exact when positive, inf without environment shapes."""
    return _clearance(q, bodies, robot, env)


@njit(cache=True)
def clearances(qs, bodies, robot, env):
    """:func:`clearance` of configurations (N, 4) -> (N,)."""
    out = np.empty(qs.shape[0])
    for i in range(qs.shape[0]):
        out[i] = _clearance(qs[i], bodies, robot, env)
    return out


@njit(cache=True)
def pair_distances(q, bodies, robot, env):
    """Signed distances (S, K) of every (capsule, shape) pair at q (for reports)."""
    cap = world_capsules(q, bodies, robot)
    out = np.empty((cap.shape[0], env.shape[0]))
    for j in range(cap.shape[0]):
        for k in range(env.shape[0]):
            out[j, k] = _pair(cap, j, env, k)
    return out


@njit(cache=True)
def _in_limits(q, lower, upper):
    for i in range(4):
        if not (lower[i] <= q[i] <= upper[i]):  # NaN fails too
            return False
    return True


@njit(cache=True)
def valid(qs, lower, upper, bodies, robot, env):
    """(N,) bool: configurations (N, 4) within the limits at clearance > 0."""
    out = np.zeros(qs.shape[0], dtype=np.bool_)
    for i in range(qs.shape[0]):
        out[i] = _in_limits(qs[i], lower, upper) and _clearance(qs[i], bodies, robot, env) > 0.0
    return out


@njit(cache=True)
def displacement(dq, lever):
    """``hypot(dx, dy) + c_s |dpsi1| + c_g |dpsi1 + dpsi2|``: the bound of
    :func:`drake_social.kinematics.displacement_bound`, per unit of t."""
    return math.hypot(dq[0], dq[1]) + lever[0] * abs(dq[2]) + lever[1] * abs(dq[2] + dq[3])


@njit(cache=True)
def _motion_valid(q_a, q_b, lower, upper, bodies, robot, env, lever):
    if not (_in_limits(q_a, lower, upper) and _in_limits(q_b, lower, upper)):
        return False
    dq = q_b - q_a
    span = displacement(dq, lever)
    c = _clearance(q_a, bodies, robot, env)
    if c <= TOLERANCE:
        return False
    if span == 0.0:
        return True
    lo = (c - STEP_MARGIN) / span  # [0, lo) is cleared
    c = _clearance(q_b, bodies, robot, env)
    if c <= TOLERANCE:
        return False
    hi = 1.0 - (c - STEP_MARGIN) / span  # (hi, 1] is cleared
    q = np.empty(4)
    for _ in range(MAX_STEPS):
        if lo > hi:
            return True
        for i in range(4):
            q[i] = q_a[i] + lo * dq[i]
        c = _clearance(q, bodies, robot, env)
        if c <= TOLERANCE:
            return False
        lo += (c - STEP_MARGIN) / span
        if lo > hi:
            return True
        for i in range(4):
            q[i] = q_a[i] + hi * dq[i]
        c = _clearance(q, bodies, robot, env)
        if c <= TOLERANCE:
            return False
        hi -= (c - STEP_MARGIN) / span
    return False


@njit(cache=True)
def motion_valid(q_a, q_b, lower, upper, bodies, robot, env, lever):
    """Whether the straight motion ``q_a + t (q_b - q_a)``, t in [0, 1], is free.

    Conservative advancement, from both ends towards the middle. Soundness:
    along the motion every body point moves with speed at most
    ``D = displacement(q_b - q_a, lever)`` per unit of t (the velocity of a
    point is the base's plus the rotations' about the shoulder and the elbow;
    ``lever`` bounds their arms, :meth:`ArmGeometry.lever`). If the robot is
    at clearance ``c > 0`` at ``q(t)``, then for ``|t' - t| < c / D`` every
    point of it is less than ``c`` from where it was, and every environment
    point is at least ``c`` from there, so ``q(t')`` is free (triangle
    inequality). The clearance is exact when positive, so each query clears
    ``[t, t + c / D)`` (from the start) or ``(t - c / D, t]`` (from the end);
    the next query sits at the first point not yet cleared, and the motion
    is valid once the two cleared parts overlap. Both end points are checked
    exactly. Floors: a reached configuration within :data:`TOLERANCE` of
    contact rejects the motion (so steps never shrink below
    ``TOLERANCE / D``), steps are ``STEP_MARGIN`` metres shorter than
    allowed (rounding), and more than :data:`MAX_STEPS` queries reject it.
    Rejecting is always safe.

    Args:
        q_a, q_b: the ends (4,).
        lower, upper: limits (4,); the limits are a box, so a motion between
            two configurations within them stays within them.
        bodies, robot, env: the scene (module docstring).
        lever: ``(c_shoulder, c_gripper)`` lever arms, metres.
    """
    return _motion_valid(q_a, q_b, lower, upper, bodies, robot, env, lever)


@njit(cache=True)
def motions_valid(q_a, q_b, lower, upper, bodies, robot, env, lever):
    """:func:`motion_valid` of motions (E, 4), (E, 4) -> (E,) bool."""
    out = np.zeros(q_a.shape[0], dtype=np.bool_)
    for e in range(q_a.shape[0]):
        out[e] = _motion_valid(q_a[e], q_b[e], lower, upper, bodies, robot, env, lever)
    return out
