"""The cells of a grid as a few disjoint rectangles whose union is exactly those cells.

:func:`cells_to_rectangles` decomposes a boolean mask in two passes, both
vectorised: each row's runs of selected cells (maximal runs, from the
changes along the row), then runs with the same columns in consecutive rows
merged into one rectangle (runs sorted by their columns, then by row; a new
rectangle starts wherever the columns change or a row is skipped). The same
is done on the transposed mask (columns first) and the decomposition with
fewer rectangles is kept: a map of long horizontal walls is cheapest by
rows, one of long vertical walls by columns. The rectangles are disjoint
(each cell belongs to exactly one run of its row or column) and cover
exactly the selected cells.

:func:`map_boxes` turns the rectangles of a map's occupied (and, by choice,
unknown) cells into world boxes: centres turned by the map's yaw about its
origin, sizes along the map's axes.
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np

from drake_social.maps.read import OCCUPIED, UNKNOWN, OccupancyMap

__all__ = ["MAP_UNKNOWN_CHOICES", "MapBoxes", "cells_to_rectangles", "map_boxes", "row_rectangles"]

#: What :func:`map_boxes` may do with unknown cells: make them obstacles, or leave them free.
MAP_UNKNOWN_CHOICES = ("obstacle", "free")


def row_rectangles(mask: np.ndarray) -> np.ndarray:
    """Rectangles covering exactly the True cells of ``mask``: row runs merged down consecutive rows.

    Args:
        mask: (H, W) boolean (anything numpy reads as truth values).

    Returns:
        (K, 4) ``int64`` rows ``[row0, col0, row1, col1)`` (half-open cell
        ranges), sorted by ``(col0, col1, row0)``; disjoint.
    """
    mask = np.asarray(mask, dtype=bool)
    if mask.ndim != 2:
        raise ValueError(f"mask: must be 2-D (rows, columns), got shape {mask.shape}")
    h, w = mask.shape
    padded = np.zeros((h, w + 2), np.int8)
    padded[:, 1:-1] = mask
    # A run starts where a cell is selected and its left neighbour is not, and ends after its last cell.
    change = np.diff(padded, axis=1)
    rows, starts = np.nonzero(change == 1)
    _, ends = np.nonzero(change == -1)  # the same rows, in the same order
    del change
    if rows.size == 0:
        return np.zeros((0, 4), np.int64)
    order = np.lexsort((rows, ends, starts))  # by start column, end column, then row
    rows, starts, ends = rows[order], starts[order], ends[order]
    new = np.ones(rows.size, bool)
    new[1:] = (starts[1:] != starts[:-1]) | (ends[1:] != ends[:-1]) | (rows[1:] != rows[:-1] + 1)
    first = np.flatnonzero(new)
    last = np.append(first[1:], rows.size) - 1
    return np.stack([rows[first], starts[first], rows[last] + 1, ends[first]], axis=1).astype(np.int64)


def cells_to_rectangles(mask: np.ndarray) -> np.ndarray:
    """Few disjoint rectangles whose union is exactly the True cells of ``mask``.

    The fewer of :func:`row_rectangles` of the mask and of its transpose
    (rows first, on a tie).

    Args:
        mask: (H, W) boolean.

    Returns:
        (K, 4) ``int64`` rows ``[row0, col0, row1, col1)`` (half-open cell ranges).
    """
    mask = np.asarray(mask, dtype=bool)
    by_rows = row_rectangles(mask)
    by_cols = row_rectangles(mask.T)[:, [1, 0, 3, 2]]
    return by_cols if len(by_cols) < len(by_rows) else by_rows


@dc.dataclass(frozen=True, eq=False)
class MapBoxes:
    """A map's obstacle cells as world boxes (see :func:`map_boxes`).

    Attributes:
        centers: (K, 2) world centres, metres.
        sizes: (K, 2) side lengths along the map's x and y axes, metres.
        yaws: (K,) each box's yaw: the map's, radians.
        cells: (K, 4) ``int64`` ``[row0, col0, row1, col1)``: each box's
            half-open range of grid cells.
    """

    centers: np.ndarray
    sizes: np.ndarray
    yaws: np.ndarray
    cells: np.ndarray

    def __len__(self) -> int:
        return len(self.cells)


def map_boxes(grid: OccupancyMap, unknown: str = "obstacle") -> MapBoxes:
    """The map's obstacle cells as few disjoint boxes whose union is exactly those cells.

    Args:
        grid: the map.
        unknown: ``"obstacle"``: occupied and unknown cells (-1 and
            ``scale``/``raw`` values 1..99) are obstacles; ``"free"``: only
            occupied cells (value 100) are.

    Returns:
        The boxes (:func:`cells_to_rectangles` of the obstacle cells), in the
        world: centres turned by the map's yaw about its origin.

    Raises:
        ValueError: ``unknown`` is not one of :data:`MAP_UNKNOWN_CHOICES`.
    """
    if unknown not in MAP_UNKNOWN_CHOICES:
        raise ValueError(f"unknown: must be one of {', '.join(MAP_UNKNOWN_CHOICES)}, got {unknown!r}")
    mask = grid.classes == OCCUPIED
    if unknown == "obstacle":
        mask |= grid.classes == UNKNOWN
    cells = cells_to_rectangles(mask)
    r0, c0, r1, c1 = cells.T.astype(float)
    res = grid.resolution
    centers = grid.to_world(np.stack([(c0 + c1) * 0.5 * res, (r0 + r1) * 0.5 * res], axis=1))
    sizes = np.stack([(c1 - c0) * res, (r1 - r0) * res], axis=1)
    yaws = np.full(len(cells), grid.origin[2])
    for a in (centers, sizes, yaws, cells):
        a.flags.writeable = False
    return MapBoxes(centers=centers.reshape(-1, 2), sizes=sizes, yaws=yaws, cells=cells)
