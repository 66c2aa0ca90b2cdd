"""``drake-social bench``: the planners over seeds, against OMPL's RRTstar.

:func:`run_bench` plans every (scenario, algorithm) with seeds
``0 .. seeds - 1`` and reports per run and as medians with spread. When
``ompl`` is importable it also runs OMPL's RRTstar in the same run on the
same problem (:mod:`drake_social.experiments.bench.ompl_baseline`), once per
objective: ``rrt_star`` (path length), ``social_rrt_star`` (multi-point)
and ``base_rrt_star`` (base-only); the informed variants are compared with
OMPL on their objective (OMPL's RRTstar does not sample informed).

Every scenario file is loaded with the paper's planner settings as its last
override (:data:`drake_social.limits.PAPER_PLANNER`: the fixed near radius,
no optimisation), whatever its own ``planner`` section says: OMPL's RRTstar
runs a fixed radius and returns its raw path, so ours do too (``bench.md``
prints these options per scenario).

Every run gets a fresh checker (built outside the timing), so no run profits
from another's caches. Every path, ours and OMPL's, is measured by the same
code afterwards: :func:`evaluate_path` gives its objective, social cost with
the scenario's full weights and lengths, and the checker verifies every
waypoint and motion (``path_valid``). ``planning_time`` is the planner's search
only (``RrtStar.solve``, OMPL's ``solve``). Each run is a run record
(:data:`drake_social.io.records.RUN_FIELDS`), as ``plan`` and the studies write.

Ratios are ours / OMPL of the medians: ``time`` (planning time), ``social_cost``
(``F_multi``) and ``objective``; not defined (null, "n/a" in the table)
where either median is 0.
"""

from __future__ import annotations

import importlib.metadata
import logging
import os
import platform
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from drake_social.collision.drake_checker import CHECKERS, make_checker
from drake_social.planning.space import ConfigurationSpace
from drake_social.collision.validity import ValidityChecker
from drake_social.experiments.bench.machine import cpu_model, load_average as _load_average
from drake_social.evaluation.records import run_record
from drake_social.io.records import write_json
from drake_social.limits import PAPER_PLANNER
from drake_social.planning.algorithms import (ALGORITHM_SPECS, algorithm_spec, evaluate_path, make_objective,
                                              plan)
from drake_social.scenario import ALGORITHMS, EXECUTIONS, SIM_MODES, Scenario, load_scenario, validate_planner_choice

__all__ = ["CHECKERS", "ompl_available", "ompl_counterpart", "run_bench", "summarize"]

_log = logging.getLogger(__name__)

#: Per-run fields summarised with median and spread.
_STAT_FIELDS = ("planning_time", "F_multi", "objective", "base_length", "path_length")
#: Per-run fields summarised with their median only.
_MEDIAN_FIELDS = ("first_solution_iteration", "tree_size", "num_config_checks", "num_motion_checks",
                  "num_cost_evaluations")


def ompl_available() -> bool:
    """Whether the ``ompl`` package (the ``bench`` extra) is importable."""
    try:
        import ompl.base  # noqa: F401
        import ompl.geometric  # noqa: F401
    except ImportError:
        return False
    return True


def _make_checker(scenario: Scenario, checker: str, path: Path | None = None) -> ValidityChecker:
    # The planners check one configuration or motion at a time; one thread
    # keeps the runs from competing with Drake's worker threads.
    return make_checker(scenario, checker, parallelism=1, source=None if path is None else str(path))


def ompl_counterpart(algorithm: str) -> str:
    """The uniform-sampling algorithm of :data:`ALGORITHM_SPECS` with the same
    objective and social weights as ``algorithm`` (the algorithm itself when it
    samples uniformly): the one OMPL's RRTstar is run as."""
    spec = algorithm_spec(algorithm, "bench")
    matches = [s.name for s in ALGORITHM_SPECS.values()
               if s.sampler == "uniform" and (s.objective, s.weights) == (spec.objective, spec.weights)]
    if len(matches) != 1:
        raise ValueError(f"bench: algorithm {algorithm!r} needs exactly one uniform-sampling algorithm with its "
                         f"objective {spec.objective!r} and weights {spec.weights!r} in ALGORITHM_SPECS, got {matches}")
    return matches[0]


