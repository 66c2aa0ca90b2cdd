"""Redundant waypoints: interior waypoints on the straight segment of their neighbours.

A waypoint that lies on the straight motion between the waypoints before and
after it adds nothing to the path's geometry, but execution comes to rest at
every waypoint. :func:`merge_collinear` removes such waypoints: from each
kept waypoint u, the farthest later waypoint v such that every waypoint
between them lies within :data:`COLLINEAR_TOLERANCE` of the segment u -> v
(in the planner's weighted configuration distance ``||W dq||``) replaces
them, and only when the validity checker accepts the merged motion u -> v.
Near-collinear is not the same motion: the merged segment passes up to the
tolerance beside the parts that were checked, and a checker that accepted
the parts may refuse it (a contact at the tolerance), so it is checked like
any other motion; a refused merge keeps the waypoints (the farthest accepted
one is taken instead). Costing the merged motions is the caller's job
(:func:`drake_social.planning.optimize.optimize_path`).
"""

from __future__ import annotations

import numpy as np

from drake_social.collision.validity import ValidityChecker

__all__ = ["COLLINEAR_TOLERANCE", "collinear_runs", "merge_collinear", "segment_deviation"]

#: Largest distance (``||W dq||``: metres and radians with the planner's
#: distance weights) of an interior waypoint from the segment of its
#: neighbours for which it counts as redundant. The optimiser's collinear
#: waypoints (equal parts of a subdivided motion, ``a + t (b - a)``) lie
#: within a few ulp of a coordinate of the room (3.6e-15 on office_bar,
#: whose nearest non-collinear waypoint is 1.5e-3 off its neighbours'
#: segment), so 1e-9 is a million times their rounding; and a body point
#: (at most a few metres from the base) of a merged motion passes within a
#: few 1e-9 m of where the parts took it, the order of the deviation from
#: the planned segments that the synchronized execution itself allows.
COLLINEAR_TOLERANCE = 1e-9


def segment_deviation(points: np.ndarray, a: np.ndarray, b: np.ndarray,
                      weights: np.ndarray | None = None) -> np.ndarray:
    """Distances ``||W (p - s)||`` of ``points`` (K, 4) from the closest
    points s of the straight segment a -> b (4,) each; a degenerate segment
    (a = b) is the point a.

    Args:
        weights: (4,) the distance's per-coordinate scale W (None: all ones).

    Returns:
        (K,) distances.
    """
    w = np.ones(4) if weights is None else np.asarray(weights, float)
    p, a, b = np.asarray(points, float) * w, np.asarray(a, float) * w, np.asarray(b, float) * w
    d = b - a
    dd = float(d @ d)
    t = np.clip((p - a) @ d / dd, 0.0, 1.0) if dd > 0 else np.zeros(len(p))
    return np.linalg.norm(p - (a + t[:, None] * d), axis=1)


def _within(wp: np.ndarray, u: int, v: int, weights, tolerance: float) -> bool:
    """Whether every waypoint strictly between u and v lies within
    ``tolerance`` of the segment u -> v."""
    return v <= u + 1 or bool(np.all(segment_deviation(wp[u + 1 : v], wp[u], wp[v], weights) <= tolerance))


def _reach(wp: np.ndarray, u: int, weights, tolerance: float) -> int:
    """The farthest v > u whose segment u -> v has every waypoint between
    within ``tolerance`` (u + 1 when the next waypoint turns)."""
    v = u + 1
    while v + 1 < len(wp) and _within(wp, u, v + 1, weights, tolerance):
        v += 1
    return v


def _walk(wp: np.ndarray, weights, tolerance: float) -> list[tuple[int, int]]:
    """Every step (u, v) of the greedy walk from the start: v = :func:`_reach` (u)."""
    steps, u = [], 0
    while u < len(wp) - 1:
        v = _reach(wp, u, weights, tolerance)
        steps.append((u, v))
        u = v
    return steps


def collinear_runs(waypoints: np.ndarray, weights: np.ndarray | None = None,
                   tolerance: float = COLLINEAR_TOLERANCE) -> list[tuple[int, int]]:
    """The runs a greedy walk from the start would merge, geometry alone.

    Args:
        waypoints: (N, 4) a path.
        weights: (4,) the distance's scale W (the planner's
            ``planner.distance_weights``; None: all ones).
        tolerance: largest distance of a waypoint from its run's segment.

    Returns:
        (u, v) index pairs, v >= u + 2, in order: from u, the farthest v such
        that every waypoint between lies within ``tolerance`` of the segment
        u -> v; the walk goes on from v.
    """
    return [(u, v) for u, v in _walk(np.asarray(waypoints, float), weights, tolerance) if v >= u + 2]


def merge_collinear(waypoints: np.ndarray, checker: ValidityChecker, weights: np.ndarray | None = None,
                    tolerance: float = COLLINEAR_TOLERANCE) -> np.ndarray:
    """The path without its redundant waypoints, every merged motion checked.

    The runs of :func:`collinear_runs` are checked in one batched call of
    ``checker.are_motions_valid``; from the u of a refused run, the farthest
    shorter run that is still within ``tolerance`` and that the checker
    accepts is taken instead (one call each, farthest first), and the walk
    goes on from its end.

    Args:
        waypoints: (N, 4) a path whose motions are valid.
        checker: checks every merged motion.
        weights, tolerance: as in :func:`collinear_runs`.

    Returns:
        (M, 4) the kept waypoints (a new array; the ends always kept).
    """
    wp = np.array(waypoints, dtype=float)
    reach = dict(_walk(wp, weights, tolerance))
    runs = np.array([(u, v) for u, v in reach.items() if v >= u + 2], dtype=int).reshape(-1, 2)
    if len(runs) == 0:
        return wp
    accepted = dict(zip(runs[:, 0].tolist(), np.asarray(checker.are_motions_valid(wp[runs[:, 0]], wp[runs[:, 1]]),
                                                            bool).tolist()))
    keep, u = [0], 0
    while u < len(wp) - 1:
        if accepted.get(u, False):
            v = reach[u]
        else:  # no run from u, a refused one, or u off the geometric walk (after a refusal)
            last = reach[u] - 1 if u in accepted else reach[u] if u in reach else _reach(wp, u, weights, tolerance)
            v = u + 1
            for w in range(last, u + 1, -1):  # farthest first
                if _within(wp, u, w, weights, tolerance) and checker.are_motions_valid(wp[u : u + 1], wp[w : w + 1])[0]:
                    v = w
                    break
        keep.append(v)
        u = v
    return wp[keep]
