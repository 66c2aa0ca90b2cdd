"""Exact planar signed distances and a sound motion check, compiled (numba).

The scene is planar by construction (every collision shape is a vertical
extrusion over the same slab, see :mod:`drake_social.model.plant`), so the
distance between two shapes is the 2-D distance between their footprints.
This module works on footprints only, in plain arrays; the Drake adapter
:class:`drake_social.collision.planar_checker.PlanarChecker` reads them from the
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
(capsule, shape) pairs. A broad phase reads only the shapes listed in the
grid's cells near each capsule (:mod:`drake_social.collision.broadphase`;
a ring search outward for the nearest) and skips pairs whose bounding
circles are already further apart than the best value found
(``|m - c| - rho_a - rho_b`` is a lower bound of their distance), which never
changes the result: the ``*_plain`` functions loop over every shape and
answer the same (tested).

Motions: :func:`motion_valid` by conservative advancement, see there.
"""

from __future__ import annotations

import math

import numpy as np

from drake_social import _kernel_cache

_kernel_cache.ensure_fresh()  # before any cached kernel is loaded

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
    "FAR",
    "GRID_MIN_SHAPES",
    "MAX_STEPS",
    "STEP_MARGIN",
    "TOLERANCE",
    "body_poses",
    "capsule_clearances",
    "capsule_clearances_plain",
    "capsule_spans",
    "clearance",
    "clearances",
    "clearances_plain",
    "displacement",
    "motion_valid",
    "motion_valid_ends",
    "motions_valid",
    "motions_valid_plain",
    "pair_distances",
    "queue_pop",
    "queue_split",
    "queue_start",
    "segment_box_distance",
    "segment_disc_distance",
    "valid",
    "valid_plain",
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
#: Motion checks measure only the shapes that can come within this of the
#: robot during the motion, metres; each step then clears at most FAR / D_j.
FAR = 1.0
#: With fewer environment shapes than this, the kernels loop over all of them
#: (the same answers; cheaper than reading grid cells in a room of a few
#: dozen shapes).
GRID_MIN_SHAPES = 64
#: A clearance search remembers this many shapes it measured, so that a long
#: shape listed in many grid cells is measured once per capsule.
SEEN = 8


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
def _pair_bound(mx, my, reach, env, k):
    """A lower bound of the distance between a capsule (all of it within
    ``reach`` of its midpoint m) and environment shape k: the distance of m
    to the shape (1-Lipschitz, exact for a point) minus reach."""
    cx, cy = env[k, 1], env[k, 2]
    if env[k, 0] == DISC:
        return math.sqrt((mx - cx) * (mx - cx) + (my - cy) * (my - cy)) - env[k, 5] - reach
    c, s = env[k, 3], env[k, 4]
    u, v = c * (mx - cx) + s * (my - cy), c * (my - cy) - s * (mx - cx)
    return _box_sdf(u, v, env[k, 5], env[k, 6]) - reach


@njit(cache=True)
def _coarse_bound(mx, my, reach, env, k):
    """A cheaper, looser lower bound than :func:`_pair_bound` (bounding
    squares: no rotation, no square root), tried first."""
    return max(abs(mx - env[k, 1]), abs(my - env[k, 2])) - env[k, 7] - reach


@njit(cache=True)
def _capsule_reach(cap, j):
    """(mx, my, reach): the midpoint of world capsule j and the distance of its
    farthest point from it."""
    mx, my = 0.5 * (cap[j, 0] + cap[j, 2]), 0.5 * (cap[j, 1] + cap[j, 3])
    dx, dy = cap[j, 2] - cap[j, 0], cap[j, 3] - cap[j, 1]
    return mx, my, 0.5 * math.sqrt(dx * dx + dy * dy) + cap[j, 4]


@njit(cache=True)
def _measure(cap, j, mx, my, reach, env, k, best):
    """min(best, the signed distance of capsule j and shape k), measured only
    when the pair's broad-phase lower bounds are below best (else best)."""
    if _coarse_bound(mx, my, reach, env, k) >= best or _pair_bound(mx, my, reach, env, k) >= best:
        return best
    return min(best, _pair(cap, j, env, k))