def _record(scenario: Scenario, result, objective, checker: ValidityChecker, iterations: int) -> dict:
    """One run's record (:data:`drake_social.io.records.RUN_FIELDS`) of K =
    ``iterations``, its path re-measured and re-checked by our code:
    ``objective`` recomputed from the waypoints and ``path_valid``."""
    run = {"iterations": int(iterations), **run_record(scenario, result, objective)}
    waypoints = run.pop("waypoints")
    if result.success:
        wp = np.asarray(result.waypoints, float)
        run["objective"] = evaluate_path(scenario, wp, objective)["objective"]
        run["path_valid"] = bool(np.all(checker.are_valid(wp)) and np.all(checker.are_motions_valid(wp[:-1], wp[1:])))
    else:
        run.update({"objective": None, "path_valid": None})
    run["waypoints"] = waypoints
    return run


def _stats(values: Sequence[float]) -> dict:
    """Median, quartiles, IQR, min and max (None when there are no values)."""
    v = np.asarray([x for x in values if x is not None], float)
    if len(v) == 0:
        return {"n": 0, "median": None, "q25": None, "q75": None, "iqr": None, "min": None, "max": None}
    q25, med, q75 = np.percentile(v, [25, 50, 75])
    return {"n": int(len(v)), "median": float(med), "q25": float(q25), "q75": float(q75),
            "iqr": float(q75 - q25), "min": float(v.min()), "max": float(v.max())}


def summarize(runs: Sequence[dict]) -> dict:
    """Summary of one (scenario, planner)'s runs.

    Planning time is over all runs; costs, lengths and the other medians over the
    successful ones.
    """
    ok = [r for r in runs if r["success"]]
    out = {"runs": len(runs), "successes": len(ok), "success_rate": len(ok) / len(runs) if runs else None,
           "paths_valid": all(r["path_valid"] for r in ok) if ok else None}
    for f in _STAT_FIELDS:
        out[f] = _stats([r[f] for r in (runs if f == "planning_time" else ok)])
    for f in _MEDIAN_FIELDS:
        out[f"median_{f}"] = _stats([r[f] for r in ok])["median"]
    return out


def _ratio(a: dict, b: dict, field: str) -> float | None:
    """Median of ``a`` over median of ``b``; None (not defined, "n/a" in the
    table) when either is missing or 0: 0 / c or c / 0 compares nothing, e.g.
    where every social planner finds a path of cost 0."""
    x, y = a[field]["median"], b[field]["median"]
    return None if x is None or y is None or x == 0 or y == 0 else x / y


def _repeated(run_once: Callable[[], tuple], repeats: int) -> tuple:
    """Runs ``run_once() -> (result, ...)`` ``repeats`` times and returns the
    first run's tuple with ``wall_time`` the median of the repeats' (the
    runs are seeded: the same path each time, only the machine's speed
    differs), and the repeats' times.

    Raises:
        RuntimeError: a repeat returned another path or cost than the first
            (the run is not deterministic, so its repeats cannot be pooled).
    """
    first, times = None, []
    for _ in range(repeats):
        out = run_once()
        times.append(float(out[0].wall_time))
        if first is None:
            first = out
        elif not (np.array_equal(out[0].waypoints, first[0].waypoints) and out[0].cost == first[0].cost):
            raise RuntimeError(f"{first[0].algorithm}: a repeat of seed {first[0].seed} returned another path "
                               f"(cost {out[0].cost!r}, first {first[0].cost!r}); --repeats needs deterministic runs")
    first[0].wall_time = float(np.median(times))
    return first, times


