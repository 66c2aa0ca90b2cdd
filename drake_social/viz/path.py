"""Figures of a planned path (the paper's Fig. 5-8) and of the planner's progress.

* :func:`path_figure`: the path over the social heat map, with the robot,
  arm and object drawn at evenly spaced configurations along it (faded) and
  at the start and goal (opaque, ringed); Fig. 5/7.
* :func:`cost_profile_figure`: the social cost S(q) against the cumulative
  configuration-space distance s along one or several paths; Fig. 6/8.
* :func:`convergence_figure`: the anytime curve, best cost after each iteration.
* :func:`write_plan_figures`: the three pictures of ``drake-social plan``;
  with walking people, ``path.png`` draws their tracks over the plan's
  nominal duration (:func:`nominal_times`, :func:`planned_people`).

The numbers behind the drawings are plain functions (:func:`sample_path`,
:func:`cost_profile`, :func:`poses_along`), so tests and scripts can use them
without a figure.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import Mapping

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from drake_social.cost import SocialCost
from drake_social.kinematics import ArmGeometry, config_distance, cumulative_distance, nominal_path_times
from drake_social.people import PeopleLog, people_model
from drake_social.planning.result import PlannerResult
from drake_social.scenario import Scenario
from drake_social.viz.labels import fit_width
from drake_social.viz.robot import RobotStyle, draw_robot
from drake_social.viz.show import MAP_DPI, map_titles, scene_with_field
from drake_social.viz.tracks import draw_people_tracks, mark_times

__all__ = [
    "PATH_COLOR",
    "convergence_figure",
    "cost_profile",
    "cost_profile_figure",
    "draw_convergence",
    "draw_cost_profile",
    "draw_path",
    "draw_tree",
    "nominal_times",
    "path_figure",
    "planned_people",
    "poses_along",
    "sample_path",
    "write_plan_figures",
]

#: Samples per second of the people's tracks drawn over a plan (:func:`planned_people`).
PLAN_TRACK_RATE = 10.0

_log = logging.getLogger(__name__)

#: Colour of the base's path on the map.
PATH_COLOR = "#1f3b73"
#: Colours of successive paths on comparison plots.
_CYCLE = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b")


def _waypoints(waypoints: np.ndarray) -> np.ndarray:
    wp = np.asarray(waypoints, dtype=float)
    if wp.ndim != 2 or wp.shape[1] != 4:
        raise ValueError(f"waypoints must have shape (N, 4), got {wp.shape}")
    if not np.all(np.isfinite(wp)):
        raise ValueError("waypoints must be finite")
    return wp


def sample_path(waypoints: np.ndarray, cost: SocialCost, refine: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Dense configurations along a waypoint path and their distance from the start.

    Each segment is cut into ``refine`` times the steps that
    :meth:`SocialCost.motion_cost` uses on it (so no weighted interest point
    moves more than ``cost.resolution / refine`` metres between samples);
    segment ends are included once.

    Args:
        waypoints: (N, 4) configurations, N >= 1.
        cost: gives the step count per segment and the distance weights of ``s``.
        refine: samples per integration step of the cost (>= 1).

    Returns:
        ``s`` (M,): cumulative configuration distance from the start (with
        ``cost.distance_weights``), non-decreasing; ``q`` (M, 4) the samples.
    """
    wp = _waypoints(waypoints)
    if refine < 1:
        raise ValueError(f"refine must be >= 1, got {refine}")
    if len(wp) == 1:
        return np.zeros(1), wp.copy()
    a, b = wp[:-1], wp[1:]
    steps = refine * cost.segments(a, b)
    seg = np.repeat(np.arange(len(a)), steps)
    t = (np.arange(int(steps.sum())) - np.repeat(np.cumsum(steps) - steps, steps)) / steps[seg]
    q = np.vstack([a[seg] + t[:, None] * (b[seg] - a[seg]), wp[-1:]])
    s0 = cumulative_distance(wp, cost.distance_weights)
    length = np.diff(s0)
    s = np.append(s0[seg] + t * length[seg], s0[-1])
    return s, q


