"""drake_social.viz.show: the scene picture and its PNG."""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from drake_social.cost import PersonalSpace, SocialCost, agf_algorithm1
from drake_social.viz import show_figure, write_show


def pixel_of(fig, x: float, y: float) -> tuple[int, int]:
    """(row, column) of the world point (x, y) in the figure rendered at its dpi."""
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    _, height = canvas.get_width_height()
    px, py = fig.axes[0].transData.transform((x, y))
    return int(height - py), int(px)


def test_show_figure_has_the_scene_elements(tiny_scenario):
    dut = show_figure(tiny_scenario)
    ax = dut.axes[0]
    assert dut.get_suptitle() == tiny_scenario.description
    assert ax.get_aspect() == 1.0
    assert len(ax.images) == 1 and ax.images[0].colorbar.ax.get_ylabel() == "social cost"
    labels = {t.get_text() for t in dut.legends[0].get_texts()}
    assert {"start", "goal", "robot base", "link 1", "link 2", "object", "person (arrow: facing)"} <= labels
    # The robot is drawn at the start and at the goal: two base discs there.
    centres = sorted(p.center for p in ax.patches if getattr(p, "radius", None) == tiny_scenario.robot.base_radius)
    assert centres == sorted([tuple(tiny_scenario.start[:2]), tuple(tiny_scenario.goal[:2])])
    # The subtitle reports S at start and goal (0.43 and 0 here: a swap would show).
    cost = SocialCost.from_scenario(tiny_scenario)
    s_start, s_goal = cost(np.array(tiny_scenario.start)), cost(np.array(tiny_scenario.goal))
    assert s_start > 0.1 and s_goal == 0.0
    assert f"S(start) = {s_start:.2f}, S(goal) = {s_goal:.2f}" in ax.get_title()
    assert show_figure(tiny_scenario, title="custom").get_suptitle() == "custom"


@pytest.mark.slow
def test_png_colours_follow_the_social_field(tiny_scenario, tmp_path):
    """Pixels of the written PNG over free floor show the colour of G(x, y),
    computed with the paper's Algorithm 1 at the heat-map cell centre: dark
    red in front of the person, the zero colour far away."""
    path = write_show(tiny_scenario, tmp_path, dpi=100)
    assert path == tmp_path / "scene.png"
    png = matplotlib.image.imread(path)
    fig = show_figure(tiny_scenario)
    fig.set_dpi(100)
    image = fig.axes[0].images[0]
    space = PersonalSpace.from_options(tiny_scenario.social)
    person = tiny_scenario.people[0]
    colours = {}
    # Cell centres of the 0.05 m heat map, clear of the robot, desk and labels.
    for x, y in [(4.025, 2.525), (3.025, 3.025), (5.175, 4.375), (6.525, 1.525), (0.525, 0.525)]:
        row, col = pixel_of(fig, x, y)
        value = agf_algorithm1(x, y, (person.x, person.y, person.theta), space)
        expected = np.array(image.cmap(image.norm(value))[:3])
        np.testing.assert_allclose(png[row, col, :3], expected, atol=3 / 255, err_msg=f"at ({x}, {y})")
        colours[(x, y)] = png[row, col, :3]
    near, far = colours[(4.025, 2.525)], colours[(6.525, 1.525)]
    assert np.abs(near - far).max() > 0.3


@pytest.mark.slow
def test_png_follows_the_scenario_not_a_fixed_picture(tiny_scenario, tmp_path):
    """A quarter of sigma_h (reach 0.9 m) empties the floor 1.3 m in front of the person."""
    point = (4.025, 2.525)
    small = dc.replace(tiny_scenario, social=dc.replace(tiny_scenario.social, sigma_h=0.5))
    pngs = [
        matplotlib.image.imread(write_show(s, tmp_path / str(i), dpi=100))
        for i, s in enumerate([tiny_scenario, small])
    ]
    fig = show_figure(small)
    fig.set_dpi(100)
    row, col = pixel_of(fig, *point)
    zero_colour = np.array(fig.axes[0].images[0].cmap(0.0)[:3])
    np.testing.assert_allclose(pngs[1][row, col, :3], zero_colour, atol=3 / 255)
    assert np.abs(pngs[0][row, col, :3] - zero_colour).max() > 0.3


def test_write_show_creates_the_directory_and_names_the_file(tiny_scenario, tmp_path):
    dut = write_show(tiny_scenario, tmp_path / "a" / "b", name="x.png", dpi=50)
    assert dut == tmp_path / "a" / "b" / "x.png"
    assert dut.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    h, w = matplotlib.image.imread(dut).shape[:2]
    fig = show_figure(tiny_scenario)
    assert (w, h) == pytest.approx(tuple(50 * fig.get_size_inches()), abs=1)


