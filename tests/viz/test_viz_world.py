"""drake_social.viz.world: boxes, the grid, the heat map and the people."""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest
from matplotlib.figure import Figure

from drake_social.cost import PersonalSpace, SocialCost, agf_algorithm1
from drake_social.scenario import Box, Person
from drake_social.viz import box_corners, draw_social_field, draw_world, field_grid


def test_box_corners_of_a_rotated_box_match_hand_values():
    dut = box_corners(Box(center=[1.0, 2.0], size=[2.0, 1.0], yaw=math.pi / 2))
    # Rotated a quarter turn: the 2 m side now runs along y.
    expected = np.array([[1.5, 1.0], [1.5, 3.0], [0.5, 3.0], [0.5, 1.0]])
    np.testing.assert_allclose(dut, expected, atol=1e-12)


def test_box_corners_at_pi_over_4_keep_the_diagonal_on_the_axes():
    dut = box_corners(Box(center=[0.0, 0.0], size=[2.0, 2.0], yaw=math.pi / 4))
    r = math.sqrt(2.0)
    np.testing.assert_allclose(dut, [[0.0, -r], [r, 0.0], [0.0, r], [-r, 0.0]], atol=1e-12)


def test_field_grid_cells_cover_the_bounds_evenly():
    # 1.0 m does not divide by 0.3 m: 4 cells of 0.25 m.
    xs, ys = field_grid([0.0, -1.0, 1.0, 1.0], 0.3)
    np.testing.assert_allclose(xs, [0.125, 0.375, 0.625, 0.875])
    np.testing.assert_allclose(ys, np.linspace(-1 + 2 / 14, 1 - 2 / 14, 7))
    with pytest.raises(ValueError, match="resolution"):
        field_grid([0, 0, 1, 1], 0.0)


def _axes() -> tuple[Figure, object]:
    fig = Figure()
    return fig, fig.add_subplot()


def test_heat_map_pixels_equal_algorithm1_at_cell_centres(tiny_scenario):
    """The image data is G(x, y) at the cell centres, checked against the
    paper's Algorithm 1 line by line, with a person rotated by pi/4 and one
    facing -x so that both branches and the cross term matter."""
    people = [Person(x=3.0, y=2.0, theta=math.pi / 4), Person(x=6.0, y=3.5, theta=math.pi)]
    scenario = dc.replace(tiny_scenario, people=people)
    cost = SocialCost.from_scenario(scenario)
    fig, ax = _axes()
    bounds = scenario.world.bounds
    dut = draw_social_field(ax, cost, bounds, resolution=0.1)
    data = np.asarray(dut.get_array())
    assert data.shape == (50, 80)  # 5 m x 8 m at 0.1 m, rows along y
    assert dut.get_extent() == pytest.approx([bounds[0], bounds[2], bounds[1], bounds[3]])
    space = PersonalSpace.from_options(scenario.social)
    rng = np.random.default_rng(7)
    checked_nonzero = 0
    for j, i in zip(rng.integers(0, 50, 200), rng.integers(0, 80, 200)):
        x, y = 0.05 + 0.1 * i, 0.05 + 0.1 * j
        expected = sum(agf_algorithm1(x, y, (p.x, p.y, p.theta), space) for p in people)
        assert data[j, i] == pytest.approx(expected, abs=1e-12)
        checked_nonzero += expected > 0
    assert checked_nonzero > 20  # the sample really reached into the personal spaces
    assert dut.norm.vmin == 0.0 and dut.norm.vmax == pytest.approx(data.max())


def test_heat_map_has_a_colour_bar_labelled_social_cost(tiny_scenario):
    fig, ax = _axes()
    dut = draw_social_field(ax, SocialCost.from_scenario(tiny_scenario), tiny_scenario.world.bounds)
    assert dut.colorbar is not None
    assert dut.colorbar.ax.get_ylabel() == "social cost"
    fig2, ax2 = _axes()
    no_bar = draw_social_field(ax2, SocialCost.from_scenario(tiny_scenario), [0, 0, 1, 1], colorbar=False)
    assert no_bar.colorbar is None


def test_heat_map_of_an_empty_room_is_zero_with_a_unit_scale(tiny_scenario):
    fig, ax = _axes()
    dut = draw_social_field(ax, SocialCost.from_scenario(dc.replace(tiny_scenario, people=[])), [0, 0, 2, 1], 0.5)
    assert np.asarray(dut.get_array()).shape == (2, 4)
    assert np.all(np.asarray(dut.get_array()) == 0.0)
    assert dut.norm.vmax == 1.0


