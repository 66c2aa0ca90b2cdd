"""Figures of the crowd study (``drake-social experiment crowd``): boxplots of
per-part metrics by variant, and snapshots of an episode over time.

:func:`part_boxplots_figure` draws a grid, one row per metric and one column
per body part, a box per variant in each panel (median, quartiles, 1.5 IQR
whiskers, every episode a dot). :func:`snapshots_figure` draws one episode of
each variant at a few common times: the room, the people where they were,
the robot and its object, the base track so far and the path it was
following then (the plan of the latest replan at or before that time).
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

from drake_social.scenario.geometry import arm_geometry
from drake_social.people import PeopleState
from drake_social.scenario import Scenario
from drake_social.viz.labels import fit_width
from drake_social.viz.path import PATH_COLOR
from drake_social.viz.robot import draw_robot
from drake_social.viz.show import draw_start_goal
from drake_social.viz.world import draw_world

__all__ = ["VARIANT_COLORS", "part_boxplots_figure", "plan_at", "snapshot_times", "snapshots_figure", "trace_people"]

#: Box colours of the variants, in the study's order.
VARIANT_COLORS = ("#7f7f7f", "#ff9896", "#1f77b4", "#2ca02c", "#9467bd")
#: Colour of the executed base track in the snapshots.
TRACK_COLOR = "#d62728"


def part_boxplots_figure(values: Mapping[str, Mapping[str, Mapping[str, Sequence[float]]]], *, title: str,
                         units: Mapping[str, str] | None = None) -> Figure:
    """A grid of boxplots: ``values[metric][part][variant]`` -> the episodes' values.

    Args:
        values: metric label -> part -> variant -> values (NaN and None left
            out; an empty list is written "no episode").
        title: the figure's title.
        units: metric label -> its axis label (default: the metric label).
    """
    metrics = list(values)
    parts = list(next(iter(values.values()))) if metrics else []
    variants = list(next(iter(next(iter(values.values())).values()))) if parts else []
    fig = Figure(figsize=(3.1 * max(1, len(parts)) + 0.6, 2.6 * max(1, len(metrics)) + 1.2), layout="constrained")
    axes = fig.subplots(max(1, len(metrics)), max(1, len(parts)), squeeze=False)
    for i, m in enumerate(metrics):
        for j, p in enumerate(parts):
            ax = axes[i][j]
            data = [np.asarray([v for v in values[m][p][k] if v is not None and np.isfinite(v)], float)
                    for k in variants]
            present = [k for k, d in enumerate(data) if len(d)]
            if present:
                box = ax.boxplot([data[k] for k in present], positions=[k + 1 for k in present], widths=0.55,
                                 patch_artist=True, showfliers=False, medianprops={"color": "black"})
                for patch, k in zip(box["boxes"], present):
                    patch.set_facecolor(VARIANT_COLORS[k % len(VARIANT_COLORS)])
                    patch.set_alpha(0.75)
                for k in present:  # every episode, spread sideways by its rank (deterministic)
                    d = data[k]
                    jitter = (np.argsort(np.argsort(d)) / max(1, len(d) - 1) - 0.5) * 0.25 if len(d) > 1 else 0.0
                    ax.plot(k + 1 + jitter, d, "o", color="black", markersize=2.5, alpha=0.6, zorder=3)
            for k, d in enumerate(data):
                if not len(d):
                    ax.text(k + 1, 0.5, "no episode", transform=ax.get_xaxis_transform(), ha="center",
                            color="#b00000", fontsize=7, rotation=90)
            ax.set_xticks(range(1, len(variants) + 1), variants if i == len(metrics) - 1 else [""] * len(variants),
                          fontsize=7, rotation=25)
            ax.set_xlim(0.4, len(variants) + 0.6)
            ax.tick_params(labelsize=7)
            ax.grid(True, axis="y", alpha=0.3)
            if i == 0:
                ax.set_title(p, fontsize=9)
            if j == 0:
                ax.set_ylabel((units or {}).get(m, m), fontsize=8)
    fig.suptitle(fit_width(title, 3.1 * max(1, len(parts)), 10, max_lines=2), fontsize=10)
    return fig


def snapshot_times(duration: float, count: int = 4) -> np.ndarray:
    """``count`` common times of the snapshots: evenly spaced in [0, duration], both ends included."""
    return np.linspace(0.0, max(0.0, float(duration)), max(2, int(count)))


def plan_at(plans: Sequence, t: float) -> np.ndarray:
    """The path followed at time ``t``: the waypoints of the latest ``[t_k,
    waypoints]`` of ``plans`` with ``t_k <= t`` (the first before any); (0, 4) when none."""
    chosen = None
    for tk, wp in plans:
        if tk <= t + 1e-9 or chosen is None:
            chosen = wp
        if tk > t + 1e-9:
            break
    return np.asarray(chosen if chosen is not None else np.zeros((0, 4)), float).reshape(-1, 4)


def trace_people(trace: Mapping, k: int) -> PeopleState | None:
    """The people of an episode's trace at its sample ``k`` (None without people)."""
    if "positions" not in trace:
        return None
    positions = np.asarray(trace["positions"][k], float)
    return PeopleState(t=float(trace["times"][k]), positions=positions,
                       headings=np.asarray(trace["headings"][k], float), velocities=np.zeros_like(positions),
                       radii=np.asarray(trace["radii"], float), names=tuple(trace["names"]),
                       present=np.asarray(trace["present"][k], bool))


