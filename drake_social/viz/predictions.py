"""The figure of what a replanning robot predicted and decided: ``predictions.png``.

:func:`predictions_figure` draws, from a run's replanning log
(``SimulationResult.replans``), its kept predictions
(``SimulationResult.predicted``,
:class:`~drake_social.people.predicted.PredictedPeople`) and where the
people really were (``SimulationResult.people``):

* **top**, over simulated time: every replan that changed the route or
  waited, one row per category of :func:`~drake_social.planning.decisions.decision`
  (new route because the current one was not safe any more, new route
  because it was cheaper, evasion, wait; each row names its count), the
  waits shaded; the replan shown below is marked by a dashed line;
* **bottom left**, the room around one chosen replan (:func:`chosen_replan`:
  the first that a person made unsafe, else the first change after the
  first plan): each kept person's predicted track (dashed, open circles at
  the kept sample times; the culprit in orange) against their real track
  over the same times (solid, filled dots at the same times, from the
  people log), the plan chosen (blue) and the base's executed track over
  the horizon (black);
* **bottom right**, the prediction's error against how far ahead it
  looked: the distance between each kept person's predicted and real
  positions at each kept sample time, for every kept prediction (grey
  dots), their median per sample time ahead (black line) and the chosen
  replan's (coloured); people who stood still as predicted (never 1 cm
  off) are left out.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Sequence

import numpy as np
from matplotlib.figure import Figure

from drake_social.people import PeopleLog
from drake_social.people.predicted import PredictedPeople
from drake_social.planning.decisions import DECISION_LABELS, decision
from drake_social.scenario import Scenario
from drake_social.viz.labels import fit_width
from drake_social.viz.replans import wait_intervals
from drake_social.viz.world import draw_world

__all__ = ["FIGURE_DECISIONS", "PREDICTIONS_PNG", "chosen_replan", "prediction_errors", "predictions_figure",
           "write_predictions_figure"]

#: File name of the figure in a run's outputs.
PREDICTIONS_PNG = "predictions.png"
#: The categories of the top panel, bottom row first.
FIGURE_DECISIONS = ("wait", "evade", "cheaper", "unsafe")
_COLOURS = {"unsafe": "#d95f02", "cheaper": "#1f77b4", "evade": "#7b3294", "wait": "#c51b8a"}
_PREDICTED, _CULPRIT = "#00998c", "#ff7f00"
_DPI = 130
#: Metres: a person whose predicted and real positions never differ by this much stood as predicted
#: (left out of the error panel, where they would pile up at 0).
_STOOD = 0.01


def _log_index(predicted: PredictedPeople, people: PeopleLog) -> np.ndarray:
    """Each kept person's index in the people log (by index when the names
    agree, else by name; -1 when absent)."""
    out = np.full(len(predicted.names), -1)
    for k, (i, name) in enumerate(zip(predicted.indices, predicted.names)):
        if 0 <= i < len(people.names) and people.names[i] == name:
            out[k] = i
        elif name in people.names:
            out[k] = people.names.index(name)
    return out


def prediction_errors(predicted: PredictedPeople, people: PeopleLog) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The distances between predicted and real positions.

    Returns:
        ``(ahead, error, person)``, one entry per kept sample time within the
        people log's span and kept person present in both (predicted and
        really): seconds ahead of the replan, metres, and the person's index
        along the kept people.
    """
    where = _log_index(predicted, people)
    ahead, error, person = [], [], []
    for j, t in enumerate(predicted.times):
        if t > people.times[-1] + 1e-9:
            break
        real = people.state_at(float(t))
        for k, i in enumerate(where):
            if i < 0 or not (predicted.present[j, k] and real.present[i]):
                continue
            ahead.append(float(t - predicted.t))
            error.append(float(np.hypot(*(predicted.positions[j, k] - real.positions[i]))))
            person.append(k)
    return np.array(ahead), np.array(error), np.array(person, int)


def chosen_replan(replans: Sequence, predicted: Sequence[PredictedPeople]) -> PredictedPeople | None:
    """The kept prediction the figure shows: the first that names a culprit,
    else the first of a replan after the first plan, else the first; None without any."""
    if not predicted:
        return None
    for p in predicted:
        if p.culprit >= 0:
            return p
    later = [p for p in predicted if decision(replans[p.replan]) != "initial"]
    return later[0] if later else predicted[0]