@pytest.mark.parametrize("theta", [0.0, math.pi / 4, -3 * math.pi / 4, math.pi])
def test_person_arrow_points_along_theta(tiny_scenario, theta):
    person = Person(x=2.0, y=2.5, theta=theta, radius=0.3, name="p")
    scenario = dc.replace(tiny_scenario, people=[person])
    fig, ax = _axes()
    dut = draw_world(ax, scenario)
    (body,) = dut["people"]
    assert body.center == pytest.approx((2.0, 2.5)) and body.radius == pytest.approx(0.3)
    (arrow,) = dut["arrows"]
    xy = arrow.get_xy()
    d = np.hypot(xy[:, 0] - 2.0, xy[:, 1] - 2.5)
    tip = xy[np.argmax(d)]
    # The tip is the farthest vertex, on the facing ray, past the body's edge.
    angle = math.atan2(tip[1] - 2.5, tip[0] - 2.0)
    assert math.remainder(angle - theta, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    assert d.max() > 0.3 + 0.4
    # The name is written behind the person (opposite the arrow).
    (label,) = dut["names"]
    lx, ly = label.get_position()
    assert (lx - 2.0) * math.cos(theta) + (ly - 2.5) * math.sin(theta) < 0


def test_draw_world_draws_every_obstacle_and_the_four_walls(tiny_scenario):
    boxes = [Box(center=[2.0, 2.0], size=[1.0, 0.5], yaw=0.3), Box(center=[6.0, 1.0], size=[0.4, 0.4])]
    scenario = dc.replace(tiny_scenario, world=dc.replace(tiny_scenario.world, obstacles=boxes))
    fig, ax = _axes()
    dut = draw_world(ax, scenario, names=False)
    assert len(dut["walls"]) == 4 and len(dut["names"]) == 0
    assert len(dut["obstacles"]) == 2
    np.testing.assert_allclose(dut["obstacles"][0].get_xy()[:4], box_corners(boxes[0]), atol=1e-12)
    # The walls enclose the bounds exactly: their union's inner edges are the bounds.
    t = scenario.world.wall_thickness
    south = dut["walls"][0]
    assert south.get_y() + south.get_height() == pytest.approx(scenario.world.bounds[1])
    assert south.get_width() == pytest.approx(8.0 + 2 * t)
    assert ax.get_aspect() == 1.0
    x_lo, x_hi = ax.get_xlim()
    assert x_lo < -t and x_hi > 8.0 + t


# ---- a turned map: its outside is drawn as such, nothing past the frame -------------------


def _rendered(fig) -> np.ndarray:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3] / 255.0


def _pixel(fig, x: float, y: float) -> tuple[int, int]:
    height = fig.canvas.get_width_height()[1]
    px, py = fig.axes[0].transData.transform((x, y))
    return int(height - py), int(px)


def test_a_turned_maps_outside_is_drawn_as_outside_and_nothing_past_the_frame(tmp_path):
    """A map turned by 30 degrees: its rectangle's corners lie at (0, 0),
    (8.66, 5), (5.66, 10.2) and (-3, 5.2); the room (its extent) is
    [-3, 0, 8.66, 10.2]. What of the room lies outside the rectangle is an
    obstacle (unknown): drawn in MAP_OUTSIDE_RGBA over the heat map, not as
    free; the boxes that close it reach metres beyond the room, and neither
    their fill nor any outline shows in the view's margin beyond the walls."""
    from drake_social.scenario import load_scenario
    from drake_social.viz import show_figure
    from drake_social.viz.world import MAP_BOX_EDGE, MAP_OUTSIDE_RGBA, VIEW_MARGIN
    from maps.test_map_scenario import write_scenario

    scenario = load_scenario(write_scenario(tmp_path, origin=(0.0, 0.0, math.pi / 6), start="1.0, 3.0",
                                            goal="3.0, 5.0"))
    x0, y0, x1, y1 = scenario.world.bounds
    np.testing.assert_allclose([x0, y0, x1, y1], [-3.0, 0.0, 5 * math.sqrt(3), 5 + 3 * math.sqrt(3)], atol=1e-9)
    dut = show_figure(scenario)
    pixels = _rendered(dut)
    zero = np.array(dut.axes[0].images[0].cmap(0.0)[:3])  # the heat map where the cost is 0 (no people)
    rgb, alpha = np.array(MAP_OUTSIDE_RGBA[:3]), MAP_OUTSIDE_RGBA[3]
    # Outside the rectangle, inside the room: the outside's colour over the heat map.
    for x, y in [(-2.5, 0.5), (8.0, 1.0), (-2.0, 9.5), (8.0, 9.5)]:
        np.testing.assert_allclose(pixels[_pixel(dut, x, y)], alpha * rgb + (1 - alpha) * zero, atol=0.02)
    # Inside the rectangle, a free cell: the heat map alone.
    np.testing.assert_allclose(pixels[_pixel(dut, 1.0, 1.5)], zero, atol=0.02)
    # The margin between the walls' outer edges and the frame: the axes' white background only.
    t = scenario.world.wall_thickness
    (r_top, c_left), (r_bottom, c_right) = _pixel(dut, x0 - t, y1 + t), _pixel(dut, x1 + t, y0 - t)
    (f_top, f_left), (f_bottom, f_right) = (_pixel(dut, x0 - t - VIEW_MARGIN, y1 + t + VIEW_MARGIN),
                                            _pixel(dut, x1 + t + VIEW_MARGIN, y0 - t - VIEW_MARGIN))
    inner = 3  # pixels kept off each edge (the walls' and the frame's antialiasing)
    bands = [pixels[f_top + inner : r_top - inner, f_left + inner : f_right - inner],
             pixels[r_bottom + inner : f_bottom - inner, f_left + inner : f_right - inner],
             pixels[f_top + inner : f_bottom - inner, f_left + inner : c_left - inner],
             pixels[f_top + inner : f_bottom - inner, c_right + inner : f_right - inner]]
    for band in bands:
        assert band.size and np.abs(band - 1.0).max() < 0.02, "something is drawn past the walls"
    # The outlines are the map's cell boxes only; the four outside boxes are the fill.
    artists = draw_world(dut.add_subplot(), scenario)["map"]
    assert len(artists) == 3 and len(artists[1].get_paths()) == 2 and len(artists[2].get_paths()) == 4
    assert MAP_BOX_EDGE


