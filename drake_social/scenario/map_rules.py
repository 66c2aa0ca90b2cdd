"""A scenario's occupancy-grid map (``world.map``): read once, its boxes, its rules.

The map is a ROS ``map_server`` YAML file and its image
(:func:`drake_social.maps.read_map`); its occupied cells, and its unknown
cells unless ``world.unknown`` is ``free``, become obstacle boxes
(:func:`drake_social.maps.map_boxes`; and :func:`outside_boxes` where the
room reaches beyond the map's rectangle, since nothing is known there) that
follow ``world.obstacles`` in
every list of the room's boxes (:func:`obstacle_arrays`,
:func:`drake_social.world.world_model`). A map and its boxes are read once per
process and file state: the cache is keyed by the YAML's and the image's
path, inode, size and modification and change times, so an edited map is
read again.

Rules (:func:`check_map`, called by
:func:`~drake_social.scenario.validate.validate_scenario`): ``world.unknown``
is one of :data:`~drake_social.scenario.schema.MAP_UNKNOWN`; the map reads
(its own errors name the map file and its field); the base centre of
``start`` and ``goal`` lies in a free cell (not an occupied one, nor an
unknown one when unknown cells are obstacles). The rest of the robot is
checked against the boxes by the checkers, with the other obstacles.
"""

from __future__ import annotations

import functools
import math
import os
from pathlib import Path
from typing import Callable

import numpy as np

from drake_social.errors import ScenarioError
from drake_social.maps import OCCUPIED, UNKNOWN, MapBoxes, OccupancyMap, map_boxes, read_map
from drake_social.scenario.schema import MAP_UNKNOWN

__all__ = ["check_map", "map_box_label", "map_extent", "obstacle_arrays", "obstacle_label", "outside_boxes", "world_map",
           "world_map_boxes", "world_map_file"]

Fail = Callable[[str, str], None]


def _stamp(path: Path) -> tuple[int, ...] | None:
    """The file's state: replaced (a new inode), rewritten (size, modification
    and change times) or gone (None) each change it."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns


@functools.lru_cache(maxsize=4)
def _read(path: str, stamp: tuple[int, ...] | None) -> tuple[OccupancyMap, tuple[int, ...] | None]:
    grid = read_map(path)
    return grid, _stamp(grid.image_path)


@functools.lru_cache(maxsize=4)
def _boxes(path: str, stamp: tuple[int, ...] | None, image_stamp: tuple[int, ...] | None,
           unknown: str) -> MapBoxes:
    return map_boxes(world_map_file(path), unknown)


def _inside(grid: OccupancyMap, points: np.ndarray) -> np.ndarray:
    """Whether world points lie in the map's rectangle (to 1e-9 m)."""
    u, v = grid.to_map(points).T
    tol = 1e-9
    return (u >= -tol) & (u <= grid.width_m + tol) & (v >= -tol) & (v <= grid.height_m + tol)


def outside_boxes(grid: OccupancyMap, bounds) -> MapBoxes | None:
    """Four boxes covering what of ``bounds`` (and beyond) lies outside the
    map's rectangle: there nothing is known, so with ``world.unknown:
    obstacle`` it is an obstacle too. None when the rectangle covers the
    bounds (a map not turned, with the default bounds). Their ``cells`` are
    -1 (no cells of the map)."""
    x0, y0, x1, y1 = (float(v) for v in bounds)
    if _inside(grid, np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])).all():
        return None
    w, h = grid.width_m, grid.height_m
    # Every point of the bounds is within this of the map's origin, so within it of the rectangle.
    t = float(np.max(np.hypot(*(np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]) - grid.origin[:2]).T))) + math.hypot(w, h)
    rects = np.array([[-t, -t, w + t, 0.0], [-t, h, w + t, h + t], [-t, 0.0, 0.0, h], [w, 0.0, w + t, h]])
    centers = grid.to_world(0.5 * (rects[:, :2] + rects[:, 2:]))
    return MapBoxes(centers=centers, sizes=rects[:, 2:] - rects[:, :2], yaws=np.full(4, float(grid.origin[2])),
                    cells=np.full((4, 4), -1, np.int64))


def world_map_file(path: str | os.PathLike) -> OccupancyMap:
    """The map of the YAML file ``path``, read once per file state.

    Raises:
        ScenarioError: the map's own errors (naming its file and field).
    """
    path = str(Path(path).absolute())
    grid, image_stamp = _read(path, _stamp(Path(path)))
    if image_stamp != _stamp(grid.image_path):  # the image changed since: read both again
        _read.cache_clear()
        grid, _ = _read(path, _stamp(Path(path)))
    return grid


def world_map(world) -> OccupancyMap | None:
    """The map of a scenario's ``world`` (``world.map``), None without one."""
    return None if world.map is None else world_map_file(world.map)


def world_map_boxes(world) -> MapBoxes | None:
    """The obstacle boxes of ``world``'s map, None without a map:
    its obstacle cells (``world.unknown`` decides the unknown ones), and,
    when unknown cells are obstacles, :func:`outside_boxes` after them (a
    turned map, or bounds beyond the map)."""
    grid = world_map(world)
    if grid is None:
        return None
    path = str(grid.path)
    boxes = _boxes(path, _stamp(grid.path), _stamp(grid.image_path), str(world.unknown))
    extra = outside_boxes(grid, world.bounds) if world.unknown == "obstacle" else None
    if extra is None:
        return boxes
    return MapBoxes(*(np.concatenate([getattr(boxes, f), getattr(extra, f)])
                      for f in ("centers", "sizes", "yaws", "cells")))


