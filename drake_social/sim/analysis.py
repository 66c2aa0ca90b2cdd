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

import itertools

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


def densify(geometry: ArmGeometry, q: np.ndarray, resolution: float, *, return_owner: bool = False):
    """Configurations along the straight pieces between consecutive ``q`` (T, 4)
    such that no body point (capsule radii included) moves more than
    ``resolution`` metres between neighbours; the given ones are kept exactly.

    With ``return_owner``, also the index (M,) into ``q`` of the configuration
    each dense one is (the given ones) or follows (those in between).
    """
    q = np.asarray(q, float).reshape(-1, 4)
    if len(q) < 2:
        return (q.copy(), np.zeros(len(q), int)) if return_owner else q.copy()
    span = geometry.max_displacement(q[:-1], q[1:], include_body=True)
    n = np.maximum(1, np.ceil(span / resolution).astype(int))
    segment = np.repeat(np.arange(len(n)), n)
    step = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n) + 1  # 1 .. n within each segment
    end = step == n[segment]
    t = (step / n[segment])[:, None]
    inner = q[segment] + t * (q[segment + 1] - q[segment])
    inner[end] = q[segment[end] + 1]  # the segment ends bit for bit
    dense = np.concatenate([q[:1], inner])
    if not return_owner:
        return dense
    return dense, np.concatenate([[0], segment + end])


def _nearest_segment(points: np.ndarray, curve: np.ndarray, candidates: int = 16) -> np.ndarray:
    """Index (T,) of the segment of the polyline ``curve`` (M >= 2, 2) nearest
    each point (T, 2), among the segments next to its nearest vertices."""
    k = min(candidates, len(curve))
    _, nearest = cKDTree(curve).query(points, k=k)
    nearest = np.asarray(nearest).reshape(len(points), k)
    best = np.full(len(points), np.inf)
    best_i = np.zeros(len(points), int)
    for i in (nearest, nearest - 1):  # segment i -> i+1, for i a near vertex or the one before it
        i = np.clip(i, 0, len(curve) - 2)
        a, b = curve[i], curve[i + 1]  # (T, k, 2)
        d = b - a
        dd = np.einsum("tkc,tkc->tk", d, d)
        t = np.einsum("tkc,tkc->tk", points[:, None, :] - a, d) / np.where(dd > 0, dd, 1.0)
        t = np.clip(np.where(dd > 0, t, 0.0), 0.0, 1.0)
        dist = np.linalg.norm(points[:, None, :] - (a + t[..., None] * d), axis=-1)
        j = np.argmin(dist, axis=1)
        better = dist[np.arange(len(points)), j] < best
        best = np.where(better, dist[np.arange(len(points)), j], best)
        best_i = np.where(better, i[np.arange(len(points)), j], best_i)
    return best_i


def _distinct_segments(planned: np.ndarray) -> np.ndarray:
    """(S,) bool: segment i of ``planned`` (N, 4) is the first of the
    segments with the same two ends (in either order), which trace the same
    curves."""
    a, b = planned[:-1], planned[1:]
    d = b - a
    nonzero = d != 0
    first = np.argmax(nonzero, axis=1)
    swap = nonzero.any(axis=1) & (d[np.arange(len(d)), first] < 0)  # b before a in lexicographic order
    ends = np.concatenate([np.where(swap[:, None], b, a), np.where(swap[:, None], a, b)], axis=1)
    distinct = np.zeros(len(d), bool)
    distinct[np.unique(ends, axis=0, return_index=True)[1]] = True
    return distinct


def _subdivide(planned: np.ndarray, parts: np.ndarray) -> np.ndarray:
    """The waypoints ``planned`` (N, 4) with segment i cut into ``parts[i]``
    equal straight parts (the given waypoints kept exactly)."""
    segment = np.repeat(np.arange(len(parts)), parts)
    k = np.arange(parts.sum()) - np.repeat(np.cumsum(parts) - parts, parts)  # 0 .. parts - 1 within each segment
    t = (k / parts[segment])[:, None]
    inner = planned[segment] + t * (planned[segment + 1] - planned[segment])
    inner[k == 0] = planned[segment[k == 0]]
    return np.concatenate([inner, planned[-1:]])


