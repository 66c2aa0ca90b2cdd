"""The figure of a replanning run: what each replan cost and what it decided.

:func:`replan_figure` stacks two panels over simulated time, one point per
replan of the log (``SimulationResult.replans``, ReplanResult records of
:mod:`drake_social.planning.replan`):

* the wall-clock time of each replan (milliseconds) with the budget line;
  replans that hit their deadline are drawn as red crosses. The first plan
  (``status == "initial"``, planned at initialization with the full
  iteration count and no deadline) is left out of this panel and named in its
  legend, as it would flatten the scale;
* the cost of the plan each replan returned (the exact time-indexed
  objective; a wait has none), with a green triangle where the path changed
  and a red mark at the foot of the panel at each replan that waited.

On both, the time the robot waited (from a replan that found no safe path to
the next one that did) is shaded. :func:`replan_series` gives the arrays the
figure plots; :func:`write_replan_figure` writes ``replans.png``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Sequence

import numpy as np
from matplotlib.figure import Figure

from drake_social.viz.labels import fit_width

__all__ = ["REPLANS_PNG", "replan_series", "replan_figure", "wait_intervals", "write_replan_figure"]

#: File name of the figure in a run's outputs.
REPLANS_PNG = "replans.png"
_DPI = 130


def replan_series(replans: Sequence) -> dict[str, np.ndarray]:
    """The log as arrays (R,), in its order: ``t`` (s), ``plan_time`` (s),
    ``cost`` (inf while waiting), ``changed``, ``wait`` (status "wait"),
    ``initial`` (status "initial"), ``deadline_hit``, ``iterations``."""
    def field(name, dtype):
        return np.array([getattr(r, name) for r in replans], dtype=dtype).reshape(len(replans))

    return {"t": field("t", float), "plan_time": field("plan_time", float), "cost": field("cost", float),
            "changed": field("changed", bool), "wait": np.array([r.status == "wait" for r in replans], bool),
            "initial": np.array([r.status == "initial" for r in replans], bool),
            "deadline_hit": field("deadline_hit", bool), "iterations": field("iterations", np.int64)}


def wait_intervals(t: np.ndarray, wait: np.ndarray, end: float | None = None) -> list[tuple[float, float]]:
    """The intervals ``[start, stop)`` (s) the robot waited: from a waiting
    replan to the next replan that did not wait; the last one, when still
    waiting, to ``end`` (None: the last replan's time)."""
    t, wait = np.asarray(t, float), np.asarray(wait, bool)
    out, start = [], None
    for ti, w in zip(t, wait):
        if w and start is None:
            start = float(ti)
        elif not w and start is not None:
            out.append((start, float(ti)))
            start = None
    if start is not None:
        out.append((start, float(t[-1]) if end is None else max(float(end), start)))
    return out


def replan_figure(replans: Sequence, *, budget: float | None = None, title: str | None = None,
                  end: float | None = None) -> Figure:
    """Plan time and cost per replan over simulated time (see the module's docstring).

    Args:
        replans: the run's ReplanResult log, in time order (not empty).
        budget: the replan budget, seconds (``planner.replan_budget``),
            drawn as a line; None: no line.
        title: the figure's title (default: the replans' counts).
        end: the run's end, seconds (shading of a wait still on at the end);
            None: the last replan's time.

    Raises:
        ValueError: an empty log or a budget that is not finite and > 0.
    """
    if len(replans) == 0:
        raise ValueError("replans is empty: nothing to draw (the run did not replan)")
    if budget is not None and not (math.isfinite(budget) and budget > 0):
        raise ValueError(f"budget must be finite and > 0 seconds, got {budget}")
    s = replan_series(replans)
    t, later = s["t"], ~s["initial"]
    fig = Figure(figsize=(9.0, 6.0))
    fig.subplots_adjust(left=0.1, right=0.97, bottom=0.09, top=0.9, hspace=0.12)
    ax_time, ax_cost = fig.subplots(2, 1, sharex=True)
    n_changed, n_wait, n_hit = int(s["changed"][later].sum()), int(s["wait"].sum()), int(s["deadline_hit"].sum())
    default = (f"{len(t)} replans: {n_changed} path changes, {n_wait} waiting, {n_hit} over the deadline")
    fig.suptitle(fit_width(title if title is not None else default, 8.7, 10), fontsize=10)
    ms = 1e3 * s["plan_time"]
    hit = later & s["deadline_hit"]
    ax_time.plot(t[later & ~hit], ms[later & ~hit], ".", color="#1f77b4", markersize=3, label="replan")
    if hit.any():
        ax_time.plot(t[hit], ms[hit], "x", color="#d62728", markersize=5, label="deadline hit")
    if budget is not None:
        ax_time.axhline(1e3 * budget, color="k", linestyle=":", linewidth=1.0, label=f"budget {1e3 * budget:g} ms")
    if s["initial"].any():
        first = ", ".join(f"{x:.3g} s" for x in s["plan_time"][s["initial"]])
        ax_time.plot([], [], " ", label=f"first plan {first} (not shown)")
    ax_time.set_ylabel("plan time (ms)")
    top = max([float(ms[later].max()) if later.any() else 0.0, 0.0 if budget is None else 1e3 * budget])
    ax_time.set_ylim(0.0, 1.3 * top if top > 0 else 1.0)  # headroom for the legend
    ax_time.legend(fontsize=7, ncol=4, loc="upper right")
    finite = np.isfinite(s["cost"])
    # NaN while waiting: the line breaks there.
    ax_cost.plot(t, np.where(finite, s["cost"], np.nan), ".-", color="#1f3b73", markersize=2, linewidth=0.8,
                 label="cost of the plan")
    if finite.any():
        lo, hi = float(s["cost"][finite].min()), float(s["cost"][finite].max())
        pad = 0.05 * (hi - lo) if hi > lo else max(abs(hi), 1.0) * 0.05
        ax_cost.set_ylim(lo - pad, hi + 6 * pad)  # headroom for the legend
    changed = s["changed"] & finite
    ax_cost.plot(t[changed], s["cost"][changed], "^", color="#2ca02c", markersize=5, label="path changed")
    if s["wait"].any():  # a mark per waiting replan at the foot of the panel: seen however short the wait
        ax_cost.plot(t[s["wait"]], np.full(int(s["wait"].sum()), 0.03), "v", color="#d62728", markersize=5,
                     transform=ax_cost.get_xaxis_transform(), label="waited")
    waits = wait_intervals(t, s["wait"], end)
    for ax in (ax_time, ax_cost):
        for a, b in waits:
            ax.axvspan(a, b, color="#d62728", alpha=0.15, linewidth=0)
        ax.grid(True, alpha=0.3)
    ax_cost.set_ylabel("cost")
    ax_cost.set_xlabel("simulated time (s)")
    ax_cost.legend(fontsize=7, ncol=4, loc="upper right")
    return fig


def write_replan_figure(source, out_dir: str | Path, *, budget: float | None = None, title: str | None = None,
                        name: str = REPLANS_PNG) -> Path:
    """Writes :func:`replan_figure` of a run as ``out_dir / name``.

    Args:
        source: a :class:`~drake_social.sim.results.SimulationResult` (its
            ``replans``; its ``sim_time`` ends a wait still on at the end)
            or the log itself (a sequence of ReplanResult).
        out_dir: the folder (must exist).
        budget, title: as :func:`replan_figure`.
        name: the file name.

    Returns:
        The path written.
    """
    replans = getattr(source, "replans", source)
    if replans is None:
        raise ValueError("source has no replanning log (replans is None): the run did not replan")
    end = getattr(source, "sim_time", None)
    fig = replan_figure(replans, budget=budget, title=title, end=end)
    path = Path(out_dir) / name
    fig.savefig(path, dpi=_DPI)
    return path