@njit(cache=True)
def _capsule_best_plain(cap, j, env, best):
    """min(best, the least signed distance of capsule j to the environment)
    over every shape (the reference of the grid's :func:`_capsule_best`)."""
    mx, my, reach = _capsule_reach(cap, j)
    for k in range(env.shape[0]):
        best = _measure(cap, j, mx, my, reach, env, k, best)
    return best


@njit(cache=True)
def _capsule_clearances_plain(cap, env, out):
    """Per capsule j, the least signed distance to the environment, into out (S,): every shape."""
    for j in range(cap.shape[0]):
        out[j] = _capsule_best_plain(cap, j, env, np.inf)


@njit(cache=True)
def _cell_of(grid, x, y):
    """The cell ``(i, j)`` of the point (x, y) on the grid's infinite
    lattice, or (-1, -1, False) where it is too far (or NaN) for int64."""
    x0, y0, cell = grid.header[0], grid.header[1], grid.header[2]
    u, v = (x - x0) / cell, (y - y0) / cell
    if not (abs(u) < 1e15 and abs(v) < 1e15):
        return -1, -1, False
    return int(math.floor(u)), int(math.floor(v)), True


@njit(cache=True)
def _visit(cap, j, mx, my, reach, env, grid, c, best, seen):
    """best after the shapes of cell c (the plain loop's broad and narrow
    phase). ``seen[:SEEN]`` holds the last shapes measured for this capsule
    (``seen[SEEN]`` counts them): a long shape listed in many cells is
    measured once (measuring it again would give the same value)."""
    for e in range(grid.start[c], grid.start[c + 1]):
        k = grid.items[e]
        again = False
        for t in range(SEEN):
            if seen[t] == k:
                again = True
                break
        if again:
            continue
        if _coarse_bound(mx, my, reach, env, k) >= best or _pair_bound(mx, my, reach, env, k) >= best:
            continue
        best = min(best, _pair(cap, j, env, k))
        seen[seen[SEEN] % SEEN] = k
        seen[SEEN] += 1
    return best


@njit(cache=True)
def _cell_far(grid, ii, jj, mx, my, reach, best):
    """Whether cell (ii, jj) can be skipped: best > 0 and every point of it
    is at least best + reach from m. A shape nearer than best has a point
    within best + reach of m (its nearest point, or one inside the capsule),
    whose cell the search reads. (Not when best <= 0: a shape overlapping
    the capsule has a signed distance down to minus its penetration depth.)"""
    if not best > 0.0:
        return False
    x0, y0, cell = grid.header[0], grid.header[1], grid.header[2]
    dx = max(x0 + ii * cell - mx, mx - (x0 + (ii + 1) * cell), 0.0)
    dy = max(y0 + jj * cell - my, my - (y0 + (jj + 1) * cell), 0.0)
    return math.sqrt(dx * dx + dy * dy) - reach >= best