def _pieces(steps: np.ndarray, distinct: np.ndarray, budget: int) -> list[tuple[int, int]]:
    """Runs ``(first, last)`` of consecutive distinct segments with at most
    ``budget`` densified steps each (at least one segment), then widened by
    one segment on either side so that the steps across a piece's ends are
    searched as they are along the whole path."""
    pieces = []
    start, total = None, 0
    for i in range(len(steps) + 1):
        if start is not None and (i == len(steps) or not distinct[i] or total + steps[i] > budget):
            pieces.append((max(start - 1, 0), min(i, len(steps) - 1)))
            start, total = None, 0
        if i < len(steps) and distinct[i]:
            if start is None:
                start = i
            total += int(steps[i])
    return pieces


#: Newton steps of the compiled search per dense step (it converges in 2-3).
_NEWTON_STEPS = 8


def point_deviation(
    geometry: ArmGeometry, planned: np.ndarray, executed: np.ndarray, spacing: float = 0.005,
    iterations: int = 30, block: int = 1 << 17, compiled: bool | None = None,
) -> dict[str, float]:
    """Largest distance of each executed body point from its planned curve, metres.

    The planned path is densified in configuration space (no body point moves
    more than ``spacing`` between samples, still on the planned straight
    segments). For each executed point, the polyline through the samples'
    positions of that point finds the nearest stretch; then a golden-section
    search along the true curve (the point at the configurations between the
    samples on either side, step by step) finds the distance. Each figure is
    the distance to a point of the true curve: an upper bound, exact when the
    nearest point lies within a step of the polyline's choice.

    Memory does not grow with the path's length: the path is densified and
    searched in pieces of consecutive segments of at most ``block`` samples
    (a longer segment is first cut into equal straight parts)
    (the smallest distance over the pieces is kept), a segment with the same
    two ends as an earlier one (the same curves) is searched once, and a
    piece is searched only for the executed points that it may bring nearer
    (its curves lie within a disc: each body point stays within a segment's
    motion bound of its position at the segment's start). A path of at most
    ``block`` samples is one piece: the result is that of searching the
    whole densified path at once.

    Args:
        geometry: the robot and object.
        planned: (N, 4) waypoints of the planned path (straight segments).
        executed: (T, 4) executed configurations.
        spacing: sample spacing along the planned curves, metres.
        iterations: golden-section steps (the bracket shrinks by 0.618 each).
        block: the most densified samples searched at once.
        compiled: search with the compiled loops of
            :mod:`~drake_social.sim.analysis_kernel` (True) or the numpy
            formulation (False, the reference: the same arithmetic over
            arrays, some 20x slower); None = compiled when numba is there.

    Returns:
        name -> largest deviation (see :func:`body_point_names`), plus
        ``"max"`` over all points.
    """
    planned = np.asarray(planned, float).reshape(-1, 4)
    executed = np.asarray(executed, float).reshape(-1, 4)
    if compiled is None or compiled:
        from drake_social.sim import analysis_kernel  # numba: imported when a search needs it

        compiled = analysis_kernel.AVAILABLE if compiled is None else True
    names = body_point_names(geometry)
    if len(executed) == 0:
        return {**{n: 0.0 for n in names}, "max": 0.0}
    executed_pts = body_points(geometry, executed)  # (T, K, 2)
    if len(planned) == 1:
        d = np.linalg.norm(executed_pts - body_points(geometry, planned[0]), axis=-1)
        out = {n: float(d[:, k].max()) for k, n in enumerate(names)}
        out["max"] = max(out.values())
        return out
    budget = max(1, int(block))
    span = geometry.max_displacement(planned[:-1], planned[1:], include_body=True)
    steps = np.maximum(1, np.ceil(span / spacing))  # densify's samples per segment
    if np.any(steps > budget):  # a segment longer than a piece: cut into equal straight parts (the same curves)
        planned = _subdivide(planned, np.ceil(steps / budget).astype(np.int64))
        span = geometry.max_displacement(planned[:-1], planned[1:], include_body=True)
        steps = np.maximum(1, np.ceil(span / spacing))
    best = np.full(executed_pts.shape[:2], np.inf)  # (T, K)
    for first, last in _pieces(steps, _distinct_segments(planned), budget):
        # Each curve of the piece lies within its disc: centre the mean of the
        # points at the segments' starts, radius the farthest start plus its motion bound.
        starts = body_points(geometry, planned[first:last + 1])  # (S, K, 2)
        centre = starts.mean(axis=0)
        radius = (np.linalg.norm(starts - centre, axis=-1) + span[first:last + 1, None]).max(axis=0)
        lower = np.linalg.norm(executed_pts - centre, axis=-1) - radius  # (T, K)
        # Margin for rounding: skip only points the piece cannot bring nearer.
        active = lower - 1e-9 * (1.0 + radius) < best
        if active.any():
            _search_piece(geometry, densify(geometry, planned[first:last + 2], spacing), executed_pts, active, best,
                          iterations, bool(compiled))
    out = {name: float(best[:, k].max()) for k, name in enumerate(names)}
    out["max"] = max(out.values())
    return out


