"""The scene picture: the map, its people and their social cost, and the
robot carrying its object at start and goal (``drake-social show``)."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Circle

from drake_social.cost import SocialCost
from drake_social.kinematics import ArmGeometry
from drake_social.scenario.geometry import arm_geometry
from drake_social.people import PeopleLog, people_model
from drake_social.scenario import Scenario
from drake_social.viz.labels import fit_width
from drake_social.viz.robot import draw_robot
from drake_social.viz.tracks import draw_people_tracks
from drake_social.viz.world import VIEW_MARGIN, draw_social_field, draw_world

__all__ = ["MAP_DPI", "START_COLOR", "GOAL_COLOR", "draw_start_goal", "scene_figure", "show_figure", "write_show"]

_log = logging.getLogger(__name__)

#: Ring around the base at the start (the paper: a yellow circle).
START_COLOR = "#e6c200"
#: Ring around the base at the goal (the paper: a green circle).
GOAL_COLOR = "#2ca02c"
#: Resolution of the written pictures, dots per inch: an 11-inch map is 1320
#: pixels wide, its 7-point labels 12 pixels tall.
MAP_DPI = 120
#: Narrowest map figure, inches: a tall room's map is centred in it, so that
#: the titles (one line each) and the two-row legend below have room.
MIN_FIGURE_WIDTH = 8.5
#: Room of the figure and axes titles, inches less than the figure's width
#: (the map axes are centred 0.2 inches left of the figure's centre).
_TITLE_MARGIN = 0.7


def scene_figure(scenario: Scenario, *, width: float = 11.0, max_map_height: float = 8.5) -> tuple[Figure, Axes]:
    """An empty figure with one map axes of the map's aspect ratio.

    The layout is fixed (no layout engine, so every rendering is identical):
    margins in inches leave room for the axis labels, the titles, a colour
    bar drawn by :func:`~drake_social.viz.world.draw_social_field` on the
    right, and a legend of two rows at the bottom. A figure is at least
    :data:`MIN_FIGURE_WIDTH` wide (a tall map is centred in it).

    Args:
        scenario: gives the map bounds and wall thickness.
        width: figure width, inches (reduced for tall maps).
        max_map_height: largest height of the map axes, inches.
    """
    x0, y0, x1, y1 = scenario.world.bounds
    pad = scenario.world.wall_thickness + VIEW_MARGIN
    view_w, view_h = x1 - x0 + 2 * pad, y1 - y0 + 2 * pad
    left, right, bottom, top = 0.75, 1.15, 1.0, 0.62  # inches
    map_w = min(width - left - right, max_map_height * view_w / view_h)
    map_h = map_w * view_h / view_w
    fig_w, fig_h = max(MIN_FIGURE_WIDTH, left + map_w + right), bottom + map_h + top
    left += (fig_w - (left + map_w + right)) / 2
    fig = Figure(figsize=(fig_w, fig_h))
    ax = fig.add_axes((left / fig_w, bottom / fig_h, map_w / fig_w, map_h / fig_h))
    return fig, ax


def draw_start_goal(ax: Axes, scenario: Scenario, *, labels: bool = True) -> list:
    """Rings around the base at the start and the goal configurations."""
    ring = scenario.robot.base_radius + 0.2
    artists = []
    for q, color, text in ((scenario.start, START_COLOR, "start"), (scenario.goal, GOAL_COLOR, "goal")):
        patch = Circle((q[0], q[1]), ring, facecolor="none", edgecolor=color, linewidth=2.5, zorder=4.5,
                       label=text if labels else None)
        artists.append(ax.add_patch(patch))
    return artists


def map_titles(fig: Figure, ax: Axes, title: str, subtitle: str, *, subtitle_color: str | None = None) -> None:
    """The figure's title (12 pt) and the map's title (9 pt), each fitted to
    one line of the figure's width by :func:`~drake_social.viz.labels.fit_width`."""
    room = fig.get_figwidth() - _TITLE_MARGIN
    fig.suptitle(fit_width(title, room, 12, max_lines=1), fontsize=12)
    ax.set_title(fit_width(subtitle, room, 9, max_lines=1), fontsize=9,
                 **({"color": subtitle_color} if subtitle_color else {}))


def scene_with_field(scenario: Scenario, resolution: float | None = None) -> tuple[Figure, Axes, SocialCost, ArmGeometry]:
    """The scene figure with the social heat map, the room, the people and the
    start and goal rings drawn; returns the cost and geometry it used too.

    ``resolution`` is the heat-map cell size, metres; None = picked from the
    world's size (:func:`~drake_social.viz.world.field_resolution`)."""
    fig, ax = scene_figure(scenario)
    cost = SocialCost.from_scenario(scenario)
    draw_social_field(ax, cost, scenario.world.bounds, resolution)
    draw_world(ax, scenario)
    draw_start_goal(ax, scenario)
    return fig, ax, cost, arm_geometry(scenario)


def show_figure(scenario: Scenario, *, title: str | None = None, resolution: float | None = None,
                people: PeopleLog | None = None) -> Figure:
    """The scene picture of a scenario.

    The social-cost heat map ``G(x, y)`` with its colour bar, walls and
    obstacles, people with their facing arrows, and the robot with arm and
    object at the start and the goal configurations.

    Args:
        scenario: a validated scenario.
        title: the figure title; None = the scenario's description (either
            fitted to one line by :func:`map_titles`).
        resolution: heat-map cell size, metres; None = picked from the
            world's size (a bounded number of cells).
        people: where the people walk (e.g. ``PeopleLog.sample`` of the
            scenario's model): their tracks and start poses are drawn
            (:func:`~drake_social.viz.tracks.draw_people_tracks`); None =
            today's picture.

    Returns:
        A matplotlib figure (not attached to pyplot; save it with ``savefig``).
    """
    fig, ax, cost, geometry = scene_with_field(scenario, resolution)
    if people is not None:
        draw_people_tracks(ax, people, names=False)  # the scene labels them
    draw_robot(ax, geometry, np.asarray(scenario.start, float), labels=True)
    draw_robot(ax, geometry, np.asarray(scenario.goal, float))
    s_start, s_goal = cost(np.array([scenario.start, scenario.goal], float))
    n = people_model(scenario).count
    people = "1 person" if n == 1 else f"{n} people"
    map_titles(fig, ax, title if title is not None else scenario.description or "scenario",
               f"{people}; social cost S(start) = {s_start:.2f}, S(goal) = {s_goal:.2f}")
    fig.legend(loc="lower center", bbox_to_anchor=(0.5, 0.0), ncol=5, fontsize=8, frameon=False)
    return fig


def write_show(scenario: Scenario, out_dir: str | Path, *, name: str = "scene.png", title: str | None = None,
               dpi: int = MAP_DPI) -> Path:
    """Writes :func:`show_figure` as a PNG into ``out_dir`` (created if needed).

    Returns:
        The path of the written picture.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / name
    show_figure(scenario, title=title).savefig(path, dpi=dpi)
    _log.info("wrote %s", path)
    return path