def cost_profile(waypoints: np.ndarray, cost: SocialCost, refine: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """S(q) along a path against the cumulative configuration distance (Fig. 6/8).

    Returns:
        ``s`` (M,) and ``S(q(s))`` (M,) at the samples of :func:`sample_path`.
        Their trapezoid integral approximates the path's social cost
        (``numpy.trapezoid(S, s)``).
    """
    s, q = sample_path(waypoints, cost, refine)
    return s, cost(q)


def poses_along(waypoints: np.ndarray, count: int, distance_weights=None) -> np.ndarray:
    """``count`` configurations (count, 4) evenly spaced in configuration
    distance along the path, the first at the start and the last at the goal."""
    wp = _waypoints(waypoints)
    if count < 2:
        raise ValueError(f"count must be >= 2 (start and goal), got {count}")
    s = cumulative_distance(wp, distance_weights)
    keep = np.concatenate([[True], np.diff(s) > 0])
    wp, s = wp[keep], s[keep]
    if len(wp) == 1:
        return np.repeat(wp, count, axis=0)
    targets = np.linspace(0.0, s[-1], count)
    out = np.stack([np.interp(targets, s, wp[:, i]) for i in range(4)], -1)
    out[0], out[-1] = wp[0], wp[-1]  # exactly, not up to rounding
    return out


# ---- the path on the map (Fig. 5/7) -----------------------------------------------


def draw_tree(ax: Axes, nodes: np.ndarray, parents: np.ndarray, *, color: str = "#7a7a7a",
              alpha: float = 0.5, label: str | None = "tree (base)") -> list:
    """The planner's tree as base-position edges (thin lines).

    Args:
        nodes: (n, 4) tree configurations; parents: (n,) parent index, -1 at the root.
    """
    nodes, parents = np.asarray(nodes, float).reshape(-1, 4), np.asarray(parents, int).reshape(-1)
    child = np.flatnonzero(parents >= 0)
    if child.size == 0:
        return []
    xy = np.stack([nodes[parents[child], :2], nodes[child, :2]], 1)  # (E, 2, 2)
    # One line with NaN breaks: thousands of edges as a single artist.
    xs = np.column_stack([xy[:, :, 0], np.full(len(xy), np.nan)]).ravel()
    ys = np.column_stack([xy[:, :, 1], np.full(len(xy), np.nan)]).ravel()
    (line,) = ax.plot(xs, ys, color=color, linewidth=0.4, alpha=alpha, zorder=3, label=label)
    return [line]


def draw_path(
    ax: Axes,
    geometry: ArmGeometry,
    waypoints: np.ndarray,
    *,
    poses: int | None = None,
    pose_alpha: float = 0.55,
    color: str = PATH_COLOR,
    style: RobotStyle = RobotStyle(),
    distance_weights=None,
    object_traces: bool = False,
    numbers: bool = True,
    labels: bool = True,
) -> dict[str, list]:
    """Draws a path: the base's track, the object ends' tracks and the robot along it.

    The robot is drawn opaque at the start and the goal and faded (``pose_alpha``)
    at ``poses - 2`` configurations evenly spaced in configuration distance
    between them.

    Args:
        ax: the map axes (world metres).
        geometry: the robot and its object.
        waypoints: (N, 4) configurations, start to goal.
        poses: robots drawn including start and goal (>= 2); None = about one
            per 1.8 units of configuration distance, between 4 and 16.
        pose_alpha: opacity of the intermediate robots.
        color: colour of the base's track.
        style: colours of the robot's parts.
        distance_weights: the configuration norm's per-coordinate scale.
        object_traces: also draw the tracks of the object's interest points.
        numbers: write the pose's number (1 = start) on each intermediate base.
        labels: legend labels for the tracks and the robot's parts.

    Returns:
        Artists: "base_track", "object_tracks", "robots" (one dict per pose),
        "numbers".
    """
    wp = _waypoints(waypoints)
    out: dict[str, list] = {"base_track": [], "object_tracks": [], "robots": [], "numbers": []}
    if object_traces and len(wp) > 1:
        # Object points move on curves (the arm rotates): 24 samples per segment, waypoints included.
        t = np.linspace(0.0, 1.0, 24, endpoint=False)
        fine = np.vstack([(wp[:-1, None] + t[:, None] * (wp[1:, None] - wp[:-1, None])).reshape(-1, 4), wp[-1:]])
        pts = geometry.interest_points(fine)[:, 3:]  # object points only
        for j in range(pts.shape[1]):
            (line,) = ax.plot(pts[:, j, 0], pts[:, j, 1], color=style.object, linewidth=1.0, alpha=0.9,
                              linestyle=(0, (3, 2)), zorder=3.5,
                              label="object ends' track" if labels and j == 0 else None)
            out["object_tracks"].append(line)
    # The base moves on straight lines between waypoints (motions are linear in q).
    (line,) = ax.plot(wp[:, 0], wp[:, 1], color=color, linewidth=1.8, zorder=3.6,
                      label="base track" if labels else None)
    out["base_track"].append(line)
    if poses is None:
        total = float(config_distance(wp[:-1], wp[1:], distance_weights).sum()) if len(wp) > 1 else 0.0
        poses = int(np.clip(math.ceil(total / 1.8) + 1, 4, 16))
    qs = poses_along(wp, poses, distance_weights)
    for k, q in enumerate(qs):
        end = k in (0, len(qs) - 1)
        out["robots"].append(draw_robot(ax, geometry, q, style=style, alpha=1.0 if end else pose_alpha,
                                        interest_points=end, labels=labels and k == 0,
                                        zorder=5.0 if end else 3.7))
        if numbers and not end:  # the ends are marked by their rings
            out["numbers"].append(ax.text(q[0], q[1], str(k + 1), ha="center", va="center", fontsize=7,
                                          color="white", fontweight="bold", zorder=4.95))
    return out


def path_figure(
    scenario: Scenario,
    result: PlannerResult,
    *,
    title: str | None = None,
    poses: int | None = None,
    tree: bool | None = None,
    resolution: float | None = None,
    people: PeopleLog | None = None,
    executed: tuple[np.ndarray, np.ndarray] | None = None,
    marks: int = 5,
) -> Figure:
    """The path over the social heat map with the robot drawn along it (Fig. 5/7).

    Args:
        scenario: the planned scenario.
        result: the planner's result; without a path, the map shows start,
            goal and the tree explored.
        title: the figure title; None = the scenario's description (either
            fitted to one line by :func:`~drake_social.viz.show.map_titles`).
        poses: see :func:`draw_path`.
        tree: draw the tree's base edges; None = only when there is no path.
        resolution: heat-map cell size, metres; None = picked from the
            world's size (a bounded number of cells).
        people: where the people were (a run's log): the walkers' tracks and
            start poses are drawn (:func:`~drake_social.viz.tracks.draw_people_tracks`);
            None = today's figure.
        executed: the executed run ``(times (T,) s, q (T, 4))``, with
            ``people``: its base track, and ``marks`` numbered markers at
            common times (:func:`~drake_social.viz.tracks.mark_times` over the
            run) on the robot's base and on each walker present then.
        marks: the number of common times marked (>= 2).
    """
    fig, ax, full, geometry = scene_with_field(scenario, resolution)
    if people is not None:
        times = None if executed is None else mark_times(float(np.asarray(executed[0], float)[-1]), marks)
        draw_people_tracks(ax, people, marks=times, robot=executed, names=False)  # the scene labels them
    if tree if tree is not None else not result.success:
        draw_tree(ax, result.tree_nodes, result.tree_parents)
    name = title if title is not None else scenario.description or "scenario"
    if result.success:
        draw_path(ax, geometry, result.waypoints, poses=poses, distance_weights=full.distance_weights)
        map_titles(fig, ax, name, f"{result.algorithm}: social cost {result.social_cost_full:.3g} (all points), "
                   f"base path {result.base_length:.1f} m, configuration path {result.path_length:.1f}")
    else:
        draw_robot(ax, geometry, np.asarray(scenario.start, float), labels=True)
        draw_robot(ax, geometry, np.asarray(scenario.goal, float))
        map_titles(fig, ax, name, f"{result.algorithm}: no path found; {result.tree_size} tree nodes",
                   subtitle_color="#b00000")
    fig.legend(loc="lower center", bbox_to_anchor=(0.5, 0.0), ncol=5, fontsize=8, frameon=False)
    return fig


# ---- cost along the path (Fig. 6/8) ----------------------------------------------


def draw_cost_profile(ax: Axes, waypoints: np.ndarray, cost: SocialCost, *, label: str | None = None,
                      color: str = _CYCLE[0], refine: int = 4, fill: bool = True) -> Line2D:
    """Plots S(q) against the cumulative configuration distance along a path.

    The line's data are exactly :func:`cost_profile` (``line.get_xdata()`` is
    s, ``line.get_ydata()`` is S); the legend label gets the integral.
    """
    s, values = cost_profile(waypoints, cost, refine)
    integral = float(np.trapezoid(values, s))
    text = f"{label}: " if label else ""
    (line,) = ax.plot(s, values, color=color, linewidth=1.4, label=f"{text}integral {integral:.3g}")
    if fill:
        ax.fill_between(s, values, color=color, alpha=0.12, linewidth=0)
    return line


def cost_profile_figure(scenario: Scenario, paths: Mapping[str, np.ndarray], *, title: str | None = None,
                        weights: np.ndarray | None = None, refine: int = 4) -> Figure:
    """Social cost against cumulative configuration distance, one line per path.

    Args:
        scenario: gives the people and the cost.
        paths: label -> (N, 4) waypoints; empty arrays are listed as "no path".
        title: the axes title; None = a description of the cost.
        weights: interest-point weights; None = the scenario's (all points).
        refine: samples per integration step of the cost.
    """
    cost = SocialCost.from_scenario(scenario, weights)
    fig = Figure(figsize=(8.0, 4.2))
    fig.subplots_adjust(left=0.09, right=0.98, bottom=0.13, top=0.9)
    ax = fig.add_subplot()
    missing = []
    for k, (label, wp) in enumerate(paths.items()):
        wp = np.asarray(wp, float).reshape(-1, 4)
        if len(wp) == 0:
            missing.append(label)
            continue
        draw_cost_profile(ax, wp, cost, label=label, color=_CYCLE[k % len(_CYCLE)], refine=refine)
    if missing:
        ax.text(0.5, 0.5, "no path: " + ", ".join(missing), transform=ax.transAxes, ha="center", va="center",
                color="#b00000")
    ax.set_xlabel("cumulative configuration-space distance s  (norm of q differences)")
    ax.set_ylabel("social cost S(q)")
    ax.set_ylim(bottom=0.0)
    ax.set_xlim(left=0.0)
    ax.grid(True, alpha=0.3)
    if len(paths) > len(missing):
        ax.legend(fontsize=8, loc="upper right")
    names = ", ".join(n for n, w in zip(cost.geometry.interest_names, cost.weights) if w > 0)
    ax.set_title(fit_width(title if title is not None else f"social cost along the path (points: {names})",
                           0.89 * 8.0, 9, max_lines=2), fontsize=9)
    return fig


# ---- the anytime curve ------------------------------------------------------------


def draw_convergence(ax: Axes, cost_history: np.ndarray, *, label: str | None = None,
                     color: str = _CYCLE[0]) -> Line2D | None:
    """Best cost after each iteration (1-based), as a step line; iterations
    before the first solution (infinite cost) are left out. Returns None when
    no iteration has a solution."""
    history = np.asarray(cost_history, float).reshape(-1)
    it = np.arange(1, len(history) + 1)
    found = np.isfinite(history)
    if not found.any():
        return None
    (line,) = ax.step(it[found], history[found], where="post", color=color, linewidth=1.4, label=label)
    first = int(np.argmax(found))
    ax.plot(it[first], history[first], marker="o", color=color, markersize=5, zorder=3)
    return line


def convergence_figure(histories: Mapping[str, np.ndarray], *, title: str | None = None,
                       ylabel: str = "best cost (planner's objective)") -> Figure:
    """The anytime curves of one or several runs (label -> (K,) cost history)."""
    fig = Figure(figsize=(8.0, 4.2))
    fig.subplots_adjust(left=0.09, right=0.98, bottom=0.13, top=0.9)
    ax = fig.add_subplot()
    missing, iterations = [], 1
    for k, (label, history) in enumerate(histories.items()):
        iterations = max(iterations, len(np.asarray(history).reshape(-1)))
        if draw_convergence(ax, history, label=label, color=_CYCLE[k % len(_CYCLE)]) is None:
            missing.append(label)
    if missing:
        ax.text(0.5, 0.5, "no solution: " + ", ".join(missing), transform=ax.transAxes, ha="center",
                va="center", color="#b00000")
    ax.set_xlim(0, iterations)
    ax.set_xlabel("iteration (samples drawn)")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    if len(histories) > len(missing):
        ax.legend(fontsize=8, loc="upper right")
    ax.set_title(title if title is not None else "anytime convergence (dot: first solution)", fontsize=9)
    return fig


# ---- the files of ``drake-social plan`` -------------------------------------------------


def nominal_times(scenario: Scenario, waypoints: np.ndarray) -> np.ndarray:
    """The time (N,) seconds at which each waypoint is reached when the path is
    driven at the execution limits (:func:`drake_social.kinematics.nominal_path_times`
    with the scenario's ``execution.max_base_speed`` and ``arm_max_velocity``;
    a lower bound on an executed run's time)."""
    opts = scenario.execution
    return nominal_path_times(waypoints, opts.max_base_speed, opts.arm_max_velocity)


def planned_people(scenario: Scenario, waypoints: np.ndarray, rate: float = PLAN_TRACK_RATE) -> PeopleLog | None:
    """Where the scenario's people walk while the path is driven: its people
    model (a crowd stepped without the robot) sampled ``rate`` times a second
    from 0 to the path's last :func:`nominal_times` (the start to goal
    straight line when ``waypoints`` has fewer than 2 rows); None when nobody
    moves."""
    model = people_model(scenario)
    if model.static or model.count == 0:
        return None
    wp = np.asarray(waypoints, float).reshape(-1, 4)
    if len(wp) < 2:
        wp = np.array([scenario.start, scenario.goal], float)
    duration = float(nominal_times(scenario, wp)[-1])
    times = np.linspace(0.0, duration, max(2, int(math.ceil(duration * rate)) + 1))
    return PeopleLog.sample(model, times)


def write_plan_figures(scenario: Scenario, result: PlannerResult, out_dir: str | Path, *,
                       title: str | None = None, dpi: int = MAP_DPI,
                       people: PeopleLog | None = None) -> dict[str, Path]:
    """Writes ``path.png``, ``cost_profile.png`` and ``convergence.png`` into ``out_dir``.

    Args:
        people: the walkers' tracks drawn on ``path.png`` (e.g.
            :func:`planned_people`); None = none.

    Returns:
        The written files by name ("path", "cost_profile", "convergence").
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    figures = {
        "path": path_figure(scenario, result, title=title, people=people),
        "cost_profile": cost_profile_figure(scenario, {result.algorithm: result.waypoints}),
        "convergence": convergence_figure({result.algorithm: result.cost_history}),
    }
    written = {}
    for name, fig in figures.items():
        path = out_dir / f"{name}.png"
        fig.savefig(path, dpi=dpi)
        written[name] = path
        _log.info("wrote %s", path)
    return written