def _plan_ompl_runs(scenario: Scenario, key: str, iterations: int, seeds: int, checker: str, tick,
                    repeats: int = 1) -> dict:
    from drake_social.experiments.bench.ompl_baseline import plan_ompl

    objective = make_objective(scenario, key)
    p = scenario.planner
    runs, settings = [], None
    for seed in range(seeds):
        chk = _make_checker(scenario, checker)

        def once():
            return plan_ompl(
                ConfigurationSpace.from_scenario(scenario), chk, objective, np.asarray(scenario.start, float),
                np.asarray(scenario.goal, float), iterations=iterations, planning_range=p.planning_range,
                near_radius=p.near_radius, goal_bias=p.goal_bias, seed=seed, name=f"ompl_rrt_star[{key}]",
            )

        (result, settings), times = _repeated(once, repeats)
        runs.append({**_record(scenario, result, objective, chk, iterations), "planning_times": times})
        tick(f"ompl_rrt_star[{key}] seed {seed}")
    return {"objective_of": key, "checker": checker, "settings": settings.to_json_dict(), "runs": runs,
            "summary": summarize(runs)}


def _machine() -> dict:
    def version(name: str) -> str | None:
        try:
            return importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            return None

    return {"platform": platform.platform(), "machine": platform.machine(), "processor": platform.processor(),
            "cpu_model": cpu_model(), "load_average_start": _load_average(),
            "python": platform.python_version(), "cpu_count": os.cpu_count(),
            "numpy": version("numpy"), "drake": version("drake"), "ompl": version("ompl")}


