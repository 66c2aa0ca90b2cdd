"""What was executed, measured against what was planned (no Drake here).

* :func:`body_points`: the tracked points of the robot (base, elbow, gripper,
  the object's interest points and polyline vertices) at configurations.
* :func:`point_deviation`: for each tracked point, the largest distance of
  its executed position from the curve that point traces along the planned
  path (metres).
* :func:`config_deviation`: the largest configuration-space distance of an
  executed configuration from the planned waypoint polyline.
* :func:`densify`: cuts an executed trajectory so that no body point moves
  more than a resolution between consecutive configurations, so that
  checking every configuration is the checker's discrete guarantee.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from drake_social.kinematics import ArmGeometry

__all__ = ["body_point_names", "body_points", "config_deviation", "densify", "point_deviation"]


def body_point_names(geometry: ArmGeometry) -> list[str]:
    """Names of :func:`body_points`, in order."""
    names = geometry.interest_names
    names += [f"object_vertex_{k + 1}" for k in range(len(geometry.object_points))]
    return names


def body_points(geometry: ArmGeometry, q: np.ndarray) -> np.ndarray:
    """World positions (..., K, 2) of the tracked points at configurations ``q`` (..., 4).

    The interest points (base centre, link-1 tip, link-2 tip, the object's
    interest points) then the object's polyline vertices; see
    :func:`body_point_names`.
    """
    q = np.asarray(q, float)
    return np.concatenate([geometry.interest_points(q), geometry.gripper_to_world(q, geometry.object_points)], -2)


def densify(geometry: ArmGeometry, q: np.ndarray, resolution: float) -> np.ndarray:
    """Configurations along the straight pieces between consecutive ``q`` (T, 4)
    such that no body point (capsule radii included) moves more than
    ``resolution`` metres between neighbours; the given ones are kept."""
    q = np.asarray(q, float).reshape(-1, 4)
    if len(q) < 2:
        return q.copy()
    span = geometry.max_displacement(q[:-1], q[1:], include_body=True)
    n = np.maximum(1, np.ceil(span / resolution).astype(int))
    pieces = [q[:1]]
    for a, b, k in zip(q[:-1], q[1:], n):
        t = (np.arange(1, k + 1) / k)[:, None]
        pieces.append(a + t * (b - a))
    return np.concatenate(pieces)


def point_deviation(
    geometry: ArmGeometry, planned: np.ndarray, executed: np.ndarray, spacing: float = 0.002
) -> dict[str, float]:
    """Largest distance of each executed body point from its planned curve, metres.

    The planned curve of a point is sampled so that consecutive samples are
    at most ``spacing`` apart; the distance to the nearest sample then
    exceeds the distance to the curve by at most ``spacing / 2``, so the
    figures are upper bounds within that.

    Args:
        geometry: the robot and object.
        planned: (N, 4) waypoints of the planned path (straight segments).
        executed: (T, 4) executed configurations.
        spacing: sample spacing along the planned curves, metres.

    Returns:
        name -> largest deviation (see :func:`body_point_names`), plus
        ``"max"`` over all points.
    """
    dense = densify(geometry, planned, spacing)
    planned_pts = body_points(geometry, dense)  # (M, K, 2)
    executed_pts = body_points(geometry, executed)  # (T, K, 2)
    out = {}
    for k, name in enumerate(body_point_names(geometry)):
        d, _ = cKDTree(planned_pts[:, k]).query(executed_pts[:, k])
        out[name] = float(np.max(d)) if len(d) else 0.0
    out["max"] = max(out.values(), default=0.0)
    return out


def config_deviation(planned: np.ndarray, executed: np.ndarray) -> float:
    """Largest Euclidean configuration-space distance (metres and radians
    mixed, as the planner's plain norm) of an executed configuration from the
    polyline through the planned waypoints; exact, point to segment."""
    p = np.asarray(planned, float).reshape(-1, 4)
    x = np.asarray(executed, float).reshape(-1, 4)
    if len(p) == 1:
        return float(np.max(np.linalg.norm(x - p[0], axis=1))) if len(x) else 0.0
    a, d = p[:-1], np.diff(p, axis=0)  # (S, 4)
    dd = np.einsum("sk,sk->s", d, d)
    best = np.full(len(x), np.inf)
    for start in range(0, len(x), 2048):  # bounded memory: (chunk, S, 4)
        xc = x[start:start + 2048, None, :]
        t = np.einsum("tsk,sk->ts", xc - a, d) / np.where(dd > 0, dd, 1.0)
        t = np.clip(np.where(dd > 0, t, 0.0), 0.0, 1.0)
        dist = np.linalg.norm(xc - (a + t[..., None] * d), axis=-1)
        best[start:start + 2048] = dist.min(axis=1)
    return float(best.max()) if len(best) else 0.0
