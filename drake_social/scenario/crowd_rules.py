"""The rules of a scenario's ``crowd`` section: :func:`crowd_problems`.

Its home is the scenario layer, so that :func:`drake_social.scenario.validate.validate_scenario`
can turn each problem into its error before anything runs;
:mod:`drake_social.people.crowd` re-exports it next to the model it guards.
Pure numpy: the obstacles are read from the scenario's ``world`` and the
robot from :class:`drake_social.kinematics.ArmGeometry`.
"""

from __future__ import annotations

import math

import numpy as np

from drake_social.kinematics import ArmGeometry
from drake_social.scenario.geometry import arm_geometry
from drake_social.scenario.map_rules import obstacle_arrays, obstacle_label

__all__ = ["MAX_CROWD_TIME_STEP", "MAX_SPEED_FACTOR", "MAX_SPEED_STD", "MAX_WALKING_SPEED", "MIN_WALKING_SPEED",
           "crowd_problems"]

#: Smallest preferred speed, m/s: a given one must exceed it, and a drawn one
#: is drawn again until it does (a crowd person always walks to their goals).
MIN_WALKING_SPEED = 0.1
#: Largest preferred speed, m/s: people walk. A given one, the mean of the
#: drawn ones and every drawn one are at most this (a draw above it is drawn again).
MAX_WALKING_SPEED = 3.0
#: Largest ``crowd.speed_std``, m/s. The drawn speeds keep to
#: (MIN_WALKING_SPEED, MAX_WALKING_SPEED], 2.9 m/s wide around the mean: with
#: a deviation of at most 1 m/s a draw lands there with probability at least
#: 0.498 (the mean at one end), so a person takes about two draws at most.
#: Measured walking speeds deviate by about 0.26 m/s (the default).
MAX_SPEED_STD = 1.0
#: Largest ``crowd.max_speed_factor``: pushed by the others, a person runs at
#: most twice their preferred speed (6 m/s at MAX_WALKING_SPEED).
MAX_SPEED_FACTOR = 2.0
#: Largest crowd time step, seconds: the explicit integration stays stable
#: and a person moves at most MAX_WALKING_SPEED * MAX_SPEED_FACTOR * 0.1 =
#: 0.6 m per step, less than a default body's diameter (0.5 m) plus the
#: obstacles' default repulsion range (0.2 m).
MAX_CROWD_TIME_STEP = 0.1


def _finite(*values) -> bool:
    try:
        return bool(np.all(np.isfinite(np.asarray(values, dtype=float))))
    except (TypeError, ValueError):
        return False


def _box_distance(x: float, y: float, boxes) -> tuple[float, int]:
    """Signed distance from (x, y) to the nearest of ``boxes`` (:func:`obstacle_arrays`), metres
    (negative inside), and that box's index (-1 without boxes)."""
    centers, sizes, yaws = boxes
    if not len(yaws):
        return math.inf, -1
    c, s = np.cos(yaws), np.sin(yaws)
    rx, ry = x - centers[:, 0], y - centers[:, 1]
    ox = np.abs(c * rx + s * ry) - sizes[:, 0] / 2
    oy = np.abs(-s * rx + c * ry) - sizes[:, 1] / 2
    d = np.hypot(np.maximum(ox, 0.0), np.maximum(oy, 0.0)) + np.minimum(np.maximum(ox, oy), 0.0)
    k = int(np.argmin(d))
    return float(d[k]), k


def _robot_distance(x: float, y: float, geometry: ArmGeometry, q) -> float:
    """Distance from (x, y) to the robot's surface (base disc, links, object) at ``q``, metres."""
    p = np.array([x, y])
    q = np.asarray(q, float)
    best = float(np.hypot(*(p - q[:2]))) - geometry.base_radius
    for (a, b), r in zip(geometry.segments(q), geometry.segment_radii):
        d = b - a
        t = 0.0 if not d @ d > 0 else min(max(float((p - a) @ d / (d @ d)), 0.0), 1.0)
        best = min(best, float(np.hypot(*(p - a - t * d))) - float(r))
    return best


def _parameter_problems(crowd) -> list[tuple[str, str]]:
    out = []
    rules = (
        ("time_step", lambda v: 0 < v <= MAX_CROWD_TIME_STEP, f"must be in (0, {MAX_CROWD_TIME_STEP:g}] seconds "
                                                              "(explicit integration; smaller is more accurate)"),
        ("speed_mean", lambda v: MIN_WALKING_SPEED < v <= MAX_WALKING_SPEED,
         f"must be in ({MIN_WALKING_SPEED:g}, {MAX_WALKING_SPEED:g}] m/s"),
        ("speed_std", lambda v: 0 <= v <= MAX_SPEED_STD,
         f"must be in [0, {MAX_SPEED_STD:g}] m/s (the drawn speeds keep to ({MIN_WALKING_SPEED:g}, "
         f"{MAX_WALKING_SPEED:g}] m/s)"),
        ("max_speed_factor", lambda v: 1 <= v <= MAX_SPEED_FACTOR,
         f"must be in [1, {MAX_SPEED_FACTOR:g}] (a multiple of each person's preferred speed)"),
        ("relaxation_time", lambda v: v > 0, "must be > 0 seconds"),
        ("goal_radius", lambda v: v > 0, "must be > 0 metres"),
        ("interaction_lambda", lambda v: v > 0, "must be > 0"),
        ("interaction_gamma", lambda v: v > 0, "must be > 0"),
        ("interaction_n", lambda v: v > 0, "must be > 0"),
        ("interaction_n_prime", lambda v: v > 0, "must be > 0"),
        ("interaction_strength", lambda v: v >= 0, "must be >= 0 m/s^2"),
        ("obstacle_strength", lambda v: v >= 0, "must be >= 0 m/s^2"),
        ("obstacle_range", lambda v: v > 0, "must be > 0 metres"),
    )
    for name, ok, rule in rules:
        value = getattr(crowd, name)
        if not _finite(value):
            out.append((f"crowd.{name}", f"must be a finite number, got {value!r}"))
        elif not ok(float(value)):
            out.append((f"crowd.{name}", f"{rule}, got {value!r}"))
    dt, tau = crowd.time_step, crowd.relaxation_time
    if _finite(dt, tau) and 0 < dt <= MAX_CROWD_TIME_STEP and tau > 0 and not dt < tau:
        out.append(("crowd.time_step", f"must be < crowd.relaxation_time ({tau!r} s): the explicit goal force "
                                       f"would overshoot the preferred velocity, got {dt!r}"))
    return out


