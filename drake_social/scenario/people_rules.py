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
  against the radius);
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
from drake_social.scenario.heading import heading_knots
from drake_social.scenario.people_file import read_people_file

__all__ = ["check_people", "robot_clearance", "segment_box_distance"]

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
    centers = np.asarray(centers, float).reshape(-1, 2)
    half = np.asarray(sizes, float).reshape(-1, 2) / 2
    yaws = np.asarray(yaws, float).reshape(-1)
    c, s = np.cos(yaws)[:, None], np.sin(yaws)[:, None]
    rel_a, rel_b = np.asarray(a, float) - centers, np.asarray(b, float) - centers
    # The ends in each box's frame, (K, 2).
    la = np.concatenate([c * rel_a[:, :1] + s * rel_a[:, 1:], -s * rel_a[:, :1] + c * rel_a[:, 1:]], 1)
    lb = np.concatenate([c * rel_b[:, :1] + s * rel_b[:, 1:], -s * rel_b[:, :1] + c * rel_b[:, 1:]], 1)
    d = lb - la
    # Liang-Barsky: the parameter interval of the segment inside each slab.
    with np.errstate(divide="ignore", invalid="ignore"):
        t1, t2 = (-half - la) / d, (half - la) / d
    flat = d == 0
    inside_slab = np.abs(la) <= half
    lo = np.where(flat, np.where(inside_slab, -np.inf, np.inf), np.minimum(t1, t2))
    hi = np.where(flat, np.where(inside_slab, np.inf, -np.inf), np.maximum(t1, t2))
    meets = np.maximum(lo.max(1), 0.0) <= np.minimum(hi.min(1), 1.0)
    # Disjoint convex shapes: the closest pair has a vertex of one of them.
    def point_box(p):
        return np.hypot(*np.maximum(np.abs(p) - half, 0.0).T)

    corners = half[:, None, :] * np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])  # (K, 4, 2)
    den = np.einsum("ki,ki->k", d, d)[:, None]
    u = np.clip(np.einsum("kji,ki->kj", corners - la[:, None], d) / np.where(den > 0, den, 1.0), 0.0, 1.0)
    corner_gap = np.linalg.norm(corners - la[:, None] - u[..., None] * d[:, None], axis=-1).min(1)
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
    boxes = world.obstacles
    return (np.array([b.center for b in boxes], float).reshape(-1, 2),
            np.array([b.size for b in boxes], float).reshape(-1, 2), np.array([b.yaw for b in boxes], float))


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
    geometry = ArmGeometry.from_scenario(scenario)
    start = scenario.start
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
                fail(f"{field}.trajectory", f"{where} passes through world.obstacles[{hit[0]}] (the body's centre "
                                            f"comes {hit[1]:.3g} m from it, closer than its radius {r:g} m)")
        start_clear(f"{field}.trajectory[0]", "the first point", first, r, True)

    _check_recorded(scenario, fail, start_clear)
    if not starts:
        return
    # Every start at once: the body against every obstacle, and at t = 0 against the robot.
    centres = np.array([c for _, _, c, _, _ in starts])
    radii = np.array([r for _, _, _, r, _ in starts])
    centers, sizes, yaws = boxes
    c, sn = np.cos(yaws), np.sin(yaws)
    rel = centres[:, None, :] - centers  # (N, K, 2)
    local = np.stack([c * rel[..., 0] + sn * rel[..., 1], -sn * rel[..., 0] + c * rel[..., 1]], -1)
    gaps = np.hypot(*np.moveaxis(np.maximum(np.abs(local) - sizes / 2, 0.0), -1, 0))  # (N, K)
    clearance, parts = robot_clearance(geometry, start, centres, radii)
    for n, (field, what, centre, radius, at_zero) in enumerate(starts):
        hit = _first_hit(gaps[n], radius)
        if hit is not None:
            fail(field, f"{what} {_fmt(centre)} puts the body (radius {radius:g} m) inside world.obstacles[{hit[0]}] "
                        f"(its centre is {hit[1]:.3g} m from the box); a person must start clear of the obstacles")
        if at_zero and clearance[n] < 0:
            fail(field, f"{what} {_fmt(centre)} puts the body (radius {radius:g} m) into the robot's {parts[n]} at "
                        f"its start configuration {list(start)} (overlap {-clearance[n]:.3g} m); a person must "
                        f"start clear of the robot")


def _check_recorded(scenario, fail: Fail, start_clear) -> None:
    ids = scenario.people_file_ids
    if scenario.people_file is None:
        if ids is not None:
            fail("people_file_ids", "needs a people_file to choose from")
        return
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
