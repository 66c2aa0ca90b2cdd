"""A pure-numpy validity checker: discs and capsules against boxes, discs and walls.

It implements :class:`~drake_social.collision.validity.ValidityChecker` with
the same planar shapes as the Drake model (:mod:`drake_social.model`), so the
two agree up to floating point; planner tests use it as a fast, Drake-free
checker.

Shapes (metres): the base is a disc of ``robot.base_radius`` at ``(x, y)``;
links and object segments are capsules (``ArmGeometry.segments`` and
``segment_radii``); obstacles are rotated boxes; people are discs of their
body radius; the room is closed by walls standing on ``world.bounds``.
Robot-robot contacts are not checked (the arm carries the object above the
base; see :mod:`drake_social.model.robot_model`).

Signed distances are exact whenever the shapes are apart:

* point to box: the box's signed-distance function in its own frame;
* capsule to box: the minimum of that convex function along the axis, found
  among twelve candidate points (the two ends, the projections of the four
  corners, and the crossings of the axis with the six lines where the
  function has kinks: x = 0, y = 0, |x| - |y| = +-(hx - hy));
* walls: since the base centre is inside the bounds and the robot is
  connected, a shape touches a wall iff it reaches a bound, and for a capsule
  whose ends are inside the room the nearest wall point is straight across
  from one end.

Everything is batched over configurations. Motions are checked soundly by
conservative advancement on these exact clearances, the same scheme as the
compiled :func:`drake_social.collision.planar_kernel.motion_valid` with the
displacement bound of ``ArmGeometry.max_displacement(include_body=True)``:
a configuration at clearance c clears every configuration of the motion
whose body points moved less than c. (Discrete checking at ``resolution``,
as before, let a 0.4 mm penetration through on a map with rotated boxes;
:meth:`GeometricChecker.motion_samples` keeps that sampling for comparison.)
"""

from __future__ import annotations

import numpy as np

from drake_social.arguments import require_scenario
from drake_social.kinematics import ArmGeometry
from drake_social.collision.broadphase import build_grid, cell_ranges
from drake_social.collision.planar_kernel import MAX_STEPS, STEP_MARGIN, TOLERANCE
from drake_social.people import people_model
from drake_social.scenario import Scenario
from drake_social.scenario.geometry import arm_geometry, configuration_limits
from drake_social.world import world_model

__all__ = ["CheckerBase", "GRID_MIN_BOXES", "GeometricChecker"]

#: From this many boxes on, a configuration's candidate boxes come from a
#: broadphase grid (:mod:`drake_social.collision.broadphase`) rather than
#: from all of them (below it, the (N, K) arrays are cheaper than the grid's
#: bookkeeping).
GRID_MIN_BOXES = 64


def _box_sdf_xy(px: np.ndarray, py: np.ndarray, hx: np.ndarray, hy: np.ndarray) -> np.ndarray:
    """Signed distance of points (px, py), in box frames, to boxes of half sizes (hx, hy)."""
    ux = np.abs(px) - hx
    uy = np.abs(py) - hy
    mx, my = np.maximum(ux, 0.0), np.maximum(uy, 0.0)
    return np.sqrt(mx * mx + my * my) + np.minimum(np.maximum(ux, uy), 0.0)


def _clip01(t: np.ndarray) -> np.ndarray:
    """t clipped to [0, 1], NaN (from 0 / 0) mapped to 0."""
    return np.fmin(np.fmax(t, 0.0), 1.0)


# Candidate lines n . p = k c of the box signed distance's kinks, c = hx - hy:
# x = 0, y = 0, x - y = -c, x - y = c, x + y = -c, x + y = c.
_LINE_NX = np.array([1.0, 0.0, 1.0, 1.0, 1.0, 1.0])
_LINE_NY = np.array([0.0, 1.0, -1.0, -1.0, 1.0, 1.0])
_LINE_K = np.array([0.0, 0.0, -1.0, 1.0, -1.0, 1.0])
_CORNER_SX = np.array([-1.0, -1.0, 1.0, 1.0])
_CORNER_SY = np.array([-1.0, 1.0, -1.0, 1.0])


