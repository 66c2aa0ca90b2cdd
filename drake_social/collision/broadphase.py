"""A uniform grid over the environment's shapes: queries touch only nearby shapes.

The grid (:class:`~drake_social.collision.validity.Grid`) covers the
axis-aligned bounding boxes of the environment rows of
:mod:`drake_social.collision.planar_kernel` (``[kind, cx, cy, c, s, hx, hy,
rho]``), each grown by :data:`PAD`. Cell ``(i, j)`` is the square
``[x0 + i cell, x0 + (i + 1) cell] x [y0 + j cell, y0 + (j + 1) cell]``,
numbered ``i + j nx``; its shapes are ``items[start[c] : start[c + 1]]``, in
ascending order, and they are every shape whose grown bounding box meets the
closed cell (a shape spanning many cells is listed in each). No pydrake here.

What the queries rely on (the kernels in
:mod:`drake_social.collision.planar_kernel`): a shape listed in no cell of a
block of cells lies, grown by :data:`PAD`, outside that block, so its
distance from any point inside the block is at least the point's distance to
the block's boundary. The grid is built in numpy (:func:`build_grid`) and read
by the compiled kernels and by :class:`~drake_social.collision.geometric.GeometricChecker`.
"""

from __future__ import annotations

import math

import numpy as np

from drake_social.collision.validity import Grid

__all__ = ["CELL", "MAX_CELLS", "MAX_ITEMS_PER_SHAPE", "PAD", "bounding_boxes", "build_grid", "cell_ranges"]

#: The grid's cell side, metres, unless the map is too large for it. A
#: clearance search reads every cell within its answer plus the capsule's
#: reach, so in open space small cells cost more than their shapes: on
#: office_bar.yaml with 10,000 boxes beyond its east wall one clearance
#: took 9.9 us with 0.5 m cells, 3.6 us with 1 m, 1.8 us with 2 m, 1.3 us
#: with 4 m (docs/broadphase.md); 2 m keeps the cells of a dense map short
#: too.
CELL = 2.0
#: At most this many cells (plus one per shape): the cell side doubles until
#: the map fits.
MAX_CELLS = 1 << 20
#: At most this many (shape, cell) entries per shape on average: the cell
#: side doubles until the shapes fit (a map of many huge shapes).
MAX_ITEMS_PER_SHAPE = 64
#: Every bounding box is grown by this, metres, so that rounding (~1e-14 m at
#: room scale) never leaves a shape out of a cell it touches.
PAD = 1e-9


def bounding_boxes(env: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper corners (K, 2), (K, 2) of the environment rows'
    axis-aligned bounding boxes grown by :data:`PAD`, metres."""
    env = np.asarray(env, float).reshape(-1, 8)
    c, s, hx, hy = np.abs(env[:, 3]), np.abs(env[:, 4]), env[:, 5], env[:, 6]
    disc = env[:, 0] == 1
    ex = np.where(disc, hx, c * hx + s * hy) + PAD
    ey = np.where(disc, hx, s * hx + c * hy) + PAD
    centre = env[:, 1:3]
    return centre - np.column_stack([ex, ey]), centre + np.column_stack([ex, ey])


def cell_ranges(grid: Grid, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, ...]:
    """``(i0, j0, i1, j1)``, each (N,) int64: the cells of ``grid`` that meet
    the boxes ``[lo, hi]`` (N, 2), clipped to the grid (empty, i0 > i1,
    where a box misses it). Boxes with a non-finite corner get the whole grid."""
    x0, y0, cell = grid.header[0], grid.header[1], grid.header[2]
    nx, ny = int(grid.dims[0]), int(grid.dims[1])
    lo, hi = np.asarray(lo, float).reshape(-1, 2), np.asarray(hi, float).reshape(-1, 2)
    finite = np.isfinite(lo).all(1) & np.isfinite(hi).all(1)
    with np.errstate(invalid="ignore"):
        out = []
        for k, (corner, origin, n) in enumerate(((lo[:, 0], x0, nx), (lo[:, 1], y0, ny),
                                                 (hi[:, 0], x0, nx), (hi[:, 1], y0, ny))):
            f = np.floor((np.where(finite, corner, 0.0) - origin) / cell)
            idx = np.clip(f, -1, n).astype(np.int64)
            if k < 2:
                idx = np.where(finite, np.maximum(idx, 0), 0)
            else:
                idx = np.where(finite, np.minimum(idx, n - 1), n - 1)
            out.append(idx)
    return tuple(out)


def build_grid(env: np.ndarray, cell: float | None = None) -> Grid:
    """The grid of the environment rows ``env`` (K, 8).

    Args:
        env: the environment (module docstring of :mod:`planar_kernel`).
        cell: the cell side, metres; None = :data:`CELL`, doubled until the
            grid has at most :data:`MAX_CELLS` cells and
            :data:`MAX_ITEMS_PER_SHAPE` entries per shape on average.
    """
    env = np.asarray(env, float).reshape(-1, 8)
    k = len(env)
    if k == 0 or not np.isfinite(env[:, 1:7]).all():
        lo, hi = np.zeros((0, 2)), np.zeros((0, 2))
        if k:
            raise ValueError("environment rows must be finite")
    else:
        lo, hi = bounding_boxes(env)
    x0, y0 = (lo.min(0) if k else np.zeros(2))
    x1, y1 = (hi.max(0) if k else np.ones(2))
    w, h = max(x1 - x0, 1e-6), max(y1 - y0, 1e-6)
    size = CELL if cell is None else float(cell)
    if not size > 0.0:
        raise ValueError(f"cell must be > 0, got {cell}")
    while True:
        nx, ny = int(math.floor(w / size)) + 1, int(math.floor(h / size)) + 1
        items = np.sum((np.floor((hi[:, 0] - x0) / size) - np.floor((lo[:, 0] - x0) / size) + 1)
                       * (np.floor((hi[:, 1] - y0) / size) - np.floor((lo[:, 1] - y0) / size) + 1))
        if cell is not None or (nx * ny <= MAX_CELLS + k and items <= MAX_ITEMS_PER_SHAPE * k + MAX_CELLS):
            break
        size *= 2.0
    grid = Grid(header=np.array([x0, y0, size, PAD]), dims=np.array([nx, ny], np.int64),
                start=np.zeros(nx * ny + 1, np.int64), items=np.zeros(0, np.int64))
    if k == 0:
        return grid
    i0, j0, i1, j1 = cell_ranges(grid, lo, hi)
    ni, nj = i1 - i0 + 1, j1 - j0 + 1
    counts = ni * nj
    shape = np.repeat(np.arange(k, dtype=np.int64), counts)
    # The r-th cell of shape s: row-major over its range.
    r = np.arange(len(shape), dtype=np.int64) - np.repeat(np.cumsum(counts) - counts, counts)
    ii = i0[shape] + r % ni[shape]
    jj = j0[shape] + r // ni[shape]
    cells = ii + jj * nx
    order = np.argsort(cells, kind="stable")  # within a cell, shapes stay in ascending order
    start = np.zeros(nx * ny + 1, np.int64)
    np.cumsum(np.bincount(cells, minlength=nx * ny), out=start[1:])
    return grid._replace(start=start, items=shape[order])