@njit(cache=True)
def _capsule_best(cap, j, env, grid, best, seen):
    """min(best, the least signed distance of capsule j to the environment),
    exactly the value of the plain loop over all shapes.

    Ring search on the grid: rings of cells at Chebyshev distance r = 0, 1,
    ... from the cell of the capsule's midpoint m. A shape not listed in the
    rings before r lies outside their block of cells (see
    :mod:`~drake_social.collision.broadphase`), so its distance from the
    capsule is at least m's distance to the block's boundary minus the
    capsule's reach; the search stops once that lower bound reaches best,
    as the plain loop skips such a pair. (Also when negative: a convex shape
    outside the block lies beyond a line at least that far from m, so its
    penetration depth is at most reach minus that distance.) The nearest
    shape is always found, so the minimum is over the same exact pair
    distances. Cells are skipped where :func:`_cell_far` allows. ``seen`` (SEEN + 1,) int64 is scratch."""
    mx, my, reach = _capsule_reach(cap, j)
    for t in range(SEEN):
        seen[t] = -1
    seen[SEEN] = 0
    ix, iy, ok = _cell_of(grid, mx, my)
    if not ok or env.shape[0] < GRID_MIN_SHAPES:  # far off, NaN or a small room: every shape
        return _capsule_best_plain(cap, j, env, best)
    x0, y0, cell = grid.header[0], grid.header[1], grid.header[2]
    nx, ny = grid.dims[0], grid.dims[1]
    r0 = max(0, -ix, ix - (nx - 1), -iy, iy - (ny - 1))  # the first ring that meets the grid
    r1 = max(ix, nx - 1 - ix, iy, ny - 1 - iy)  # the last
    for r in range(r0, r1 + 1):
        if r > 0:
            lb = min(mx - (x0 + (ix - r + 1) * cell), (x0 + (ix + r) * cell) - mx,
                     my - (y0 + (iy - r + 1) * cell), (y0 + (iy + r) * cell) - my) - reach
            if lb >= best:
                break
        for side in range(2):  # the ring's bottom and top rows
            jj = iy - r if side == 0 else iy + r
            if 0 <= jj < ny:
                for ii in range(max(0, ix - r), min(nx - 1, ix + r) + 1):
                    if not _cell_far(grid, ii, jj, mx, my, reach, best):
                        best = _visit(cap, j, mx, my, reach, env, grid, ii + jj * nx, best, seen)
            if r == 0:
                break
        if r > 0:
            for side in range(2):  # its left and right columns, corners done
                ii = ix - r if side == 0 else ix + r
                if 0 <= ii < nx:
                    for jj in range(max(0, iy - r + 1), min(ny - 1, iy + r - 1) + 1):
                        if not _cell_far(grid, ii, jj, mx, my, reach, best):
                            best = _visit(cap, j, mx, my, reach, env, grid, ii + jj * nx, best, seen)
    return best


@njit(cache=True)
def _capsule_clearances(cap, env, grid, out):
    """Per capsule j, the least signed distance to the environment, into out (S,)."""
    seen = np.empty(SEEN + 1, dtype=np.int64)
    for j in range(cap.shape[0]):
        out[j] = _capsule_best(cap, j, env, grid, np.inf, seen)


@njit(cache=True)
def _clearance(q, bodies, robot, env, grid):
    cap = world_capsules(q, bodies, robot)
    best = np.inf
    seen = np.empty(SEEN + 1, dtype=np.int64)
    for j in range(cap.shape[0]):
        best = _capsule_best(cap, j, env, grid, best, seen)
    return best


@njit(cache=True)
def _clearance_plain(q, bodies, robot, env):
    cap = world_capsules(q, bodies, robot)
    best = np.inf
    for j in range(cap.shape[0]):
        best = _capsule_best_plain(cap, j, env, best)
    return best


@njit(cache=True)
def capsule_clearances(q, bodies, robot, env, grid):
    """Per robot capsule (S,), its least signed distance to the environment at
    q (4,); :func:`clearance` is their minimum. Exact when positive."""
    out = np.empty(robot.shape[0])
    _capsule_clearances(world_capsules(q, bodies, robot), env, grid, out)
    return out


@njit(cache=True)
def capsule_clearances_plain(q, bodies, robot, env):
    """:func:`capsule_clearances` from every shape, without the grid (the reference)."""
    out = np.empty(robot.shape[0])
    _capsule_clearances_plain(world_capsules(q, bodies, robot), env, out)
    return out


@njit(cache=True)
def _cell_block(grid, lo_x, lo_y, hi_x, hi_y):
    """``(i0, j0, i1, j1)``: the grid's cells meeting the box [lo, hi], clipped
    (i0 > i1 or j0 > j1 when it misses the grid); the whole grid for a
    box too far off or NaN."""
    a, b, ok_a = _cell_of(grid, lo_x, lo_y)
    c, d, ok_b = _cell_of(grid, hi_x, hi_y)
    nx, ny = grid.dims[0], grid.dims[1]
    if not (ok_a and ok_b):
        return 0, 0, nx - 1, ny - 1
    return max(a, 0), max(b, 0), min(c, nx - 1), min(d, ny - 1)


