"""The picture of ``drake-social map inspect``: a map's cells under its boxes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from drake_social.maps import MapBoxes, OccupancyMap
from drake_social.viz.world import MAP_BOX_EDGE, MAP_MAX_OUTLINES, MAP_OCCUPIED_RGBA, MAP_UNKNOWN_RGBA, draw_map
from drake_social.world import Boxes

__all__ = ["map_figure", "write_map_picture"]

#: Dots per inch of the picture; the map's longer side is drawn 10 inches long.
MAP_PICTURE_DPI = 150


def map_figure(grid: OccupancyMap, boxes: MapBoxes, *, unknown: str = "obstacle") -> Figure:
    """The map's occupied and unknown cells, the outlines of ``boxes`` and
    its extent (dashed), titled with its size and counts."""
    corners = Boxes(centers=boxes.centers, sizes=boxes.sizes, yaws=boxes.yaws).corners
    x0, y0, x1, y1 = (float(v) for v in grid.extent())
    w, h = x1 - x0, y1 - y0
    scale = 10.0 / max(w, h)
    fig = Figure(figsize=(max(w * scale, 4.0) + 1.0, max(h * scale, 3.0) + 1.4))
    ax = fig.add_axes((0.08, 0.12, 0.88, 0.78))
    draw_map(ax, grid, corners)
    ring = np.vstack([grid.corners(), grid.corners()[:1]])
    ax.plot(ring[:, 0], ring[:, 1], "--", color="#888888", linewidth=0.8)
    pad = 0.02 * max(w, h)
    ax.set_xlim(x0 - pad, x1 + pad)
    ax.set_ylim(y0 - pad, y1 + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    height, width = grid.shape
    ax.set_title(f"{grid.path.name}: {width} x {height} cells of {grid.resolution:g} m, "
                 f"{len(boxes.yaws):,} boxes (unknown cells as {unknown})", fontsize=9)
    handles = [Patch(facecolor=MAP_OCCUPIED_RGBA, label="occupied cells"),
               Patch(facecolor=MAP_UNKNOWN_RGBA, label="unknown cells"),
               Patch(facecolor="none", edgecolor=MAP_BOX_EDGE, label="boxes (the obstacles planned against)"
                     if len(boxes.yaws) <= MAP_MAX_OUTLINES else
                     f"boxes: not outlined, more than {MAP_MAX_OUTLINES:,} (they cover the cells drawn)")]
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=3, fontsize=8, frameon=False)
    return fig


def write_map_picture(grid: OccupancyMap, boxes: MapBoxes, path: str | Path, *, unknown: str = "obstacle") -> Path:
    """Writes :func:`map_figure` to ``path`` (PNG)."""
    path = Path(path)
    map_figure(grid, boxes, unknown=unknown).savefig(path, dpi=MAP_PICTURE_DPI)
    return path