@pytest.mark.slow
def test_readme_drawing_snippet_runs(tmp_path, monkeypatch):
    """The composition example of docs/architecture.md runs as printed and writes its PNG."""
    readme = (Path(__file__).resolve().parents[2] / "docs" / "architecture.md").read_text()
    start = readme.index("```python\n", readme.index("The drawing functions compose")) + len("```python\n")
    code = readme[start : readme.index("```", start)]
    monkeypatch.chdir(Path(__file__).resolve().parents[2])
    code = code.replace('fig.savefig("generic.png"', f'fig.savefig(r"{tmp_path / "generic.png"}"')
    namespace: dict = {}
    exec(compile(code, "README.md", "exec"), namespace)
    assert (tmp_path / "generic.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    ax = namespace["ax"]
    assert len(ax.images) == 1 and len(ax.patches) > 10


# ---- the heat map scales with the world (issue 9, part 1) ---------------------------


@pytest.mark.parametrize("side", [1000.0, 1e6])
def test_figures_of_a_huge_world_have_a_bounded_number_of_cells(tiny_scenario, monkeypatch, side):
    """``show`` and ``plan`` figures of a 1000 m and a 10^6 m world evaluate
    the heat map on at most FIELD_MAX_CELLS cells a side (on the old 0.05 m
    grid: 4e8 and 4e14 cells, killed for memory)."""
    from drake_social.planning.result import PlannerResult
    from drake_social.viz.path import path_figure
    from drake_social.viz.world import FIELD_MAX_CELLS

    seen = []
    field = SocialCost.field

    def counted(self, x, y):
        cells = np.broadcast_shapes(np.shape(x), np.shape(y))
        seen.append(cells)
        assert int(np.prod(cells)) <= FIELD_MAX_CELLS**2, f"{cells} heat-map cells for a {side} m world"
        return field(self, x, y)

    monkeypatch.setattr(SocialCost, "field", counted)
    world = dc.replace(tiny_scenario.world, bounds=[0.0, 0.0, side, side / 3])
    scenario = dc.replace(tiny_scenario, world=world)
    dut = show_figure(scenario)
    assert np.asarray(dut.axes[0].images[0].get_array()).shape == (171, 512) == seen[-1]
    no_path = PlannerResult(algorithm="rrt_star", success=False, message="no path", waypoints=np.zeros((0, 4)),
                            cost=float("inf"), tree_nodes=np.array([scenario.start]), tree_parents=np.array([-1]))
    path = path_figure(scenario, no_path)
    assert np.asarray(path.axes[0].images[0].get_array()).shape == (171, 512)
    # A small room keeps the fine 0.05 m cells.
    assert np.asarray(show_figure(tiny_scenario).axes[0].images[0].get_array()).shape == (100, 160)


_TALL = """description: "{description}"
world:
  bounds: [0.0, 0.0, {w}, {h}]
people:
  - {{x: 1.5, y: 1.0, theta: 3.14, radius: 0.25, name: "standing"}}
robot: {{base_radius: 0.35, link_lengths: [0.6, 0.5], link_width: 0.08}}
object: !Bar {{length: 1.0, thickness: 0.05}}
start: [1.5, 3.0, 1.5708, 0.0]
goal: [1.5, 5.0, 1.5708, 0.0]
"""


@pytest.mark.parametrize("w, h", [(3.0, 20.0), (3.0, 60.0), (8.0, 5.0)])
def test_map_titles_and_legend_fit_a_tall_room(tmp_path, w, h):
    from drake_social.scenario import load_scenario
    from drake_social.viz.show import MIN_FIGURE_WIDTH

    description = "tall: a corridor-like room with one person standing near the middle and " + "W" * 47
    assert len(description) == 119
    (tmp_path / "tall.yaml").write_text(_TALL.format(description=description, w=w, h=h))
    fig = show_figure(load_scenario(tmp_path / "tall.yaml"))
    assert fig.get_figwidth() >= MIN_FIGURE_WIDTH
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    boxes = [(fig.get_suptitle(), fig._suptitle.get_window_extent(renderer)),
             (ax.get_title(), ax.title.get_window_extent(renderer))]
    boxes += [(f"legend ({len(legend.get_texts())} entries)", legend.get_window_extent(renderer))
              for legend in fig.legends]
    assert len(boxes) == 3
    for text, box in boxes:
        assert fig.bbox.x0 - 0.5 <= box.x0 and box.x1 <= fig.bbox.x1 + 0.5, f"{text!r} is clipped: {box}"
        assert fig.bbox.y0 - 0.5 <= box.y0 and box.y1 <= fig.bbox.y1 + 0.5, f"{text!r} is clipped: {box}"
    assert fig.get_suptitle().endswith("\u2026") and fig.get_suptitle()[:-1] in description
    # The map stays centred and the title clear of it.
    assert boxes[0][1].y0 >= boxes[1][1].y1 - 0.5 and boxes[1][1].y0 >= ax.get_window_extent().y1 - 0.5