def _search_piece(geometry: ArmGeometry, dense: np.ndarray, executed_pts: np.ndarray, active: np.ndarray,
                  best: np.ndarray, iterations: int, compiled: bool) -> None:
    """Lowers ``best`` (T, K) to the distance of each ``active`` executed
    point (T, K, 2) from its curve along the densified piece ``dense`` (M >= 2, 4)
    (``compiled``: by the loops of :mod:`~drake_social.sim.analysis_kernel`)."""
    names = body_point_names(geometry)
    planned_pts = body_points(geometry, dense)  # (M, K, 2)
    last = len(dense) - 1

    l1, l2 = geometry.link_lengths
    # Body point k as (link, p): link 0 the base centre, 1 the elbow (link-1
    # tip), 2 a point p of the gripper frame (link-2 tip, object points).
    n_interest = geometry.num_interest_points
    gripper_points = np.concatenate([[[0.0, 0.0]], geometry.object_interest, geometry.object_points])

    def point(q: np.ndarray, k: int) -> np.ndarray:
        xy = q[:, :2].copy()
        if k == 0:
            return xy
        xy[:, 0] += l1 * np.cos(q[:, 2])
        xy[:, 1] += l1 * np.sin(q[:, 2])
        if k == 1:
            return xy
        g = gripper_points[k - 2] if k < n_interest else gripper_points[1 + len(geometry.object_interest) + k - n_interest]
        c, s_ = np.cos(q[:, 2] + q[:, 3]), np.sin(q[:, 2] + q[:, 3])
        xy[:, 0] += c * (l2 + g[0]) - s_ * g[1]
        xy[:, 1] += s_ * (l2 + g[0]) + c * g[1]
        return xy

    def distance(u: np.ndarray, k: int, x: np.ndarray) -> np.ndarray:
        i = np.clip(np.floor(u).astype(int), 0, last - 1)
        f = (u - i)[:, None]
        q = dense[i] + f * (dense[i + 1] - dense[i])  # on the planned segments
        return np.linalg.norm(point(q, k) - x, axis=-1)

    # The per-point form above must be body_points' (checked once, cheaply).
    probe = dense[: min(len(dense), 8)]
    if not all(np.allclose(point(probe, k), body_points(geometry, probe)[:, k], atol=1e-12)
               for k in range(len(names))):
        raise RuntimeError("point_deviation: the per-point kinematics disagree with body_points (a bug)")

    golden = (np.sqrt(5.0) - 1.0) / 2.0
    for k in range(len(names)):
        rows = np.flatnonzero(active[:, k])
        if len(rows) == 0:
            continue
        x = executed_pts[rows, k]
        curve = planned_pts[:, k]
        # Where the point stands still (the base while only the arm turns) its
        # samples repeat; keep the last of each run so that the segment that
        # leaves the spot is next to the spot's vertex.
        moves = np.concatenate([np.any(curve[1:] != curve[:-1], axis=1), [True]])
        keep = np.flatnonzero(moves)
        if len(keep) == 1:
            best[rows, k] = np.minimum(best[rows, k], np.linalg.norm(x - curve[keep[0]], axis=1))
            continue
        if compiled:
            from drake_social.sim import analysis_kernel

            polyline = np.ascontiguousarray(curve[keep])
            _, nearest = cKDTree(polyline).query(x, k=min(16, len(polyline)))
            nearest = np.asarray(nearest, np.int64).reshape(len(x), -1)
            j = analysis_kernel.nearest_segments(np.ascontiguousarray(x), polyline, nearest)
            kind = min(k, 2)
            g = (0.0, 0.0) if k < 2 else (
                gripper_points[k - 2] if k < n_interest
                else gripper_points[1 + len(geometry.object_interest) + k - n_interest])
            found = analysis_kernel.step_distances(np.ascontiguousarray(dense, float), np.ascontiguousarray(x),
                                                   keep[j].astype(np.int64), kind, float(l1), float(l2),
                                                   float(g[0]), float(g[1]), _NEWTON_STEPS)
            best[rows, k] = np.minimum(best[rows, k], found)
            continue
        j = _nearest_segment(x, curve[keep])
        # The segment's motion is the dense step keep[j] -> keep[j] + 1 (the
        # samples after it repeat until keep[j + 1]). Search that step and the
        # steps either side, each on its own: within one step (a short arc)
        # the distance is unimodal, across a waypoint where the path turns
        # back it need not be.
        found = np.full(len(x), np.inf)
        for offset in (-1, 0, 1):
            step = np.clip(keep[j] + offset, 0, last - 1)
            lo, hi = step.astype(float), step + 1.0
            a, b = hi - golden * (hi - lo), lo + golden * (hi - lo)
            fa, fb = distance(a, k, x), distance(b, k, x)
            found = np.minimum(found, np.minimum(distance(lo, k, x), distance(hi, k, x)))
            for _ in range(iterations):
                left = fa < fb
                hi = np.where(left, b, hi)
                lo = np.where(left, lo, a)
                new = np.where(left, hi - golden * (hi - lo), lo + golden * (hi - lo))
                fnew = distance(new, k, x)
                a, b, fa, fb = (np.where(left, new, b), np.where(left, a, new),
                                np.where(left, fnew, fb), np.where(left, fa, fnew))
            found = np.minimum(found, np.minimum(fa, fb))
        best[rows, k] = np.minimum(best[rows, k], found)


