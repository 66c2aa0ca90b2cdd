"""People's tracks on the map: who walked where, and who was where when.

:func:`draw_people_tracks` draws, from a :class:`~drake_social.people.PeopleLog`,
a thin line per walking person (broken where they are absent), a ring of their
body at the first pose they were present in, with a tick along their heading,
and, at a few common times (:func:`mark_times`), numbered markers on each
present walker and on the robot's base: marker k of a person and of the robot
are the same instant. People who stand all along are left to
:func:`~drake_social.viz.world.draw_world`.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.lines import Line2D
from matplotlib.patches import Circle

from drake_social.people import PeopleLog

__all__ = ["TRACK_COLORS", "draw_people_tracks", "mark_times", "moving_people"]

#: Colours of successive walkers' tracks (cycled), none of them the heat map's red.
TRACK_COLORS = ("#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf", "#8c564b", "#e377c2", "#7f7f7f",
                "#bcbd22", "#393b79")
#: Colour of the robot's executed base track and its time marks.
ROBOT_MARK_COLOR = "#1f3b73"


def moving_people(people: PeopleLog) -> np.ndarray:
    """(P,) True for each person who moves, turns, appears or leaves, or has
    a non-zero velocity in some sample of ``people``."""
    positions, headings, present = people.positions, people.headings, people.present
    return ((positions != positions[:1]).any(axis=(0, 2)) | (headings != headings[:1]).any(axis=0)
            | (present != present[:1]).any(axis=0) | (people.velocities != 0).any(axis=(0, 2)))


def mark_times(duration: float, count: int = 5) -> np.ndarray:
    """``count`` (>= 2) common times evenly spaced from 0 to ``duration`` seconds."""
    if count < 2:
        raise ValueError(f"count must be >= 2 (start and end), got {count}")
    if not (math.isfinite(duration) and duration >= 0):
        raise ValueError(f"duration must be a finite time >= 0 in seconds, got {duration}")
    return np.linspace(0.0, float(duration), count)


def _seconds(t: float) -> str:
    return f"{t:.0f}" if abs(t - round(t)) < 0.05 else f"{t:.1f}"


def draw_people_tracks(ax: Axes, people: PeopleLog, *, marks: Sequence[float] | None = None,
                       robot: tuple[np.ndarray, np.ndarray] | None = None, names: bool = True,
                       labels: bool = True) -> dict[str, list]:
    """Draws the walking people's tracks, start poses and time marks.

    Args:
        ax: the map axes (world metres).
        people: where the people were (only the movers of
            :func:`moving_people` are drawn).
        marks: common times, seconds; at each, marker k (1-based) on every
            walker present then (at :meth:`PeopleLog.state_at`) and on the
            robot's base. None: no marks.
        robot: the executed run ``(times (T,), q (T, >= 2))``: its base track
            is drawn thin and dashed, and marked at ``marks`` (base position
            interpolated linearly in time, held outside the run).
        names: write each walker's name by their start pose.
        labels: legend labels ("people's tracks", "executed base track", and
            one entry listing the marks' times).

    Returns:
        Artists by kind: "tracks", "starts" (rings and heading ticks),
        "names", "marks" (people's markers), "robot_track", "robot_marks",
        "legend" (the marks' legend proxy).
    """
    out: dict[str, list] = {k: [] for k in ("tracks", "starts", "names", "marks", "robot_track", "robot_marks",
                                            "legend")}
    walkers = np.flatnonzero(moving_people(people))
    mark_list = [] if marks is None else [float(t) for t in marks]
    states = [people.state_at(t) for t in mark_list]
    for n, i in enumerate(walkers):
        color = TRACK_COLORS[n % len(TRACK_COLORS)]
        present = people.present[:, i]
        if not present.any():
            continue
        xy = np.where(present[:, None], people.positions[:, i], np.nan)
        (line,) = ax.plot(xy[:, 0], xy[:, 1], color=color, linewidth=0.9, alpha=0.9, zorder=3.4,
                          label="people's tracks" if labels and not out["tracks"] else None)
        out["tracks"].append(line)
        k0 = int(np.argmax(present))
        (x, y), theta, radius = people.positions[k0, i], float(people.headings[k0, i]), float(people.radii[i])
        ring = Circle((x, y), radius, facecolor="none", edgecolor=color, linewidth=1.2, zorder=3.45)
        out["starts"].append(ax.add_patch(ring))
        c, s = math.cos(theta), math.sin(theta)
        (tick,) = ax.plot([x + radius * c, x + 2.2 * radius * c], [y + radius * s, y + 2.2 * radius * s],
                          color=color, linewidth=1.4, zorder=3.45)
        out["starts"].append(tick)
        if names and people.names[i]:
            out["names"].append(ax.text(x, y - radius - 0.08, people.names[i], fontsize=6, color=color,
                                        ha="center", va="top", zorder=6))
        for m, state in enumerate(states, start=1):
            if not state.present[i]:
                continue
            px, py = state.positions[i]
            (dot,) = ax.plot([px], [py], marker="o", markersize=9, color=color, markeredgecolor="white",
                             markeredgewidth=0.6, linestyle="none", zorder=7.0)
            out["marks"].append(dot)
            out["marks"].append(ax.text(px, py, str(m), ha="center", va="center", fontsize=5.5, color="white",
                                        fontweight="bold", zorder=7.1))
    if robot is not None:
        times, q = np.asarray(robot[0], float).reshape(-1), np.asarray(robot[1], float)
        if len(times) and q.shape[0] == len(times):
            (line,) = ax.plot(q[:, 0], q[:, 1], color=ROBOT_MARK_COLOR, linewidth=0.9, linestyle=(0, (4, 2)),
                              zorder=3.55, label="executed base track" if labels else None)
            out["robot_track"].append(line)
            for m, t in enumerate(mark_list, start=1):
                bx, by = np.interp(t, times, q[:, 0]), np.interp(t, times, q[:, 1])
                (sq,) = ax.plot([bx], [by], marker="s", markersize=9, color=ROBOT_MARK_COLOR,
                                markeredgecolor="white", markeredgewidth=0.6, linestyle="none", zorder=7.0)
                out["robot_marks"].append(sq)
                out["robot_marks"].append(ax.text(bx, by, str(m), ha="center", va="center", fontsize=5.5,
                                                  color="white", fontweight="bold", zorder=7.1))
    if labels and mark_list and (out["marks"] or out["robot_marks"]):
        text = ", ".join(f"{m}: {_seconds(t)}" for m, t in enumerate(mark_list, start=1))
        proxy = Line2D([], [], marker="o", markersize=7, color="#555555", linestyle="none",
                       label=f"time marks (s) {text}")
        ax.add_line(proxy)
        out["legend"].append(proxy)
    return out
