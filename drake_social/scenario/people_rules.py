"""The rules of a scenario's people: trajectories, the recorded file, where people start.

Called by :func:`drake_social.scenario.validate.validate_scenario` with its
``fail(field, message)``; each rule names the dotted field (``people[2].trajectory[3]``),
the segment or the file's line, and what is allowed:

* a trajectory has at least 2 points ``[t, x, y]``, finite, ``t >= 0`` and
  strictly increasing; ``x, y`` of a person with a trajectory are left at
  0 or equal its first point; ``loop`` needs a trajectory whose last point is
  its first and whose heading repeats (:func:`~drake_social.scenario.heading.heading_knots`);
* the body disc swept along each segment stays inside ``world.bounds`` (so out
  of the walls) and out of every obstacle box (exact segment-to-box distance
  against the radius): each segment of a trajectory, and each segment between
  consecutive samples of a kept id of the people file (an id's lone sample:
  its point), the latter named by the file and the line of the segment's end
  row, checked in numpy batches;
* a person (standing, a trajectory's first point, a recorded id at its first
  time) does not start with the body in an obstacle, nor (at t = 0: the
  robot is at its start only then) overlapping the robot at ``start``;
* ``people_file`` is read and checked
  (:func:`~drake_social.scenario.people_file.read_people_file`), and
  ``people_file_ids`` are distinct ids of it.

The robot-to-body distance here is that of
:func:`drake_social.people.proximity.part_distances` (``robot``: the base disc
and the capsules), computed from :class:`~drake_social.kinematics.ArmGeometry`
directly because the scenario package sits below the people package; a
test holds the two equal.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from drake_social.errors import ScenarioError
from drake_social.io.textfile import shorten
from drake_social.kinematics import ArmGeometry
from drake_social.scenario.geometry import arm_geometry
from drake_social.scenario.map_rules import obstacle_arrays, obstacle_label
from drake_social.scenario.heading import heading_knots
from drake_social.scenario.people_file import read_people_file

__all__ = ["check_people", "robot_clearance", "segment_box_distance", "segments_box_distances"]

Fail = Callable[[str, str], None]


def segment_box_distance(a, b, centers, sizes, yaws) -> np.ndarray:
    """Distances from segment a-b to rotated boxes (0 where they meet), metres.

    Args:
        a, b: the segment's ends [x, y], metres (equal: a point).
        centers, sizes: (K, 2) the boxes' centres and side lengths, metres.
        yaws: (K,) the boxes' rotations, radians.

    Returns:
        (K,) distances.
    """
    return segments_box_distances(np.reshape(np.asarray(a, float), (1, 2)), np.reshape(np.asarray(b, float), (1, 2)),
                                  centers, sizes, yaws)[0]


def segments_box_distances(a, b, centers, sizes, yaws) -> np.ndarray:
    """Distances from N segments ``a[n]-b[n]`` to K rotated boxes (0 where
    they meet), metres: :func:`segment_box_distance` for many segments at once.

    Args:
        a, b: (N, 2) the segments' ends [x, y], metres (equal: a point).
        centers, sizes: (K, 2) the boxes' centres and side lengths, metres.
        yaws: (K,) the boxes' rotations, radians.

    Returns:
        (N, K) distances.
    """
    a, b = np.asarray(a, float).reshape(-1, 2), np.asarray(b, float).reshape(-1, 2)
    centers = np.asarray(centers, float).reshape(-1, 2)
    half = np.asarray(sizes, float).reshape(-1, 2) / 2
    yaws = np.asarray(yaws, float).reshape(-1)
    return _segment_box(a[:, None], b[:, None], centers[None], half[None], np.cos(yaws)[None], np.sin(yaws)[None])


def _segment_box(a, b, centers, half, c, s) -> np.ndarray:
    """Segment-to-box distances, broadcast: ``a``, ``b``, ``centers`` and
    ``half`` (half sides) of shape (..., 2), ``c``, ``s`` (the cosine and sine
    of the yaw) of shape (...); returns (...) metres, 0 where they meet."""

    def local(p):  # in each box's frame
        rx, ry = p[..., 0] - centers[..., 0], p[..., 1] - centers[..., 1]
        return np.stack([c * rx + s * ry, -s * rx + c * ry], -1)

    la, lb = local(a), local(b)
    d = lb - la
    # Liang-Barsky: the parameter interval of the segment inside each slab.
    with np.errstate(divide="ignore", invalid="ignore"):
        t1, t2 = (-half - la) / d, (half - la) / d
    flat = d == 0
    inside_slab = np.abs(la) <= half
    lo = np.where(flat, np.where(inside_slab, -np.inf, np.inf), np.minimum(t1, t2))
    hi = np.where(flat, np.where(inside_slab, np.inf, -np.inf), np.maximum(t1, t2))
    meets = np.maximum(lo.max(-1), 0.0) <= np.minimum(hi.min(-1), 1.0)

    # Disjoint convex shapes: the closest pair has a vertex of one of them.
    def point_box(p):
        g = np.maximum(np.abs(p) - half, 0.0)
        return np.hypot(g[..., 0], g[..., 1])

    corners = half[..., None, :] * np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])  # (..., 4, 2)
    rel = corners - la[..., None, :]
    den = (d * d).sum(-1)[..., None]
    u = np.clip((rel * d[..., None, :]).sum(-1) / np.where(den > 0, den, 1.0), 0.0, 1.0)  # (..., 4)
    gap = rel - u[..., None] * d[..., None, :]
    corner_gap = np.hypot(gap[..., 0], gap[..., 1]).min(-1)
    return np.where(meets, 0.0, np.minimum(np.minimum(point_box(la), point_box(lb)), corner_gap))


def robot_clearance(geometry: ArmGeometry, q, centres, radii) -> tuple[np.ndarray, list[str]]:
    """Surface distance from body discs to the robot at ``q`` and the nearest
    part of each (``base``, ``arm`` or ``object``), metres (negative: overlap).

    The same distance as ``part_distances(...)["robot"]`` of
    :mod:`drake_social.people.proximity` for each person alone: the base disc
    and the link and object capsules.

    Args:
        geometry: the robot and its object.
        q: (4,) the configuration.
        centres: (P, 2) body centres, metres.
        radii: (P,) body radii, metres.

    Returns:
        ((P,) distances, P part names).
    """
    q = np.asarray(q, float).reshape(1, 4)
    p = np.asarray(centres, float).reshape(-1, 2)
    radii = np.asarray(radii, float).reshape(-1)
    base = np.hypot(*(p - q[0, :2]).T) - radii - geometry.base_radius
    seg = geometry.segments(q)[0]  # (S, 2, 2)
    a, d = seg[:, 0], seg[:, 1] - seg[:, 0]
    den = np.einsum("si,si->s", d, d)
    u = np.clip(np.einsum("psi,si->ps", p[:, None] - a, d) / np.where(den > 0, den, 1.0), 0.0, 1.0)  # (P, S)
    caps = np.linalg.norm(p[:, None] - a - u[..., None] * d, axis=-1) - radii[:, None] - geometry.segment_radii
    parts = np.stack([base, caps[:, :2].min(1), caps[:, 2:].min(1)], 1)  # (P, 3)
    names = ("base", "arm", "object")
    return parts.min(1), [names[k] for k in parts.argmin(1)]


def _boxes(world) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The obstacles' centres (K, 2), sizes (K, 2) and yaws (K,)."""
    return obstacle_arrays(world)


