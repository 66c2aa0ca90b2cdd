"""Drawing the room: walls, obstacles, people and the social-cost heat map.

Every function draws on a caller's :class:`matplotlib.axes.Axes` and returns
its artists, so figures are built by composing calls (the scene picture of
:mod:`drake_social.viz.show`, and later path figures on top of it). Nothing
here uses ``pyplot``: figures are plain :class:`matplotlib.figure.Figure`
objects, independent of any GUI backend.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.image import AxesImage
from matplotlib.collections import PolyCollection
from matplotlib.patches import Circle, FancyArrow, Polygon, Rectangle
from matplotlib.transforms import Affine2D

from drake_social.cost import SocialCost
from drake_social.maps import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from drake_social.people import PeopleState, people_model
from drake_social.scenario import Box, Scenario
from drake_social.scenario.map_rules import world_map_boxes
from drake_social.viz.labels import MAX_LABEL_CHARS, fit_text
from drake_social.world import Boxes, world_model

__all__ = [
    "FIELD_CMAP",
    "MAP_BOX_EDGE",
    "MAP_MAX_OUTLINES",
    "MAP_PICTURE_CELLS",
    "MAP_OCCUPIED_RGBA",
    "MAP_OUTSIDE_RGBA",
    "MAP_UNKNOWN_RGBA",
    "OBSTACLE_COLOR",
    "PERSON_COLOR",
    "VIEW_MARGIN",
    "box_corners",
    "draw_social_field",
    "draw_map",
    "draw_world",
    "FIELD_MAX_CELLS",
    "FIELD_MIN_RESOLUTION",
    "field_grid",
    "field_resolution",
    "map_picture_factor",
    "map_rgba",
]

#: Fill of walls and obstacles.
OBSTACLE_COLOR = "#5b5b5b"
#: A map's occupied and unknown cells (RGBA, 0-1) and the outline of its boxes.
MAP_OCCUPIED_RGBA = (0.25, 0.25, 0.25, 1.0)
MAP_UNKNOWN_RGBA = (0.55, 0.55, 0.6, 0.45)
MAP_BOX_EDGE = "#1f77b4"
#: What of the room lies outside a turned map's rectangle (an obstacle when
#: unknown cells are: :func:`drake_social.scenario.map_rules.outside_boxes`).
MAP_OUTSIDE_RGBA = (0.55, 0.55, 0.6, 0.75)
#: Most pixels along either side of a map's cells in a figure (:func:`map_rgba`):
#: a larger map is drawn in blocks of cells. The map picture of ``map inspect``
#: is 10 inches at 150 dpi (1,500 pixels) along the map's longer side.
MAP_PICTURE_CELLS = 2048
#: Most map boxes a figure outlines (some 0.8 kB of matplotlib's each; 20,000
#: tiny outlines already fill a picture): a map of more is drawn by its cells.
MAP_MAX_OUTLINES = 20_000
#: Fill of person bodies.
PERSON_COLOR = "#e8c39e"
#: Colour map of the social-cost heat map (white at zero cost).
FIELD_CMAP = "Reds"
#: Free space shown around the outer walls, metres.
VIEW_MARGIN = 0.3
#: Largest number of heat-map cells along either side of the map, so that a
#: 1000 m (or 10^6 m) world costs the same figure or texture as a 25 m one.
FIELD_MAX_CELLS = 512
#: Finest heat-map cell, metres (a cell of a small room's figure).
FIELD_MIN_RESOLUTION = 0.05


def box_corners(box: Box) -> np.ndarray:
    """The four corners (4, 2) of a box obstacle in the world frame, metres."""
    return Boxes(centers=[box.center], sizes=[box.size], yaws=[box.yaw]).corners[0]


def draw_world(ax: Axes, scenario: Scenario, *, names: bool = True, margin: float = VIEW_MARGIN,
               people: PeopleState | None = None) -> dict[str, list]:
    """Draws the boundary walls, the obstacles and the people.

    People are discs of their body radius with an arrow along their facing
    direction ``theta``. Sets equal aspect and limits covering the walls.

    Args:
        ax: the axes to draw on (world metres on both axes).
        scenario: the scenario whose world and people are drawn.
        names: also write each person's ``name`` next to them (its first
            line, cut to :data:`~drake_social.viz.labels.MAX_LABEL_CHARS`
            characters).
        margin: free space around the outer walls in the view, metres.
        people: the people to draw (those present only,
            :meth:`~drake_social.people.PeopleState.visible`); None = the
            scenario's people model at t = 0
            (:func:`drake_social.people.people_model`).

    Returns:
        Artists by kind: "walls", "obstacles", "people", "arrows", "names",
        and with a map "map" (:func:`draw_map`). The first wall is labelled
        "wall / obstacle" and the first person "person (arrow: facing)" for
        legends.
    """
    w = world_model(scenario)
    x0, y0, x1, y1 = (float(v) for v in w.bounds)
    t = w.wall_thickness
    if people is None:
        people = people_model(scenario).state_at(0.0)
    people = people.visible()  # an absent person (not entered yet, or gone) is not drawn
    out: dict[str, list] = {"walls": [], "obstacles": [], "people": [], "arrows": [], "names": []}
    # Boundary walls stand outside the bounds (see World.wall_thickness).
    for x, y, dx, dy in (
        (x0 - t, y0 - t, x1 - x0 + 2 * t, t),
        (x0 - t, y1, x1 - x0 + 2 * t, t),
        (x0 - t, y0, t, y1 - y0),
        (x1, y0, t, y1 - y0),
    ):
        patch = Rectangle((x, y), dx, dy, facecolor=OBSTACLE_COLOR, edgecolor="none", zorder=2)
        out["walls"].append(ax.add_patch(patch))
    out["walls"][0].set_label("wall / obstacle")
    hand = len(w.boxes) - w.map_box_count
    for corners in w.boxes.corners[:hand]:
        patch = Polygon(corners, closed=True, facecolor=OBSTACLE_COLOR, edgecolor="#2b2b2b",
                        linewidth=0.6, zorder=2)
        out["obstacles"].append(ax.add_patch(patch))
    if w.map is not None:
        outside = world_map_boxes(scenario.world).cells[:, 0] < 0  # the boxes that close a turned map's outside
        out["map"] = draw_map(ax, w.map, w.boxes.corners[hand:], outside=outside, clip=w.bounds)
    for i, ((px, py), theta, radius, name) in enumerate(zip(people.positions, people.headings, people.radii,
                                                           people.names)):
        px, py, theta, radius = float(px), float(py), float(theta), float(radius)
        body = Circle((px, py), radius, facecolor=PERSON_COLOR, edgecolor="black", linewidth=1.0, zorder=4,
                      label="person (arrow: facing)" if i == 0 else None)
        out["people"].append(ax.add_patch(body))
        # The arrow starts at the body's edge so that it reads as a nose.
        length = max(0.45, 1.6 * radius)
        c, s = math.cos(theta), math.sin(theta)
        arrow = FancyArrow(px + radius * c, py + radius * s, length * c, length * s, width=0.06,
                           head_width=0.26, head_length=0.22, length_includes_head=True, color="black", zorder=4)
        out["arrows"].append(ax.add_patch(arrow))
        if names and name:
            # Label on the side opposite to the facing arrow, to keep it readable.
            off = radius + 0.2
            out["names"].append(ax.text(px - off * c, py - off * s, fit_text(name, MAX_LABEL_CHARS, 1),
                                        fontsize=7,
                                        ha="left" if c < -0.3 else ("right" if c > 0.3 else "center"),
                                        va="bottom" if s < -0.3 else ("top" if s > 0.3 else "center"),
                                        zorder=6, color="#202020"))
    ax.set_xlim(x0 - t - margin, x1 + t + margin)
    ax.set_ylim(y0 - t - margin, y1 + t + margin)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    return out


def map_picture_factor(shape: Sequence[int], max_cells: int = MAP_PICTURE_CELLS) -> int:
    """The side f of the blocks of f x f cells that :func:`map_rgba` draws as one
    pixel, for a map of ``shape`` (rows, columns): the smallest f (>= 1) that
    leaves at most ``max_cells`` pixels along either side."""
    return max(1, math.ceil(max(int(shape[0]), int(shape[1])) / max_cells))


def map_rgba(grid: OccupancyMap, max_cells: int = MAP_PICTURE_CELLS) -> np.ndarray:
    """The map's cells as an RGBA image of ``uint8`` in the map's grid order
    (row 0 = the bottom row): occupied :data:`MAP_OCCUPIED_RGBA`, unknown
    :data:`MAP_UNKNOWN_RGBA`, free transparent.

    A map of at most ``max_cells`` cells along either side is drawn cell for
    cell, (H, W, 4). A larger one in blocks of f x f cells
    (:func:`map_picture_factor`), (ceil(H / f), ceil(W / f), 4), the last row and
    column of blocks padded with free cells: a block is occupied where any of
    its cells is, else unknown where any is, else free, so that a wall one
    cell thick is still drawn. The picture then costs at most 4 bytes a pixel
    (16 MB), however large the map.
    """
    classes = grid.classes
    f = map_picture_factor(classes.shape, max_cells)
    if f == 1:
        occupied, unknown = classes == OCCUPIED, classes == UNKNOWN
    else:
        rows, cols = -(-classes.shape[0] // f), -(-classes.shape[1] // f)
        occupied, unknown = np.zeros((rows, cols), bool), np.zeros((rows, cols), bool)
        step = max(1, (1 << 22) // (f * f * cols))  # rows of blocks at a time: about 4 M cells
        for r0 in range(0, rows, step):
            band = classes[r0 * f:(r0 + step) * f]
            padded = np.full((-(-len(band) // f) * f, cols * f), FREE, classes.dtype)
            padded[:band.shape[0], :band.shape[1]] = band
            blocks = padded.reshape(-1, f, cols, f)
            occupied[r0:r0 + len(blocks)] = (blocks == OCCUPIED).any(axis=(1, 3))
            unknown[r0:r0 + len(blocks)] = (blocks == UNKNOWN).any(axis=(1, 3))
    out = np.zeros((*occupied.shape, 4), np.uint8)
    out[occupied] = np.round(np.multiply(MAP_OCCUPIED_RGBA, 255))
    out[unknown & ~occupied] = np.round(np.multiply(MAP_UNKNOWN_RGBA, 255))
    return out


def draw_map(ax: Axes, grid: OccupancyMap, corners: np.ndarray, *, outside: np.ndarray | None = None,
             clip: Sequence[float] | None = None) -> list:
    """Draws an occupancy-grid map's cells under the outlines of its boxes.

    The image (:func:`map_rgba`, free cells transparent, so the heat map
    shows through) is placed by the map's origin and yaw; the boxes
    (``corners`` (K, 4, 2)) the planner sees are outlined on top of it, at
    most :data:`MAP_MAX_OUTLINES` of them: more are not outlined (their
    union is the cells drawn), the outlines then empty.

    Args:
        outside: (K,) bool, the boxes that close the outside of a turned
            map's rectangle (:func:`~drake_social.scenario.map_rules.outside_boxes`):
            filled in :data:`MAP_OUTSIDE_RGBA`, not outlined (they reach far
            beyond the room). None = none.
        clip: ``[x_min, y_min, x_max, y_max]``: nothing of the map is drawn
            beyond it (the room's bounds). None = no clipping.

    Returns:
        ``[image, outlines]``, then the outside's fill when there is one; the
        image is labelled "map: occupied / unknown cells", the outlines "map
        boxes" and the fill "map: outside its rectangle" for legends.
    """
    x, y, yaw = (float(v) for v in grid.origin)
    rgba = map_rgba(grid)
    side = map_picture_factor(grid.shape) * grid.resolution  # of a pixel (the last ones padded with free cells)
    height, width = rgba.shape[0] * side, rgba.shape[1] * side
    image = ax.imshow(rgba, origin="lower", extent=(0.0, width, 0.0, height), interpolation="nearest",
                      zorder=1, label="map: occupied / unknown cells")
    image.set_transform(Affine2D().rotate(yaw).translate(x, y) + ax.transData)
    corners = np.asarray(corners, float).reshape(-1, 4, 2)
    outside = np.zeros(len(corners), bool) if outside is None else np.asarray(outside, bool)
    cells = corners[~outside]
    # Thinner outlines when there are many boxes, so that ragged walls stay readable.
    outlines = PolyCollection(list(cells) if len(cells) <= MAP_MAX_OUTLINES else [], closed=True,
                              facecolors="none", edgecolors=MAP_BOX_EDGE,
                              linewidths=0.4 if len(cells) <= 500 else 0.15, zorder=2, label="map boxes")
    ax.add_collection(outlines)
    artists = [image, outlines]
    if outside.any():
        fill = PolyCollection(list(corners[outside]), closed=True, facecolors=[MAP_OUTSIDE_RGBA],
                              edgecolors="none", zorder=1, label="map: outside its rectangle")
        artists.append(ax.add_collection(fill))
    if clip is not None:
        x0, y0, x1, y1 = (float(v) for v in clip)
        frame = Rectangle((x0, y0), x1 - x0, y1 - y0, transform=ax.transData)
        for artist in artists:
            artist.set_clip_path(frame)
    return artists


def field_resolution(bounds: Sequence[float], max_cells: int = FIELD_MAX_CELLS) -> float:
    """Heat-map cell size for a map, metres: :data:`FIELD_MIN_RESOLUTION` or
    coarser, so that neither side of :func:`field_grid` has more than
    ``max_cells`` cells (the figures and the Meshcat texture both use it)."""
    x0, y0, x1, y1 = (float(v) for v in bounds)
    if not max_cells >= 1:
        raise ValueError(f"max_cells must be >= 1, got {max_cells}")
    return max(FIELD_MIN_RESOLUTION, max(x1 - x0, y1 - y0) / max_cells)


def field_grid(bounds: Sequence[float], resolution: float) -> tuple[np.ndarray, np.ndarray]:
    """Cell-centre coordinates of a grid over ``bounds`` with cells of about
    ``resolution`` metres: returns (xs (nx,), ys (ny,))."""
    x0, y0, x1, y1 = (float(v) for v in bounds)
    if not resolution > 0:
        raise ValueError(f"resolution must be > 0 metres, got {resolution}")
    nx = max(1, math.ceil((x1 - x0) / resolution - 1e-9))
    ny = max(1, math.ceil((y1 - y0) / resolution - 1e-9))
    xs = x0 + (np.arange(nx) + 0.5) * (x1 - x0) / nx
    ys = y0 + (np.arange(ny) + 0.5) * (y1 - y0) / ny
    return xs, ys


def draw_social_field(
    ax: Axes,
    cost: SocialCost,
    bounds: Sequence[float],
    resolution: float | None = None,
    *,
    colorbar: bool = True,
    vmax: float | None = None,
    cmap: str = FIELD_CMAP,
) -> AxesImage:
    """Draws the heat map of ``G(x, y) = sum_i AGF_i(x, y)`` under everything else.

    Args:
        ax: the axes to draw on.
        cost: gives :meth:`SocialCost.field` (people, variances, threshold).
        bounds: [x_min, y_min, x_max, y_max] of the map, metres.
        resolution: size of a heat-map cell, metres; None =
            :func:`field_resolution` of ``bounds`` (at most
            :data:`FIELD_MAX_CELLS` cells a side, whatever the world's size).
        colorbar: add a colour bar labelled "social cost" beside the axes.
        vmax: top of the colour scale; None = the field's maximum (1 when the
            field is zero everywhere, e.g. in an empty room).
        cmap: a matplotlib colour-map name.

    Returns:
        The image; ``image.get_array()[j, i]`` is G at ``(xs[i], ys[j])`` of
        :func:`field_grid`.
    """
    xs, ys = field_grid(bounds, field_resolution(bounds) if resolution is None else resolution)
    values = cost.field(xs[None, :], ys[:, None])
    top = float(values.max()) if vmax is None else float(vmax)
    if not top > 0:
        top = 1.0
    image = ax.imshow(values, origin="lower", extent=(bounds[0], bounds[2], bounds[1], bounds[3]),
                      cmap=cmap, vmin=0.0, vmax=top, interpolation="nearest", zorder=0)
    if colorbar:
        # An inset keeps the bar exactly as tall as the (equal-aspect) map.
        cax = ax.inset_axes((1.015, 0.0, 0.025, 1.0))
        ax.figure.colorbar(image, cax=cax, label="social cost")
    return image