# ---- a map's cells in a figure --------------------------------------------------


def _grid(classes: np.ndarray, resolution: float = 0.1):
    from pathlib import Path

    from drake_social.maps import OccupancyMap

    classes = np.asarray(classes, np.int8)
    return OccupancyMap(path=Path("m.yaml"), image_path=Path("m.pgm"), resolution=resolution,
                        origin=(1.0, 2.0, 0.0), negate=False, occupied_thresh=0.65, free_thresh=0.196,
                        mode="trinary", values=np.where(classes == 1, 100, np.where(classes == 0, 0, -1)).astype(
                            np.int8), classes=classes)


@pytest.mark.parametrize("shape, max_cells, factor", [
    ((4, 4), 4, 1), ((5, 4), 4, 2), ((4, 5), 4, 2), ((8, 3), 4, 2), ((9, 3), 4, 3), ((5000, 5000), 2048, 3)])
def test_the_picture_factor_is_the_smallest_block_that_fits(shape, max_cells, factor):
    from drake_social.viz.world import map_picture_factor

    assert map_picture_factor(shape, max_cells) == factor


def test_a_large_map_is_drawn_in_blocks_that_keep_every_wall():
    """Blocks of f x f cells, each occupied where any cell is, else unknown where any is, else free;
    the last row and column of blocks padded with free cells. Checked block by block."""
    from drake_social.maps import FREE, OCCUPIED, UNKNOWN
    from drake_social.viz.world import MAP_OCCUPIED_RGBA, MAP_UNKNOWN_RGBA, map_rgba

    rng = np.random.default_rng(3)
    classes = rng.choice(np.array([FREE, OCCUPIED, UNKNOWN]), p=[0.88, 0.04, 0.08], size=(10, 7))
    grid = _grid(classes)
    dut = map_rgba(grid, max_cells=4)  # f = 3: 4 x 3 blocks, the last padded
    assert dut.dtype == np.uint8 and dut.shape == (4, 3, 4)
    occupied, unknown = (np.round(np.multiply(rgba, 255)) for rgba in (MAP_OCCUPIED_RGBA, MAP_UNKNOWN_RGBA))
    seen = set()
    for i in range(4):
        for j in range(3):
            cells = classes[3 * i:3 * i + 3, 3 * j:3 * j + 3]
            expected = (occupied if (cells == OCCUPIED).any() else unknown if (cells == UNKNOWN).any()
                        else np.zeros(4))
            np.testing.assert_array_equal(dut[i, j], expected)
            seen.add(tuple(expected))
    assert len(seen) == 3  # all three kinds of block occur
    # A wall one cell thick in a 5000 x 5000 map: every block it crosses is occupied, no other.
    wall = np.zeros((5000, 5000), np.int8)
    wall[:, 4001] = OCCUPIED
    big = map_rgba(_grid(wall))
    assert big.shape == (1667, 1667, 4)
    assert (big[:, 1333, 3] == 255).all() and big[:, np.r_[:1333, 1334:1667], 3].max() == 0
    np.testing.assert_array_equal(map_rgba(grid), map_rgba(grid, max_cells=10))  # small: cell for cell


def test_draw_map_places_the_blocks_and_outlines_at_most_the_stated_boxes():
    from drake_social.maps import OCCUPIED
    from drake_social.viz.world import MAP_MAX_OUTLINES, draw_map

    classes = np.zeros((5000, 4000), np.int8)
    classes[0, 0] = OCCUPIED
    grid = _grid(classes, resolution=0.05)
    square = np.array([[0.0, 0.0], [0.05, 0.0], [0.05, 0.05], [0.0, 0.05]])
    for boxes, outlined in ((MAP_MAX_OUTLINES, MAP_MAX_OUTLINES), (MAP_MAX_OUTLINES + 1, 0)):
        fig = Figure()
        image, outlines = draw_map(fig.add_subplot(), grid, np.tile(square, (boxes, 1, 1)))[:2]
        assert len(outlines.get_paths()) == outlined
        # 1667 x 1334 pixels of 3 x 3 cells: the padded blocks reach past the map by up to two cells.
        assert image.get_array().shape[:2] == (1667, 1334)
        np.testing.assert_allclose(image.get_extent(), [0.0, 1334 * 0.15, 0.0, 1667 * 0.15], rtol=1e-12)