@njit(cache=True)
def _free(q, bodies, robot, env, grid):
    """clearance(q) > 0, deciding each pair by its broad-phase bound where it
    can; only the shapes listed in the cells that meet a capsule's bounding
    square (grown by the grid's pad) are looked at: every other one is
    apart from the capsule."""
    if env.shape[0] < GRID_MIN_SHAPES:
        return _free_plain(q, bodies, robot, env)
    cap = world_capsules(q, bodies, robot)
    pad = grid.header[3]
    nx = grid.dims[0]
    for j in range(cap.shape[0]):
        mx, my, reach = _capsule_reach(cap, j)
        i0, j0, i1, j1 = _cell_block(grid, mx - reach - pad, my - reach - pad, mx + reach + pad, my + reach + pad)
        for jj in range(j0, j1 + 1):
            for ii in range(i0, i1 + 1):
                c = ii + jj * nx
                for e in range(grid.start[c], grid.start[c + 1]):
                    if not _apart(cap, j, mx, my, reach, env, grid.items[e]):
                        return False
    return True


@njit(cache=True)
def _free_plain(q, bodies, robot, env):
    """:func:`_free` over every shape (the reference)."""
    cap = world_capsules(q, bodies, robot)
    for j in range(cap.shape[0]):
        mx, my, reach = _capsule_reach(cap, j)
        for k in range(env.shape[0]):
            if not _apart(cap, j, mx, my, reach, env, k):
                return False
    return True


@njit(cache=True)
def _apart(cap, j, mx, my, reach, env, k):
    """Whether world capsule j (midpoint m, all of it within ``reach`` of m)
    and shape k are apart: by a broad-phase bound where it decides, else by
    their distance."""
    if _coarse_bound(mx, my, reach, env, k) > 0.0 or _pair_bound(mx, my, reach, env, k) > 0.0:
        return True
    return _pair(cap, j, env, k) > 0.0


@njit(cache=True)
def clearance(q, bodies, robot, env, grid):
    """The least signed distance (metres) from the robot to the environment
    at q (4,); exact when positive, inf without environment shapes.
    ``grid`` is the broadphase over ``env``
    (:func:`drake_social.collision.broadphase.build_grid`)."""
    return _clearance(q, bodies, robot, env, grid)


@njit(cache=True)
def clearances(qs, bodies, robot, env, grid):
    """:func:`clearance` of configurations (N, 4) -> (N,)."""
    out = np.empty(qs.shape[0])
    for i in range(qs.shape[0]):
        out[i] = _clearance(qs[i], bodies, robot, env, grid)
    return out


@njit(cache=True)
def clearances_plain(qs, bodies, robot, env):
    """:func:`clearances` from every shape, without the grid (the reference)."""
    out = np.empty(qs.shape[0])
    for i in range(qs.shape[0]):
        out[i] = _clearance_plain(qs[i], bodies, robot, env)
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
def valid(qs, lower, upper, bodies, robot, env, grid):
    """(N,) bool: configurations (N, 4) within the limits at clearance > 0."""
    out = np.zeros(qs.shape[0], dtype=np.bool_)
    for i in range(qs.shape[0]):
        out[i] = _in_limits(qs[i], lower, upper) and _free(qs[i], bodies, robot, env, grid)
    return out


@njit(cache=True)
def valid_plain(qs, lower, upper, bodies, robot, env):
    """:func:`valid` from every shape, without the grid (the reference)."""
    out = np.zeros(qs.shape[0], dtype=np.bool_)
    for i in range(qs.shape[0]):
        out[i] = _in_limits(qs[i], lower, upper) and _free_plain(qs[i], bodies, robot, env)
    return out


@njit(cache=True)
def displacement(dq, lever):
    """``hypot(dx, dy) + c_s |dpsi1| + c_g |dpsi1 + dpsi2|``: the bound of
    :func:`drake_social.kinematics.displacement_bound`, per unit of t."""
    return math.hypot(dq[0], dq[1]) + lever[0] * abs(dq[2]) + lever[1] * abs(dq[2] + dq[3])


