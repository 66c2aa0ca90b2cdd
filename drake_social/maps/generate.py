"""Seeded office floors as map_server maps, and writing a map (image + YAML).

:func:`office_floor_layout` draws a floor plan from a
:class:`numpy.random.Generator`: outer walls inside a band of unknown grey
(as a SLAM map has outside the building), a vertical corridor along the
left, one horizontal corridor per about 14 m of height, rooms on both sides
of each horizontal corridor (4 to 7 m wide), one door per room onto its
corridor, and desks and shelves in the rooms. Corridors are 3.0 to 3.6 m
wide and doors 1.8 to 2.2 m (a robot of base radius 0.3 m carrying a 1.5 m
bar passes). The free space is one connected region: desks keep 1 m from
walls and from each other, shelves stand against the wall facing the door
1 m from the side walls, and nothing stands within 2 m of a door.

:func:`office_floor_image` rasterises it as map_saver writes a trinary map
(255 free, 0 occupied, 205 unknown; image row 0 at the top),
:func:`ragged_edges` roughens its walls' edges as a SLAM map's are (a clean
floor decomposes into a hundred boxes, a ragged one into thousands), and
:func:`write_map` writes an image and its YAML.
"""

from __future__ import annotations

import dataclasses as dc
import math
import os
from pathlib import Path

import numpy as np

from drake_social.io.textfile import replace_file
from drake_social.maps.read import check_map_field

__all__ = ["MAP_IMAGE_FORMATS", "OfficeFloorLayout", "office_floor_image", "office_floor_layout", "ragged_edges",
           "write_map"]

#: Image formats :func:`write_map` writes (file suffixes).
MAP_IMAGE_FORMATS = ("pgm", "png", "bmp")
#: map_saver's shades of a trinary map: free, occupied, unknown.
WHITE, BLACK, GREY = 255, 0, 205

_MARGIN = 0.4  # unknown grey outside the outer wall, metres
_CORRIDOR = (3.0, 3.6)  # corridor widths, metres
_DOOR = (1.8, 2.2)  # door widths, metres
_ROOM = (4.0, 7.0)  # room widths along a corridor, metres
_CLEAR = 1.0  # furniture's clearance from walls and from other furniture, metres
_DOOR_CLEAR = 2.0  # depth kept free in front of a door (and 0.6 m either side), metres

Rect = tuple[float, float, float, float]  # x0, y0, x1, y1 in the map frame, metres (y up)