def _first_hit(gaps: np.ndarray, radius: float) -> tuple[int, float] | None:
    """The first box closer than ``radius`` (index, distance), or None."""
    hits = np.flatnonzero(gaps < radius)
    return None if len(hits) == 0 else (int(hits[0]), float(gaps[hits[0]]))


def _fmt(p) -> str:
    return "(" + ", ".join(f"{v:g}" for v in p) + ")"


def check_people(scenario, fail: Fail) -> None:
    """Checks the people rules (module docstring) of ``scenario``, whose world,
    robot, object and start are already valid; ``fail(field, message)`` raises."""
    w = scenario.world
    x_min, y_min, x_max, y_max = w.bounds
    geometry = arm_geometry(scenario)
    boxes = _boxes(w)

    starts: list[tuple[str, str, tuple[float, float], float, bool]] = []  # (field, what, centre, radius, at t = 0)

    def start_clear(field: str, what: str, centre, radius: float, at_zero: bool) -> None:
        starts.append((field, what, (float(centre[0]), float(centre[1])), float(radius), at_zero))

    for i, p in enumerate(scenario.people):
        field = f"people[{i}]"
        if p.trajectory is None:
            if p.loop:
                fail(f"{field}.loop", "needs a trajectory (a person without one stands still)")
            start_clear(field, "the position", (p.x, p.y), p.radius, True)
            continue
        route = p.trajectory
        if len(route) < 2:
            fail(f"{field}.trajectory", f"needs at least 2 points [t, x, y], got {len(route)}")
        for k, point in enumerate(route):
            if len(point) != 3:
                fail(f"{field}.trajectory[{k}]", f"must be [t, x, y] (seconds, metres, metres), got {point}")
            if not all(math.isfinite(v) for v in point):
                fail(f"{field}.trajectory[{k}]", f"must be finite numbers, got {point}")
            if point[0] < 0:
                fail(f"{field}.trajectory[{k}]", f"time t must be >= 0 seconds, got {point[0]:g}")
            if k and not point[0] > route[k - 1][0]:
                fail(f"{field}.trajectory[{k}]", f"time t must be > {route[k - 1][0]:g}, the time of point {k - 1} "
                                                 f"(times strictly increasing), got {point[0]:g}")
        first = (route[0][1], route[0][2])
        if (p.x, p.y) != (0.0, 0.0) and (p.x, p.y) != first:
            fail(field, f"x, y {_fmt((p.x, p.y))} must be left out (0, 0) or equal the trajectory's first point "
                        f"{_fmt(first)}: the person starts there")
        if p.loop and (route[-1][1], route[-1][2]) != first:
            fail(f"{field}.loop", f"needs a closed route: the trajectory's last point {_fmt(route[-1][1:])} must be "
                                  f"its first {_fmt(first)}")
        if p.loop:
            try:
                heading_knots(np.asarray(route)[:, 0], np.asarray(route)[:, 1:], p.theta, True)
            except ValueError as e:
                fail(f"{field}.loop", str(e))
        r = p.radius
        for k in range(len(route) - 1):
            a, b = route[k][1:], route[k + 1][1:]
            where = f"segment {k} (from point {k} {_fmt(route[k])} to point {k + 1} {_fmt(route[k + 1])}, [t, x, y])"
            lo_x, hi_x, lo_y, hi_y = min(a[0], b[0]), max(a[0], b[0]), min(a[1], b[1]), max(a[1], b[1])
            if lo_x - r < x_min or hi_x + r > x_max or lo_y - r < y_min or hi_y + r > y_max:
                fail(f"{field}.trajectory", f"{where} takes the body (radius {r:g} m) out of world.bounds "
                                            f"{list(w.bounds)} into the walls; the whole body must stay inside")
            hit = _first_hit(segment_box_distance(a, b, *boxes), r)
            if hit is not None:
                fail(f"{field}.trajectory", f"{where} passes through {obstacle_label(w, hit[0])} (the body's centre "
                                            f"comes {hit[1]:.3g} m from it, closer than its radius {r:g} m)")
        start_clear(f"{field}.trajectory[0]", "the first point", first, r, True)

    recorded = _check_recorded(scenario, fail, start_clear)
    if starts:
        _check_starts(scenario, geometry, boxes, starts, fail)
    if recorded is not None:
        _check_recorded_segments(scenario, *recorded, boxes, fail)