@njit(cache=True)
def _probe(cap, env, keep, n_keep, spans, tau_max):
    """The step tau of one query with the world capsules ``cap`` at q(t): every
    capsule j (moving at most ``spans[j]`` per unit of t) stays free for
    ``|t' - t| < tau``; or -1 when a capsule is within TOLERANCE of contact.
    ``tau <= tau_max`` (no more is needed): a pair whose broad-phase bound
    already allows the step found so far is not measured. Only the shapes
    ``keep[:n_keep]`` are measured; ``tau_max`` also keeps the step within
    what the others (at least FAR away) allow."""
    tau = tau_max
    for j in range(cap.shape[0]):
        d_j = spans[j]
        if d_j == 0.0:  # a capsule that does not move stays as free as at the ends
            continue
        mx, my, reach = _capsule_reach(cap, j)
        for i in range(n_keep):
            k = keep[i]
            if (_coarse_bound(mx, my, reach, env, k) - STEP_MARGIN >= tau * d_j
                    or _pair_bound(mx, my, reach, env, k) - STEP_MARGIN >= tau * d_j):
                continue
            d = _pair(cap, j, env, k)
            if d <= TOLERANCE:
                return -1.0
            tau = min(tau, (d - STEP_MARGIN) / d_j)
    return tau


@njit(cache=True)
def capsule_spans(dq, levers):
    """Per capsule (S,), ``displacement(dq, levers[j])``: the most any point of
    capsule j moves per unit of t along the motion ``dq``."""
    out = np.empty(levers.shape[0])
    for j in range(levers.shape[0]):
        out[j] = displacement(dq, levers[j])
    return out


@njit(cache=True)
def _near_motion(env, k, x, y, radius, span):
    """Whether shape k's bounding circle comes within FAR of the disc of
    ``radius + span`` about (x, y)."""
    dx, dy = env[k, 1] - x, env[k, 2] - y
    return not math.sqrt(dx * dx + dy * dy) - env[k, 7] - radius - span >= FAR


@njit(cache=True)
def _keep_plain(env, x, y, radius, span):
    """The shapes (ascending) whose bounding circle comes within FAR of the
    disc of ``radius + span`` about (x, y), from every shape."""
    keep = np.empty(env.shape[0], dtype=np.int64)
    n_keep = 0
    for k in range(env.shape[0]):
        if _near_motion(env, k, x, y, radius, span):
            keep[n_keep] = k
            n_keep += 1
    return keep, n_keep


@njit(cache=True)
def _keep_grid(env, grid, x, y, radius, span):
    """:func:`_keep_plain` among the shapes listed in the cells that meet the
    square of half side ``radius + span + FAR`` (+ pad) about (x, y), ascending,
    each once. A shape of the plain list left out lies, grown by the pad,
    outside that square, so it stays more than FAR from the robot: measured,
    it would allow a step longer than FAR allows, which changes nothing
    (:func:`_probe` caps each step at FAR's)."""
    half = radius + span + FAR + grid.header[3]
    i0, j0, i1, j1 = _cell_block(grid, x - half, y - half, x + half, y + half)
    nx = grid.dims[0]
    n = 0
    for jj in range(j0, j1 + 1):
        n += grid.start[i1 + 1 + jj * nx] - grid.start[i0 + jj * nx] if i0 <= i1 else 0
    keep = np.empty(n, dtype=np.int64)
    n = 0
    for jj in range(j0, j1 + 1):
        for ii in range(i0, i1 + 1):
            c = ii + jj * nx
            for e in range(grid.start[c], grid.start[c + 1]):
                k = grid.items[e]
                if _near_motion(env, k, x, y, radius, span):
                    keep[n] = k
                    n += 1
    keep[:n].sort()
    n_keep = 0
    for i in range(n):
        if i == 0 or keep[i] != keep[i - 1]:
            keep[n_keep] = keep[i]
            n_keep += 1
    return keep, n_keep


@njit(cache=True)
def queue_start(lo, hi):
    """The conservative advancement's queue of the part ``[lo, hi]`` of a
    motion not yet cleared: closed intervals of t, first in first out, in a
    ring buffer (``buffer`` (size, 2), ``ends`` (2,) int64: head, tail) that
    doubles when full. Each query at an interval's midpoint clears
    ``(t - tau, t + tau)`` and queues what is left (:func:`queue_split`), so
    the motion is searched coarse to fine (a collision is found after a few
    queries) and each query clears both ways; the motion is cleared when the
    queue is empty (``ends[0] == ends[1]``). The planar check and the
    people's (:mod:`drake_social.collision.people_kernel`) run it."""
    buffer = np.empty((64, 2))
    buffer[0, 0], buffer[0, 1] = lo, hi
    return buffer, np.array([0, 1], dtype=np.int64)