@dc.dataclass(frozen=True)
class OfficeFloorLayout:
    """A floor plan, rectangles ``(x0, y0, x1, y1)`` in the map frame (metres, y up, from the image's lower-left).

    Attributes:
        width_m: the map's width, metres.
        height_m: the map's height, metres.
        resolution: metres per cell of the image.
        outer: the outer wall's outline (outside it: unknown).
        wall: outer wall thickness, metres.
        inner_wall: thickness of the walls between rooms and corridors, metres.
        corridors: the corridors' free rectangles.
        rooms: the rooms' free rectangles (inside their walls).
        doors: each room's door: the opening cut through its wall (same order as ``rooms``).
        furniture: desks and shelves (occupied).
    """

    width_m: float
    height_m: float
    resolution: float
    outer: Rect
    wall: float
    inner_wall: float
    corridors: tuple[Rect, ...]
    rooms: tuple[Rect, ...]
    doors: tuple[Rect, ...]
    furniture: tuple[Rect, ...]

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W) of the image, cells."""
        return round(self.height_m / self.resolution), round(self.width_m / self.resolution)

    def image(self) -> np.ndarray:
        """The layout as a map_saver trinary image: (H, W) ``uint8``, row 0 the top row."""
        h, w = self.shape
        grid = np.full((h, w), GREY, np.uint8)  # row 0 at the bottom while drawing
        paint = _painter(grid, self.resolution)
        paint(self.outer, BLACK)
        x0, y0, x1, y1 = self.outer
        t = self.wall
        paint((x0 + t, y0 + t, x1 - t, y1 - t), BLACK)  # inner walls: what rooms and corridors leave
        for r in self.corridors + self.rooms + self.doors:
            paint(r, WHITE)
        for r in self.furniture:
            paint(r, BLACK)
        return np.ascontiguousarray(grid[::-1])


def _painter(grid: np.ndarray, resolution: float):
    """A function filling the cells whose centres lie in a rectangle (metres) with a shade."""
    h, w = grid.shape

    def cells(a: float, b: float, n: int) -> slice:
        return slice(min(max(math.ceil(a / resolution - 0.5), 0), n), min(max(math.ceil(b / resolution - 0.5), 0), n))

    def paint(rect: Rect, shade: int) -> None:
        x0, y0, x1, y1 = rect
        grid[cells(y0, y1, h), cells(x0, x1, w)] = shade

    return paint


def _split(rng: np.random.Generator, a: float, b: float, low: float, high: float, wall: float) -> list[tuple]:
    """[a, b] cut into spans of width in [low, high] (the last may be up to low + high) separated by walls."""
    spans, x = [], a
    while b - x >= 2 * low + wall:
        width = min(rng.uniform(low, high), b - x - low - wall)
        spans.append((x, x + width))
        x += width + wall
    spans.append((x, b))
    return spans


def office_floor_layout(width_m: float, height_m: float, resolution: float,
                        rng: np.random.Generator) -> OfficeFloorLayout:
    """A seeded office floor plan (see the module docstring).

    Args:
        width_m: the map's width, metres (at least 14).
        height_m: the map's height, metres (at least 12).
        resolution: metres per cell, in (0, 0.2].
        rng: the random stream; the same stream state gives the same floor.

    Returns:
        The layout.

    Raises:
        ValueError: a size or resolution out of range.
    """
    if not (math.isfinite(width_m) and width_m >= 14.0 and math.isfinite(height_m) and height_m >= 12.0):
        raise ValueError(f"width_m, height_m: an office floor needs at least 14 x 12 m, got {width_m} x {height_m}")
    if not (math.isfinite(resolution) and 0 < resolution <= 0.2):
        raise ValueError(f"resolution: must be in (0, 0.2] metres per cell, got {resolution}")
    wall, inner = max(0.25, resolution), max(0.15, resolution)
    outer = (_MARGIN, _MARGIN, width_m - _MARGIN, height_m - _MARGIN)
    ix0, iy0, ix1, iy1 = outer[0] + wall, outer[1] + wall, outer[2] - wall, outer[3] - wall
    spine = rng.uniform(*_CORRIDOR)
    corridors: list[Rect] = [(ix0, iy0, ix0 + spine, iy1)]
    rooms_x0 = ix0 + spine + inner
    slabs = max(1, round((iy1 - iy0) / 14.0))
    slab_h = (iy1 - iy0 - (slabs - 1) * inner) / slabs
    rooms, doors, furniture = [], [], []
    for k in range(slabs):
        y0 = iy0 + k * (slab_h + inner)
        width = rng.uniform(*_CORRIDOR)
        depth = (slab_h - width - 2 * inner) / 2
        cy0 = y0 + depth + inner
        corridors.append((ix0, cy0, ix1, cy0 + width))  # open onto the spine
        for below in (True, False):
            ry0, ry1 = (y0, y0 + depth) if below else (cy0 + width + inner, cy0 + width + inner + depth)
            for rx0, rx1 in _split(rng, rooms_x0, ix1, *_ROOM, inner):
                room = (rx0, ry0, rx1, ry1)
                door_w = rng.uniform(*_DOOR)
                dx = rng.uniform(rx0 + 0.3, rx1 - 0.3 - door_w)
                door = (dx, ry1, dx + door_w, ry1 + inner) if below else (dx, ry0 - inner, dx + door_w, ry0)
                rooms.append(room)
                doors.append(door)
                furniture.extend(_furnish(rng, room, door, back_at_bottom=below))
    return OfficeFloorLayout(width_m=float(width_m), height_m=float(height_m), resolution=float(resolution),
                             outer=outer, wall=wall, inner_wall=inner, corridors=tuple(corridors),
                             rooms=tuple(rooms), doors=tuple(doors), furniture=tuple(furniture))


def _overlaps(a: Rect, b: Rect, gap: float = 0.0) -> bool:
    return a[0] < b[2] + gap and b[0] < a[2] + gap and a[1] < b[3] + gap and b[1] < a[3] + gap


def _furnish(rng: np.random.Generator, room: Rect, door: Rect, *, back_at_bottom: bool) -> list[Rect]:
    """Up to three desks and one shelf in ``room``, placed by rejection (a bounded number of draws)."""
    x0, y0, x1, y1 = room
    keep_free = (door[0] - 0.6, y1 - _DOOR_CLEAR, door[2] + 0.6, y1) if back_at_bottom else \
        (door[0] - 0.6, y0, door[2] + 0.6, y0 + _DOOR_CLEAR)
    placed: list[Rect] = []

    def try_place(piece: Rect) -> None:
        if _overlaps(piece, keep_free) or any(_overlaps(piece, p, _CLEAR) for p in placed):
            return
        placed.append(piece)

    shelf_len = rng.uniform(1.5, 2.5)
    if x1 - x0 - 2 * _CLEAR > shelf_len:
        sx = rng.uniform(x0 + _CLEAR, x1 - _CLEAR - shelf_len)
        try_place((sx, y0, sx + shelf_len, y0 + 0.45) if back_at_bottom else (sx, y1 - 0.45, sx + shelf_len, y1))
    for _ in range(int(rng.integers(1, 4))):
        for _attempt in range(8):
            dw, dh = (1.6, 0.8) if rng.random() < 0.5 else (0.8, 1.6)
            if x1 - x0 - 2 * _CLEAR <= dw or y1 - y0 - 2 * _CLEAR <= dh:
                break
            dx = rng.uniform(x0 + _CLEAR, x1 - _CLEAR - dw)
            dy = rng.uniform(y0 + _CLEAR, y1 - _CLEAR - dh)
            before = len(placed)
            try_place((dx, dy, dx + dw, dy + dh))
            if len(placed) > before:
                break
    return placed


def office_floor_image(width_m: float, height_m: float, resolution: float, rng: np.random.Generator) -> np.ndarray:
    """A seeded office floor as a map_saver trinary image (see the module docstring).

    Args:
        width_m: the map's width, metres (at least 14).
        height_m: the map's height, metres (at least 12).
        resolution: metres per cell, in (0, 0.2].
        rng: the random stream.

    Returns:
        (H, W) ``uint8``, ``H = round(height_m / resolution)``: 255 free,
        0 occupied, 205 unknown; row 0 is the image's top row.
    """
    return office_floor_layout(width_m, height_m, resolution, rng).image()


def ragged_edges(image: np.ndarray, rng: np.random.Generator, p: float = 0.3) -> np.ndarray:
    """``image`` with the ragged wall edges of a SLAM map: each free cell
    beside an occupied one (4-neighbours) turns occupied, and each occupied
    cell beside a free one turns free, with probability ``p`` (one draw per
    cell, all from ``rng``). Walls at least 3 cells thick stay closed; a
    door narrows by at most a cell on each side.

    Args:
        image: (H, W) ``uint8`` trinary image (255 free, 0 occupied, 205 unknown).
        rng: the random stream.
        p: the probability, in [0, 1].

    Returns:
        A new image of the same shape.
    """
    image = np.asarray(image)
    if image.ndim != 2 or image.dtype != np.uint8:
        raise ValueError(f"image: must be a (H, W) uint8 array, got {image.dtype} {image.shape}")
    if not 0.0 <= p <= 1.0:
        raise ValueError(f"p: must be in [0, 1], got {p}")
    occupied, free = image == BLACK, image == WHITE

    def beside(mask: np.ndarray) -> np.ndarray:
        out = np.zeros_like(mask)
        out[1:] |= mask[:-1]
        out[:-1] |= mask[1:]
        out[:, 1:] |= mask[:, :-1]
        out[:, :-1] |= mask[:, 1:]
        return out

    flip = rng.random(image.shape) < p
    out = image.copy()
    out[free & beside(occupied) & flip] = BLACK
    out[occupied & beside(free) & flip] = WHITE
    return out


def _format_number(value: float) -> str:
    return repr(float(value))


def write_map(directory: str | Path, name: str, image_u8: np.ndarray, resolution: float,
              origin: tuple[float, float, float] = (0.0, 0.0, 0.0), *, negate: int = 0,
              occupied_thresh: float = 0.65, free_thresh: float = 0.196, mode: str = "trinary",
              fmt: str = "pgm") -> Path:
    """Writes a map_server map: ``<name>.<fmt>`` and ``<name>.yaml`` naming it.

    Each file is written to a temporary file in ``directory`` and moved into
    place (``os.replace``), the image first, so a reader never sees half a
    file. The PGM is binary (P5).

    Args:
        directory: an existing folder.
        name: the files' stem (no folder).
        image_u8: ``uint8`` pixels, row 0 the top row: (H, W) grey, or
            (H, W, 3) RGB or (H, W, 4) RGBA for ``png`` and ``bmp``.
        resolution: metres per cell.
        origin: x, y (metres) and yaw (radians) of the bottom-left pixel's lower-left corner.
        negate: 0 or 1.
        occupied_thresh: map_server's ``occupied_thresh``.
        free_thresh: map_server's ``free_thresh``.
        mode: one of :data:`~drake_social.maps.read.MAP_MODES`.
        fmt: one of :data:`MAP_IMAGE_FORMATS`.

    Returns:
        The YAML file's path.

    Raises:
        ValueError: a parameter :func:`~drake_social.maps.read.read_map` would refuse, a bad name or image.
    """
    from PIL import Image

    if fmt not in MAP_IMAGE_FORMATS:
        raise ValueError(f"fmt: must be one of {', '.join(MAP_IMAGE_FORMATS)}, got {fmt!r}")
    if not name or "/" in name or os.sep in name or name in (".", ".."):
        raise ValueError(f"name: must be a file name stem without a folder, got {name!r}")
    fields = {"resolution": resolution, "origin": list(origin), "negate": negate,
              "occupied_thresh": occupied_thresh, "free_thresh": free_thresh, "mode": mode}
    checked = {}
    for key, value in fields.items():
        try:
            checked[key] = check_map_field(key, value)
        except ValueError as e:
            raise ValueError(f"{key}: {e}") from None
    if checked["free_thresh"] >= checked["occupied_thresh"]:
        raise ValueError(f"free_thresh: must be below occupied_thresh ({occupied_thresh}), got {free_thresh}")
    image_u8 = np.asarray(image_u8)
    allowed = ((2,) if fmt == "pgm" else (2, 3, 4))
    channels = 1 if image_u8.ndim == 2 else image_u8.shape[-1] if image_u8.ndim == 3 else 0
    if image_u8.dtype != np.uint8 or image_u8.size == 0 or {1: 2, 3: 3, 4: 4}.get(channels) not in allowed:
        raise ValueError(f"image_u8: must be a non-empty uint8 array of shape (H, W)"
                         f"{'' if fmt == 'pgm' else ', (H, W, 3) or (H, W, 4)'} for {fmt}, got {image_u8.dtype} "
                         f"{image_u8.shape}")
    directory = Path(directory)
    image_name = f"{name}.{fmt}"
    image = Image.fromarray(np.ascontiguousarray(image_u8), {1: "L", 3: "RGB", 4: "RGBA"}[channels])
    x, y, yaw = checked["origin"]
    yaml_text = (f"image: {image_name}\nmode: {checked['mode']}\nresolution: {_format_number(resolution)}\n"
                 f"origin: [{_format_number(x)}, {_format_number(y)}, {_format_number(yaw)}]\n"
                 f"negate: {int(checked['negate'])}\noccupied_thresh: {_format_number(occupied_thresh)}\n"
                 f"free_thresh: {_format_number(free_thresh)}\n")
    replace_file(directory / image_name, lambda f: image.save(f, format={"pgm": "PPM", "png": "PNG", "bmp": "BMP"}[fmt]))
    yaml_path = directory / f"{name}.yaml"
    replace_file(yaml_path, lambda f: f.write(yaml_text.encode("utf-8")))
    return yaml_path
