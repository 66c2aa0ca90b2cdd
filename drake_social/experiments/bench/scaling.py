"""``drake-social bench --scaling``: how the planner's time and cost grow with the work.

Three measurements per scenario, all with the scenario's own checker kind and
the compiled loop:

* **K scaling**: one plan per K in ``ks`` with the shrinking near radius
  (``planner.near_radius_mode: shrinking``, OMPL's gamma), its wall time,
  tree size and cost evaluations per iteration, and the exponent ``b`` of
  ``time ~ K^b`` fitted (least squares on the logarithms) over the K from
  ``2000`` on.
* **Optimisation against many samples**: K = 2000 with ``planner.optimize``
  over ``seeds`` seeds (the scenario's radius), its median cost against the
  median cost of ``reference_seeds`` runs of ``reference_k`` samples with the
  shrinking radius and no optimisation (the first of them is the K scaling's
  run at that K when ``reference_k`` is in ``ks``).
* **People far away**: ``far_people`` extra people in a row 10 m beyond the
  scenario's east wall (outside the room, so that no sample, motion or
  social term can touch them, which keeps the tree the same), in the checker
  (their body discs, read from the SceneGraph like every shape) and in the
  social cost. The same K = 2000 plans with and without them, alternating,
  ``far_repeats`` times over the seeds: the trees must be identical, and
  the ratio of the median times is what the far people cost.
* **Obstacle count**: the scenario with ``n`` extra boxes in a field 10 m
  beyond its east wall (:func:`far_boxes_scenario`; in the checker, read from
  the SceneGraph like every shape, but out of every sample's and motion's
  reach), per ``n`` in ``obstacle_counts``: the checker's construction time
  and the median time of ``seeds`` K = ``obstacle_iterations`` plans (the
  counts alternating, ``obstacle_repeats`` times), their ratios to the first
  count, and whether every tree is the one of the first count (the
  broadphase must change no answer); with the planar checker also the
  kernel's microseconds per clearance, validity and motion check, with its
  grid and over every shape, and whether they answer alike (:func:`kernel_times`).

Wall times are of the search in ``RrtStar.solve`` (with ``planner.optimize``
the optimiser's time is ``optimize_time``); ratios are of medians in the same run.
Nothing is asserted about time.
"""

from __future__ import annotations

import copy
import dataclasses as dc
import math
import time
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from drake_social.collision.drake_checker import make_checker
from drake_social.collision.validity import CompiledSceneChecker
from drake_social.people import with_people
from drake_social.planning.algorithms import make_planner, plan
from drake_social.scenario import Box, Person, Scenario, load_scenario
from drake_social.world import with_obstacles

__all__ = ["far_boxes_scenario", "far_people_scenario", "fit_exponent", "kernel_times", "run_scaling_bench"]


def fit_exponent(ks: Sequence[int], times: Sequence[float]) -> float | None:
    """b of ``time = a K^b``, least squares on log time against log K (None with fewer than two K)."""
    k, t = np.log(np.asarray(ks, float)), np.log(np.asarray(times, float))
    if len(k) < 2 or np.ptp(k) == 0:
        return None
    return float(np.polyfit(k, t, 1)[0])