def _segment_box_sdf_xy(ax, ay, bx, by, hx, hy) -> np.ndarray:
    """Minimum over segments [a, b] of the box signed distance (all arrays (...))."""
    ax, ay, hx, hy = ax[..., None], ay[..., None], hx[..., None], hy[..., None]
    dx, dy = bx[..., None] - ax, by[..., None] - ay
    with np.errstate(divide="ignore", invalid="ignore"):
        # Projections of the four corners (stationary points of the corner regions) ...
        t_corner = ((_CORNER_SX * hx - ax) * dx + (_CORNER_SY * hy - ay) * dy) / (dx * dx + dy * dy)
        # ... and crossings of the kink lines.
        t_line = ((hx - hy) * _LINE_K - ax * _LINE_NX - ay * _LINE_NY) / (dx * _LINE_NX + dy * _LINE_NY)
    t = np.concatenate([_clip01(t_corner), _clip01(t_line), np.zeros_like(ax), np.ones_like(ax)], -1)
    return _box_sdf_xy(ax + t * dx, ay + t * dy, hx, hy).min(-1)


def _segment_box_sdf(a: np.ndarray, b: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Minimum over segment [a, b] of the box signed distance.

    Args:
        a, b: segment ends (..., 2) in the box frames.
        half: box half sizes (..., 2), broadcastable.

    Returns:
        (...,) the minimum of the box's signed distance along each segment
        (negative when the segment enters the box).
    """
    a, b, half = np.broadcast_arrays(np.asarray(a, float), np.asarray(b, float), np.asarray(half, float))
    return _segment_box_sdf_xy(a[..., 0], a[..., 1], b[..., 0], b[..., 1], half[..., 0], half[..., 1])


class CheckerBase:
    """What every validity checker of a scenario shares: geometry, limits, resolution.

    Args:
        scenario: the room, people, robot and object.
        resolution: largest displacement of any body point between two
            checked configurations of a motion, metres; None =
            ``scenario.planner.collision_resolution``.

    Attributes:
        scenario: the scenario checked.
        geometry: the robot's :class:`ArmGeometry`.
        lower, upper: (4,) limits of a valid ``q``: the room bounds for
            ``(x, y)``, the joint limits for ``(psi1, psi2)``.
        resolution: see above.
    """

    def __init__(self, scenario: Scenario, resolution: float | None = None):
        require_scenario(scenario, type(self).__name__)
        self.scenario = scenario
        self.geometry = arm_geometry(scenario)
        self.resolution = float(scenario.planner.collision_resolution if resolution is None else resolution)
        if not self.resolution > 0:
            raise ValueError(f"resolution must be > 0 metres, got {resolution}")
        self.lower, self.upper = configuration_limits(scenario)

    @property
    def motion_check(self) -> str:
        """How a straight motion is checked, in words (for messages): sampled
        at :attr:`resolution`."""
        return f"sampled every {self.resolution:g} m of body-point motion (planner.collision_resolution)"

    def in_limits(self, qs: np.ndarray) -> np.ndarray:
        """Whether configurations (..., 4) lie within :attr:`lower`, :attr:`upper`."""
        qs = np.asarray(qs, float)
        return np.all((qs >= self.lower) & (qs <= self.upper), axis=-1)


class GeometricChecker(CheckerBase):
    """The Drake-free :class:`ValidityChecker` of a scenario.

    Args:
        scenario, resolution: see :class:`CheckerBase`.
        chunk: configurations evaluated per numpy batch (bounds memory).
    """

    def __init__(self, scenario: Scenario, resolution: float | None = None, chunk: int = 1024):
        super().__init__(scenario, resolution)
        self.chunk = int(chunk)
        world = world_model(scenario)
        self.bounds = np.array(world.bounds)
        boxes = world.boxes
        self._box_center, self._box_half = boxes.centers, boxes.halves
        self._box_cos, self._box_sin = boxes.cos, boxes.sin
        rows = np.column_stack([np.zeros(len(boxes)), boxes.centers, boxes.cos, boxes.sin, boxes.halves,
                                np.hypot(*boxes.halves.T)])
        #: The broadphase over the boxes (None below GRID_MIN_BOXES boxes).
        self.grid = build_grid(rows) if len(boxes) >= GRID_MIN_BOXES else None
        # The people present at t = 0 (a recorded id entering later is no obstacle).
        people = people_model(scenario).state_at(0.0).visible()
        self._people, self._people_r = people.positions, people.radii
        g = self.geometry
        self._radii = g.segment_radii
        # Segment s runs from vertex _seg[s, 0] to vertex _seg[s, 1] of _vertices().
        m = len(g.object_points)
        self._seg = np.array([[0, 1], [1, 2]] + [[3 + k, 4 + k] for k in range(m - 1)])
        self._joint_points = np.arange(3)  # base centre, elbow, gripper among the interest points
        # No body point is further than this from the base centre, metres.
        self._reach = max(float(g.reach(include_body=True)[2]), g.base_radius)

    # ---- geometry -------------------------------------------------------------

    def _vertices(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World x and y (N, 3 + M): base centre, elbow, gripper, object vertices."""
        x, y = self.geometry.interest_xy(q, self._joint_points)
        obj = self.geometry.gripper_to_world(q, self.geometry.object_points)
        return np.concatenate([x, obj[..., 0]], -1), np.concatenate([y, obj[..., 1]], -1)

    def _clearances(self, q: np.ndarray) -> np.ndarray:
        x, y = self._vertices(q)  # (N, V)
        i0, i1 = self._seg[:, 0], self._seg[:, 1]
        rb, r = self.geometry.base_radius, self._radii
        x0, y0, x1, y1 = self.bounds
        margin = np.minimum(np.minimum(x - x0, x1 - x), np.minimum(y - y0, y1 - y))  # walls
        best = np.minimum(margin[:, 0] - rb, (np.minimum(margin[:, i0], margin[:, i1]) - r).min(-1))
        if len(self._people_r):
            px, py, pr = self._people[:, 0], self._people[:, 1], self._people_r
            best = np.minimum(best, (np.hypot(x[:, :1] - px, y[:, :1] - py) - pr).min(-1) - rb)
            ax, ay = x[:, i0, None], y[:, i0, None]  # (N, S, 1) against (P,)
            dx, dy = x[:, i1, None] - ax, y[:, i1, None] - ay
            wx, wy = px - ax, py - ay
            with np.errstate(divide="ignore", invalid="ignore"):
                t = _clip01((wx * dx + wy * dy) / (dx * dx + dy * dy))
            d = np.hypot(wx - t * dx, wy - t * dy) - pr - r[:, None]
            best = np.minimum(best, d.min(-1).min(-1))
        if len(self._box_half):
            best = self._box_terms(x, y, best)
        return best

    #: Metres about the base whose boxes are measured first (grid branch of :meth:`_box_terms`).
    NEAR_BOXES = 1.0

    def _box_terms(self, x: np.ndarray, y: np.ndarray, best: np.ndarray) -> np.ndarray:
        """The clearances (N,) after the boxes, given ``best`` (N,) from the rest.

        Work is spent only where it can change the result, without losing
        exactness. Broad phase: every body point lies within ``_reach`` of the
        base centre and signed distances are 1-Lipschitz, so a box further
        than the best clearance known so far plus that reach cannot be the
        nearest. Narrow phase: a capsule-box minimum is at most its value at
        either end of the axis and at least its value at the midpoint minus
        half the length; only pairs whose lower bound beats the best value
        known get the exact twelve-candidate minimum.
        """
        hx, hy = self._box_half[:, 0], self._box_half[:, 1]
        c, s = self._box_cos, self._box_sin
        if self.grid is None:
            dx = x[:, :1] - self._box_center[:, 0]  # the base centre in every box frame: (N, K)
            dy = y[:, :1] - self._box_center[:, 1]
            d0 = _box_sdf_xy(c * dx + s * dy, c * dy - s * dx, hx, hy)
            best = np.minimum(best, d0.min(-1) - self.geometry.base_radius)
            n, k = np.nonzero(d0 - self._reach < best[:, None])  # (configuration, box) pairs kept
        else:
            # The boxes within NEAR_BOXES of the base first: their base terms
            # shrink the known clearance (on a map the walls' is metres), so
            # the search below reads fewer cells. It still reaches every box
            # whose base term beats the result, so the answers are unchanged.
            best = best.copy()
            for radius in (np.minimum(best, self.NEAR_BOXES), None):
                n, k = self._candidates(x[:, 0], y[:, 0], best + self._reach if radius is None else radius)
                dx, dy = x[n, 0] - self._box_center[k, 0], y[n, 0] - self._box_center[k, 1]
                d0 = _box_sdf_xy(c[k] * dx + s[k] * dy, c[k] * dy - s[k] * dx, hx[k], hy[k])
                np.minimum.at(best, n, d0 - self.geometry.base_radius)
            keep = d0 - self._reach < best[n]
            n, k = n[keep], k[keep]
        if len(n) == 0:
            return best
        # Every vertex of the kept pairs in the box frame: (M, V).
        dx = x[n] - self._box_center[k, :1]
        dy = y[n] - self._box_center[k, 1:]
        ck, sk, hxk, hyk = c[k, None], s[k, None], hx[k, None], hy[k, None]
        bx, by = ck * dx + sk * dy, ck * dy - sk * dx
        i0, i1 = self._seg[:, 0], self._seg[:, 1]
        r = self._radii
        v_sd = _box_sdf_xy(bx, by, hxk, hyk)
        upper = np.minimum(v_sd[:, i0], v_sd[:, i1]) - r  # (M, S)
        np.minimum.at(best, n, upper.min(-1))
        half_len = np.hypot(bx[:, i1] - bx[:, i0], by[:, i1] - by[:, i0]) / 2
        lower = _box_sdf_xy((bx[:, i0] + bx[:, i1]) / 2, (by[:, i0] + by[:, i1]) / 2, hxk, hyk) - half_len - r
        m, j = np.nonzero(lower < best[n, None])
        if len(m):
            exact = _segment_box_sdf_xy(
                bx[m, i0[j]], by[m, i0[j]], bx[m, i1[j]], by[m, i1[j]], hx[k[m]], hy[k[m]]
            ) - r[j]
            np.minimum.at(best, n[m], exact)
        return best

    def _candidates(self, x: np.ndarray, y: np.ndarray, radius: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The (configuration, box) pairs (M,), (M,), sorted, each once, of
        the boxes listed in the grid's cells that meet the square of half
        side ``radius`` (N,) about the base centres (x, y) (N,).

        With ``radius`` = the clearance known from the walls and people plus
        the reach, every box left out has a base-centre distance above it:
        it can neither be the nearest nor pass :meth:`_box_terms`' broad
        phase, so the answers are those over all boxes (tested)."""
        grid = self.grid
        i0, j0, i1, j1 = cell_ranges(grid, np.column_stack([x - radius, y - radius]),
                                     np.column_stack([x + radius, y + radius]))
        ni, nj = np.maximum(i1 - i0 + 1, 0), np.maximum(j1 - j0 + 1, 0)
        per = ni * nj
        conf = np.repeat(np.arange(len(x)), per)
        r = np.arange(len(conf)) - np.repeat(np.cumsum(per) - per, per)
        cells = (i0[conf] + r % np.maximum(ni[conf], 1)) + (j0[conf] + r // np.maximum(ni[conf], 1)) * int(grid.dims[0])
        first, count = grid.start[cells], grid.start[cells + 1] - grid.start[cells]
        conf = np.repeat(conf, count)
        e = np.arange(len(conf)) - np.repeat(np.cumsum(count) - count, count) + np.repeat(first, count)
        k_total = len(self._box_half)
        key = np.unique(conf * k_total + grid.items[e])
        return key // k_total, key % k_total

    def clearances(self, qs: np.ndarray) -> np.ndarray:
        """Signed distances (N,) from the robot and object to the environment.

        Exact (metres) when positive; negative when some shape penetrates an
        obstacle, a person or a wall, and then only its sign is meaningful.
        Ignores the limits (see :meth:`in_limits`).
        """
        qs = np.asarray(qs, float).reshape(-1, 4)
        out = np.empty(len(qs))
        for i in range(0, len(qs), self.chunk):
            out[i : i + self.chunk] = self._clearances(qs[i : i + self.chunk])
        return out

    # ---- ValidityChecker ------------------------------------------------------

    def clearance(self, q: np.ndarray) -> float:
        """Signed distance (metres) of one configuration; see :meth:`clearances`."""
        return float(self.clearances(np.asarray(q, float)[None])[0])

    def are_valid(self, qs: np.ndarray) -> np.ndarray:
        """(N,) bool: within the limits and at positive clearance."""
        qs = np.asarray(qs, float).reshape(-1, 4)
        return self.in_limits(qs) & (self.clearances(qs) > 0.0)

    def is_valid(self, q: np.ndarray) -> bool:
        """One configuration (4,)."""
        return bool(self.are_valid(np.asarray(q, float)[None])[0])

    def motion_samples(self, q_a: np.ndarray, q_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The configurations a discrete check at :attr:`resolution` would visit.

        Edge e is cut into ``n_e = max(1, ceil(max_displacement / resolution))``
        equal steps and its ``n_e + 1`` configurations ``q_a + (k / n_e) dq``
        are listed, so no body point moves more than ``resolution`` between
        two of them. Not what :meth:`are_motions_valid` checks (it advances
        by clearance, soundly); kept for benchmarks and tests.

        Returns:
            ``(qs, starts)``: all samples (T, 4), edge after edge, and the
            index (E,) of each edge's first sample.
        """
        q_a = np.asarray(q_a, float).reshape(-1, 4)
        q_b = np.asarray(q_b, float).reshape(-1, 4)
        disp = self.geometry.max_displacement(q_a, q_b, include_body=True)
        n = np.maximum(1, np.ceil(disp / self.resolution)).astype(np.int64)
        counts = n + 1
        starts = np.cumsum(counts) - counts
        edge = np.repeat(np.arange(len(n)), counts)
        t = (np.arange(counts.sum()) - starts[edge]) / n[edge]
        qs = q_a[edge] + t[:, None] * (q_b - q_a)[edge]
        return qs, starts

    def are_motions_valid(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """(E,) bool: each straight motion is free, ends included (sound).

        Conservative advancement from both ends, all motions at once: a query
        at clearance c clears ``c / D`` of t around it (D the displacement
        bound per unit t), the next query sits at the first point not yet
        cleared; see :func:`drake_social.collision.planar_kernel.motion_valid`
        for the proof and the floors (``TOLERANCE``, ``STEP_MARGIN``,
        ``MAX_STEPS``), which are the same here.
        """
        q_a = np.asarray(q_a, float).reshape(-1, 4)
        q_b = np.asarray(q_b, float).reshape(-1, 4)
        dq = q_b - q_a
        span = self.geometry.max_displacement(q_a, q_b, include_body=True)
        ok = self.in_limits(q_a) & self.in_limits(q_b)
        c_a, c_b = self.clearances(q_a), self.clearances(q_b)
        ok &= (c_a > TOLERANCE) & (c_b > TOLERANCE)
        moving = ok & (span > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            lo = np.where(moving, (c_a - STEP_MARGIN) / span, 0.0)  # [0, lo) cleared
            hi = np.where(moving, 1.0 - (c_b - STEP_MARGIN) / span, 1.0)  # (hi, 1] cleared
        active = moving & (lo <= hi)
        for _ in range(MAX_STEPS):
            idx = np.flatnonzero(active)
            if len(idx) == 0:
                break
            qs = np.concatenate([q_a[idx] + lo[idx, None] * dq[idx], q_a[idx] + hi[idx, None] * dq[idx]])
            c = self.clearances(qs)
            c_lo, c_hi = c[: len(idx)], c[len(idx):]
            hit = (c_lo <= TOLERANCE) | (c_hi <= TOLERANCE)
            ok[idx[hit]] = False
            lo[idx] += (c_lo - STEP_MARGIN) / span[idx]
            hi[idx] -= (c_hi - STEP_MARGIN) / span[idx]
            active[idx] = ~hit & (lo[idx] <= hi[idx])
        ok[active] = False  # out of steps: rejected
        return ok

    def is_motion_valid(self, q_a: np.ndarray, q_b: np.ndarray) -> bool:
        """The straight motion from q_a to q_b (4,), ends included."""
        return bool(self.are_motions_valid(q_a, q_b)[0])
