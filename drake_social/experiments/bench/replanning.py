"""Replanning benchmark: how long a replan takes, and how fast a replanning run simulates.

Two measurements on one scenario (by default ``scenarios/office_walkers.yaml``,
the office with 7 walkers; issue 21's targets: median replan time at most
0.05 s, 95th percentile at most the budget, realtime factor of the kinematic
mode with replanning at 10 Hz at least 5x):

* **rollout** (:func:`rollout_replans`): the first ``count`` replans at
  ``planner.replan_rate`` of a run without Drake: the robot drives the path
  the replanner decided at the nominal speeds
  (:func:`~drake_social.kinematics.nominal_path_times`), holds while it
  waits, and each replan sees the people of the scenario's model at its time
  through ``planner.prediction``. The replans are those of
  :class:`~drake_social.planning.replan.Replanner` with the scenario's budget,
  so their times are the ones a run would see on this machine, without the
  Simulator around them;
* **simulation**: ``runs`` runs of ``simulate`` in the kinematic mode with
  ``planner.replan`` on (synchronized execution): the realtime factor
  (simulated seconds per wall second of ``AdvanceTo``, the replans included)
  and the times of every replan of the first run's log.

Replan times exclude the first plan (``replan_index`` 0, ``status == "initial"`` unless it waits: the full
iteration count, no deadline, at initialization); it is reported apart. The
processor is named: wall-clock times hold for it alone.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from drake_social.experiments.bench.machine import cpu_model, load_average
from drake_social.kinematics import nominal_path_times
from drake_social.scenario import Scenario, load_scenario
from drake_social.scenario.shipped import shipped_scenario

__all__ = ["REPLAN_SCENARIO", "position_at", "replan_markdown", "replan_time_stats", "rollout_replans",
           "run_replan_bench"]

_log = logging.getLogger(__name__)

#: The scenario of the replanning benchmark: the shipped office with walkers, found beside the package.
REPLAN_SCENARIO = shipped_scenario("office_walkers.yaml")
#: Issue 21's targets: median replan time (s) and the realtime factor of the kinematic mode.
TARGET_MEDIAN = 0.05
TARGET_REALTIME_FACTOR = 5.0


def replan_time_stats(replans: Sequence, budget: float) -> dict:
    """The times of a replanning log, the first plan apart.

    Args:
        replans: ReplanResult records (``plan_time``, ``status``,
            ``deadline_hit``, ``changed``).
        budget: the replan budget, seconds.

    Returns:
        ``n`` (replans but the first plan), ``median``, ``p95``, ``max``,
        ``mean`` (seconds; None when n = 0), ``deadline_hits`` (the search
        stopped at the budget), ``over_budget`` (plan_time > budget, the
        judging included), ``path_changes`` (status "new" or "evade"), ``waits``,
        ``initial_plan_time`` (s, None without a first plan), ``searches``
        (replans that grew a search tree) and ``search_median``,
        ``search_p95`` (seconds of those; None without any).
    """
    is_first = [r.status == "initial" or getattr(r, "replan_index", None) == 0 for r in replans]  # a wait too
    later = [r for r, f in zip(replans, is_first) if not f]
    first = [r for r, f in zip(replans, is_first) if f]
    times = np.array([float(r.plan_time) for r in later], float)
    searched = np.array([float(r.plan_time) for r in later if getattr(r, "searched", True)], float)
    out = {"n": int(len(later)), "median": None, "p95": None, "max": None, "mean": None,
           "deadline_hits": int(sum(bool(r.deadline_hit) for r in later)),
           "over_budget": int(np.sum(times > budget)),
           "path_changes": int(sum(bool(r.changed) for r in later)),
           "waits": int(sum(r.status == "wait" for r in later)),
           "initial_plan_time": float(first[0].plan_time) if first else None,
           "searches": int(len(searched)),
           "search_median": float(np.median(searched)) if len(searched) else None,
           "search_p95": float(np.percentile(searched, 95)) if len(searched) else None}
    if len(times):
        out.update(median=float(np.median(times)), p95=float(np.percentile(times, 95)), max=float(times.max()),
                   mean=float(times.mean()))
    return out


def position_at(waypoints: np.ndarray, times: np.ndarray, t: float) -> tuple[np.ndarray, int]:
    """Where a path driven on ``times`` (N,) is at ``t``, and the index of
    the next waypoint (N when the path is done): on motion k,
    ``q = q_k + u (q_{k+1} - q_k)`` with ``u = (t - t_k) / (t_{k+1} - t_k)``."""
    wp, times = np.asarray(waypoints, float), np.asarray(times, float)
    if t >= times[-1]:
        return wp[-1].copy(), len(wp)
    k = int(np.searchsorted(times, t, side="right"))  # times[k - 1] <= t < times[k]
    if k == 0:
        return wp[0].copy(), 1
    span = times[k] - times[k - 1]
    u = (t - times[k - 1]) / span if span > 0 else 1.0
    return wp[k - 1] + u * (wp[k] - wp[k - 1]), k


def rollout_replans(scenario: Scenario, count: int, *, checker: str = "planar", warm: bool = True,
                    progress: Callable[[int], None] | None = None) -> list:
    """The first plan and up to ``count`` replans of a kinematic rollout (see
    the module's docstring); fewer when the goal is reached first. With
    ``warm`` the first plan is made twice and the first one left out (it
    compiles the kernels or loads them from numba's cache); ``progress(k)``
    after replan k.

    Returns:
        The ReplanResult log, the first plan first.
    """
    from drake_social.collision.drake_checker import make_checker
    from drake_social.people import people_model, without_people
    from drake_social.people.prediction import predict
    from drake_social.planning.replan import Replanner

    if count < 1:
        raise ValueError(f"count must be >= 1 replans, got {count}")
    p, ex = scenario.planner, scenario.execution
    replanner = Replanner(scenario, make_checker(without_people(scenario), checker))
    model = people_model(scenario)
    goal = np.asarray(scenario.goal, float)

    interactive = replanner.interactive  # the interactive prediction: the replanner rolls the people out itself

    def prediction(t: float):
        return predict(p.prediction, model, model.state_at(t), float(p.replan_horizon), interactive=interactive)

    def people(t: float) -> dict:
        return {} if interactive is None else {"people": model.state_at(t)}

    def timed(path: np.ndarray, t0: float) -> np.ndarray:
        return nominal_path_times(path, ex.max_base_speed, ex.arm_max_velocity, t0)

    q = np.asarray(scenario.start, float)
    if warm:  # compiles the kernels (or loads numba's cache) outside the log's times
        replanner.plan(q, 0.0, prediction(0.0), None, replan_index=0, **people(0.0))
    first = replanner.plan(q, 0.0, prediction(0.0), None, replan_index=0, **people(0.0))
    log = [first]
    # The path being driven from time t_path, or waited on (it starts where the robot holds); None: no path.
    path, t_path, waiting = (None if first.waiting else first.waypoints), 0.0, first.waiting
    searched_at = 0.0
    for k in range(1, count + 1):
        t = k / float(p.replan_rate)
        remaining = path
        if path is not None and not waiting:
            q, index = position_at(path, timed(path, t_path), t)
            remaining = np.vstack([q[None], path[index:]])
        if np.array_equal(q, goal):
            break
        # As ReplanningPlannerSystem: the motion being driven is committed, and a search is due every
        # replan_search_period s while the path stays safe, or after a wait.
        search = waiting or t - searched_at >= float(p.replan_search_period) - 1e-9
        r = replanner.plan(q, t, prediction(t), remaining, replan_index=k, commit=path is not None and not waiting,
                           search=search, **people(t))
        searched_at = t if r.searched else searched_at
        log.append(r)
        waiting = r.waiting
        if waiting:
            path = remaining  # held where it is: resumed from q once it is safe again
        else:
            path, t_path = r.waypoints, t
        if progress:
            progress(k)
    return log


def _simulated(scenario: Scenario, runs: int, progress) -> dict:
    """``runs`` kinematic runs with replanning: realtime factors and the first run's log."""
    from drake_social.sim.run import simulate

    factors, first = [], None
    for i in range(runs):
        run = simulate(scenario, mode="kinematic", execution="synchronized", analyze=False, replan=True)
        factors.append(float(run.realtime_factor))
        first = run if first is None else first
        if progress:
            progress(f"replanning run {i + 1}/{runs}")
    return {"runs": runs, "reached": bool(first.reached), "time_to_goal": first.time_to_goal,
            "sim_time": float(first.sim_time), "stopped_time": float(first.stopped_time),
            "realtime_factor": {"median": float(np.median(factors)), "min": float(np.min(factors)),
                                "max": float(np.max(factors)), "n": len(factors)},
            "replan_time": replan_time_stats(first.replans, float(scenario.planner.replan_budget))}


def run_replan_bench(scenario_path: str | Path = REPLAN_SCENARIO, *, count: int = 200, runs: int = 1,
                     checker: str = "planar", progress: Callable[[str], None] | None = None) -> dict:
    """The replanning benchmark (see the module's docstring).

    Args:
        scenario_path: the scenario file (walking people; its planner's
            replan options are used as they are).
        count: replans of the rollout (>= 1).
        runs: simulated runs with replanning (>= 0; 0 leaves the simulation out).
        checker: the rollout's room checker (the replanner's needs a compiled
            scene: planar); the simulated runs use ``simulate``'s replanner.
        progress: optional ``progress(label)`` after the rollout and each run.

    Returns:
        ``{"scenario", "settings": {...}, "processor", "load_average_start",
        "rollout": replan_time_stats + {"replans"}, "simulation": {...} or None,
        "load_average_end"}`` (load averages: 1, 5, 15 min, or None).
    """
    if runs < 0:
        raise ValueError(f"runs must be >= 0, got {runs}")
    path = Path(scenario_path)
    scenario = load_scenario(path)
    p = scenario.planner
    budget = float(p.replan_budget)
    load_start = load_average()
    log = rollout_replans(scenario, count, checker=checker)
    if progress:
        progress(f"{path.stem} rollout of {len(log) - 1} replans")
    out = {
        "scenario": path.name,
        "settings": {"algorithm": p.algorithm, "replan_rate": float(p.replan_rate), "replan_budget": budget,
                     "replan_iterations": int(p.replan_iterations), "replan_horizon": float(p.replan_horizon),
                     "replan_margin": float(p.replan_margin), "prediction": p.prediction,
                     "iterations": int(p.iterations), "count": int(count), "runs": int(runs), "checker": checker},
        "processor": cpu_model(),
        "load_average_start": load_start,
        "rollout": {"replans": int(len(log) - 1), **replan_time_stats(log, budget)},
        "simulation": _simulated(scenario, runs, progress) if runs > 0 else None,
    }
    out["load_average_end"] = load_average()
    return out


def _load(entry: dict) -> str:
    """The load averages around the run, in words ("" when unknown)."""
    a, b = entry.get("load_average_start"), entry.get("load_average_end")
    if not a or not b:
        return ""
    return f" (1-minute load average {a[0]:.2f} at the start, {b[0]:.2f} at the end)"


def _ms(x: float | None) -> str:
    return "n/a" if x is None else f"{1e3 * x:.1f}"


def replan_markdown(entry: dict) -> list[str]:
    """The Markdown lines of the replanning section of ``bench.md``."""
    s = entry["settings"]
    lines = ["", f"## Replanning ({Path(entry['scenario']).stem})", "",
             f"{s['algorithm']}, {s['replan_rate']:g} Hz, budget {1e3 * s['replan_budget']:g} ms, at most "
             f"{s['replan_iterations']} samples per replan, horizon {s['replan_horizon']:g} s, "
             f"{s['prediction']} prediction; processor: {entry['processor'] or 'unknown'}{_load(entry)}. Replan times "
             f"(wall clock, the first plan apart; targets: median <= {1e3 * TARGET_MEDIAN:g} ms, 95th "
             f"percentile <= the budget):", "",
             "| replans of | n | median ms | p95 ms | max ms | searches | their median / p95 ms | deadline hits "
             "| over budget | path changes | waits | first plan s |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    rows = [("kinematic rollout (first replans)", entry["rollout"])]
    sim = entry.get("simulation")
    if sim:
        rows.append(("simulated run (kinematic)", sim["replan_time"]))
    for label, r in rows:
        first = "n/a" if r["initial_plan_time"] is None else f"{r['initial_plan_time']:.2f}"
        lines.append(f"| {label} | {r['n']} | {_ms(r['median'])} | {_ms(r['p95'])} | {_ms(r['max'])} "
                     f"| {r['searches']} | {_ms(r['search_median'])} / {_ms(r['search_p95'])} | {r['deadline_hits']} | {r['over_budget']} | {r['path_changes']} | {r['waits']} | {first} |")
    if sim:
        rf = sim["realtime_factor"]
        ttg = "not reached" if sim["time_to_goal"] is None else f"goal at {sim['time_to_goal']:.1f} s"
        lines += ["", f"Kinematic mode with replanning at {s['replan_rate']:g} Hz: realtime factor "
                  f"{rf['median']:.1f}x [{rf['min']:.1f}, {rf['max']:.1f}] over {rf['n']} run(s) (target >= "
                  f"{TARGET_REALTIME_FACTOR:g}x); {ttg}, {sim['sim_time']:.1f} s simulated, safety stops "
                  f"{sim['stopped_time']:.1f} s."]
    lines.append("")
    return lines