def run_bench(
    *,
    scenario_paths: Sequence[str | Path],
    algorithms: Sequence[str] | None = None,
    iterations: int = 2000,
    seeds: int = 10,
    checker: str = "planar",
    ompl_checker: str = "drake",
    include_ompl: bool = True,
    include_checker: bool = True,
    sim_runs: int = 0,
    scaling: bool = False,
    repeats: int = 1,
    replan_runs: int = 0,
    replan_count: int = 200,
    replan_scenario: str | Path | None = None,
    map_bench: bool = False,
    out_dir: str | Path,
    progress: Callable[[int, int, str], None] | None = None,
) -> dict:
    """Benchmarks the planners and writes ``bench.json`` and ``bench.md``.

    Args:
        scenario_paths: scenario YAML files.
        algorithms: planners to run (default: all of ``scenario.ALGORITHMS``).
        iterations: samples per run, K.
        seeds: runs per (scenario, algorithm), seeds ``0 .. seeds - 1``.
        checker: our planners' checker, one of ``CHECKERS`` (default the
            exact planar one).
        ompl_checker: the checker OMPL's RRTstar plans with (default Drake's
            SceneGraph, the baseline of issue 8); when it differs from
            ``checker``, OMPL also runs with ``checker`` (``ompl_same_checker``,
            ratios ``vs_ompl_same_checker``): the same checks on both sides.
        include_ompl: also run OMPL's RRTstar when ``ompl`` is importable.
        include_checker: also measure the checkers
            (:func:`run_checker_bench` on 2000 configurations and 200 motions).
        sim_runs: when > 0, also the execution benchmark
            (:func:`~drake_social.experiments.bench.execution.run_sim_bench`) with
            this many timed runs per (mode, execution).
        scaling: also :func:`~drake_social.experiments.bench.scaling.run_scaling_bench`
            (K up to 50,000 with the shrinking radius, optimisation against
            K = 50,000, 50 far people) on every scenario with ``checker``.
        repeats: runs of each seed, ours and OMPL's: a run's planning_time is the
            median of its repeats' (``planning_times``: all of them). A seeded run
            repeats its path exactly, so this only filters the machine's
            noise (other processes, a shared host) out of the times.
        replan_runs: when > 0, also the replanning benchmark
            (:func:`~drake_social.experiments.bench.replanning.run_replan_bench`
            on ``replan_scenario``): replan times over a rollout of
            ``replan_count`` replans and the realtime factor of this many
            simulated kinematic runs with replanning (``replan_bench``).
        replan_count: replans of that rollout (>= 1).
        replan_scenario: its scenario file (None:
            :data:`~drake_social.experiments.bench.replanning.REPLAN_SCENARIO`,
            the office with walkers).
        map_bench: also :func:`~drake_social.experiments.bench.maps.run_map_bench`:
            a generated 30 x 50 m floor map at 0.03 m against the first of
            ``scenario_paths`` (``map_bench``).
        out_dir: where the two files go (created).
        progress: optional ``progress(done, total, label)`` after each run.

    Returns:
        ``{"settings", "machine", "ompl", "scenarios", "checker_bench", "sim_bench",
        "scaling_bench", "replan_bench", "map_bench"}`` (the last four None when not run);
        ``scenarios[file name]`` has ``algorithms[name] = {"runs": [...],
        "summary": {...}, "vs_ompl": {...}}`` and ``ompl[objective] =
        {"settings", "runs", "summary"}``. Per run: a run record
        (:data:`drake_social.io.records.RUN_FIELDS`: planning_time (s), cost
        (the planner's own), raw_cost, F_multi, F_base, F_planner,
        path_length, base_length (m), first_solution_iteration, tree_size,
        check and cost counts, waypoints) with objective (recomputed),
        path_valid and planning_times.
        Summaries give ``{n, median, q25, q75, iqr, min, max}`` of planning time
        (all runs) and of the costs and lengths (successful runs).
    """
    algorithms = list(ALGORITHMS if algorithms is None else algorithms)
    _check_arguments(algorithms, checker, ompl_checker, iterations, seeds, repeats, replan_runs, replan_count)
    paths = [Path(p) for p in scenario_paths]
    if not paths:
        raise ValueError("scenario_paths is empty")
    use_ompl = include_ompl and ompl_available()
    if include_ompl and not use_ompl:
        _log.info("ompl is not importable (pip install 'drake-social[bench]'); skipping the OMPL baseline")
    keys = list(dict.fromkeys(ompl_counterpart(a) for a in algorithms)) if use_ompl else []
    ompl_sets = [("ompl", ompl_checker)] + ([("ompl_same_checker", checker)] if ompl_checker != checker else [])
    total = len(paths) * seeds * (len(algorithms) + len(keys) * len(ompl_sets)) + (1 if include_checker else 0)
    total += len(paths) * len(SIM_MODES) * len(EXECUTIONS) * (sim_runs + 1) if sim_runs > 0 else 0
    total += len(paths) * (4 + 2 + 5 + 3) if scaling else 0  # run_scaling_bench's defaults
    total += 1 + replan_runs if replan_runs > 0 else 0  # the rollout and the runs
    total += 1 + 1 + 3 + 1 if map_bench else 0  # run_map_bench's defaults: load, checkers, 3 seeds, replay
    done = 0

    def tick(label: str) -> None:
        nonlocal done
        done += 1
        _log.debug("bench %d/%d %s", done, total, label)
        if progress:
            progress(done, total, label)

    machine = _machine()  # the load average before this run's planning
    # Every file is loaded with the paper's planner settings over its own (as
    # OMPL's RRTstar plans: fixed radius, raw path), and checked with each
    # planner of the bench (which replaces its planner.algorithm), before the
    # first run.
    loaded = [load_scenario(path, [PAPER_PLANNER]) for path in paths]
    for path, scenario in zip(paths, loaded):
        for algorithm in algorithms:
            validate_planner_choice(scenario, algorithm, source=f"{path} with the bench's algorithm {algorithm}")
    scenarios = {path.name: _scenario_runs(path, scenario, algorithms, keys, ompl_sets, checker, iterations, seeds,
                                           repeats, tick)
                 for path, scenario in zip(paths, loaded)}
    extras = _other_benches(paths, include_checker, sim_runs, scaling, checker, replan_runs, replan_count,
                            replan_scenario, map_bench, iterations, tick)
    out = {
        "settings": {"scenario_paths": [str(p) for p in paths], "algorithms": algorithms, "iterations": iterations,
                     "seeds": list(range(seeds)), "checker": checker, "ompl_checker": ompl_checker,
                     "sim_runs": sim_runs, "repeats": repeats},
        "machine": {**machine, "load_average_end": _load_average()},
        "ompl": {"requested": include_ompl, "available": ompl_available(), "objectives": keys},
        "scenarios": scenarios,
        **extras,
    }
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    write_json(out_dir / "bench.json", out, indent=1)
    (out_dir / "bench.md").write_text(_markdown(out))
    _log.info("bench written to %s", out_dir)
    return out


