"""Meshcat recording and the standalone HTML replay (drake_social.sim.replay).

The recorded run is our own small diagram: the tiny scenario's plant and
scene graph, its geometry posed by a known first-order-hold trajectory of
q = [x, y, psi1, psi2] (TrajectorySource -> MultibodyPositionToGeometryPose),
so the replay's base positions can be checked against the trajectory in a
headless browser (tests/sim/browser.py).
"""

from __future__ import annotations

import dataclasses as dc
import io
import math
import os
from pathlib import Path

import browser
import matplotlib
import numpy as np
import pytest
from matplotlib.image import imread
from pydrake.geometry import SceneGraph
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import TrajectorySource
from pydrake.systems.rendering import MultibodyPositionToGeometryPose
from pydrake.trajectories import PiecewisePolynomial

from drake_social.cost import SocialCost
from drake_social.model.plant import add_environment, add_robot
from drake_social.scenario import load_scenario
from drake_social.sim import replay
from drake_social.viz.world import FIELD_CMAP, field_grid

# Knots of the recorded trajectory: times (s) and q = [x, y, psi1, psi2].
TIMES = [0.0, 1.5, 3.0, 4.0]
KNOTS = np.array([
    [1.0, 2.5, 0.0, 1.5708],
    [3.0, 2.8, 0.8, 1.0],
    [5.0, 2.2, -0.5, 1.8],
    [6.5, 2.5, 0.0, 1.5708],
])
SHOT_SIZE = (1280, 720)


@dc.dataclass
class Recorded:
    html: Path
    size: int
    trajectory: PiecewisePolynomial
    fps: float
    scenario: object


def record(scenario, trajectory: PiecewisePolynomial, html: Path, waypoints: np.ndarray | None, *,
           people=None, before_overlays=None) -> int:
    """Records ``trajectory`` posing the scenario's robot; returns the page size.

    With ``people`` (a PeopleLog) the overlays are drawn after the recording,
    as ``simulate`` draws them, with the walkers animated;
    ``before_overlays(meshcat)`` runs after the recording, before them.
    """
    builder = DiagramBuilder()
    scene_graph = builder.AddSystem(SceneGraph())
    plant = MultibodyPlant(0.0)  # not in the diagram: only its geometry is posed
    plant.RegisterAsSourceForSceneGraph(scene_graph)
    add_robot(plant, scenario)
    add_environment(plant, scenario)
    plant.Finalize()
    source = builder.AddSystem(TrajectorySource(trajectory))
    to_pose = builder.AddSystem(MultibodyPositionToGeometryPose(plant))
    builder.Connect(source.get_output_port(), to_pose.get_input_port())
    builder.Connect(to_pose.get_output_port(), scene_graph.get_source_pose_port(plant.get_source_id()))
    meshcat = replay.make_meshcat()
    fps = scenario.execution.replay_fps
    replay.add_visualizer(builder, scene_graph, meshcat, fps=fps)
    simulator = Simulator(builder.Build())
    if people is None:
        replay.draw_overlays(meshcat, scenario, waypoints)
    fit = replay.set_top_view(meshcat, scenario)
    replay.start_recording(meshcat, fps)
    simulator.Initialize()
    simulator.AdvanceTo(trajectory.end_time())
    replay.finish_recording(meshcat)
    if before_overlays is not None:
        before_overlays(meshcat)
    if people is not None:
        replay.draw_overlays(meshcat, scenario, waypoints, people=people)
    return replay.write_replay_html(meshcat, html, fit=fit)


@pytest.fixture(scope="module")
def tiny_replay(tmp_path_factory, tiny_scenario_path) -> Recorded:
    scenario = load_scenario(tiny_scenario_path)
    trajectory = PiecewisePolynomial.FirstOrderHold(TIMES, KNOTS.T)
    html = tmp_path_factory.mktemp("replay") / "replay.html"
    size = record(scenario, trajectory, html, KNOTS)
    return Recorded(html, size, trajectory, scenario.execution.replay_fps, scenario)


