"""The room as arrays: bounds, the four boundary walls and the obstacle boxes."""

from __future__ import annotations

import dataclasses as dc

import numpy as np

from drake_social.maps import OccupancyMap
from drake_social.scenario.map_rules import obstacle_arrays, world_map

__all__ = ["Boxes", "WALL_NAMES", "WorldGeometry", "with_obstacles", "world_model"]

#: Names of the boundary walls, in the order of :attr:`WorldGeometry.walls`.
WALL_NAMES = ("wall_south", "wall_north", "wall_west", "wall_east")


def _frozen(value, shape: tuple[int, ...], what: str) -> np.ndarray:
    """``value`` as a read-only float array of ``shape`` (else a ValueError naming ``what``)."""
    out = np.array(value, dtype=float)
    if out.shape != shape:
        raise ValueError(f"{what} has shape {out.shape}; expected {shape}")
    out.flags.writeable = False
    return out


@dc.dataclass(frozen=True, eq=False)
class Boxes:
    """Rotated rectangles in the world frame, extruded over the robot's height.

    Given ``centers``, ``sizes`` and ``yaws``; the rest is derived once when
    the record is made. Every array is read-only.

    Attributes:
        centers: (K, 2) box centres [x, y], metres.
        sizes: (K, 2) side lengths along the box's own x and y axes, metres.
        yaws: (K,) rotations about z, radians, counter-clockwise from +x.
        halves: (K, 2) half side lengths, metres.
        cos, sin: (K,) cosine and sine of the yaws.
        corners: (K, 4, 2) corners, counter-clockwise from the box's own
            (-x, -y) corner, metres.
        radii: (K,) half diagonals: each box lies within this distance of
            its centre, metres.
    """

    centers: np.ndarray
    sizes: np.ndarray
    yaws: np.ndarray
    halves: np.ndarray = dc.field(init=False, repr=False)
    cos: np.ndarray = dc.field(init=False, repr=False)
    sin: np.ndarray = dc.field(init=False, repr=False)
    corners: np.ndarray = dc.field(init=False, repr=False)
    radii: np.ndarray = dc.field(init=False, repr=False)

    def __post_init__(self) -> None:
        yaws = np.array(self.yaws, dtype=float)
        if yaws.ndim != 1:
            raise ValueError(f"Boxes.yaws must be one angle per box (shape (K,)), got shape {yaws.shape}")
        k = len(yaws)
        put = lambda name, value: object.__setattr__(self, name, value)  # noqa: E731 (a frozen record)
        put("yaws", _frozen(yaws, (k,), "Boxes.yaws"))
        for name in ("centers", "sizes"):
            value = np.array(getattr(self, name), dtype=float)
            put(name, _frozen(value.reshape(0, 2) if value.size == 0 else value, (k, 2), f"Boxes.{name}"))
        c, s = np.cos(self.yaws), np.sin(self.yaws)
        half = self.sizes / 2
        hx, hy = half[:, 0, None], half[:, 1, None]
        lx, ly = np.array([-1.0, 1.0, 1.0, -1.0]) * hx, np.array([-1.0, -1.0, 1.0, 1.0]) * hy  # (K, 4)
        corners = self.centers[:, None, :] + np.stack([lx * c[:, None] - ly * s[:, None],
                                                       lx * s[:, None] + ly * c[:, None]], -1)
        radii = 0.5 * np.hypot(self.sizes[:, 0], self.sizes[:, 1])
        for name, value in (("halves", half), ("cos", c), ("sin", s), ("corners", corners), ("radii", radii)):
            value.flags.writeable = False
            put(name, value)

    def __len__(self) -> int:
        return len(self.yaws)


@dc.dataclass(frozen=True, eq=False)
class WorldGeometry:
    """The room a scenario describes, read by the checkers, the plant, the
    figures and the replay.

    Attributes:
        bounds: (4,) [x_min, y_min, x_max, y_max] of the free room, metres
            (read-only).
        wall_thickness: thickness of the four boundary walls, metres; they
            stand outside the bounds.
        boxes: the obstacles: the scenario's ``world.obstacles`` in order,
            then the boxes of its map (the last :attr:`map_box_count`).
        map: the scenario's occupancy-grid map
            (:class:`drake_social.maps.OccupancyMap`), None without one.
        map_box_count: how many of :attr:`boxes` (the last ones) are the map's.
        walls: the boundary walls, in the order of :data:`WALL_NAMES`. South
            and north span x in [x_min - t, x_max + t] so the corners are
            closed; west and east span y in [y_min, y_max] (t the thickness).
        wall_names: :data:`WALL_NAMES`.
    """

    bounds: np.ndarray
    wall_thickness: float
    boxes: Boxes
    map: OccupancyMap | None = None
    map_box_count: int = 0
    walls: Boxes = dc.field(init=False)
    wall_names: tuple[str, ...] = dc.field(init=False, default=WALL_NAMES)

    def __post_init__(self) -> None:
        object.__setattr__(self, "bounds", _frozen(self.bounds, (4,), "WorldGeometry.bounds"))
        object.__setattr__(self, "wall_thickness", float(self.wall_thickness))
        if not isinstance(self.boxes, Boxes):
            raise TypeError(f"WorldGeometry.boxes must be Boxes, got {type(self.boxes).__name__}")
        if not 0 <= int(self.map_box_count) <= len(self.boxes):
            raise ValueError(f"WorldGeometry.map_box_count must be in [0, {len(self.boxes)}], got {self.map_box_count}")
        object.__setattr__(self, "map_box_count", int(self.map_box_count))
        x_min, y_min, x_max, y_max = (float(v) for v in self.bounds)
        t = self.wall_thickness
        cx, cy = (x_min + x_max) / 2, (y_min + y_max) / 2
        w, h = x_max - x_min, y_max - y_min
        walls = Boxes(centers=[[cx, y_min - t / 2], [cx, y_max + t / 2], [x_min - t / 2, cy], [x_max + t / 2, cy]],
                      sizes=[[w + 2 * t, t], [w + 2 * t, t], [t, h], [t, h]], yaws=np.zeros(4))
        object.__setattr__(self, "walls", walls)

    @property
    def box_names(self) -> list[str]:
        """The obstacles' names: ``obstacle[i]`` for ``world.obstacles[i]``,
        ``map[j]`` for the map's box j."""
        n = len(self.boxes) - self.map_box_count
        return [f"obstacle[{i}]" for i in range(n)] + [f"map[{j}]" for j in range(self.map_box_count)]


def world_model(scenario) -> WorldGeometry:
    """The room of a scenario (its ``world``: bounds, wall thickness, obstacles
    and the boxes of its map, :func:`drake_social.scenario.map_rules.world_map_boxes`)."""
    w = scenario.world
    centers, sizes, yaws = obstacle_arrays(w)
    return WorldGeometry(
        bounds=w.bounds,
        wall_thickness=w.wall_thickness,
        boxes=Boxes(centers=centers, sizes=sizes, yaws=yaws),
        map=world_map(w),
        map_box_count=len(yaws) - len(w.obstacles),
    )


def with_obstacles(scenario, extra):
    """A deep copy of ``scenario`` whose ``world.obstacles`` are its own
    followed by ``extra`` (scenario ``Box`` records); not validated again
    (for measurements: e.g. more boxes than a YAML file may hold)."""
    import copy

    out = copy.deepcopy(scenario)
    out.world = dc.replace(out.world, obstacles=[*out.world.obstacles, *extra])
    return out
