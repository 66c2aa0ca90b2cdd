"""One run of a planning study (a sweep, the paper's), in any process.

:func:`run_task` is the planning study's per-task function (its kind in
:mod:`.kinds`; the framework runs every task on an executor): it loads the
task's scenario from its text, plans, measures the path
(:mod:`drake_social.evaluation.metrics`) and, with ``simulate``, executes it
and measures the executed trajectory too.
"""

from __future__ import annotations

import functools
import time

import numpy as np

from drake_social.experiments.study.scenarios import load_cached

__all__ = ["PROGRESS_POINTS", "run_task"]

#: Points of the anytime curve kept per run (evenly spaced iterations, the last included).
PROGRESS_POINTS = 50


@functools.lru_cache(maxsize=16)
def _checker(source: str, text: str, overrides: tuple[str, ...], overrides_name: str, kind: str):
    from drake_social.collision.drake_checker import make_checker  # Drake, imported by the runs that need it

    return make_checker(load_cached(source, text, overrides, overrides_name), kind, parallelism=1)


def run_task(task: dict) -> dict:
    """Plans one task and measures it; returns a record of plain data.

    The record has the task's keys (without the scenario text), the run
    record's fields (:data:`drake_social.io.records.RUN_FIELDS`: ``success``,
    ``cost`` (the planner's objective), ``planning_time`` (s), ``raw_cost``,
    ``first_solution_iteration``, ``tree_size``, ...; ``F_multi`` and the
    other path measures None on failure), every metric of
    :func:`~drake_social.evaluation.metrics.path_metrics` (on success),
    ``waypoints``, the anytime curve ``progress`` ([iteration, best cost]
    at :data:`PROGRESS_POINTS` iterations) and ``progress_time`` (seconds
    since the start of solve at those iterations); with ``simulate``, the
    ``exec_*`` metrics and the metrics over time against where people were
    (``nav_*``, :data:`drake_social.io.records.NAV_FIELDS`).
    """
    # Imported when a task runs, not with the package: defining and checking a study needs neither.
    from drake_social.evaluation.metrics import executed_metrics, path_metrics
    from drake_social.evaluation.records import run_record
    from drake_social.planning.algorithms import make_objective, plan
    from drake_social.planning.objective import SocialObjective

    key = (task["source"], task["scenario_text"], tuple(task["overrides"]), task["override_name"])
    scenario = load_cached(*key)
    checker = _checker(*key, task["checker"])
    k = int(task["iterations"])
    marks = set(np.unique(np.linspace(1, k, min(k, PROGRESS_POINTS)).round().astype(int)).tolist())
    curve: list[list[float]] = []
    stamps: list[float] = []
    t0 = time.perf_counter()

    def progress(iteration: int, best: float) -> None:
        if iteration in marks:
            stamps.append(time.perf_counter() - t0)
            curve.append([iteration, best if np.isfinite(best) else None])

    result = plan(scenario, checker, algorithm=task["algorithm"], iterations=k, seed=int(task["seed"]),
                  progress=progress)
    objective = make_objective(scenario, task["algorithm"])
    weights = objective.social.weights if isinstance(objective, SocialObjective) else None
    record = {key: task[key] for key in ("index", "group", "scenario", "overrides", "algorithm", "run", "seed",
                                         "iterations")}
    shared = run_record(scenario, result, objective)  # the run-record schema of plan and bench
    record.update({k: v for k, v in shared.items() if k not in record and k != "waypoints"})
    if result.success:
        record.update(path_metrics(scenario, result.waypoints, weights))
    if task["simulate"] and result.success:
        record.update(_execute(scenario, result.waypoints, checker, executed_metrics))
    record["waypoints"] = np.asarray(result.waypoints, float).tolist()
    record["progress"] = curve
    record["progress_time"] = stamps
    return record


def _execute(scenario, waypoints, checker, executed_metrics) -> dict:
    from drake_social.evaluation.metrics import execution_metrics
    from drake_social.sim.run import simulate

    # With walking people the analysis swaps the planning checker (people at t = 0) for one of
    # the same kind of the room alone (sim.execution_analysis.analyze_execution); the metrics read the run's log.
    run = simulate(scenario, mode="kinematic", waypoints=np.asarray(waypoints, float), checker=checker, analyze=True,
                   analysis_checker=checker)
    r = run.report
    out = {
        "exec_reached": bool(run.reached),
        "exec_time_to_goal": run.time_to_goal,
        "exec_wall_time": float(run.wall_time),
        "exec_planned_cost": r.planned_social_cost if r else None,
        "exec_cost": r.executed_social_cost if r else None,
        "exec_cost_ratio": (r.executed_social_cost / r.planned_social_cost
                            if r and r.planned_social_cost > 0 else None),
        "exec_max_deviation": r.max_point_deviation["max"] if r else None,
        "exec_collision_free": bool(r.collision_free) if r else None,
        "exec_within_limits": bool(r.within_limits) if r else None,
    }
    if len(run.times) > 1:
        out.update(executed_metrics(scenario, run.times, run.q, run.people))
        out.update(execution_metrics(scenario, run))
    return out
