"""One episode of the crowd study: a closed-loop run among walking people, measured.

:func:`run_episode` is the crowd study's per-task function (its kind in
:mod:`.kinds`): it loads the task's perturbed scenario
(:func:`~drake_social.experiments.study.crowd.episode_scenario`), runs it
closed loop in the kinematic simulation with the planner in the diagram,
and records the social-navigation metrics over time per part
(:func:`~drake_social.evaluation.nav_metrics.execution_metrics`, ``nav_*``)
and the replanning statistics (:func:`replan_stats`).
"""

from __future__ import annotations

import math
import time
from typing import Sequence

import numpy as np

from drake_social.experiments.study.crowd import NO_REPLANNING, episode_scenario, replanning_available
from drake_social.scenario import Scenario

__all__ = ["TRACE_STEP", "episode_record", "replan_stats", "run_episode"]

#: Seconds between the samples of an episode's trace (the snapshots' data).
TRACE_STEP = 0.25


def _first(r) -> bool:
    """The first plan of a replanning run (``replan_index`` 0, or status "initial"; it may be a wait)."""
    return r.status == "initial" or getattr(r, "replan_index", None) == 0


def replan_stats(replans: Sequence | None) -> dict[str, float]:
    """The replanning statistics of an episode from its replan log
    (``SimulationResult.replans``: ``ReplanResult`` s with ``status``,
    ``changed``, ``plan_time`` and ``deadline_hit``).

    The first plan (status ``"initial"``: ``planner.iterations``, no deadline)
    is left out: the rest are the periodic replans.

    Returns:
        ``replans`` (count), ``replan_changes`` (the path changed),
        ``replan_waits`` (status ``"wait"``: no safe path, the robot held),
        ``replan_evasions`` (status ``"evade"``: the robot stepped aside),
        ``replan_searches`` (replans that grew a search tree),
        ``replan_time_median`` / ``_p95`` / ``_max`` (wall seconds; NaN
        without replans), ``replan_search_time_median`` (of the replans
        that searched; NaN without any), ``replan_deadline_hits``; all NaN when
        ``replans`` is None (a plan-once episode).
    """
    keys = ("replans", "replan_changes", "replan_waits", "replan_evasions", "replan_searches", "replan_time_median",
            "replan_time_p95", "replan_time_max", "replan_search_time_median", "replan_deadline_hits")
    if replans is None:
        return dict.fromkeys(keys, math.nan)
    periodic = [r for r in replans if not _first(r)]
    times = np.array([r.plan_time for r in periodic], float)
    searched = np.array([r.plan_time for r in periodic if getattr(r, "searched", True)], float)
    return {
        "replans": float(len(periodic)),
        "replan_changes": float(sum(bool(r.changed) for r in periodic)),
        "replan_waits": float(sum(r.status == "wait" for r in periodic)),
        "replan_evasions": float(sum(r.status == "evade" for r in periodic)),
        "replan_searches": float(len(searched)),
        "replan_time_median": float(np.median(times)) if len(times) else math.nan,
        "replan_time_p95": float(np.percentile(times, 95)) if len(times) else math.nan,
        "replan_time_max": float(times.max()) if len(times) else math.nan,
        "replan_search_time_median": float(np.median(searched)) if len(searched) else math.nan,
        "replan_deadline_hits": float(sum(bool(r.deadline_hit) for r in periodic)),
    }


def _simulate(scenario: Scenario, checker, time_limit):
    from drake_social.sim.run import simulate

    options = {}
    if scenario.planner.replan:
        # Replanning is the diagram's; a simulator without it would silently plan once.
        if not replanning_available():
            raise RuntimeError(NO_REPLANNING)
        options["replan"] = True
    # analyze=False: the executed trajectory's own analysis (social cost
    # against the plan, the room's collision check) is not the study's and
    # costs more than the run; the metrics over time are measured from the log.
    run = simulate(scenario, mode="kinematic", checker=checker, time_limit=time_limit, analyze=False, **options)
    if scenario.planner.replan and getattr(run, "replans", None) is None:
        raise RuntimeError("simulate(..., replan=True) returned no replan log (SimulationResult.replans)")
    return run