# --- the page -----------------------------------------------------------------


def test_page_is_standalone(tiny_replay):
    text = tiny_replay.html.read_text(encoding="utf-8")
    assert tiny_replay.size == tiny_replay.html.stat().st_size
    assert browser.remote_loads(text) == []
    assert "<script src" not in text.lower()
    assert not [n for n in os.listdir(tiny_replay.html.parent) if n.endswith(".tmp")]
    # 4 s of recording on top of meshcat.js (~2.2 MB): a small share.
    assert 2.0e6 < tiny_replay.size < 3.0e6


def test_remote_loads_finds_remote_resources():
    page = """<script src="https://cdn.example.org/three.js"></script>
              <link rel="stylesheet" href="//fonts.example.org/a.css">
              <img src='http://example.org/a.png'> <script>fetch("https://example.org/x.bin")</script>
              <script>fetch("data:application/octet-binary;base64,AAAA")</script>
              <script>this.path="https://cdn.example.org/profiles"</script>"""
    assert browser.remote_loads(page) == [
        "//fonts.example.org/a.css",
        "http://example.org/a.png",
        "https://cdn.example.org/three.js",
        "https://example.org/x.bin",
    ]


def test_write_replay_html_replaces_atomically(tmp_path):
    dut = tmp_path / "sub" / "replay.html"
    dut.parent.mkdir()
    dut.write_text("old")
    meshcat = replay.make_meshcat()
    size = replay.write_replay_html(meshcat, dut)
    assert size == dut.stat().st_size > 1e6
    assert dut.read_text(encoding="utf-8").lstrip().lower().startswith("<!doctype html")
    assert sorted(os.listdir(dut.parent)) == ["replay.html"]


# --- overlays -----------------------------------------------------------------


def test_field_texture_uses_the_figure_colour_map(tiny_scenario_path):
    scenario = load_scenario(tiny_scenario_path)
    png = replay._field_png(scenario)
    image = imread(io.BytesIO(png))  # (ny, nx, 4), row 0 = north
    xs, ys = field_grid(scenario.world.bounds, replay.field_resolution(scenario.world.bounds))
    values = SocialCost.from_scenario(scenario).field(xs[None, :], ys[:, None])
    expected = matplotlib.colormaps[FIELD_CMAP](values / values.max())[::-1, :, :3]
    assert image.shape[:2] == (len(ys), len(xs)) == (100, 160)
    np.testing.assert_allclose(image[:, :, :3], expected, atol=1.5 / 255)
    assert len(png) < 50e3


def test_field_resolution_bounds_the_cell_count():
    assert replay.field_resolution([0, 0, 20, 12]) == pytest.approx(0.05)
    dut = replay.field_resolution([0, 0, 1000, 400])
    xs, ys = field_grid([0, 0, 1000, 400], dut)
    assert (len(xs), len(ys)) == (replay.FIELD_MAX_CELLS, 205)


def test_ribbon_keeps_its_width_and_mitres_corners():
    points = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 0.0], [2.0, 3.0]])  # a repeated point, a right angle
    vertices, faces = replay.ribbon_mesh(points, 0.2, 0.05)
    assert vertices.shape == (3, 6) and faces.shape == (3, 4) and faces.dtype == np.int32
    np.testing.assert_allclose(vertices[2], 0.05)
    left, right = vertices[:2, 0::2].T, vertices[:2, 1::2].T
    np.testing.assert_allclose(left[0], [0.0, 0.1], atol=1e-12)
    np.testing.assert_allclose(right[0], [0.0, -0.1], atol=1e-12)
    np.testing.assert_allclose(left[1], [1.9, 0.1], atol=1e-12)  # the inner mitre corner
    np.testing.assert_allclose(right[1], [2.1, -0.1], atol=1e-12)
    np.testing.assert_allclose(left[2], [1.9, 3.0], atol=1e-12)
    # Every triangle has positive area (no folded strip).
    a, b, c = (vertices[:2, faces[k]].T for k in range(3))
    cross = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]
    assert np.all(np.abs(cross) > 1e-3)