def _check_arguments(algorithms: list[str], checker: str, ompl_checker: str, iterations: int, seeds: int,
                     repeats: int, replan_runs: int, replan_count: int) -> None:
    """:func:`run_bench`'s arguments in range, or a ValueError naming the one that is not."""
    unknown = [a for a in algorithms if a not in ALGORITHMS]
    if unknown or not algorithms:
        raise ValueError(f"algorithms {unknown or '[]'} not allowed; allowed: {', '.join(ALGORITHMS)}")
    for label, value in (("checker", checker), ("ompl_checker", ompl_checker)):
        if value not in CHECKERS:
            raise ValueError(f"{label} {value!r} not allowed; allowed: {', '.join(CHECKERS)}")
    if iterations < 1 or seeds < 1 or repeats < 1:
        raise ValueError(f"iterations, seeds and repeats must be >= 1, got {iterations}, {seeds}, {repeats}")
    if replan_runs < 0 or replan_count < 1:
        raise ValueError(f"replan_runs must be >= 0 and replan_count >= 1, got {replan_runs}, {replan_count}")


def _scenario_runs(path: Path, scenario: Scenario, algorithms: list[str], keys: list[str],
                   ompl_sets: list[tuple[str, str]], checker: str, iterations: int, seeds: int, repeats: int,
                   tick: Callable[[str], None]) -> dict:
    """One scenario's entry of ``bench.json``'s ``scenarios``: our planners'
    runs with ``checker``, OMPL's with each of ``ompl_sets`` (for the OMPL
    objectives ``keys``), and each planner's ratios to OMPL's."""
    _make_checker(scenario, checker, path)  # a start or goal in collision: a clear error naming the file
    # Warm-up, untimed: loads (or compiles) the motion-cost kernel and each
    # planner's loop (numba's cache is read on the first call: about 0.15 s
    # that would otherwise land in the first timed run).
    make_objective(scenario, "social_rrt_star").motion_cost(np.array(scenario.start), np.array(scenario.goal))
    for algorithm in algorithms:
        plan(scenario, _make_checker(scenario, checker), algorithm=algorithm, iterations=10, seed=0)
    entry = {"algorithms": {}, "ompl": {}, "ompl_same_checker": {},
             # The planner options that change how paths are made (see PlannerOptions).
             "planner_options": {"near_radius_mode": scenario.planner.near_radius_mode,
                                 "near_radius_gamma": scenario.planner.near_radius_gamma,
                                 "optimize": scenario.planner.optimize}}
    for algorithm in algorithms:
        objective = make_objective(scenario, algorithm)
        runs = []
        for seed in range(seeds):
            chk = _make_checker(scenario, checker)
            (result,), times = _repeated(
                lambda: (plan(scenario, chk, algorithm=algorithm, iterations=iterations, seed=seed),), repeats)
            runs.append({**_record(scenario, result, objective, chk, iterations), "planning_times": times})
            tick(f"{path.stem} {algorithm} seed {seed}")
        entry["algorithms"][algorithm] = {"runs": runs, "summary": summarize(runs)}
    for field, ompl_chk in ompl_sets:
        for key in keys:
            entry[field][key] = _plan_ompl_runs(scenario, key, iterations, seeds, ompl_chk,
                                                lambda label: tick(f"{path.stem} {label} ({ompl_chk})"), repeats)
    for algorithm, data in entry["algorithms"].items():
        for field in ("ompl", "ompl_same_checker"):
            base = entry[field].get(ompl_counterpart(algorithm))
            data[f"vs_{field}"] = None if base is None else {
                "ompl": f"ompl_rrt_star[{ompl_counterpart(algorithm)}]", "ompl_checker": base["checker"],
                **{f: _ratio(data["summary"], base["summary"], g)
                   for f, g in (("time", "planning_time"), ("social_cost", "F_multi"),
                                ("objective", "objective"))},
            }
    return entry


