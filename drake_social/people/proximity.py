"""How close the robot's parts come to people: surface-to-surface distances.

The one home of the robot-to-people distance read by the safety monitor
(:class:`drake_social.control.SafetyMonitor`), the crowd's view of the robot
and the metrics (:mod:`drake_social.evaluation.metrics`). A person is a body
disc (centre, radius); the robot is its base disc, its interest points (the
elbow, the gripper and the object's points, as points) and its capsules (two
links, the object's segments). Distances are exact for these shapes.
"""

from __future__ import annotations

import numpy as np

from drake_social.kinematics import ArmGeometry
from drake_social.people import proximity_kernel

__all__ = ["DISTANCE_CHUNK_ELEMENTS", "part_distances", "part_names", "robot_distance", "robot_distance_args", "segment_point_distance"]

#: (configuration, point or segment, person) distances per block of :func:`part_distances`: each
#: temporary holds at most this many values (2 MB, 4 MB for the offsets), however many configurations
#: and people (at least one configuration per block).
DISTANCE_CHUNK_ELEMENTS = 1 << 18


def part_names(geometry: ArmGeometry) -> list[str]:
    """The interest points (base first), then ``arm``, ``object`` and ``robot``."""
    return geometry.interest_names + ["arm", "object", "robot"]


def segment_point_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from points ``p`` (..., H, 2) to segments a-b (..., S, 2): (..., S, H), metres.

    ``p`` has the same leading dimensions as the segments (or none)."""
    p = np.asarray(p, float)
    d = b - a
    ap = p[..., None, :, :] - a[..., :, None, :]  # (..., S, H, 2)
    denom = np.einsum("...i,...i->...", d, d)[..., None]
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(denom > 0, np.einsum("...hi,...i->...h", ap, d) / np.where(denom > 0, denom, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    closest = a[..., :, None, :] + t[..., None] * d[..., :, None, :]
    return np.linalg.norm(p[..., None, :, :] - closest, axis=-1)


def part_distances(geometry: ArmGeometry, q: np.ndarray, centres: np.ndarray, radii: np.ndarray,
                   present: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Surface-to-surface distance (M,) of every part to the nearest present
    person's body disc, metres; 0 is contact, negative is overlap, +inf when
    nobody is present.

    Args:
        geometry: the robot and its object.
        q: (M, 4) configurations.
        centres: people's body centres, (P, 2) for people standing still, or
            (M, P, 2), where they are at each configuration's time.
        radii: (P,) body radii, metres.
        present: (P,) or (M, P) booleans; None = everyone.

    Returns:
        ``{part: (M,) distances}`` for :func:`part_names`.

    Memory does not grow with M: the configurations are measured in blocks
    (:data:`DISTANCE_CHUNK_ELEMENTS`).
    """
    q = np.asarray(q, float).reshape(-1, 4)
    m = len(q)
    radii = np.asarray(radii, float).reshape(-1)
    n = len(radii)
    centres = np.broadcast_to(np.asarray(centres, float).reshape(-1, n, 2) if n else np.zeros((1, 0, 2)), (m, n, 2))
    present = np.ones((m, n), bool) if present is None else np.broadcast_to(np.asarray(present, bool), (m, n))
    names = part_names(geometry)
    if n == 0:
        return {name: np.full(m, np.inf) for name in names}
    rows = max(1, DISTANCE_CHUNK_ELEMENTS // (n * max(len(geometry.interest_names), len(geometry.segment_radii))))
    if m > rows:  # in blocks of configurations: each row's distances are those of the whole at once
        blocks = [part_distances(geometry, q[i:i + rows], centres[i:i + rows], radii, present[i:i + rows])
                  for i in range(0, m, rows)]
        return {name: np.concatenate([b[name] for b in blocks]) for name in names}
    absent = np.where(present, 0.0, np.inf)[:, None, :]  # (M, 1, P)
    pts = geometry.interest_points(q)  # (M, K, 2)
    d_pts = np.linalg.norm(pts[:, :, None, :] - centres[:, None, :, :], axis=-1) - radii + absent  # (M, K, P)
    d_pts[:, 0] -= geometry.base_radius
    out = {name: d_pts[:, k].min(-1) for k, name in enumerate(geometry.interest_names)}
    seg = geometry.segments(q)  # (M, S, 2, 2)
    d_seg = segment_point_distance(centres, seg[..., 0, :], seg[..., 1, :]) - radii + absent  # (M, S, P)
    d_seg -= geometry.segment_radii[:, None]
    out["arm"] = d_seg[:, :2].min(axis=(1, 2))
    out["object"] = d_seg[:, 2:].min(axis=(1, 2))
    out["robot"] = np.minimum.reduce([out["base"], out["arm"], out["object"]])
    return out


def robot_distance_args(geometry: ArmGeometry) -> tuple:
    """The robot's arguments of :func:`drake_social.people.proximity_kernel.robot_distance`
    (link lengths, link radius, base radius, object polyline, object radius),
    packed once for a caller that asks many times (the safety monitor)."""
    return (np.asarray(geometry.link_lengths, float).reshape(2), float(geometry.link_radius),
            float(geometry.base_radius), np.ascontiguousarray(geometry.object_points, float).reshape(-1, 2),
            float(geometry.object_radius))


def robot_distance(geometry: ArmGeometry | tuple, q: np.ndarray, centres: np.ndarray, radii: np.ndarray,
                   present: np.ndarray | None = None) -> float:
    """Surface-to-surface distance of the robot (base disc, links, object) at one
    configuration to the nearest present person, metres: the ``robot`` entry of
    :func:`part_distances` for ``q`` (4,), computed without its arrays (a
    compiled loop, the same operations; +inf when nobody is present).

    Args:
        geometry: the robot and its object, or :func:`robot_distance_args` of them.
        q: (4,) configuration.
        centres: (P, 2) body centres, metres; radii: (P,) body radii, metres.
        present: (P,) booleans; None = everyone.
    """
    args = robot_distance_args(geometry) if isinstance(geometry, ArmGeometry) else geometry
    q = np.asarray(q, float).reshape(4)
    centres = np.asarray(centres, float).reshape(-1, 2)
    radii = np.asarray(radii, float).reshape(-1)
    present = np.ones(len(radii), bool) if present is None else np.asarray(present, bool).reshape(-1)
    if not (len(centres) == len(radii) == len(present)):
        raise ValueError(f"robot_distance: {len(centres)} centres, {len(radii)} radii and {len(present)} "
                         "presence flags; one of each per person")
    return float(proximity_kernel.robot_distance(q, np.cos(q[2:]), np.sin(q[2:]), *args, centres, radii, present))