def far_people_scenario(scenario: Scenario, count: int, gap: float = 10.0) -> Scenario:
    """``scenario`` with ``count`` people in a row ``gap`` metres beyond its
    east wall, 1 m apart (their own room: outside the planner's bounds).
    Not validated (people outside the bounds are not allowed in a scenario
    file); for measurements only."""
    x0, y0, x1, y1 = scenario.world.bounds
    rows = max(1, int(y1 - y0))
    extra = [Person(x=x1 + gap + (i // rows), y=y0 + 0.5 + (i % rows), theta=math.pi * (i % 3) / 3,
                    radius=0.25, name=f"far {i}") for i in range(count)]
    return with_people(scenario, extra)


def far_boxes_scenario(scenario: Scenario, count: int, gap: float = 10.0) -> Scenario:
    """``scenario`` with ``count`` extra obstacles, 0.4 x 0.3 m boxes at five
    yaws, in a field of 1 m pitch starting ``gap`` metres beyond its east
    wall (outside the planner's bounds, as many rows as the room is high).
    Built in Python (10,000 boxes exceed the YAML loader's node limit); not
    validated (obstacles outside the bounds); for measurements only."""
    x0, y0, x1, y1 = scenario.world.bounds
    rows = max(1, int(y1 - y0))
    extra = [Box(center=[x1 + gap + (i // rows), y0 + 0.5 + (i % rows)], size=[0.4, 0.3], yaw=0.3 * (i % 5))
             for i in range(count)]
    return with_obstacles(scenario, extra)


def kernel_times(checker, count: int = 2000, repeats: int = 3) -> dict:
    """Microseconds per configuration (per motion) of the planar kernel's
    clearance, validity and motion checks with the checker's grid and over
    every shape (``*_plain``), the best of ``repeats``, on ``count`` seeded
    configurations in the limits and motions to within 0.3 of them; and
    whether the two give the same answers (``same``)."""
    from drake_social.collision import planar_kernel as pk

    lower, upper, bodies, robot, env, levers, grid = checker.compiled_scene()
    rng = np.random.default_rng(0)
    qa = rng.uniform(lower, upper, (count, 4))
    qb = np.clip(qa + rng.uniform(-0.3, 0.3, (count, 4)), lower, upper)
    calls = {
        "clearance": (lambda: pk.clearances(qa, bodies, robot, env, grid),
                      lambda: pk.clearances_plain(qa, bodies, robot, env)),
        "valid": (lambda: pk.valid(qa, lower, upper, bodies, robot, env, grid),
                  lambda: pk.valid_plain(qa, lower, upper, bodies, robot, env)),
        "motion": (lambda: pk.motions_valid(qa, qb, lower, upper, bodies, robot, env, grid, levers),
                   lambda: pk.motions_valid_plain(qa, qb, lower, upper, bodies, robot, env, grid, levers)),
    }
    out, same = {}, True
    for name, (with_grid, plain) in calls.items():
        answers = []
        for label, fn in (("grid", with_grid), ("plain", plain)):
            answers.append(fn())  # also the warm-up
            best = min(_timed(fn) for _ in range(repeats))
            out[f"{name}_{label}"] = 1e6 * best / count
        same &= bool(np.array_equal(answers[0], answers[1]))
    out["same"] = same
    return out


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def _obstacle_scaling(scenario: Scenario, checker: str, algorithm: str, counts: Sequence[int], iterations: int,
                      seeds: int, repeats: int, tick: Callable[[str], None], label: str) -> dict:
    """The obstacle-count measurement of the module docstring."""
    start, goal = np.asarray(scenario.start, float), np.asarray(scenario.goal, float)
    rows, planners = [], []
    for n in counts:
        s = far_boxes_scenario(scenario, n)
        s.planner = dc.replace(s.planner, iterations=iterations)
        t0 = time.perf_counter()
        c = make_checker(s, checker, parallelism=1)
        build = time.perf_counter() - t0
        planners.append(make_planner(s, c, algorithm))
        planners[-1].solve(start, goal, np.random.default_rng(0))  # warm-up, untimed
        rows.append({"extra_boxes": int(n), "environment_shapes": int(len(getattr(c, "env", ()))),
                     "construction_time": build, "times": [],
                     "kernel_us": kernel_times(c) if isinstance(c, CompiledSceneChecker) else None})
        tick(f"{label} {n} extra boxes: checker built in {build:.2f} s")
    same = True
    for _ in range(repeats):
        for seed in range(seeds):
            first = None
            for row, p in zip(rows, planners):
                r = p.solve(start, goal, np.random.default_rng(seed))
                row["times"].append(r.wall_time)
                if first is None:
                    first = r
                else:
                    same &= bool(np.array_equal(first.tree_nodes, r.tree_nodes)
                                 and np.array_equal(first.tree_parents, r.tree_parents) and first.cost == r.cost)
        tick(f"{label} obstacle counts, {seeds} seeds")
    for row in rows:
        row["median_time"] = _median(row["times"])
        row["time_ratio"] = row["median_time"] / rows[0]["median_time"] if rows[0]["median_time"] else None
        row["construction_ratio"] = row["construction_time"] / rows[0]["construction_time"]
    return {"iterations": iterations, "seeds": seeds, "repeats": repeats, "rows": rows, "same_trees": same}


def _plan(scenario: Scenario, checker_kind: str, algorithm: str, iterations: int, seed: int, **planner) -> dict:
    s = copy.deepcopy(scenario)
    s.planner = dc.replace(s.planner, **planner)
    checker = make_checker(s, checker_kind, parallelism=1)
    r = plan(s, checker, algorithm=algorithm, iterations=iterations, seed=seed)
    return {"iterations": iterations, "seed": seed, "planning_time": float(r.wall_time),
            "optimize_time": float(r.optimize_time), "success": bool(r.success),
            "cost": float(r.cost) if r.success else None, "raw_cost": float(r.raw_cost) if r.success else None,
            "tree_size": int(r.tree_size), "cost_evaluations_per_iteration": r.num_cost_evaluations / iterations,
            "motion_checks": int(r.num_motion_checks), "optimized": bool(getattr(r, "optimized", False))}


def _median(values) -> float | None:
    v = [x for x in values if x is not None]
    return float(np.median(v)) if v else None


def run_scaling_bench(
    *,
    scenario_paths: Sequence[str | Path],
    algorithm: str = "social_rrt_star",
    checker: str = "planar",
    ks: Sequence[int] = (2000, 5000, 20000, 50000),
    reference_k: int = 50000,
    reference_seeds: int = 3,
    seeds: int = 5,
    far_people: int = 50,
    far_repeats: int = 3,
    obstacle_counts: Sequence[int] = (10, 100, 1000, 10000),
    obstacle_iterations: int = 2000,
    obstacle_repeats: int = 1,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """The four measurements of the module docstring, per scenario.

    Returns:
        ``{"settings", "scenarios": {file name: {"scaling", "optimized",
        "far_people", "obstacles"}}}``; see the module docstring
        (``"obstacles"`` is left out when ``obstacle_counts`` is empty).
    """
    tick = progress or (lambda label: None)
    out = {"settings": {"algorithm": algorithm, "checker": checker, "ks": list(ks), "reference_k": reference_k,
                        "reference_seeds": reference_seeds, "seeds": seeds, "far_people": far_people,
                        "far_repeats": far_repeats, "obstacle_counts": list(obstacle_counts),
                        "obstacle_iterations": obstacle_iterations, "obstacle_repeats": obstacle_repeats},
           "scenarios": {}}
    for path in map(Path, scenario_paths):
        scenario = load_scenario(path)
        plan(scenario, make_checker(scenario, checker, parallelism=1), algorithm=algorithm, iterations=50,
             seed=0)  # warm-up (loads the compiled kernels)
        entry = {}
        # ---- K scaling, shrinking radius
        runs = []
        for k in ks:
            runs.append(_plan(scenario, checker, algorithm, k, 0, near_radius_mode="shrinking", optimize=False))
            tick(f"{path.stem} K = {k} (shrinking radius)")
        big = [(r["iterations"], r["planning_time"]) for r in runs if r["iterations"] >= 2000]
        entry["scaling"] = {"near_radius_mode": "shrinking", "runs": runs,
                            "exponent": fit_exponent(*zip(*big)) if len(big) >= 2 else None}
        # ---- optimisation at K = 2000 against the reference K
        reference = [r for r in runs if r["iterations"] == reference_k][:1]
        for seed in range(len(reference), reference_seeds):
            reference.append(_plan(scenario, checker, algorithm, reference_k, seed, near_radius_mode="shrinking",
                                   optimize=False))
            tick(f"{path.stem} reference K = {reference_k} seed {seed}")
        optimized = []
        for seed in range(seeds):
            optimized.append(_plan(scenario, checker, algorithm, 2000, seed, optimize=True))
            tick(f"{path.stem} K = 2000 optimised seed {seed}")
        ref_median = _median(r["cost"] for r in reference)
        opt_median = _median(r["cost"] for r in optimized)
        raw_median = _median(r["raw_cost"] for r in optimized)
        entry["optimized"] = {
            "reference": reference, "runs": optimized, "reference_median_cost": ref_median,
            "median_cost": opt_median, "median_raw_cost": raw_median,
            "ratio_to_reference": None if not (ref_median and opt_median is not None) else opt_median / ref_median,
            "raw_ratio_to_reference": None if not (ref_median and raw_median is not None) else raw_median / ref_median,
        }
        # ---- far people: the same plans with and without them, alternating
        far = far_people_scenario(scenario, far_people)
        k2000 = []
        for s in (scenario, far):
            s = copy.deepcopy(s)
            s.planner = dc.replace(s.planner, iterations=2000)
            k2000.append(s)
        planners = [make_planner(s, make_checker(s, checker, parallelism=1), algorithm) for s in k2000]
        start, goal = np.asarray(scenario.start, float), np.asarray(scenario.goal, float)
        for p in planners:  # warm-up, untimed
            p.solve(start, goal, np.random.default_rng(0))
        times, same = ([], []), True
        for _ in range(far_repeats):
            for seed in range(seeds):
                a, b = (p.solve(start, goal, np.random.default_rng(seed)) for p in planners)
                same &= bool(np.array_equal(a.tree_nodes, b.tree_nodes) and np.array_equal(a.tree_parents, b.tree_parents)
                             and a.cost == b.cost)
                times[0].append(a.wall_time)
                times[1].append(b.wall_time)
            tick(f"{path.stem} far people, {seeds} seeds")
        t0, t1 = _median(times[0]), _median(times[1])
        entry["far_people"] = {"count": far_people, "repeats": far_repeats, "times_without": times[0],
                               "times_with": times[1], "same_trees": same, "median_time_without": t0,
                               "median_time_with": t1, "time_ratio": t1 / t0 if t0 else None}
        # ---- obstacle count: the same plans with more and more far boxes
        if len(obstacle_counts):
            entry["obstacles"] = _obstacle_scaling(scenario, checker, algorithm, obstacle_counts, obstacle_iterations,
                                                   seeds, obstacle_repeats, tick, path.stem)
        out["scenarios"][path.name] = entry
    return out


def _us(row: dict, name: str) -> str:
    """A row's kernel time ``grid / all shapes`` (and "differ" when the answers did), "n/a" without."""
    k = row.get("kernel_us")
    if not k:
        return "n/a"
    return f"{k[name + '_grid']:.3g} / {k[name + '_plain']:.3g}" + ("" if k["same"] else " (answers differ)")


def markdown(out: dict) -> list[str]:
    """The scaling section of bench.md."""
    s = out["settings"]
    lines = ["", f"## Scaling ({s['algorithm']}, checker `{s['checker']}`)", "",
             "Time against K with the shrinking near radius (seed 0), and the exponent b of time ~ K^b fitted "
             "from K = 2000 on:", "",
             "| scenario | " + " | ".join(f"K = {k}" for k in s["ks"]) + " | b |",
             "|---|" + "---:|" * (len(s["ks"]) + 1)]
    for name, e in out["scenarios"].items():
        cells = [f"{r['planning_time']:.3g} s ({r['cost_evaluations_per_iteration']:.0f} costs/it.)"
                 for r in e["scaling"]["runs"]]
        b = e["scaling"]["exponent"]
        lines.append(f"| {Path(name).stem} | " + " | ".join(cells) + f" | {'n/a' if b is None else f'{b:.2f}'} |")
    lines += ["", f"Cost at K = 2000 with `planner.optimize` (median of {s['seeds']} seeds) against the median of "
                  f"{s['reference_seeds']} runs of K = {s['reference_k']} (shrinking radius, no optimisation):", "",
              "| scenario | K = 2000 raw | K = 2000 optimised | reference | optimised / reference "
              "| raw / reference |", "|---|---:|---:|---:|---:|---:|"]
    fmt = lambda x, f=".4g": "n/a" if x is None else format(x, f)  # noqa: E731
    for name, e in out["scenarios"].items():
        o = e["optimized"]
        lines.append(f"| {Path(name).stem} | {fmt(o['median_raw_cost'])} | {fmt(o['median_cost'])} "
                     f"| {fmt(o['reference_median_cost'])} | {fmt(o['ratio_to_reference'], '.3f')} "
                     f"| {fmt(o['raw_ratio_to_reference'], '.3f')} |")
    lines += ["", f"{s['far_people']} people 10 m beyond the east wall, in the checker and the cost (median of "
                  f"{s['seeds']} seeds x {s['far_repeats']} K = 2000 plans with and without them, alternating):", "",
              "| scenario | without s | with s | ratio | same trees |", "|---|---:|---:|---:|---|"]
    for name, e in out["scenarios"].items():
        f_ = e["far_people"]
        lines.append(f"| {Path(name).stem} | {fmt(f_['median_time_without'], '.3g')} "
                     f"| {fmt(f_['median_time_with'], '.3g')} | {fmt(f_['time_ratio'], '.3f')} "
                     f"| {'yes' if f_['same_trees'] else 'no'} |")
    if any("obstacles" in e for e in out["scenarios"].values()):
        lines += ["", f"Extra boxes 10 m beyond the east wall, in the checker (construction time, and the median of "
                      f"{s['seeds']} seeds x {s.get('obstacle_repeats', 1)} K = {s.get('obstacle_iterations', 2000)} "
                      f"plans; ratios to the first row):", "",
                  "| scenario | extra boxes | shapes | construction s | plan s | plan ratio | construction ratio "
                  "| same trees | clearance us, grid / all shapes | motion us, grid / all shapes |",
                  "|---|---:|---:|---:|---:|---:|---:|---|---:|---:|"]
        for name, e in out["scenarios"].items():
            if "obstacles" not in e:
                continue
            o = e["obstacles"]
            for row in o["rows"]:
                lines.append(f"| {Path(name).stem} | {row['extra_boxes']} | {row['environment_shapes']} "
                             f"| {row['construction_time']:.3g} | {fmt(row['median_time'], '.3g')} "
                             f"| {fmt(row['time_ratio'], '.3f')} | {row['construction_ratio']:.3g} "
                             f"| {'yes' if o['same_trees'] else 'no'} | {_us(row, 'clearance')} "
                             f"| {_us(row, 'motion')} |")
    return lines