def test_ribbon_caps_a_hairpin_mitre():
    vertices, _ = replay.ribbon_mesh(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 0.01]]), 0.2, 0.0)
    corner = np.linalg.norm(vertices[:2, 2] - [1.0, 0.0])
    assert corner <= 3 * 0.1 + 1e-12


def test_ribbon_needs_two_distinct_points():
    with pytest.raises(ValueError, match="2 distinct points"):
        replay.ribbon_mesh(np.array([[1.0, 1.0], [1.0, 1.0]]), 0.1, 0.0)


def test_arguments_are_checked(tiny_scenario_path):
    scenario = load_scenario(tiny_scenario_path)
    meshcat = replay.make_meshcat()
    with pytest.raises(ValueError, match="absolute Meshcat path"):
        replay.draw_overlays(meshcat, scenario, prefix="drake_social")
    with pytest.raises(ValueError, match="aspect"):
        replay.set_top_view(meshcat, scenario, aspect=0.0)
    with pytest.raises(ValueError, match="fps"):
        replay.start_recording(meshcat, 0.0)
    replay.draw_overlays(meshcat, scenario, KNOTS[:1])  # one waypoint: no path, no error
    assert meshcat.HasPath("/drake_social/field") and not meshcat.HasPath("/drake_social/path")
    assert meshcat.HasPath("/drake_social/people/0")


# --- in the browser -----------------------------------------------------------


def test_replay_follows_the_trajectory(tiny_replay):
    browser.require_chromium()
    times = [0.5, 2.0, 3.7]
    result = browser.probe(tiny_replay.html, times)
    assert result["duration"] == pytest.approx(TIMES[-1], abs=1.0 / tiny_replay.fps)
    assert sorted(result["overlays"]) == ["field", "path", "people"]
    speed = np.max(np.linalg.norm(np.diff(KNOTS[:, :2], axis=0), axis=1) / np.diff(TIMES))
    # A few mm (float32 in the page) plus one frame of motion: Drake's
    # recording can file a publish time into the neighbouring frame.
    tolerance = 0.003 + speed / tiny_replay.fps
    positions = {t: np.array(xyz) for t, *xyz in result["positions"]}
    assert sorted(positions) == times
    for t in times:
        expected = np.r_[tiny_replay.trajectory.value(t).ravel()[:2], 0.0]
        np.testing.assert_allclose(positions[t], expected, atol=tolerance, err_msg=f"t = {t} s")


def test_seek_positions_returns_xyz_by_time(tiny_replay):
    browser.require_chromium()
    dut = browser.seek_positions(tiny_replay.html, [0.0, TIMES[-1]])
    np.testing.assert_allclose(dut[0.0], [*KNOTS[0, :2], 0.0], atol=0.003)
    np.testing.assert_allclose(dut[TIMES[-1]], [*KNOTS[-1, :2], 0.0], atol=0.003)


def _to_pixel(scenario, x: float, y: float, size: tuple[int, int] = SHOT_SIZE) -> tuple[int, int]:
    """The screenshot pixel (column, row) of a world point in a window of
    ``size`` where the page fits the walls and margin, centred."""
    cx, cy, half_w, half_h = replay.top_view_frame(scenario, aspect=size[0] / size[1])
    metres_per_pixel = 2 * half_h / size[1]
    assert 2 * half_w / size[0] == pytest.approx(metres_per_pixel)
    return int(round(size[0] / 2 + (x - cx) / metres_per_pixel)), int(round(size[1] / 2 - (y - cy) / metres_per_pixel))