def _check_starts(scenario, geometry: ArmGeometry, boxes, starts, fail: Fail) -> None:
    start = scenario.start
    # The starts in batches: each body against every obstacle, and at t = 0 against the robot.
    centres = np.array([c for _, _, c, _, _ in starts])
    radii = np.array([r for _, _, _, r, _ in starts])
    centers, sizes, yaws = boxes
    c, sn = np.cos(yaws), np.sin(yaws)
    clearance, parts = robot_clearance(geometry, start, centres, radii)
    step = max(1, _SEGMENT_BATCH // max(len(yaws), 1))
    for n, (field, what, centre, radius, at_zero) in enumerate(starts):
        if n % step == 0:  # the gaps (m, K) of the next batch of starts
            rel = centres[n:n + step, None, :] - centers
            local = np.stack([c * rel[..., 0] + sn * rel[..., 1], -sn * rel[..., 0] + c * rel[..., 1]], -1)
            gaps = np.hypot(*np.moveaxis(np.maximum(np.abs(local) - sizes / 2, 0.0), -1, 0))
        hit = _first_hit(gaps[n % step], radius)
        if hit is not None:
            fail(field, f"{what} {_fmt(centre)} puts the body (radius {radius:g} m) inside "
                        f"{obstacle_label(scenario.world, hit[0])} (its centre is {hit[1]:.3g} m from the box); a "
                        f"person must start clear of the obstacles")
        if at_zero and clearance[n] < 0:
            fail(field, f"{what} {_fmt(centre)} puts the body (radius {radius:g} m) into the robot's {parts[n]} at "
                        f"its start configuration {list(start)} (overlap {-clearance[n]:.3g} m); a person must "
                        f"start clear of the robot")


def _check_recorded(scenario, fail: Fail, start_clear):
    """Reads and checks the people file and its ids; queues each id's start.

    Returns:
        (the recording, the ids kept), or None without a people file.
    """
    ids = scenario.people_file_ids
    if scenario.people_file is None:
        if ids is not None:
            fail("people_file_ids", "needs a people_file to choose from")
        return None
    if not str(scenario.people_file).strip():
        fail("people_file", "must name a CSV file (relative to the scenario file), got ''")
    try:
        recording = read_people_file(scenario.people_file)
    except ScenarioError as e:
        fail("people_file", str(e))
    if ids is not None:
        if not ids:
            fail("people_file_ids", "must list at least one id (null = every id of the file)")
        for k, ident in enumerate(ids):
            if ident not in recording.tracks:
                known = list(recording.tracks)
                shown = ", ".join(known[:20]) + (f", ... ({len(known)} ids)" if len(known) > 20 else "")
                fail(f"people_file_ids[{k}]", f"id {shorten(repr(ident))} is not in {recording.path}; its ids: {shown}")
            if ident in ids[:k]:
                fail(f"people_file_ids[{k}]", f"id {shorten(repr(ident))} twice; each id once")
    for ident in (recording.tracks if ids is None else ids):
        tr = recording.tracks[ident]
        where = f"people_file ({recording.path}, line {tr.first_line}, id {shorten(repr(ident))})"
        start_clear(where, f"the first sample (t = {tr.times[0]:g} s) at", tr.positions[0], tr.radius, False)
        if tr.times[0] <= 0.0 <= tr.times[-1]:
            at_zero = [float(np.interp(0.0, tr.times, tr.positions[:, c])) for c in range(2)]
            start_clear(where, "the position at t = 0", at_zero, tr.radius, True)
    return recording, list(recording.tracks if ids is None else ids)


#: Segments of a people file checked per numpy batch against the boxes, times
#: the number of boxes (bounds the temporary arrays to a few MB).
_SEGMENT_BATCH = 1 << 15


def _check_recorded_segments(scenario, recording, ids, boxes, fail: Fail) -> None:
    """The scripted rule on each kept id of the people file: the body disc
    swept along each segment between consecutive samples (a lone sample: its
    point) stays inside ``world.bounds`` and out of every obstacle box. A
    failure names the file, the line of the segment's end row and the id."""
    w = scenario.world
    x_min, y_min, x_max, y_max = w.bounds
    tracks = [recording.tracks[i] for i in ids]
    # Every segment of every id: (start, end) rows, the track, the sample index of the end.
    a = np.concatenate([tr.positions[:-1] if len(tr.times) > 1 else tr.positions for tr in tracks])
    b = np.concatenate([tr.positions[1:] if len(tr.times) > 1 else tr.positions for tr in tracks])
    which = np.concatenate([np.full(max(len(tr.times) - 1, 1), n) for n, tr in enumerate(tracks)])
    end = np.concatenate([np.arange(1, len(tr.times)) if len(tr.times) > 1 else np.zeros(1, int) for tr in tracks])
    r = np.array([tr.radius for tr in tracks])[which]
    out = ((np.minimum(a[:, 0], b[:, 0]) - r < x_min) | (np.maximum(a[:, 0], b[:, 0]) + r > x_max)
           | (np.minimum(a[:, 1], b[:, 1]) - r < y_min) | (np.maximum(a[:, 1], b[:, 1]) + r > y_max))
    first_out = int(np.argmax(out)) if out.any() else len(a)
    first_box, box, gap = len(a), -1, 0.0
    centers, sizes, yaws = boxes
    if len(yaws):
        half, c, sn = sizes / 2, np.cos(yaws), np.sin(yaws)
        reach = np.hypot(half[:, 0], half[:, 1])  # a box lies within this of its centre
        step = max(1, _SEGMENT_BATCH // len(yaws))
        for n0 in range(0, min(len(a), first_out), step):
            sa, sb, sr = a[n0:n0 + step], b[n0:n0 + step], r[n0:n0 + step]
            # Broad phase: the box's centre within its half diagonal plus the radius of the segment.
            d = sb - sa
            rel = centers[None] - sa[:, None]  # (m, K, 2)
            den = (d * d).sum(-1)[:, None]
            u = np.clip((rel * d[:, None]).sum(-1) / np.where(den > 0, den, 1.0), 0.0, 1.0)
            off = rel - u[..., None] * d[:, None]
            seg, k = np.nonzero(np.hypot(off[..., 0], off[..., 1]) < reach + sr[:, None])
            if not len(seg):
                continue
            # Exact distances of the pairs left (in segment order, then box order).
            gaps = _segment_box(sa[seg], sb[seg], centers[k], half[k], c[k], sn[k])
            hit = np.flatnonzero(gaps < sr[seg])
            if len(hit):
                first_box, box, gap = n0 + int(seg[hit[0]]), int(k[hit[0]]), float(gaps[hit[0]])
                break
    n = min(first_out, first_box)
    if n == len(a):
        return
    tr, k = tracks[which[n]], int(end[n])
    line = lambda j: tr.first_line if tr.lines is None else int(tr.lines[j])  # noqa: E731
    field = f"people_file ({recording.path}, line {line(k)}, id {shorten(repr(tr.id))})"
    if len(tr.times) > 1:
        where = (f"the segment from t = {tr.times[k - 1]:g} s at {_fmt(tr.positions[k - 1])} (line {line(k - 1)}) "
                 f"to t = {tr.times[k]:g} s at {_fmt(tr.positions[k])}")
    else:
        where = f"the sample at t = {tr.times[0]:g} s at {_fmt(tr.positions[0])}"
    if n == first_out:
        fail(field, f"{where} takes the body (radius {tr.radius:g} m) out of world.bounds {list(w.bounds)} into "
                    "the walls; the whole body must stay inside")
    fail(field, f"{where} passes through {obstacle_label(w, box)} (the body's centre comes {gap:.3g} m from it, "
                f"closer than its radius {tr.radius:g} m)")