def _decisions(ax, replans: Sequence, chosen: PredictedPeople | None, end: float | None) -> None:
    t = np.array([float(r.t) for r in replans])
    kinds = np.array([decision(r) for r in replans])
    for row, kind in enumerate(FIGURE_DECISIONS):
        at = t[kinds == kind]
        ax.plot(at, np.full(len(at), row), "|" if kind == "wait" else "o", color=_COLOURS[kind],
                markersize=9 if kind == "wait" else 5, markeredgewidth=1.5)
    for a, b in wait_intervals(t, kinds == "wait", end):
        ax.axvspan(a, b, color=_COLOURS["wait"], alpha=0.12, linewidth=0)
    ax.set_yticks(range(len(FIGURE_DECISIONS)))
    ax.set_yticklabels([f"{DECISION_LABELS[k]} ({int((kinds == k).sum())})" for k in FIGURE_DECISIONS], fontsize=8)
    ax.set_ylim(-0.6, len(FIGURE_DECISIONS) - 0.4)
    ax.set_xlim(0.0, max(float(t.max()) if len(t) else 0.0, end or 0.0, 1e-3) * 1.01)
    if chosen is not None:
        ax.axvline(chosen.t, color="k", linestyle="--", linewidth=0.9)
        ax.annotate("shown below", (chosen.t, len(FIGURE_DECISIONS) - 0.45), xytext=(4, -2),
                    textcoords="offset points", fontsize=7, va="top")
    ax.set_xlabel("simulated time (s)", fontsize=8)
    ax.set_title("what each replan decided (count)", fontsize=9)
    ax.grid(True, axis="x", alpha=0.3)
    ax.tick_params(labelsize=8)