def test_top_view_frame_holds_the_walls_and_a_margin():
    scenario = load_scenario(Path(__file__).parents[2] / "scenarios" / "office_bar.yaml")
    cx, cy, half_w, half_h = replay.top_view_frame(scenario, aspect=16 / 9)
    # 20 x 12 m, walls 0.1 m, margin 3 % of 20 m: the height decides.
    assert (cx, cy) == (10.0, 6.0)
    assert half_h == pytest.approx((12 + 2 * 0.1 + 2 * 0.6) / 2)
    assert half_w == pytest.approx(half_h * 16 / 9)
    scenario.world.bounds = [0.0, 0.0, 1000.0, 10.0]  # a corridor: the width decides
    cx, cy, half_w, half_h = replay.top_view_frame(scenario, aspect=2.0, margin=1.0)
    assert half_w == pytest.approx(1000 / 2 + 1.1) and half_h == pytest.approx(half_w / 2)
    # Without an aspect: the walls and the margin alone, as set_top_view returns them.
    assert replay.top_view_frame(scenario, aspect=None, margin=1.0) == pytest.approx((500.0, 5.0, 501.1, 6.1))


def test_first_view_is_a_top_down_map(tiny_replay, tmp_path):
    browser.require_chromium()
    s = tiny_replay.scenario
    png = browser.screenshot(tiny_replay.html, tmp_path / "first_view.png", SHOT_SIZE)
    image = np.round(imread(png)[:, :, :3] * 255).astype(int)
    assert image.shape == (SHOT_SIZE[1], SHOT_SIZE[0], 3)
    colours = np.unique(image.reshape(-1, 3), axis=0)
    assert len(colours) > 200, f"only {len(colours)} colours: a blank page?"

    def at(x, y):
        col, row = _to_pixel(s, x, y)
        return image[row, col]

    x0, y0, x1, y1 = s.world.bounds
    t = s.world.wall_thickness
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    # The whole map: the four walls are drawn where the camera puts them, in
    # one grey, and outside them is the white background.
    walls = [at(cx, y0 - t / 2), at(cx, y1 + t / 2), at(x0 - t / 2, cy), at(x1 + t / 2, cy)]
    for wall in walls:
        assert np.ptp(wall) <= 6 and 100 < wall.mean() < 230, f"not wall grey: {wall}"
        np.testing.assert_allclose(wall, walls[0], atol=6)
    for outside in (at(cx, y0 - t - 0.2), at(cx, y1 + t + 0.2), at(x0 - t - 0.2, cy), at(x1 + t + 0.2, cy)):
        assert np.all(outside >= 250), f"not background: {outside}"
    # The heat map: red in front of the person, the colour map's white far from them.
    p = s.people[0]
    front = at(p.x + 1.0 * math.cos(p.theta), p.y + 1.0 * math.sin(p.theta))
    assert front[0] > front[1] + 80, f"no heat in front of the person: {front}"
    np.testing.assert_allclose(at(x0 + 0.3, y1 - 0.3), np.round(np.array(matplotlib.colormaps[FIELD_CMAP](0.0)[:3]) * 255),
                               atol=3)
    # The person's arrow (black) just beyond the body, the path ribbon (blue)
    # between the knots and the robot's base (dark blue) at the start.
    tip = at(p.x + (p.radius + 0.2) * math.cos(p.theta), p.y + (p.radius + 0.2) * math.sin(p.theta))
    assert np.all(tip < 60), f"no facing arrow: {tip}"
    mid = (KNOTS[1, :2] + KNOTS[2, :2]) / 2
    ribbon = at(*mid)
    assert ribbon[2] > ribbon[0] + 80, f"no path ribbon: {ribbon}"
    base = at(*KNOTS[0, :2] + [0.0, -0.2])
    assert base[2] > base[0] + 40 and base.mean() < 100, f"no robot base: {base}"


