"""Planar mobile-manipulator kinematics, batched over configurations (pure numpy).

Conventions (the paper's configuration ``q = [x, y, psi1, psi2]``):

* the base is a disc centred at ``p_WB = (x, y)``; it translates, never rotates;
* link 1 starts at the base centre, at angle ``psi1`` from the world x axis;
* link 2 starts at the tip of link 1, at angle ``psi2`` relative to link 1;
* the gripper frame G sits at the tip of link 2 with its x axis along link 2,
  so its world angle is ``psi1 + psi2``;
* the object is rigid in G: a polyline of vertices ``p_GO`` with a thickness.

Every function takes ``q`` of shape ``(..., 4)`` and keeps the leading shape.
Motions are straight lines in these coordinates (``(1 - t) q_a + t q_b``).
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np

__all__ = [
    "ArmGeometry",
    "config_distance",
    "cumulative_distance",
    "displacement_bound",
    "nominal_durations",
    "nominal_path_times",
    "polyline_distance",
]


def _gripper_cos_sin(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """cos and sin of the gripper's world angle psi1 + psi2, shape (...).

    By the angle-addition formulas: the sum itself overflows to inf (and its
    cosine to NaN) for finite angles beyond ~9e307.
    """
    c1, s1 = np.cos(q[..., 2]), np.sin(q[..., 2])
    c2, s2 = np.cos(q[..., 3]), np.sin(q[..., 3])
    return c1 * c2 - s1 * s2, s1 * c2 + c1 * s2


@dc.dataclass(frozen=True)
class ArmGeometry:
    """Dimensions of the robot and its object; all lengths in metres.

    Attributes:
        base_radius: radius of the base disc.
        link_lengths: (l1, l2).
        link_radius: radius of the link capsules (half the link width).
        object_points: (M, 2) object polyline in the gripper frame.
        object_radius: radius of the object capsules (half its thickness).
        object_interest: (P, 2) object interest points in the gripper frame.
    """

    base_radius: float
    link_lengths: tuple[float, float]
    link_radius: float
    object_points: np.ndarray
    object_radius: float
    object_interest: np.ndarray

    # ---- names and counts -------------------------------------------------

    @property
    def num_interest_points(self) -> int:
        """Base, link-1 tip, link-2 tip, then the object's points."""
        return 3 + len(self.object_interest)

    @property
    def interest_names(self) -> list[str]:
        return ["base", "link1_tip", "link2_tip"] + [
            f"object_{k + 1}" for k in range(len(self.object_interest))
        ]

    @property
    def num_segments(self) -> int:
        """Link 1, link 2, then the M - 1 object segments."""
        return 2 + len(self.object_points) - 1

    @property
    def segment_radii(self) -> np.ndarray:
        """(S,) capsule radii, in the order of :meth:`segments`."""
        n_obj = len(self.object_points) - 1
        return np.array([self.link_radius] * 2 + [self.object_radius] * n_obj)

    # ---- forward kinematics ------------------------------------------------

    def joints(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Shoulder (base centre), elbow and gripper origin, each (..., 2)."""
        q = np.asarray(q, dtype=float)
        x, y = self.interest_xy(q, np.arange(3))
        p = np.stack([x, y], -1)
        return p[..., 0, :], p[..., 1, :], p[..., 2, :]

    def gripper_to_world(self, q: np.ndarray, p_G: np.ndarray) -> np.ndarray:
        """Maps gripper-frame points (K, 2) to world points (..., K, 2)."""
        x, y = self._to_world_xy(np.asarray(q, dtype=float), np.asarray(p_G, float).reshape(-1, 2))
        return np.stack([x, y], -1)

    def _to_world_xy(self, q: np.ndarray, p_G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World x and y (..., K) of gripper-frame points p_G (K, 2)."""
        l1, l2 = self.link_lengths
        c1, s1 = np.cos(q[..., 2]), np.sin(q[..., 2])
        c12, s12 = _gripper_cos_sin(q)
        gx = (q[..., 0] + l1 * c1 + l2 * c12)[..., None]
        gy = (q[..., 1] + l1 * s1 + l2 * s12)[..., None]
        c12, s12 = c12[..., None], s12[..., None]
        return gx + c12 * p_G[:, 0] - s12 * p_G[:, 1], gy + s12 * p_G[:, 0] + c12 * p_G[:, 1]

    def interest_xy(self, q: np.ndarray, active: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """World x and y (..., K) of the interest points ``active`` (None = all).

        The batched fast path of :meth:`interest_points` (no rotation
        matrices, no (..., 2) stacking), used by the social cost.
        """
        q = np.asarray(q, dtype=float)
        l1, l2 = self.link_lengths
        c1, s1 = np.cos(q[..., 2]), np.sin(q[..., 2])
        c12, s12 = _gripper_cos_sin(q)
        ex, ey = q[..., 0] + l1 * c1, q[..., 1] + l1 * s1
        gx, gy = ex + l2 * c12, ey + l2 * s12
        xs = [q[..., 0], ex, gx]
        ys = [q[..., 1], ey, gy]
        if len(self.object_interest):
            p = self.object_interest
            xs.append(gx[..., None] + c12[..., None] * p[:, 0] - s12[..., None] * p[:, 1])
            ys.append(gy[..., None] + s12[..., None] * p[:, 0] + c12[..., None] * p[:, 1])
        x = np.concatenate([np.stack(xs[:3], -1), *xs[3:]], -1)
        y = np.concatenate([np.stack(ys[:3], -1), *ys[3:]], -1)
        if active is not None:
            x, y = x[..., active], y[..., active]
        return x, y

    def interest_points(self, q: np.ndarray) -> np.ndarray:
        """World interest points (..., 3 + P, 2), in :attr:`interest_names` order."""
        return np.stack(self.interest_xy(q), -1)

    def segments(self, q: np.ndarray) -> np.ndarray:
        """Capsule axes (..., S, 2, 2): link 1, link 2, object segments.

        ``segments(q)[..., s, 0]`` and ``[..., s, 1]`` are the ends of capsule s,
        whose radius is ``segment_radii[s]``. The base disc is ``q[..., :2]``
        with radius :attr:`base_radius`.
        """
        p_WB, p_WE, p_WG = self.joints(q)
        links = np.stack([np.stack([p_WB, p_WE], -2), np.stack([p_WE, p_WG], -2)], -3)
        verts = self.gripper_to_world(q, self.object_points)  # (..., M, 2)
        obj = np.stack([verts[..., :-1, :], verts[..., 1:, :]], -2)  # (..., M-1, 2, 2)
        return np.concatenate([links, obj], -3)

    # ---- displacement bounds -------------------------------------------------

    def reach(self, include_body: bool = False, active: np.ndarray | None = None) -> np.ndarray:
        """Lever arms (1, 1, c1, c2) bounding point displacement per coordinate.

        ``c2`` is the largest distance of a tracked point from the elbow and
        ``c1`` bounds its distance from the shoulder (``l1 + c2``), so a
        point moves at most ``hypot(dx, dy) + c1 |dpsi1| + c2 |dpsi2|``: the
        per-coordinate form Drake's weighted distance needs
        (:mod:`drake_social.collision.drake_checker`). :meth:`lever` gives a tighter
        bound in the coordinates (psi1, psi1 + psi2).

        Args:
            include_body: False tracks interest points (for the social
                integral); True tracks every point of the links and the object,
                capsule radii included (for collision checking).
            active: with include_body False, the indices of the tracked
                interest points (None = all); e.g. only those with a weight.
        """
        l1, l2 = self.link_lengths
        if include_body:
            extra = max(self.object_radius, self.link_radius)
            from_elbow = [l2, *np.hypot(l2 + self.object_points[:, 0], self.object_points[:, 1])]
            c2 = max(from_elbow) + extra
            return np.array([1.0, 1.0, l1 + c2, c2])
        idx = set(range(self.num_interest_points) if active is None else np.asarray(active).tolist())
        from_elbow = [l2] if 2 in idx else []
        from_elbow += [
            float(np.hypot(l2 + p[0], p[1])) for k, p in enumerate(self.object_interest) if 3 + k in idx
        ]
        c2 = max(from_elbow, default=0.0)
        c1 = l1 + c2 if from_elbow else (l1 if 1 in idx else 0.0)
        return np.array([1.0, 1.0, c1, c2])

    def lever(self, include_body: bool = False, active: np.ndarray | None = None) -> np.ndarray:
        """Lever arms ``(c_shoulder, c_gripper)`` of :func:`displacement_bound`.

        A point rigid with link 1 within ``c_shoulder`` of the shoulder, or a
        point ``p = p_elbow + R(psi1 + psi2) g`` with ``|g| <= c_gripper``
        moves at most ``hypot(dx, dy) + c_shoulder |dpsi1| + c_gripper
        |dpsi1 + dpsi2|`` along a straight motion: the elbow turns with psi1
        alone, everything beyond it with the sum. Tighter than
        :meth:`reach` when the joints counter-rotate.

        Args:
            include_body: as in :meth:`reach` (capsule radii included).
            active: as in :meth:`reach`.
        """
        l1, l2 = self.link_lengths
        if include_body:
            r = max(self.object_radius, self.link_radius)
            g = max(l2, *np.hypot(l2 + self.object_points[:, 0], self.object_points[:, 1]))
            return np.array([l1 + r, g + r])
        idx = set(range(self.num_interest_points) if active is None else np.asarray(active).tolist())
        g = [l2] if 2 in idx else []
        g += [float(np.hypot(l2 + p[0], p[1])) for k, p in enumerate(self.object_interest) if 3 + k in idx]
        return np.array([l1 if (g or 1 in idx) else 0.0, max(g, default=0.0)])

    def max_displacement(
        self, q_a: np.ndarray, q_b: np.ndarray, include_body: bool = False, active: np.ndarray | None = None
    ) -> np.ndarray:
        """An upper bound (...,) on how far any tracked point moves from q_a to q_b.

        See :meth:`lever` and :func:`displacement_bound`.
        """
        return displacement_bound(np.asarray(q_b, float) - np.asarray(q_a, float), self.lever(include_body, active))


def displacement_bound(dq: np.ndarray, lever: np.ndarray) -> np.ndarray:
    """``hypot(dx, dy) + c_s |dpsi1| + c_g |dpsi1 + dpsi2|`` for motions dq
    (..., 4) and lever arms ``(c_s, c_g)`` from :meth:`ArmGeometry.lever`."""
    return (
        np.hypot(dq[..., 0], dq[..., 1])
        + lever[0] * np.abs(dq[..., 2])
        + lever[1] * np.abs(dq[..., 2] + dq[..., 3])
    )


def config_distance(q_a: np.ndarray, q_b: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Configuration-space distance ``|| W (q_b - q_a) ||`` (the paper's norm).

    Args:
        q_a, q_b: configurations (..., 4), broadcastable.
        weights: optional per-coordinate scale factors (4,); None = all ones.

    Returns:
        Distances of the broadcast leading shape.
    """
    d = np.asarray(q_b, float) - np.asarray(q_a, float)
    if weights is not None:
        d = d * np.asarray(weights, float)
    return np.sqrt(np.einsum("...i,...i->...", d, d))


def cumulative_distance(waypoints: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Cumulative configuration distance (N,) at each of N waypoints (N, 4),
    starting at 0: the path parameter of the paper's Fig. 6/8."""
    wp = np.asarray(waypoints, float).reshape(-1, 4)
    if len(wp) == 0:
        return np.zeros(0)
    return np.concatenate([[0.0], np.cumsum(config_distance(wp[:-1], wp[1:], weights))])


def nominal_durations(q_a: np.ndarray, q_b: np.ndarray, max_base_speed: float,
                      arm_max_velocity) -> np.ndarray:
    """The time (E,) seconds of each straight motion q_a[e] -> q_b[e] driven
    at the execution limits: the longest of its base distance /
    ``max_base_speed`` and each joint's ``|delta psi_j| / arm_max_velocity[j]``
    (no acceleration phases: a lower bound on an executed motion's time).
    The planner's time along a path (time-indexed cost and safety) and the
    plan figures' walker tracks both use it."""
    a = np.asarray(q_a, float).reshape(-1, 4)
    b = np.asarray(q_b, float).reshape(-1, 4)
    d = b - a
    base = np.hypot(d[:, 0], d[:, 1]) / float(max_base_speed)
    arm = np.abs(d[:, 2:]) / np.asarray(arm_max_velocity, float).reshape(2)
    return np.maximum(base, arm.max(axis=1))


def nominal_path_times(waypoints: np.ndarray, max_base_speed: float, arm_max_velocity,
                       t0: float = 0.0) -> np.ndarray:
    """The time (N,) at which each waypoint is reached when the path is driven
    from ``t0`` at the execution limits (:func:`nominal_durations` summed)."""
    wp = np.asarray(waypoints, float).reshape(-1, 4)
    if len(wp) < 2:
        return np.full(len(wp), float(t0))
    return float(t0) + np.concatenate([[0.0], np.cumsum(nominal_durations(wp[:-1], wp[1:], max_base_speed,
                                                                          arm_max_velocity))])


def polyline_distance(points: np.ndarray, line: np.ndarray) -> np.ndarray:
    """The distance (...,) of each point (..., 2) to the polyline ``line``
    (L, 2), L >= 1 (a point when L = 1), metres."""
    points, line = np.asarray(points, float), np.asarray(line, float).reshape(-1, 2)
    if len(line) == 1:
        return np.linalg.norm(points - line[0], axis=-1)
    a, b = line[:-1], line[1:]
    ab = b - a
    den = np.maximum(np.einsum("sd,sd->s", ab, ab), 1e-300)
    rel = points[..., None, :] - a  # (..., S, 2)
    u = np.clip(np.einsum("...sd,sd->...s", rel, ab) / den, 0.0, 1.0)
    nearest = a + u[..., None] * ab
    return np.linalg.norm(points[..., None, :] - nearest, axis=-1).min(axis=-1)