def _map(ax, scenario: Scenario, replans: Sequence, chosen: PredictedPeople, people: PeopleLog,
         executed: tuple[np.ndarray, np.ndarray] | None) -> None:
    real_now = people.state_at(chosen.t)
    draw_world(ax, scenario, names=False, people=real_now)
    where = _log_index(chosen, people)
    times = chosen.times[chosen.times <= people.times[-1] + 1e-9]
    real_at = [people.state_at(float(t)).positions for t in times]  # (P, 2) each: the people at the kept times
    xs, ys = [], []
    for k, i in enumerate(where):
        colour = _CULPRIT if k == chosen.culprit else _PREDICTED
        shown = chosen.present[:, k]
        pred = chosen.positions[shown, k]
        if len(pred) == 0 or np.ptp(pred, axis=0).max() < 0.05 and k != chosen.culprit:
            continue  # standing still as predicted: the disc of draw_world
        ax.plot(pred[:, 0], pred[:, 1], "--o", color=colour, markerfacecolor="none", markersize=4, linewidth=1.2,
                zorder=5)
        xs += list(pred[:, 0])
        ys += list(pred[:, 1])
        if i >= 0 and len(times):
            real = np.array([positions[i] for positions in real_at])
            ax.plot(real[:, 0], real[:, 1], "-o", color=colour, markersize=3, linewidth=1.2, alpha=0.8, zorder=5)
            xs += list(real[:, 0])
            ys += list(real[:, 1])
    plan = np.asarray(replans[chosen.replan].waypoints, float)[:, :2]
    ax.plot(plan[:, 0], plan[:, 1], "-", color="#2b6cc4", linewidth=1.5, zorder=4)
    if executed is not None:
        tq, q = executed
        window = (tq >= chosen.t) & (tq <= chosen.times[-1])
        if window.any():
            ax.plot(q[window, 0], q[window, 1], "-", color="k", linewidth=1.6, zorder=6)
            xs += list(q[window, 0])
            ys += list(q[window, 1])
    ax.plot(*plan[0], "s", color="k", markersize=6, zorder=7)
    ax.plot([], [], "--o", color=_PREDICTED, markerfacecolor="none", markersize=4, label="predicted")
    ax.plot([], [], "-o", color=_PREDICTED, markersize=3, label="real (same times)")
    if chosen.culprit >= 0:
        ax.plot([], [], "--o", color=_CULPRIT, markerfacecolor="none", markersize=4,
                label=fit_width(f"made the path unsafe: {chosen.culprit_name}", 3.2, 7))
    ax.plot([], [], "-", color="#2b6cc4", label="plan chosen")
    ax.plot([], [], "-", color="k", label="base, executed")
    if xs:  # zoom on what the replan was about, at least 6 m wide, inside the room
        x0, y0, x1, y1 = (float(v) for v in scenario.world.bounds)
        xs += [float(plan[0, 0])]
        ys += [float(plan[0, 1])]
        cx, cy = (min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2
        half = max(3.0, (max(xs) - min(xs)) / 2 + 1.0, (max(ys) - min(ys)) / 2 + 1.0)
        ax.set_xlim(max(cx - half, x0 - 0.5), min(cx + half, x1 + 0.5))
        ax.set_ylim(max(cy - half, y0 - 0.5), min(cy + half, y1 + 0.5))
    r = replans[chosen.replan]
    ax.set_title(fit_width(f"replan at t = {chosen.t:.1f} s: {DECISION_LABELS[decision(r)]}", 4.4, 9), fontsize=9)
    ax.set_xlabel("x (m)", fontsize=8)
    ax.set_ylabel("y (m)", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.legend(fontsize=6.5, loc="best", framealpha=0.85)


def _moved(error: np.ndarray, who: np.ndarray) -> list:
    """The people (values of ``who``) whose prediction erred by ``_STOOD`` or more: not standing as predicted."""
    return [k for k in np.unique(who) if error[who == k].max() >= _STOOD]


def _errors(ax, predicted: Sequence[PredictedPeople], chosen: PredictedPeople, people: PeopleLog) -> None:
    all_ahead, all_error, chosen_errors = [], [], None
    for p in predicted:
        a, e, who = prediction_errors(p, people)
        if p is chosen:
            chosen_errors = (a, e, who)
        moved = np.isin(who, _moved(e, who))
        all_ahead.append(a[moved])
        all_error.append(e[moved])
    ahead, error = np.concatenate(all_ahead), np.concatenate(all_error)
    ax.plot(ahead, error, ".", color="0.6", markersize=3, label=f"every kept prediction ({len(predicted)})")
    if len(ahead):
        levels = np.unique(np.round(ahead, 6))
        ax.plot(levels, [np.median(error[np.isclose(ahead, v)]) for v in levels], "-", color="k", linewidth=1.2,
                label="median")
    a, e, who = chosen_errors if chosen_errors is not None else prediction_errors(chosen, people)
    for k in _moved(e, who):
        colour = _CULPRIT if k == chosen.culprit else _PREDICTED
        ax.plot(a[who == k], e[who == k], "-o", color=colour, markersize=3, linewidth=0.9, alpha=0.9)
    ax.plot([], [], "-o", color=_PREDICTED, markersize=3, label=f"the replan at t = {chosen.t:.1f} s")
    ax.set_xlabel("time ahead of the replan (s)", fontsize=8)
    ax.set_ylabel("predicted - real position (m)", fontsize=8)
    ax.set_title("how far the predicted people were from the real ones", fontsize=9)
    ax.set_ylim(bottom=0.0)
    ax.grid(True, alpha=0.3)
    ax.tick_params(labelsize=7)
    ax.legend(fontsize=7, loc="upper left")


def predictions_figure(scenario: Scenario, replans: Sequence, predicted: Sequence[PredictedPeople],
                       people: PeopleLog, *, executed: tuple[np.ndarray, np.ndarray] | None = None,
                       end: float | None = None, title: str | None = None) -> Figure:
    """The figure of the module's docstring.

    Args:
        scenario: the room.
        replans: the run's ReplanResult log (not empty).
        predicted: its kept predictions (not empty).
        people: where the people really were.
        executed: the run's ``(times (T,), q (T, 4))``: the base's track over
            the chosen replan's horizon; None: not drawn.
        end: the run's end, seconds (a wait still on at the end); None: the last replan's time.
        title: the figure's title (default: the counts).

    Raises:
        ValueError: an empty log or no kept prediction.
    """
    if len(replans) == 0 or len(predicted) == 0:
        raise ValueError("predictions_figure: needs replans and kept predictions (the run did not replan)")
    chosen = chosen_replan(replans, predicted)
    fig = Figure(figsize=(11.0, 8.0))
    ax_dec = fig.add_gridspec(1, 1, left=0.2, right=0.98, bottom=0.71, top=0.9).subplots()
    ax_map, ax_err = fig.add_gridspec(1, 2, width_ratios=[1.15, 1.0], left=0.06, right=0.98, bottom=0.07,
                                      top=0.6, wspace=0.2).subplots()
    _decisions(ax_dec, replans, chosen, end)
    _map(ax_map, scenario, replans, chosen, people, executed)
    _errors(ax_err, predicted, chosen, people)
    kinds = [decision(r) for r in replans]
    default = (f"{len(replans)} replans: {sum(k in ('unsafe', 'cheaper', 'evade') for k in kinds)} route changes, "
               f"{sum(k == 'wait' for k in kinds)} waiting; {len(predicted)} predictions kept")
    fig.suptitle(fit_width(title if title is not None else default, 10.6, 10), fontsize=10)
    return fig


def write_predictions_figure(run, scenario: Scenario, out_dir: str | Path, *, title: str | None = None,
                             name: str = PREDICTIONS_PNG) -> Path:
    """Writes :func:`predictions_figure` of a run (a
    :class:`~drake_social.sim.results.SimulationResult` with ``replans``,
    ``predicted`` and ``people``) as ``out_dir / name``; returns the path."""
    if run.people is None:
        raise ValueError("write_predictions_figure: the run has no people log")
    fig = predictions_figure(scenario, run.replans, run.predicted, run.people, executed=(run.times, run.q),
                             end=getattr(run, "sim_time", None), title=title)
    path = Path(out_dir) / name
    fig.savefig(path, dpi=_DPI)
    return path
