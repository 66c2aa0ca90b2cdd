"""Hall's proxemic zones and the geometric measures of a track shared by the
path metrics (:mod:`drake_social.evaluation.metrics`) and the metrics over
time (:mod:`drake_social.evaluation.nav_metrics`).
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np

from drake_social.kinematics import ArmGeometry

__all__ = ["HEADING_STEP", "SHAPE_SPACING", "ZONES", "HallZones", "base_irregularity", "shape_points", "zone_shares"]

#: Spacing of the points sampled along a capsule's axis for its AGF, metres.
SHAPE_SPACING = 0.05
#: Resampling step of the base track before heading changes are summed, metres.
HEADING_STEP = 0.05


@dc.dataclass(frozen=True)
class HallZones:
    """Upper bounds of Hall's proxemic zones (surface-to-surface), metres.

    Attributes:
        intimate: below this, intimate (0.45 m).
        personal: below this, personal (1.2 m).
        social: below this, social (3.6 m); beyond, public.
    """

    intimate: float = 0.45
    personal: float = 1.2
    social: float = 3.6

    @property
    def names(self) -> tuple[str, ...]:
        return ("intimate", "personal", "social", "public")

    def classify(self, distance: np.ndarray) -> np.ndarray:
        """Zone index (0 intimate .. 3 public) of each distance."""
        return np.searchsorted([self.intimate, self.personal, self.social], np.asarray(distance, float), side="right")


#: The zones used by the studies.
ZONES = HallZones()


def shape_points(geometry: ArmGeometry, q: np.ndarray, which: slice, reference: np.ndarray | None = None) -> np.ndarray:
    """Points (M, n, 2) every <= :data:`SHAPE_SPACING` metres along the capsule
    axes ``which`` (a slice of :meth:`ArmGeometry.segments`) at configurations q (M, 4).

    The axes are rigid, but their lengths measured at a configuration differ
    in the last bit from one configuration to another, which can change n:
    n is that of ``reference`` (4,), None = ``q[0]``; a caller that takes a
    run in parts passes the run's first configuration to get the points of
    the whole at once.
    """
    seg = geometry.segments(q)[:, which]  # (M, S', 2, 2)
    ref = seg[0] if reference is None else geometry.segments(np.asarray(reference, float).reshape(1, 4))[0, which]
    lengths = np.linalg.norm(ref[:, 1] - ref[:, 0], axis=-1)
    pieces = []
    for s, length in enumerate(lengths):
        t = np.linspace(0.0, 1.0, max(2, int(np.ceil(length / SHAPE_SPACING)) + 1))
        pieces.append(seg[:, s, 0, None, :] + t[None, :, None] * (seg[:, s, 1, None, :] - seg[:, s, 0, None, :]))
    return np.concatenate(pieces, axis=1)


def zone_shares(distance: np.ndarray, weights: np.ndarray, zones: HallZones = ZONES) -> dict[str, float]:
    """Share of the total weight spent in each zone.

    Args:
        distance: (M,) distances at the samples, metres.
        weights: (M - 1,) weight of each step between samples (arc length, time).

    Returns:
        zone name -> share in [0, 1] (NaN each when the weights sum to 0).
    """
    distance = np.asarray(distance, float)
    w = np.asarray(weights, float)
    total = float(w.sum())
    if len(distance) < 2 or not total > 0:
        return {z: float("nan") for z in zones.names}
    zone = zones.classify(0.5 * (distance[:-1] + distance[1:]))
    share = np.bincount(zone, weights=w, minlength=4) / total
    return {z: float(share[k]) for k, z in enumerate(zones.names)}


def base_irregularity(xy: np.ndarray, step: float = HEADING_STEP) -> float:
    """Total absolute heading change of a base track per metre of it, rad/m.

    The track (M, 2) is resampled every ``step`` metres of arc length (its
    end kept) so that steps far below the resolution do not count; 0 for a
    straight or motionless track.
    """
    xy = np.asarray(xy, float).reshape(-1, 2)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))]) if len(xy) else np.zeros(0)
    if len(xy) < 2 or s[-1] <= step:
        return 0.0
    keep = np.concatenate([[True], np.diff(s) > 0])
    xy, s = xy[keep], s[keep]
    targets = np.append(np.arange(0.0, s[-1], step), s[-1])
    r = np.stack([np.interp(targets, s, xy[:, 0]), np.interp(targets, s, xy[:, 1])], -1)
    d = np.diff(r, axis=0)
    d = d[np.hypot(d[:, 0], d[:, 1]) > 1e-12]
    heading = np.arctan2(d[:, 1], d[:, 0])
    turn = np.abs(np.angle(np.exp(1j * np.diff(heading))))
    return float(turn.sum() / s[-1])