@pytest.mark.parametrize("size", [(480, 480), (1200, 400)], ids=["square", "wide"])
def test_the_whole_room_stays_in_view_at_any_window_size(tiny_replay, tmp_path, size):
    """Meshcat alone keeps the frame's height and west edge (a square window
    would crop the east wall); the page's fit script frames walls and margin
    centred instead: all four walls where the fit puts them, background
    beyond them, in a square and in a wide window."""
    browser.require_chromium()
    s = tiny_replay.scenario
    png = browser.screenshot(tiny_replay.html, tmp_path / f"view_{size[0]}x{size[1]}.png", size)
    image = np.round(imread(png)[:, :, :3] * 255).astype(int)
    assert image.shape == (size[1], size[0], 3)
    x0, y0, x1, y1 = s.world.bounds
    t = s.world.wall_thickness
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2

    def at(x, y):
        col, row = _to_pixel(s, x, y, size)
        return image[row, col]

    walls = [at(cx, y0 - t / 2), at(cx, y1 + t / 2), at(x0 - t / 2, cy), at(x1 + t / 2, cy)]
    for wall in walls:
        assert np.ptp(wall) <= 6 and 100 < wall.mean() < 230, f"not wall grey: {wall}"
    for outside in (at(cx, y0 - t - 0.2), at(cx, y1 + t + 0.2), at(x0 - t - 0.2, cy), at(x1 + t + 0.2, cy)):
        assert np.all(outside >= 250), f"not background: {outside}"
    # The walls and margin fill the window's narrower direction: the room is centred.
    _, _, half_w, half_h = replay.top_view_frame(s, aspect=None)
    col_w, _ = _to_pixel(s, cx - half_w, cy, size)
    _, row_n = _to_pixel(s, cx, cy + half_h, size)
    assert min(col_w, row_n) in (0, 1) and abs(col_w - (size[0] - _to_pixel(s, cx + half_w, cy, size)[0])) <= 1


def test_write_replay_html_fit_script(tmp_path):
    meshcat = replay.make_meshcat()
    plain = replay.write_replay_html(meshcat, tmp_path / "plain.html")
    fitted = replay.write_replay_html(meshcat, tmp_path / "fitted.html", fit=(12.5, 7.25))
    text = (tmp_path / "fitted.html").read_text(encoding="utf-8")
    assert fitted > plain and text.count("const FIT = [12.5, 7.25];") == 1
    assert text.rstrip().endswith("</html>") and text.index("const FIT") < text.rindex("</body>")
    assert "const FIT" not in (tmp_path / "plain.html").read_text(encoding="utf-8")
    for bad in ((0.0, 1.0), (1.0, -2.0), (float("nan"), 1.0), (1.0, float("inf"))):
        with pytest.raises(ValueError, match="fit must be two finite half extents > 0"):
            replay.write_replay_html(meshcat, tmp_path / "bad.html", fit=bad)
    assert not (tmp_path / "bad.html").exists()


def test_a_page_without_a_body_end_gets_the_fit_script_at_its_end(tmp_path, caplog):
    class Page:  # what write_replay_html uses of a Meshcat
        @staticmethod
        def StaticHtml():
            return "<html><script>var viewer;</script></html>"

    with caplog.at_level("WARNING", logger="drake_social.sim.replay"):
        replay.write_replay_html(Page(), tmp_path / "page.html", fit=(3.0, 2.0))
    text = (tmp_path / "page.html").read_text(encoding="utf-8")
    assert text.startswith(Page.StaticHtml()) and text.rstrip().endswith("</script>")
    assert "const FIT = [3.0, 2.0];" in text and "has no </body>" in caplog.text


def test_office_replay_of_a_minute_stays_under_5_mb(tmp_path):
    scenario = load_scenario(Path(__file__).parents[2] / "scenarios" / "office_bar.yaml")
    assert scenario.execution.replay_fps == 30.0
    xy = np.array([[1.5, 4.8], [6.0, 4.8], [9.0, 5.6], [12.0, 5.2], [16.0, 4.8], [18.5, 4.8]])
    q = np.c_[xy, np.full(len(xy), scenario.start[2]), np.full(len(xy), scenario.start[3])]
    q[:, 2] += 0.3 * np.sin(np.arange(len(xy)))  # the arm moves too
    times = np.linspace(0.0, 60.0, len(xy))
    size = record(scenario, PiecewisePolynomial.FirstOrderHold(times, q.T), tmp_path / "replay.html", q)
    # meshcat.js ~2.2 MB + the office's geometry and heat map + ~16 kB per second.
    assert size < 5e6