def _other_benches(paths: list[Path], include_checker: bool, sim_runs: int, scaling: bool, checker: str,
                   replan_runs: int, replan_count: int, replan_scenario: str | Path | None, map_bench: bool,
                   iterations: int, tick: Callable[[str], None]) -> dict:
    """The benchmarks :func:`run_bench` was asked for beside the planners'
    (``checker_bench``, ``sim_bench``, ``scaling_bench``, ``replan_bench``,
    ``map_bench``; None where not asked for)."""
    out = {"checker_bench": None, "sim_bench": None, "scaling_bench": None, "replan_bench": None, "map_bench": None}
    if include_checker:
        from drake_social.experiments.bench.checkers import run_checker_bench

        out["checker_bench"] = run_checker_bench(scenario_paths=paths, num_configs=2000, num_edges=200, repeats=1)
        tick("checker bench")
    if sim_runs > 0:
        from drake_social.experiments.bench.execution import run_sim_bench

        out["sim_bench"] = run_sim_bench(scenario_paths=paths, runs=sim_runs, progress=tick)
    if scaling:
        from drake_social.experiments.bench.scaling import run_scaling_bench

        out["scaling_bench"] = run_scaling_bench(scenario_paths=paths, checker=checker, progress=tick)
    if replan_runs > 0:
        from drake_social.experiments.bench.replanning import REPLAN_SCENARIO, run_replan_bench

        out["replan_bench"] = run_replan_bench(REPLAN_SCENARIO if replan_scenario is None else replan_scenario,
                                               count=replan_count, runs=replan_runs, progress=tick)
    if map_bench:
        from drake_social.experiments.bench.maps import run_map_bench

        out["map_bench"] = run_map_bench(paths[0], iterations=iterations, progress=tick)
    return out


def _fmt(s: dict, digits: int = 3) -> str:
    if s["median"] is None:
        return "n/a"
    return f"{s['median']:.{digits}g} [{s['q25']:.{digits}g}, {s['q75']:.{digits}g}]"


def _num(x, fmt: str = ".3g") -> str:
    return "n/a" if x is None else format(x, fmt)


def _machine_line(m: dict) -> list[str]:
    """The processor and the load averages around the run (absolute times
    hold for that processor and load only; ratios in one run are robust)."""
    parts = []
    if m.get("cpu_model"):
        parts.append(f"processor: {m['cpu_model']}")
    for label, key in (("start", "load_average_start"), ("end", "load_average_end")):
        if m.get(key):
            parts.append(f"load average (1, 5, 15 min) at the {label}: " + ", ".join(f"{x:.2f}" for x in m[key]))
    if not parts:
        return []
    line = "; ".join(parts)
    return [line[0].upper() + line[1:] + ".", ""]