@njit(cache=True)
def queue_pop(buffer, ends):
    """The queue's first interval (a, b), taken off it."""
    head = ends[0] % buffer.shape[0]
    ends[0] += 1
    return buffer[head, 0], buffer[head, 1]


@njit(cache=True)
def queue_split(buffer, ends, a, b, t, tau):
    """Queues what a query at t that cleared ``(t - tau, t + tau)`` leaves of
    ``[a, b]``: ``[a, t - tau]``, then ``[t + tau, b]``, each when not empty.
    Returns the buffer (a new one, twice as large and in order, when it was full)."""
    for lo, hi in ((a, t - tau), (t + tau, b)):
        if lo <= hi:
            size = buffer.shape[0]
            if ends[1] - ends[0] == size:  # full: double it, in order
                larger = np.empty((2 * size, 2))
                for r in range(size):
                    larger[r, 0], larger[r, 1] = buffer[(ends[0] + r) % size, 0], buffer[(ends[0] + r) % size, 1]
                buffer = larger
                ends[0], ends[1] = 0, size
            tail = ends[1] % buffer.shape[0]
            buffer[tail, 0], buffer[tail, 1] = lo, hi
            ends[1] += 1
    return buffer


@njit(cache=True)
def _motion_valid_ends(q_a, q_b, c_a, c_b, lower, upper, bodies, robot, env, grid, levers, plain):
    if not (_in_limits(q_a, lower, upper) and _in_limits(q_b, lower, upper)):
        return False
    s_count = robot.shape[0]
    for j in range(s_count):
        if c_a[j] <= TOLERANCE or c_b[j] <= TOLERANCE:
            return False
    dq = q_b - q_a
    spans = capsule_spans(dq, levers)
    span = 0.0
    for j in range(s_count):
        span = max(span, spans[j])
    if span == 0.0:
        return True
    lo, hi = np.inf, -np.inf  # [0, lo) and (hi, 1] are cleared
    for j in range(s_count):
        if spans[j] > 0.0:
            lo = min(lo, (c_a[j] - STEP_MARGIN) / spans[j])
            hi = max(hi, 1.0 - (c_b[j] - STEP_MARGIN) / spans[j])
    if lo > hi:
        return True
    # The shapes that can come within FAR of the robot: every robot point stays
    # within radius + span of the base's start (x, y).
    cap = world_capsules(q_a, bodies, robot)
    radius = 0.0
    for j in range(s_count):
        radius = max(radius, math.hypot(cap[j, 0] - q_a[0], cap[j, 1] - q_a[1]) + cap[j, 4],
                     math.hypot(cap[j, 2] - q_a[0], cap[j, 3] - q_a[1]) + cap[j, 4])
    if plain or env.shape[0] < GRID_MIN_SHAPES:
        keep, n_keep = _keep_plain(env, q_a[0], q_a[1], radius, span)
    else:
        keep, n_keep = _keep_grid(env, grid, q_a[0], q_a[1], radius, span)
    tau_far = np.inf
    for j in range(s_count):
        if spans[j] > 0.0:
            tau_far = min(tau_far, (FAR - STEP_MARGIN) / spans[j])
    # The part [lo, hi] not yet cleared, searched coarse to fine (queue_start).
    buffer, ends = queue_start(lo, hi)
    q = np.empty(4)
    for _ in range(MAX_STEPS):
        if ends[0] == ends[1]:
            return True
        a, b = queue_pop(buffer, ends)
        t = 0.5 * (a + b)
        for i in range(4):
            q[i] = q_a[i] + t * dq[i]
        tau = _probe(world_capsules(q, bodies, robot), env, keep, n_keep, spans, min(tau_far, 0.5 * (b - a) + 1e-12))
        if tau < 0.0:
            return False
        buffer = queue_split(buffer, ends, a, b, t, tau)
    return False


@njit(cache=True)
def motion_valid_ends(q_a, q_b, c_a, c_b, lower, upper, bodies, robot, env, grid, levers):
    """:func:`motion_valid` given :func:`capsule_clearances` ``c_a``, ``c_b``
    of both ends (the tree loop keeps them for every node)."""
    return _motion_valid_ends(q_a, q_b, c_a, c_b, lower, upper, bodies, robot, env, grid, levers, False)


