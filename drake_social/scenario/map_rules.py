"""A scenario's occupancy-grid map (``world.map``): read once, its boxes, its rules.

The map is a ROS ``map_server`` YAML file and its image
(:func:`drake_social.maps.read_map`); its occupied cells, and its unknown
cells unless ``world.unknown`` is ``free``, become obstacle boxes
(:func:`drake_social.maps.map_boxes`) that follow ``world.obstacles`` in
every list of the room's boxes (:func:`obstacle_arrays`,
:func:`drake_social.world.world_model`). A map and its boxes are read once per
process and file state: the cache is keyed by the YAML's and the image's
path, size and modification time, so an edited map is read again.

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
import os
from pathlib import Path
from typing import Callable

import numpy as np

from drake_social.errors import ScenarioError
from drake_social.maps import OCCUPIED, UNKNOWN, MapBoxes, OccupancyMap, map_boxes, read_map
from drake_social.scenario.schema import MAP_UNKNOWN

__all__ = ["check_map", "map_extent", "obstacle_arrays", "obstacle_label", "world_map", "world_map_boxes"]

Fail = Callable[[str, str], None]


def _stamp(path: Path) -> tuple[int, int] | None:
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_size, st.st_mtime_ns


@functools.lru_cache(maxsize=4)
def _read(path: str, stamp: tuple[int, int] | None) -> tuple[OccupancyMap, tuple[int, int] | None]:
    grid = read_map(path)
    return grid, _stamp(grid.image_path)


@functools.lru_cache(maxsize=4)
def _boxes(path: str, stamp: tuple[int, int] | None, image_stamp: tuple[int, int] | None,
           unknown: str) -> MapBoxes:
    return map_boxes(world_map_file(path), unknown)


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
    """The obstacle boxes of ``world``'s map (``world.unknown`` decides the
    unknown cells), None without a map."""
    grid = world_map(world)
    if grid is None:
        return None
    path = str(grid.path)
    return _boxes(path, _stamp(grid.path), _stamp(grid.image_path), str(world.unknown))


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
    ``world.obstacles[k]``, or a box of the map with its image pixels."""
    k = int(k)
    n = len(world.obstacles)
    if k < n:
        return f"world.obstacles[{k}]"
    boxes = world_map_boxes(world)
    grid = world_map(world)
    r0, c0, r1, c1 = (int(v) for v in boxes.cells[k - n])
    # Grid rows count from the image's bottom row.
    top, bottom = grid.shape[0] - r1, grid.shape[0] - 1 - r0
    return (f"the box of world.map {grid.path.name} over image rows {top}-{bottom}, columns {c0}-{c1 - 1}"
            if (top, c0) != (bottom, c1 - 1) else f"the cell of world.map {grid.path.name} at image row {top}, "
                                                   f"column {c0}")


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
            continue  # outside the map's rectangle: the room there is free
        kind = int(grid.classes[row, col])
        if kind in blocked:
            i, j = grid.image_pixel(row, col)
            fail(name, f"the base centre ({q[0]:g}, {q[1]:g}) lies in {blocked[kind]} of world.map {grid.path} "
                       f"(image row {int(i)}, column {int(j)}); the robot must start and end in free cells")
