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


def segment_box_distance(a, b, center, size, yaw: float) -> float:
    """Distance from segment a-b to a rotated box (0 when they meet), metres.

    Args:
        a, b: the segment's ends [x, y], metres.
        center, size: the box's centre and side lengths [x, y], metres.
        yaw: the box's rotation, radians.
    """
    c, s = math.cos(yaw), math.sin(yaw)
    hx, hy = size[0] / 2, size[1] / 2

    def local(p):
        dx, dy = p[0] - center[0], p[1] - center[1]
        return c * dx + s * dy, -s * dx + c * dy

    (ax, ay), (bx, by) = local(a), local(b)
    # Liang-Barsky: does the segment cross the box?
    lo, hi = 0.0, 1.0
    for p0, d, h in ((ax, bx - ax, hx), (ay, by - ay, hy)):
        if d == 0.0:
            if abs(p0) > h:
                lo, hi = 1.0, 0.0
                break
            continue
        t1, t2 = (-h - p0) / d, (h - p0) / d
        lo, hi = max(lo, min(t1, t2)), min(hi, max(t1, t2))
    if lo <= hi:
        return 0.0

    def point_box(x, y):
        return math.hypot(max(abs(x) - hx, 0.0), max(abs(y) - hy, 0.0))

    def point_segment(x, y):
        dx, dy = bx - ax, by - ay
        den = dx * dx + dy * dy
        u = 0.0 if den == 0 else min(max(((x - ax) * dx + (y - ay) * dy) / den, 0.0), 1.0)
        return math.hypot(x - ax - u * dx, y - ay - u * dy)

    # Disjoint convex shapes: the closest pair has a vertex of one of them.
    return min(point_box(ax, ay), point_box(bx, by),
               *(point_segment(sx * hx, sy * hy) for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))))


def robot_clearance(geometry: ArmGeometry, q, centre, radius: float) -> tuple[float, str]:
    """Surface distance from a body disc to the robot at ``q`` and the nearest
    part (``base``, ``arm`` or ``object``), metres (negative: overlap).

    The same distance as ``part_distances(...)["robot"]`` of
    :mod:`drake_social.people.proximity`: the base disc and the link and
    object capsules."""
    q = np.asarray(q, float).reshape(1, 4)
    p = np.asarray(centre, float)
    base = float(np.hypot(*(q[0, :2] - p))) - radius - geometry.base_radius
    seg = geometry.segments(q)[0]  # (S, 2, 2)
    a, d = seg[:, 0], seg[:, 1] - seg[:, 0]
    den = np.einsum("si,si->s", d, d)
    u = np.clip(np.einsum("si,si->s", p - a, d) / np.where(den > 0, den, 1.0), 0.0, 1.0)
    caps = np.hypot(*(p - a - u[:, None] * d).T) - radius - geometry.segment_radii
    parts = [("base", base), ("arm", float(caps[:2].min())), ("object", float(caps[2:].min()))]
    name, value = min(parts, key=lambda kv: kv[1])
    return value, name


def _in_obstacle(world, centre, radius: float) -> tuple[int, float] | None:
    """The first obstacle the body disc at ``centre`` overlaps (index, distance
    from the centre to the box), or None."""
    for j, box in enumerate(world.obstacles):
        d = segment_box_distance(centre, centre, box.center, box.size, box.yaw)
        if d < radius:
            return j, d
    return None


def _fmt(p) -> str:
    return "(" + ", ".join(f"{v:g}" for v in p) + ")"


def check_people(scenario, fail: Fail) -> None:
    """Checks the people rules (module docstring) of ``scenario``, whose world,
    robot, object and start are already valid; ``fail(field, message)`` raises."""
    w = scenario.world
    x_min, y_min, x_max, y_max = w.bounds
    geometry = ArmGeometry.from_scenario(scenario)
    start = scenario.start

    def start_clear(field: str, what: str, centre, radius: float, at_zero: bool) -> None:
        hit = _in_obstacle(w, centre, radius)
        if hit is not None:
            fail(field, f"{what} {_fmt(centre)} puts the body (radius {radius:g} m) inside world.obstacles[{hit[0]}] "
                        f"(its centre is {hit[1]:.3g} m from the box); a person must start clear of the obstacles")
        if at_zero:
            gap, part = robot_clearance(geometry, start, centre, radius)
            if gap < 0:
                fail(field, f"{what} {_fmt(centre)} puts the body (radius {radius:g} m) into the robot's {part} at "
                            f"its start configuration {list(start)} (overlap {-gap:.3g} m); a person must start "
                            f"clear of the robot")

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
            for j, box in enumerate(w.obstacles):
                d = segment_box_distance(a, b, box.center, box.size, box.yaw)
                if d < r:
                    fail(f"{field}.trajectory", f"{where} passes through world.obstacles[{j}] (the body's centre "
                                                f"comes {d:.3g} m from it, closer than its radius {r:g} m)")
        start_clear(f"{field}.trajectory[0]", "the first point", first, r, True)

    _check_recorded(scenario, fail, start_clear)


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