@njit(cache=True)
def _motion_valid(q_a, q_b, lower, upper, bodies, robot, env, grid, levers):
    c_a = capsule_clearances(q_a, bodies, robot, env, grid)
    c_b = capsule_clearances(q_b, bodies, robot, env, grid)
    return _motion_valid_ends(q_a, q_b, c_a, c_b, lower, upper, bodies, robot, env, grid, levers, False)


@njit(cache=True)
def motions_valid_plain(q_a, q_b, lower, upper, bodies, robot, env, grid, levers):
    """:func:`motions_valid` from every shape, without the grid (the
    reference; ``grid`` is not read)."""
    out = np.zeros(q_a.shape[0], dtype=np.bool_)
    for e in range(q_a.shape[0]):
        c_a = capsule_clearances_plain(q_a[e], bodies, robot, env)
        c_b = capsule_clearances_plain(q_b[e], bodies, robot, env)
        out[e] = _motion_valid_ends(q_a[e], q_b[e], c_a, c_b, lower, upper, bodies, robot, env, grid, levers, True)
    return out


@njit(cache=True)
def motion_valid(q_a, q_b, lower, upper, bodies, robot, env, grid, levers):
    """Whether the straight motion ``q_a + t (q_b - q_a)``, t in [0, 1], is free.

    Conservative advancement per capsule, coarse to fine.
    Soundness: along the motion every point of capsule j moves with speed at
    most ``D_j = displacement(q_b - q_a, levers[j])`` per unit of t (a
    point's velocity is the base's plus the rotations' about the shoulder and
    the elbow; ``levers[j]`` bounds their arms for that capsule: zero for the
    base, see :meth:`PlanarChecker._levers`). If capsule j is at distance at
    least ``d_j > 0`` from every shape at ``q(t)``, then for
    ``|t' - t| < d_j / D_j`` each of its points is less than ``d_j`` from
    where it was, so it stays free (triangle inequality); a query at q(t)
    clears ``tau = min_j d_j / D_j`` both ways. The distances are exact when
    positive; a pair whose broad-phase lower bound already allows the step
    found so far is not measured (its bound is used: still a lower bound).
    Shapes that cannot come within :data:`FAR` of the robot anywhere on the
    motion (the robot stays within its bounding circle at q_a grown by
    max_j D_j) are not measured either, and each step is capped at what FAR
    allows. Both ends are checked exactly and clear ``[0, lo)`` and
    ``(hi, 1]``; what is left is searched coarse to fine, as a queue of
    closed intervals: a query at an interval's midpoint clears
    ``(t - tau, t + tau)`` and queues what is left of it, so a collision is
    found after a few queries. The motion is valid when the queue is empty.
    Floors: a reached configuration with a capsule within :data:`TOLERANCE`
    of contact rejects the motion (so steps never shrink below
    ``min(TOLERANCE, FAR) / max_j D_j``), steps are ``STEP_MARGIN`` metres
    shorter than allowed (rounding), and more than :data:`MAX_STEPS` queries
    in all reject it. Rejecting is always safe.

    Args:
        q_a, q_b: the ends (4,).
        lower, upper: limits (4,); the limits are a box, so a motion between
            two configurations within them stays within them.
        bodies, robot, env: the scene (module docstring).
        grid: the broadphase over env
            (:func:`drake_social.collision.broadphase.build_grid`): the
            clearances and the list of shapes within FAR read only the
            cells near the robot, with the same answers.
        levers: (S, 2) per capsule ``(c_shoulder, c_gripper)`` lever arms, metres.
    """
    return _motion_valid(q_a, q_b, lower, upper, bodies, robot, env, grid, levers)


@njit(cache=True)
def motions_valid(q_a, q_b, lower, upper, bodies, robot, env, grid, levers):
    """:func:`motion_valid` of motions (E, 4), (E, 4) -> (E,) bool."""
    out = np.zeros(q_a.shape[0], dtype=np.bool_)
    for e in range(q_a.shape[0]):
        out[e] = _motion_valid(q_a[e], q_b[e], lower, upper, bodies, robot, env, grid, levers)
    return out