def _markdown(out: dict) -> str:
    s, m = out["settings"], out["machine"]
    lines = [
        "# drake-social bench",
        "",
        f"K = {s['iterations']} iterations, seeds 0..{len(s['seeds']) - 1}, checker `{s['checker']}` "
        f"(OMPL: `{s.get('ompl_checker', s['checker'])}`); "
        f"{m['platform']}, {m['cpu_count']} CPUs, numpy {m['numpy']}, drake {m['drake']}, ompl {m['ompl']}.",
        "",
        *_machine_line(m),
        "Planner options (the paper's, set over every scenario file): " + "; ".join(
            f"{name}: near radius {e['planner_options']['near_radius_mode']}, "
            f"optimize {'on' if e['planner_options']['optimize'] else 'off'}"
            for name, e in out["scenarios"].items() if "planner_options" in e) + ".",
        "",
        "Planning time (s, the search alone) over all runs and social cost (F_multi: weight 1 on every interest "
        "point) over successful runs: "
        "median [25th, 75th percentile]"
        + (f"; each run's time is the median of {s.get('repeats', 1)} repeats of it" if s.get("repeats", 1) > 1 else "")
        + ". Ratios: ours / OMPL RRTstar with the same objective, of the medians "
        f"(objective: each planner's own, recomputed from its path); OMPL checks with "
        f"`{s.get('ompl_checker', s['checker'])}`, and where that is not ours also with ours (\"same checks\").",
        "",
        "| scenario | algorithm | runs | success | planning time s | social cost | first solution it. "
        "| time ratio vs OMPL | time ratio vs OMPL, same checks | social cost ratio vs OMPL "
        "| objective ratio vs OMPL |",
        "|---|---|---:|---:|---|---|---:|---:|---:|---:|---:|",
    ]
    for name, entry in out["scenarios"].items():
        rows = [(a, d["summary"], d.get("vs_ompl"), d.get("vs_ompl_same_checker"))
                for a, d in entry["algorithms"].items()]
        rows += [(f"ompl_rrt_star[{k}] ({d.get('checker', s['checker'])})", d["summary"], None, None)
                 for field in ("ompl", "ompl_same_checker") for k, d in entry.get(field, {}).items()]
        for label, sm, vs, same in rows:
            lines.append(
                f"| {Path(name).stem} | {label} | {sm['runs']} | {sm['success_rate']:.0%} | {_fmt(sm['planning_time'])} "
                f"| {_fmt(sm['F_multi'])} | {_num(sm['median_first_solution_iteration'], '.0f')} "
                f"| {_num(vs and vs['time'])} | {_num(same and same['time'])} | {_num(vs and vs['social_cost'])} "
                f"| {_num(vs and vs['objective'])} |"
            )
    ompl_rows = [(name, k, d["settings"]) for name, e in out["scenarios"].items() for k, d in e["ompl"].items()]
    if ompl_rows:
        lines += ["", "OMPL settings (range, radius = min(range, our near radius), rewire factor):", ""]
        seen = set()
        for name, _, st in ompl_rows:
            if name not in seen:
                seen.add(name)
                lines.append(
                    f"- {Path(name).stem}: range {st['planning_range']:g}, radius {st['radius']:.4g} "
                    f"(ours {st['our_near_radius']:g}), rewire factor {st['rewire_factor']:.4g}, "
                    f"goal bias {st['goal_bias']:g}, goal threshold {st['goal_threshold']:.3g}"
                )
    elif out["ompl"]["requested"]:
        lines += ["", "OMPL was not importable: no baseline (install the `bench` extra)."]
    cb = out.get("checker_bench")
    if cb:
        lines += ["", "## Checkers (per second)", "",
                  "| scenario | drake configs (per call) | numpy configs (per call) | drake motions (per call) "
                  "| numpy motions (per call) |", "|---|---:|---:|---:|---:|"]
        for name, r in cb["scenarios"].items():
            c, e = r["configs_per_s"], r["edges_per_s"]
            lines.append(f"| {Path(name).stem} | {c['drake_per_call']:.0f} | {c['numpy_per_call']:.0f} "
                         f"| {e['drake_per_call']:.0f} | {e['numpy_per_call']:.0f} |")
    if cb and all("per_call_us" in r for r in cb["scenarios"].values()):
        lines += ["", "## Checkers, one call (microseconds of CPU, best of the repeats)", "",
                  "| scenario | planar clearance | Drake clearance | planar is_valid | Drake is_valid "
                  "| planar motion | Drake motion | motion speed-up |", "|---|---:|---:|---:|---:|---:|---:|---:|"]
        for name, r in cb["scenarios"].items():
            u = r["per_call_us"]
            lines.append(f"| {Path(name).stem} | {u['planar_clearance']:.1f} | {u['drake_clearance']:.1f} "
                         f"| {u['planar_is_valid']:.1f} | {u['drake_is_valid']:.1f} | {u['planar_motion']:.1f} "
                         f"| {u['drake_motion']:.1f} | {u['drake_motion'] / u['planar_motion']:.0f}x |")
    if out.get("sim_bench"):
        from drake_social.experiments.bench.execution import sim_markdown

        lines += sim_markdown(out["sim_bench"])
    if out.get("scaling_bench"):
        from drake_social.experiments.bench.scaling import markdown as scaling_markdown

        lines += scaling_markdown(out["scaling_bench"])
    if out.get("replan_bench"):
        from drake_social.experiments.bench.replanning import replan_markdown

        lines += replan_markdown(out["replan_bench"])
    if out.get("map_bench"):
        from drake_social.experiments.bench.maps import markdown as map_markdown

        lines += map_markdown(out["map_bench"])
    return "\n".join(lines) + "\n"
