"""A pure-numpy validity checker: discs and capsules against boxes, discs and walls.

It implements :class:`~drake_social.planning.validity.ValidityChecker` with
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

Everything is batched over configurations; motions are sampled so that no
body point moves more than ``resolution`` between checks
(``ArmGeometry.max_displacement(include_body=True)``).
"""

from __future__ import annotations

import numpy as np

from drake_social.kinematics import ArmGeometry
from drake_social.scenario import Scenario

__all__ = ["GeometricChecker"]


def _box_sdf(p: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Signed distance (...,) of points p (..., 2), in box frames, to boxes of half sizes (..., 2)."""
    u = np.abs(p) - half
    outside = np.sqrt(np.square(np.maximum(u, 0.0)).sum(-1))
    return outside + np.minimum(np.maximum(u[..., 0], u[..., 1]), 0.0)


def _segment_box_sdf(a: np.ndarray, b: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Minimum over segment [a, b] of the box signed distance.

    Args:
        a, b: segment ends (..., 2) in the box frames.
        half: box half sizes (..., 2), broadcastable.

    Returns:
        (...,) the minimum of ``_box_sdf`` along each segment (negative when
        the segment enters the box).
    """
    d = b - a
    hx, hy = half[..., 0], half[..., 1]
    c = hx - hy
    ax, ay, dx, dy = a[..., 0], a[..., 1], d[..., 0], d[..., 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        dd = dx * dx + dy * dy
        cand = [
            # corner projections (the stationary points of the corner regions)
            ((sx * hx - ax) * dx + (sy * hy - ay) * dy) / dd
            for sx in (-1.0, 1.0)
            for sy in (-1.0, 1.0)
        ]
        cand += [-ax / dx, -ay / dy]  # x = 0, y = 0
        cand += [(s * c - (ax - ay)) / (dx - dy) for s in (-1.0, 1.0)]  # x - y = +-c
        cand += [(s * c - (ax + ay)) / (dx + dy) for s in (-1.0, 1.0)]  # x + y = +-c
        t = np.stack(cand, -1)
    t = np.clip(np.nan_to_num(t, nan=0.0, posinf=0.0, neginf=0.0), 0.0, 1.0)
    t = np.concatenate([t, np.zeros_like(t[..., :1]), np.ones_like(t[..., :1])], -1)
    p = a[..., None, :] + t[..., None] * d[..., None, :]
    return _box_sdf(p, half[..., None, :]).min(-1)


def _point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance (...,) from points p to segments [a, b], all (..., 2) broadcastable."""
    d = b - a
    dd = np.einsum("...i,...i->...", d, d)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.einsum("...i,...i->...", p - a, d) / dd
    t = np.clip(np.nan_to_num(t, nan=0.0), 0.0, 1.0)
    closest = a + t[..., None] * d
    return np.sqrt(np.square(p - closest).sum(-1))


class GeometricChecker:
    """The Drake-free :class:`ValidityChecker` of a scenario.

    Args:
        scenario: the room, people, robot and object.
        resolution: largest displacement of any body point between two
            checked configurations of a motion, metres; None =
            ``scenario.planner.collision_resolution``.
        chunk: configurations evaluated per numpy batch (bounds memory).

    Attributes:
        geometry: the robot's :class:`ArmGeometry`.
        lower, upper: (4,) limits of ``q``: the room bounds for ``(x, y)``,
            the joint limits for ``(psi1, psi2)``.
        resolution: see above.
    """

    def __init__(self, scenario: Scenario, resolution: float | None = None, chunk: int = 4096):
        self.geometry = ArmGeometry.from_scenario(scenario)
        self.resolution = float(scenario.planner.collision_resolution if resolution is None else resolution)
        if not self.resolution > 0:
            raise ValueError(f"resolution must be > 0 metres, got {resolution}")
        self.chunk = int(chunk)
        w, r = scenario.world, scenario.robot
        self.bounds = np.asarray(w.bounds, float)
        self.lower = np.array([self.bounds[0], self.bounds[1], *r.joint_lower], float)
        self.upper = np.array([self.bounds[2], self.bounds[3], *r.joint_upper], float)
        boxes = w.obstacles
        self._box_center = np.array([b.center for b in boxes], float).reshape(-1, 2)
        self._box_half = np.array([b.size for b in boxes], float).reshape(-1, 2) / 2
        yaw = np.array([b.yaw for b in boxes], float)
        # R_BW: rows are the box axes in world coordinates, (K, 2, 2).
        self._box_R = np.stack([np.stack([np.cos(yaw), np.sin(yaw)], -1), np.stack([-np.sin(yaw), np.cos(yaw)], -1)], -2)
        self._people = np.array([[p.x, p.y] for p in scenario.people], float).reshape(-1, 2)
        self._people_r = np.array([p.radius for p in scenario.people], float)
        g = self.geometry
        self._radii = g.segment_radii
        # Segment s runs from vertex _seg[s, 0] to vertex _seg[s, 1] of _vertices().
        m = len(g.object_points)
        self._seg = np.array([[0, 1], [1, 2]] + [[3 + k, 4 + k] for k in range(m - 1)])

    # ---- geometry -------------------------------------------------------------

    def _vertices(self, q: np.ndarray) -> np.ndarray:
        """(N, 3 + M, 2): base centre, elbow, gripper, object vertices."""
        p_WB, p_WE, p_WG = self.geometry.joints(q)
        obj = self.geometry.gripper_to_world(q, self.geometry.object_points)
        return np.concatenate([np.stack([p_WB, p_WE, p_WG], -2), obj], -2)

    def in_limits(self, qs: np.ndarray) -> np.ndarray:
        """Whether configurations (..., 4) lie within :attr:`lower`, :attr:`upper`."""
        qs = np.asarray(qs, float)
        return np.all((qs >= self.lower) & (qs <= self.upper), axis=-1)

    def _clearances(self, q: np.ndarray) -> np.ndarray:
        v = self._vertices(q)  # (N, V, 2)
        a, b = v[:, self._seg[:, 0]], v[:, self._seg[:, 1]]  # (N, S, 2)
        rb = self.geometry.base_radius
        x0, y0, x1, y1 = self.bounds
        margin = np.minimum(np.minimum(v[..., 0] - x0, x1 - v[..., 0]), np.minimum(v[..., 1] - y0, y1 - v[..., 1]))
        terms = [
            margin[:, 0] - rb,
            (np.minimum(margin[:, self._seg[:, 0]], margin[:, self._seg[:, 1]]) - self._radii).min(-1),
        ]
        if len(self._box_center):
            # Vertices in every box frame: (N, V, K, 2).
            v_B = np.einsum("kij,nvkj->nvki", self._box_R, v[:, :, None, :] - self._box_center)
            terms.append(_box_sdf(v_B[:, 0], self._box_half).min(-1) - rb)
            seg_sd = _segment_box_sdf(v_B[:, self._seg[:, 0]], v_B[:, self._seg[:, 1]], self._box_half)
            terms.append((seg_sd.min(-1) - self._radii).min(-1))
        if len(self._people):
            c = self._people  # (P, 2)
            base_d = np.sqrt(np.square(v[:, 0, None, :] - c).sum(-1)) - self._people_r - rb
            terms.append(base_d.min(-1))
            seg_d = _point_segment_distance(c, a[:, :, None, :], b[:, :, None, :])  # (N, S, P)
            terms.append((seg_d - self._people_r - self._radii[:, None]).min(-1).min(-1))
        return np.min(np.stack(terms, -1), -1)

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
        """The configurations checked along straight motions.

        Edge e is cut into ``n_e = max(1, ceil(max_displacement / resolution))``
        equal steps and its ``n_e + 1`` configurations ``q_a + (k / n_e) dq``
        are checked, so no body point moves more than ``resolution`` between
        two of them.

        Returns:
            ``(qs, starts)``: all samples (T, 4), edge after edge, and the
            index (E,) of each edge's first sample.
        """
        q_a = np.asarray(q_a, float).reshape(-1, 4)
        q_b = np.asarray(q_b, float).reshape(-1, 4)
        disp = self.geometry.max_displacement(q_a, q_b, include_body=True)
        n = np.maximum(1, np.ceil(disp / self.resolution)).astype(np.int64)
        counts = n + 1
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        edge = np.repeat(np.arange(len(n)), counts)
        t = (np.arange(counts.sum()) - starts[edge]) / n[edge]
        qs = q_a[edge] + t[:, None] * (q_b - q_a)[edge]
        return qs, starts

    def are_motions_valid(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """(E,) bool: every sampled configuration of each motion is valid."""
        qs, starts = self.motion_samples(q_a, q_b)
        return np.logical_and.reduceat(self.are_valid(qs), starts)

    def is_motion_valid(self, q_a: np.ndarray, q_b: np.ndarray) -> bool:
        """The straight motion from q_a to q_b (4,), ends included."""
        return bool(self.are_motions_valid(q_a, q_b)[0])