def map_extent(world) -> list[float]:
    """``[x_min, y_min, x_max, y_max]`` of ``world``'s map (its rectangle's
    axis-aligned bounding box, metres): the default ``world.bounds``."""
    return [float(v) for v in world_map(world).extent()]


def obstacle_arrays(world) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(centers (K, 2), sizes (K, 2), yaws (K,))`` of every obstacle box:
    ``world.obstacles`` in order, then the map's boxes."""
    boxes = world.obstacles
    centers = np.array([b.center for b in boxes], float).reshape(-1, 2)
    sizes = np.array([b.size for b in boxes], float).reshape(-1, 2)
    yaws = np.array([b.yaw for b in boxes], float).reshape(-1)
    extra = world_map_boxes(world)
    if extra is not None and len(extra.yaws):
        centers = np.concatenate([centers, extra.centers])
        sizes = np.concatenate([sizes, extra.sizes])
        yaws = np.concatenate([yaws, extra.yaws])
    return centers, sizes, yaws


def obstacle_label(world, k: int) -> str:
    """How messages name obstacle ``k`` of :func:`obstacle_arrays`:
    ``world.obstacles[k]``, or a box of the map (:func:`map_box_label`)."""
    k = int(k)
    n = len(world.obstacles)
    if k < n:
        return f"world.obstacles[{k}]"
    return map_box_label(world, k - n)


def map_box_label(world, j: int) -> str:
    """How messages name box ``j`` of ``world``'s map (:func:`world_map_boxes`):
    the image rows and columns it covers (as an image viewer numbers them:
    row 0 at the top) and the world coordinates it spans (metres; the axis-
    aligned range of its corners), e.g. ``the box of world.map lab.yaml over
    image rows 3-11, columns 8-9 (x 4.00 .. 5.00 m, y 0.00 .. 4.50 m)``; or
    the outside of a turned map's rectangle (:func:`outside_boxes`)."""
    boxes = world_map_boxes(world)
    grid = world_map(world)
    j = int(j)
    r0, c0, r1, c1 = (int(v) for v in boxes.cells[j])
    if r0 < 0:
        return (f"the outside of world.map {grid.path.name}'s rectangle (unknown: world.unknown is obstacle; "
                f"docs/maps.md)")
    # Grid rows count from the image's bottom row.
    top, bottom = grid.shape[0] - r1, grid.shape[0] - 1 - r0
    c, s = math.cos(float(boxes.yaws[j])), math.sin(float(boxes.yaws[j]))
    hx, hy = 0.5 * np.asarray(boxes.sizes[j], float)
    corners = np.asarray(boxes.centers[j], float) + np.array([[c * u - s * v, s * u + c * v]
                                                              for u in (-hx, hx) for v in (-hy, hy)])
    (x0, y0), (x1, y1) = corners.min(axis=0), corners.max(axis=0)
    where = f"(x {x0:.2f} .. {x1:.2f} m, y {y0:.2f} .. {y1:.2f} m)"
    if (top, c0) != (bottom, c1 - 1):
        return f"the box of world.map {grid.path.name} over image rows {top}-{bottom}, columns {c0}-{c1 - 1} {where}"
    return f"the cell of world.map {grid.path.name} at image row {top}, column {c0} {where}"


def check_map(scenario, fail: Fail) -> None:
    """Checks ``world.map`` and ``world.unknown`` (module docstring);
    ``fail(field, message)`` raises."""
    w = scenario.world
    if w.unknown not in MAP_UNKNOWN:
        fail("world.unknown", f"must be one of {', '.join(MAP_UNKNOWN)}, got {w.unknown!r}")
    if w.map is None:
        return
    if not str(w.map).strip():
        fail("world.map", "must name a map_server YAML file (relative to the scenario file), got ''")
    try:
        grid = world_map(w)
        world_map_boxes(w)
    except ScenarioError as e:
        fail("world.map", str(e))
    blocked = {OCCUPIED: "an occupied cell"}
    if w.unknown == "obstacle":
        blocked[UNKNOWN] = "an unknown cell (world.unknown: obstacle)"
    for name in ("start", "goal"):
        q = getattr(scenario, name)
        xy = np.array([[float(q[0]), float(q[1])]])
        rows, cols = grid.cell_at(xy)
        row, col = int(rows[0]), int(cols[0])
        if row < 0:
            if w.unknown == "obstacle":
                fail(name, f"the base centre ({q[0]:g}, {q[1]:g}) lies outside world.map {grid.path} (unknown there, "
                           f"and world.unknown is obstacle); the robot must start and end in free cells")
            continue  # outside the map's rectangle, with unknown cells free: the room there is free
        kind = int(grid.classes[row, col])
        if kind in blocked:
            i, j = grid.image_pixel(row, col)
            fail(name, f"the base centre ({q[0]:g}, {q[1]:g}) lies in {blocked[kind]} of world.map {grid.path} "
                       f"(image row {int(i)}, column {int(j)}); the robot must start and end in free cells")