def _segment_distances(x: np.ndarray, a: np.ndarray, d: np.ndarray, dd: np.ndarray) -> np.ndarray:
    """Distance of each point ``x`` (P, 4) from its segment ``a + t d``, t in
    [0, 1] (P, 4 each; ``dd = |d|^2``): the clamped projection."""
    t = np.einsum("pk,pk->p", x - a, d) / np.where(dd > 0, dd, 1.0)
    t = np.clip(np.where(dd > 0, t, 0.0), 0.0, 1.0)
    return np.linalg.norm(x - (a + t[:, None] * d), axis=-1)


def _nearest_of_all(x: np.ndarray, a: np.ndarray, d: np.ndarray, dd: np.ndarray, block: int) -> np.ndarray:
    """Distance (P,) of each configuration ``x`` (P, 4) from the nearest of
    all segments ``a + t d`` (the full comparison), in blocks of at most
    ``block`` pairs."""
    rows = max(1, block // len(a))
    out = np.empty(len(x))
    for r0 in range(0, len(x), rows):
        xr = x[r0:r0 + rows]
        i = np.repeat(np.arange(len(xr)), len(a))
        j = np.tile(np.arange(len(a)), len(xr))
        out[r0:r0 + rows] = _segment_distances(xr[i], a[j], d[j], dd[j]).reshape(len(xr), len(a)).min(axis=1)
    return out


def config_deviation(planned: np.ndarray, executed: np.ndarray, block: int = 1 << 16) -> float:
    """Largest Euclidean configuration-space distance (metres and radians
    mixed, as the planner's plain norm) of an executed configuration from the
    polyline through the planned waypoints; exact, point to segment: the
    figure of the full comparison of every (configuration, segment) pair,
    bit for bit (a NaN gives NaN, an infinity inf, as there).

    Not every pair is measured: points are sampled along the segments (at
    most ``h`` apart) into a KD-tree; the segment owning a configuration's
    nearest sample gives an upper bound ``u`` of its distance, and only
    segments with a sample within ``u + h / 2`` (every point of a segment
    lies within ``h / 2`` of one of its samples) can be nearer. Those pairs
    are measured with the point-to-segment formula, in blocks of at most
    ``block`` pairs, so memory stays a few megabytes whatever the lengths. A
    configuration with as many candidate samples as there are segments (the
    segments all overlap there) is compared with every segment instead, so
    that it never costs much more than the full comparison; so are all when
    a value is not finite or so large (> 1e150) that the sampling's squares
    would overflow.
    """
    p = np.asarray(planned, float).reshape(-1, 4)
    x = np.asarray(executed, float).reshape(-1, 4)
    if len(x) == 0:
        return 0.0
    if len(p) == 1:
        return float(np.max(np.linalg.norm(x - p[0], axis=1)))
    a, d = p[:-1], np.diff(p, axis=0)  # (S, 4)
    dd = np.einsum("sk,sk->s", d, d)
    block = max(1, int(block))
    with np.errstate(all="ignore"):
        tame = bool(np.all(np.abs(p) <= 1e150) and np.all(np.abs(x) <= 1e150) and np.all(np.isfinite(d)))
    if not tame:
        with np.errstate(all="ignore"):
            return float(_nearest_of_all(x, a, d, dd, block).max())
    length = np.sqrt(dd)
    # Samples along the segments, about 4 per segment on average, each
    # segment cut into n equal pieces of at most h.
    h = max(float(length.sum()) / (4 * len(a)), 1e-12)
    n = np.maximum(1, np.ceil(length / h)).astype(np.int64)
    owner = np.repeat(np.arange(len(a)), n + 1)
    frac = (np.arange(len(owner)) - np.repeat(np.cumsum(n + 1) - (n + 1), n + 1)) / np.repeat(n, n + 1)
    samples = a[owner] + frac[:, None] * d[owner]
    half = float(np.max(length / n)) / 2  # every segment point is this near one of its samples
    tree = cKDTree(samples)
    best = np.empty(len(x))
    for t0 in range(0, len(x), block):
        xc = x[t0:t0 + block]
        _, nearest = tree.query(xc)
        s_near = owner[nearest]
        upper = _segment_distances(xc, a[s_near], d[s_near], dd[s_near])
        # Margin for the rounding of the samples' positions and the bound.
        radius = upper + half + 1e-9 * (1.0 + upper + half + np.abs(xc).max(axis=1))
        counts = np.asarray(tree.query_ball_point(xc, radius, return_length=True), np.int64)
        local = upper.copy()
        crowded = counts >= len(a)  # as many candidates as segments: compare with all
        if crowded.any():
            local[crowded] = np.minimum(local[crowded], _nearest_of_all(xc[crowded], a, d, dd, block))
        sparse = np.flatnonzero(~crowded)
        # Groups of configurations with at most `block` candidate samples in all (at least one configuration).
        ends = np.cumsum(counts[sparse])
        g0 = 0
        while g0 < len(sparse):
            g1 = max(g0 + 1, int(np.searchsorted(ends, (ends[g0 - 1] if g0 else 0) + block, side="right")))
            rows = sparse[g0:g1]
            hits = tree.query_ball_point(xc[rows], radius[rows])
            point = np.repeat(rows, counts[rows])
            segment = owner[np.fromiter(itertools.chain.from_iterable(hits), np.int64, int(counts[rows].sum()))]
            pairs = np.unique(point * len(a) + segment)  # each (configuration, segment) once
            i, j = pairs // len(a), pairs % len(a)
            np.minimum.at(local, i, _segment_distances(xc[i], a[j], d[j], dd[j]))
            g0 = g1
        best[t0:t0 + block] = local
    return float(best.max())
