"""Figures of a study: boxplots of a metric per algorithm (the paper's Fig. 9)
and best paths side by side over the heat map (Fig. 5, 7 and 10).

Cost against distance (Fig. 6/8) is :func:`drake_social.viz.path.cost_profile_figure`.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

from drake_social.cost import SocialCost
from drake_social.scenario.geometry import arm_geometry
from drake_social.scenario import Scenario
from drake_social.viz.labels import fit_width
from drake_social.viz.path import draw_path
from drake_social.viz.show import draw_start_goal
from drake_social.viz.world import VIEW_MARGIN, draw_social_field, draw_world

__all__ = ["boxplot_figure", "paths_side_by_side"]

_BOX_COLORS = ("#1f77b4", "#aec7e8", "#d62728", "#ff9896", "#2ca02c", "#98df8a", "#9467bd")


def boxplot_figure(values: Mapping[str, Sequence[float]], *, title: str, ylabel: str,
                   note: str | None = None) -> Figure:
    """One box per label (median, quartiles, 1.5 IQR whiskers) with every run as a dot.

    Each run is drawn once, as a dot: the boxes draw no fliers of their own
    (the runs beyond the whiskers are the dots there).

    Args:
        values: label -> the runs' values (NaN and None left out; an empty
            list is drawn as "no run").
        title: the axes title (wrapped to the axes' width, 3 lines at most).
        ylabel: the value's name and unit.
        note: a text under the axes (e.g. what was left out; wrapped to the
            figure's width, 3 lines at most).
    """
    labels = list(values)
    data = [np.asarray([v for v in values[k] if v is not None and np.isfinite(v)], float) for k in labels]
    width, height = max(5.0, 1.5 * len(labels) + 1.5), 4.4  # inches
    left, right = 0.12, 0.98
    # Title, note and tick labels are wrapped to the room they have: the axes'
    # width, the figure's, one box's slot; the margins grow with their lines.
    title = fit_width(title, (right - left) * width, 9, max_lines=3)
    note = fit_width(note, width - 0.2, 8, max_lines=3) if note else None
    slot = (right - left) * width / max(1, len(labels))
    ticks = [fit_width(k, slot - 0.05, 8, max_lines=2) for k in labels]
    title_pt = 9 * 1.25 * (title.count("\n") + 1) + 10
    note_pt = 10 * (note.count("\n") + 1) + 2.7 if note else 0.0
    tick_pt = 10 * max((t.count("\n") for t in ticks), default=0)
    fig = Figure(figsize=(width, height))
    fig.subplots_adjust(left=left, right=right, bottom=0.2 + (note_pt + tick_pt) / (72 * height),
                        top=min(0.9, 1 - title_pt / (72 * height)))
    ax = fig.add_subplot()
    present = [k for k, d in enumerate(data) if len(d)]
    if present:
        box = ax.boxplot([data[k] for k in present], positions=[k + 1 for k in present], widths=0.55,
                         patch_artist=True, showfliers=False, medianprops={"color": "black"})
        for patch, k in zip(box["boxes"], present):
            patch.set_facecolor(_BOX_COLORS[k % len(_BOX_COLORS)])
            patch.set_alpha(0.75)
        for k in present:  # the runs themselves, spread sideways by their rank (deterministic)
            d = data[k]
            jitter = (np.argsort(np.argsort(d)) / max(1, len(d) - 1) - 0.5) * 0.25 if len(d) > 1 else np.zeros(1)
            ax.plot(k + 1 + jitter, d, "o", color="black", markersize=3, alpha=0.6, zorder=3)
    for k, d in enumerate(data):
        if not len(d):
            ax.text(k + 1, 0.5, "no run", transform=ax.get_xaxis_transform(), ha="center", color="#b00000")
    ax.set_xticks(range(1, len(labels) + 1), ticks, fontsize=8, rotation=12)
    ax.set_xlim(0.4, len(labels) + 0.6)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.grid(True, axis="y", alpha=0.3)
    if note:
        fig.text(0.5, 4 / (72 * height), note, ha="center", va="bottom", fontsize=8, color="#444444")
    return fig


def paths_side_by_side(scenario: Scenario, paths: Mapping[str, np.ndarray], *, title: str | None = None,
                       scenarios: Mapping[str, Scenario] | None = None, width: float = 6.5) -> Figure:
    """Paths over the social heat map (all interest points), one map per path.

    Args:
        scenario: the map, people and robot.
        paths: panel title -> (N, 4) waypoints (an empty array: "no path").
        title: the figure's title.
        scenarios: panel title -> its own scenario (e.g. other weights), when
            it differs from ``scenario``; the heat map is always the unweighted
            field of the people.
        width: width of one panel, inches.
    """
    x0, y0, x1, y1 = scenario.world.bounds
    pad = scenario.world.wall_thickness + VIEW_MARGIN
    aspect = (y1 - y0 + 2 * pad) / (x1 - x0 + 2 * pad)
    n = max(1, len(paths))
    map_h = width * aspect
    # Constrained layout places the labels, tick labels and titles outside
    # every map and inside the figure; the maps share their axes, so only the
    # outer ones carry tick labels and axis labels (label_outer below).
    fig = Figure(figsize=(n * width + 0.6, map_h + 1.2), layout="constrained")
    axes = fig.subplots(1, n, sharex=True, sharey=True, squeeze=False)[0]
    cost = SocialCost.from_scenario(scenario)
    geometry = arm_geometry(scenario)
    vmax = None
    for ax, (label, wp) in zip(axes, paths.items()):
        image = draw_social_field(ax, cost, scenario.world.bounds, colorbar=False, vmax=vmax)
        vmax = image.get_clim()[1]
        draw_world(ax, scenario, names=False)
        draw_start_goal(ax, scenario, labels=False)
        wp = np.asarray(wp, float).reshape(-1, 4)
        own = (scenarios or {}).get(label, scenario)
        if len(wp):
            draw_path(ax, arm_geometry(own) if own is not scenario else geometry, wp,
                      distance_weights=cost.distance_weights, numbers=False, labels=False)
        else:
            ax.text(0.5, 0.5, "no path", transform=ax.transAxes, ha="center", color="#b00000", fontsize=12)
        ax.set_title(fit_width(label, width - 0.2, 9, max_lines=2), fontsize=9)
        ax.tick_params(labelsize=7)
    for ax in axes:
        ax.label_outer()
    if title:
        fig.suptitle(fit_width(title, n * width + 0.2, 10, max_lines=2), fontsize=10)
    return fig