def snapshots_figure(scenario: Scenario, traces: Mapping[str, Mapping], *, count: int = 4, title: str | None = None,
                     width: float = 4.2) -> Figure:
    """One episode per variant (rows) at ``count`` common times (columns).

    Args:
        scenario: the map and the robot (the episode's people come from the traces).
        traces: row label -> an episode's trace (``run_episode``'s ``trace``:
            ``times``, ``q``, the people's ``positions``, ``headings``,
            ``present``, ``radii``, ``names``, and ``plans`` [[t, waypoints], ...]).
        count: snapshots per episode, evenly spaced over the longest episode.
        title: the figure's title.
        width: width of one panel, inches.
    """
    x0, y0, x1, y1 = scenario.world.bounds
    aspect = (y1 - y0 + 1.0) / (x1 - x0 + 1.0)
    rows = max(1, len(traces))
    duration = max((tr["times"][-1] for tr in traces.values() if len(tr["times"])), default=0.0)
    marks = snapshot_times(duration, count)
    fig = Figure(figsize=(len(marks) * width + 0.4, rows * (width * aspect + 0.5) + 0.8), layout="constrained")
    axes = fig.subplots(rows, len(marks), squeeze=False, sharex=True, sharey=True)
    geometry = arm_geometry(scenario)
    for i, (label, tr) in enumerate(traces.items()):
        times = np.asarray(tr["times"], float)
        q = np.asarray(tr["q"], float).reshape(-1, 4)
        for j, t in enumerate(marks):
            ax = axes[i][j]
            if not len(times):
                draw_world(ax, scenario, names=False)
                ax.text(0.5, 0.5, "no run", transform=ax.transAxes, ha="center", color="#b00000")
                continue
            k = int(min(np.searchsorted(times, t, side="right") - 1, len(times) - 1)) if t >= times[0] else 0
            draw_world(ax, scenario, names=False, people=trace_people(tr, k))
            draw_start_goal(ax, scenario, labels=False)
            plan = plan_at(tr.get("plans", ()), times[k])
            if len(plan):
                ax.plot(plan[:, 0], plan[:, 1], "-", color=PATH_COLOR, linewidth=1.0, alpha=0.6, zorder=3)
            ax.plot(q[: k + 1, 0], q[: k + 1, 1], "--", color=TRACK_COLOR, linewidth=1.3, zorder=4)
            draw_robot(ax, geometry, q[k], interest_points=False)
            ended = " (ended)" if t > times[-1] + 1e-9 else ""
            ax.set_title(fit_width(f"{label}: t = {times[k]:.1f} s{ended}", width - 0.2, 8, max_lines=2), fontsize=8)
            ax.tick_params(labelsize=6)
            ax.set_xlabel("")
            ax.set_ylabel("")
    if title:
        fig.suptitle(fit_width(title, len(marks) * width, 10, max_lines=2), fontsize=10)
    return fig