def crowd_problems(scenario) -> list[tuple[str, str]]:
    """Everything wrong with ``scenario.crowd``, as ``(dotted field, message)`` pairs.

    The rules: the parameters' ranges (see the messages); at least one
    person; each person's start, radius, goals and preferred speed finite and
    in range; every start and goal at least a radius inside ``world.bounds``
    and clear of every obstacle (the body disc may touch, not overlap); no
    start overlapping the robot at ``scenario.start`` (base, links, object)
    nor another crowd person or a person of the ``people`` list (at their
    position at t = 0). An empty list when there is no crowd or nothing is wrong.
    """
    crowd = scenario.crowd
    if crowd is None:
        return []
    out = _parameter_problems(crowd)
    if not crowd.people:
        out.append(("crowd.people", "needs at least one person (leave out the crowd section for none)"))
    x_min, y_min, x_max, y_max = (float(v) for v in scenario.world.bounds)
    boxes = obstacle_arrays(scenario.world)
    try:
        geometry = arm_geometry(scenario)
        robot_q = np.asarray(scenario.start, float).reshape(4)
    except (TypeError, ValueError):
        geometry = None
    others = []
    for k, p in enumerate(scenario.people):
        xy = (p.trajectory[0][1], p.trajectory[0][2]) if p.trajectory else (p.x, p.y)
        if _finite(*xy, p.radius):
            others.append((f"people[{k}]", float(xy[0]), float(xy[1]), float(p.radius)))

    def place(field: str, x: float, y: float, r: float, what: str) -> None:
        if not (x_min + r <= x <= x_max - r and y_min + r <= y <= y_max - r):
            out.append((field, f"{what} ({x:g}, {y:g}) must lie at least the radius {r:g} m inside world.bounds "
                               f"{list(scenario.world.bounds)}"))
            return
        d, k = _box_distance(x, y, boxes)
        if d < r:
            out.append((field, f"{what} ({x:g}, {y:g}) puts the body (radius {r:g} m) inside "
                               f"{obstacle_label(scenario.world, k)} (the centre is {d:.3g} m from it; must be >= {r:g})"))

    for i, p in enumerate(crowd.people):
        f = f"crowd.people[{i}]"
        if not (_finite(p.x, p.y)):
            out.append((f, f"x and y must be finite numbers, got ({p.x!r}, {p.y!r})"))
            continue
        if not (_finite(p.radius) and p.radius > 0):
            out.append((f"{f}.radius", f"must be > 0 metres, got {p.radius!r}"))
            continue
        if p.desired_speed is not None and not (_finite(p.desired_speed)
                                                and MIN_WALKING_SPEED < p.desired_speed <= MAX_WALKING_SPEED):
            out.append((f"{f}.desired_speed", f"must be in ({MIN_WALKING_SPEED:g}, {MAX_WALKING_SPEED:g}] m/s "
                                              f"or left out (drawn), got {p.desired_speed!r}"))
        if not p.goals:
            out.append((f"{f}.goals", "needs at least one goal [x, y]"))
        for j, g in enumerate(p.goals):
            if len(g) != 2 or not _finite(*g):
                out.append((f"{f}.goals[{j}]", f"must be a point [x, y] of finite numbers, got {g!r}"))
            else:
                place(f"{f}.goals[{j}]", float(g[0]), float(g[1]), float(p.radius), "goal")
        place(f, float(p.x), float(p.y), float(p.radius), "start")
        if geometry is not None and np.isfinite(robot_q).all():
            d = _robot_distance(p.x, p.y, geometry, robot_q)
            if d < p.radius:
                out.append((f, f"start ({p.x:g}, {p.y:g}) overlaps the robot at its start configuration "
                               f"(the body of radius {p.radius:g} m is {d - p.radius:.3g} m from its surface; "
                               f"must be >= 0)"))
        for name, ox, oy, r in others:
            gap = math.hypot(p.x - ox, p.y - oy) - r - p.radius
            if gap < 0:
                out.append((f, f"start ({p.x:g}, {p.y:g}) overlaps {name} at ({ox:g}, {oy:g}) by {-gap:.3g} m "
                               f"(bodies must not overlap)"))
        others.append((f, float(p.x), float(p.y), float(p.radius)))
    return out
