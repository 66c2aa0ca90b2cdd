"""The robot's smallest surface distance to people, compiled with numba.

:func:`drake_social.people.proximity.robot_distance` calls :func:`robot_distance`
for one configuration: the safety monitor asks it every control period, where
:func:`~drake_social.people.proximity.part_distances` (the numpy reference,
batched over configurations) would build a dozen small arrays. The kernel does
the same floating-point operations in the same order as the reference (the
forward kinematics of :class:`~drake_social.kinematics.ArmGeometry`, then the
point and segment distances), so its value is the reference's ``robot``
distance; the tests compare the two on random cases.

The kernel calls no other module's compiled function, so numba's own cache
check (this file's source) keeps its on-disk cache fresh.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["robot_distance"]


@njit(cache=True)
def _segment(px, py, ax, ay, bx, by):
    """Distance from (px, py) to segment a-b, as ``proximity.segment_point_distance``."""
    dx, dy = bx - ax, by - ay
    denom = dx * dx + dy * dy
    t = ((px - ax) * dx + (py - ay) * dy) / denom if denom > 0 else 0.0
    t = min(max(t, 0.0), 1.0)
    ex, ey = px - (ax + t * dx), py - (ay + t * dy)
    return math.sqrt(ex * ex + ey * ey)


@njit(cache=True)
def robot_distance(q, cos, sin, link_lengths, link_radius, base_radius, object_points, object_radius,
                   centres, radii, present):
    """Smallest surface distance of the base disc, the links and the object's
    capsules to a present person's body disc, metres (+inf with nobody present).

    Args:
        q: (4,) configuration [x, y, psi1, psi2].
        cos, sin: (2,) cosines and sines of psi1 and psi2 (numpy's, as the
            reference's kinematics).
        link_lengths: (2,) metres; link_radius, base_radius, object_radius: metres.
        object_points: (V, 2) the object's polyline in the gripper frame, V >= 2.
        centres: (P, 2) body centres; radii: (P,) body radii; present: (P,) booleans.
    """
    l1, l2 = link_lengths[0], link_lengths[1]
    c1, s1, c2, s2 = cos[0], sin[0], cos[1], sin[1]
    c12 = c1 * c2 - s1 * s2
    s12 = s1 * c2 + c1 * s2
    bx, by = q[0], q[1]
    ex, ey = bx + l1 * c1, by + l1 * s1
    gx, gy = ex + l2 * c12, ey + l2 * s12
    nv = object_points.shape[0]
    vx = np.empty(nv)
    vy = np.empty(nv)
    for k in range(nv):
        vx[k] = gx + c12 * object_points[k, 0] - s12 * object_points[k, 1]
        vy[k] = gy + s12 * object_points[k, 0] + c12 * object_points[k, 1]
    best = math.inf
    for i in range(centres.shape[0]):
        if not present[i]:
            continue
        px, py, r = centres[i, 0], centres[i, 1], radii[i]
        dx, dy = bx - px, by - py
        best = min(best, math.sqrt(dx * dx + dy * dy) - r - base_radius)
        best = min(best, _segment(px, py, bx, by, ex, ey) - r - link_radius)
        best = min(best, _segment(px, py, ex, ey, gx, gy) - r - link_radius)
        for k in range(nv - 1):
            best = min(best, _segment(px, py, vx[k], vy[k], vx[k + 1], vy[k + 1]) - r - object_radius)
    return best