def run_episode(task: dict) -> dict:
    """Runs one episode (closed loop, kinematic) and measures it; a record of plain data.

    The record: the task's keys (``scenario``, ``variant``, ``episode``,
    ``seed``, ``jitter``), ``delays`` (walker index -> start delay, s),
    ``reached``, ``time_to_goal``, ``sim_time``, ``wall_time`` (seconds of
    simulation, planning included), ``plan_time_initial`` (the first plan's
    wall seconds), ``plan_found`` (the first plan found a path), every ``nav_*`` metric
    (:func:`~drake_social.evaluation.nav_metrics.execution_metrics`: per
    part, contacts, zone times, minimum distance, time to goal, stops,
    success), :func:`replan_stats`, ``replan_times`` (every periodic replan's
    wall seconds) and, when ``task["trace"]``, ``trace``: the episode
    sampled every :data:`TRACE_STEP` seconds (``times``, ``q``, the people's
    ``positions``, ``headings``, ``present``, ``radii``, ``names``) and
    ``plans`` ([t, waypoints] of every path followed, from its start).
    """
    scenario, delays = episode_scenario(task)
    return episode_record(task, scenario, delays)[0]


def episode_record(task: dict, scenario: Scenario, delays: dict[int, float]) -> tuple[dict, object]:
    """Runs ``scenario`` (a task's episode, ``delays`` its walkers' start
    delays) closed loop, kinematic, and measures it: the record of
    :func:`run_episode` and the :class:`~drake_social.sim.results.SimulationResult`."""
    from drake_social.collision.drake_checker import make_checker
    from drake_social.evaluation.nav_metrics import execution_metrics

    checker = make_checker(scenario, "planar", parallelism=1)
    t0 = time.perf_counter()
    run = _simulate(scenario, checker, task["time_limit"])
    wall = time.perf_counter() - t0
    replans = getattr(run, "replans", None) if scenario.planner.replan else None
    record = {key: task[key] for key in ("index", "scenario", "variant", "episode", "seed", "jitter")}
    record["delays"] = {str(i): d for i, d in delays.items()}
    record.update({
        "plan_found": (float(math.isfinite(replans[0].cost)) if replans
                       else float(run.planner is not None and bool(run.planner.success))),
        "reached": float(bool(run.reached)),
        "time_to_goal": math.nan if run.time_to_goal is None else float(run.time_to_goal),
        "sim_time": float(run.sim_time),
        "wall_time": float(wall),
        "plan_time_initial": (float(replans[0].plan_time) if replans
                              else float(run.planner.wall_time) if run.planner is not None else math.nan),
    })
    record.update(execution_metrics(scenario, run))
    record.update(replan_stats(replans))
    # Microseconds: finer is the machine's noise (and 3000 replans an episode make records.json large).
    record["replan_times"] = [round(float(r.plan_time), 6) for r in replans if not _first(r)] if replans else []
    if task.get("trace"):
        record["trace"] = _trace(run, replans)
    return record, run


def _trace(run, replans) -> dict:
    """The episode every :data:`TRACE_STEP` seconds, and the paths it followed."""
    times = np.asarray(run.times, float)
    if not len(times):
        return {"times": [], "q": [], "plans": []}
    marks = np.arange(times[0], times[-1] + 1e-9, TRACE_STEP)
    idx = np.minimum(np.searchsorted(times, marks), len(times) - 1)
    out = {"times": times[idx].tolist(), "q": np.asarray(run.q)[idx].tolist()}
    people = run.people
    if people is not None and people.count:
        out.update(positions=people.positions[idx].tolist(), headings=people.headings[idx].tolist(),
                   present=people.present[idx].astype(bool).tolist(), radii=np.asarray(people.radii).tolist(),
                   names=list(people.names))
    if replans:
        plans = [[float(r.t), np.asarray(r.waypoints, float).tolist()] for r in replans
                 if r.status == "initial" or r.changed or r.status == "wait"]
    else:
        plans = [[0.0, np.asarray(run.waypoints, float).tolist()]]
    out["plans"] = plans
    return out
