"""The figure of a run's motion: speed, acceleration and jerk over time, and the slow-down.

:func:`motion_figure` stacks three panels over time: the speed, the
acceleration and the jerk (log scale: a hard stop's thousands of m/s^3 and
a jerk-limited motion's few in one panel) of the tracks it is given (the
base, the object's fastest point: :func:`drake_social.evaluation.time_series.motion_profile`),
with the base's limits dashed. The speed panel shows the slow-down's speed
limit where it is in force; the time under a limit is shaded light, the
slow-down's stops orange and the safety monitor's stops red in every panel.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from drake_social.viz.labels import fit_width

__all__ = ["motion_figure"]

_COLORS = ("#1f77b4", "#9467bd", "#2ca02c", "#8c564b")
_LIMITED, _SLOW_STOP, _SAFETY_STOP = "#fff2b3", "#f5a623", "#d62728"
#: The jerk panel's floor, m/s^3 (a log scale has no 0).
_JERK_FLOOR = 1e-2


def _spans(ax, intervals: Sequence[tuple[float, float]], color: str, alpha: float) -> None:
    for start, end in intervals:
        ax.axvspan(start, end, color=color, alpha=alpha, lw=0)


def _limited_spans(times: np.ndarray, limit: np.ndarray) -> list[tuple[float, float]]:
    """The time intervals where ``limit`` is finite, sample-and-hold."""
    finite = np.isfinite(limit)
    spans, start = [], None
    for k, on in enumerate(finite):
        if on and start is None:
            start = times[k]
        elif not on and start is not None:
            spans.append((start, times[k]))
            start = None
    if start is not None:
        spans.append((start, times[-1]))
    return spans


def _stop_spans(stops: Sequence[Mapping], end: float) -> list[tuple[float, float]]:
    return [(float(s["start"]), float(end if s["end"] is None else s["end"])) for s in stops]


def motion_figure(times: np.ndarray, profiles: Mapping[str, Mapping[str, tuple[np.ndarray, np.ndarray]]], *,
                  speed_limit: np.ndarray | None = None, stops: Sequence[Mapping] = (),
                  slow_stops: Sequence[Mapping] = (), limits: tuple[float, float, float] | None = None,
                  title: str = "") -> Figure:
    """Speed, acceleration and jerk over time.

    Args:
        times: (T,) the run's sample times, seconds.
        profiles: track name -> ``{"speed" | "accel" | "jerk": (t, values)}``
            (:func:`~drake_social.evaluation.time_series.motion_profile`).
        speed_limit: (T,) the slow-down's limit at ``times`` (m/s, +inf where
            none), or None.
        stops, slow_stops: the safety monitor's and the slow-down's stops
            (dicts with ``start`` and ``end``, None while still stopped).
        limits: the base's speed, acceleration and jerk limits, dashed.
        title: the figure's title (fitted to two lines).
    """
    times = np.asarray(times, float).reshape(-1)
    fig = Figure(figsize=(9.0, 7.5))
    fig.subplots_adjust(left=0.1, right=0.97, bottom=0.07, top=0.9, hspace=0.25)
    axes = fig.subplots(3, 1, sharex=True)
    fig.suptitle(fit_width(title, 8.7, 10), fontsize=10)
    if len(times) < 2:
        axes[0].text(0.5, 0.5, "nothing was executed", transform=axes[0].transAxes, ha="center")
        return fig
    end = float(times[-1])
    limit = None if speed_limit is None else np.asarray(speed_limit, float).reshape(-1)
    limited = _limited_spans(times, limit) if limit is not None and len(limit) == len(times) else []
    for ax in axes:
        _spans(ax, limited, _LIMITED, 0.8)
        _spans(ax, _stop_spans(slow_stops, end), _SLOW_STOP, 0.35)
        _spans(ax, _stop_spans(stops, end), _SAFETY_STOP, 0.35)
    units = {"speed": "speed (m/s)", "accel": "acceleration (m/s^2)", "jerk": "jerk (m/s^3)"}
    for ax, key in zip(axes, ("speed", "accel", "jerk")):
        for (name, profile), color in zip(profiles.items(), _COLORS):
            t, values = profile[key]
            if key == "jerk":
                values = np.maximum(values, _JERK_FLOOR)
            ax.plot(t, values, color=color, lw=0.9, label=name)
        ax.set_ylabel(units[key])
        ax.grid(alpha=0.3)
    if limits is not None:
        for ax, value in zip(axes, limits):
            ax.axhline(value, color="k", ls="--", lw=0.8, label="base limit")
    if limited:
        shown = np.where(np.isfinite(limit), limit, np.nan)
        axes[0].step(times, shown, where="post", color="#e67e00", lw=1.2, label="speed limit (fastest point)")
    axes[2].set_yscale("log")
    axes[2].set_ylim(bottom=_JERK_FLOOR)
    axes[2].set_xlabel("t (s)")
    handles, labels = axes[0].get_legend_handles_labels()
    handles += [Patch(color=_LIMITED, label="under a speed limit"), Patch(color=_SLOW_STOP, alpha=0.35,
                label="slow-down stop"), Patch(color=_SAFETY_STOP, alpha=0.35, label="safety stop")]
    axes[0].legend(handles=handles, fontsize=7, loc="upper right", ncol=2)
    return fig
