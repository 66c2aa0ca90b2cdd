"""``drake-social bench --map``: a real-size building map, measured.

A 30 x 50 m office floor at 0.03 m (1,000 x 1,667 = 1.67 million cells) is
generated (:func:`drake_social.maps.office_floor_layout`, seeded), its walls'
edges roughened as a SLAM map's are (:func:`drake_social.maps.ragged_edges`,
thousands of boxes), and written as a map_server map into a temporary
folder with a scenario around it: the bar carried from the bottom of the
west corridor to the far end of the top corridor (about 70 m), past people
standing in the corridors. Measured, in one run:

* **load**: :func:`~drake_social.maps.read_map` plus
  :func:`~drake_social.maps.map_boxes`, the median of ``load_repeats``;
* **checker**: building the planar checker of the scenario (its shapes read
  from SceneGraph);
* **plan**: Social Risk-RRT* at K = ``iterations`` on the map and on a
  scenario to compare with (``bench --map``: the first ``--scenarios`` file,
  by default the shipped ``office_bar.yaml``), ``seeds`` seeds each,
  alternating; the ratio of the median times;
* **replay**: the planned path executed (kinematic, synchronized) and
  recorded; the replay's bytes and the run's simulated seconds.

Targets of issue 22: load under 2 s, the plan-time ratio under 2, the
replay of a 2-minute run under 10 MB. Nothing is asserted about time.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Callable

import numpy as np

from drake_social.maps import map_boxes, office_floor_layout, ragged_edges, read_map, write_map
from drake_social.scenario import load_scenario

__all__ = ["MAP_BENCH_SEED", "map_bench_scenario", "markdown", "run_map_bench"]

#: The generated floor's seed.
MAP_BENCH_SEED = 30
#: Probability of a wall edge's cell flipping (:func:`ragged_edges`).
RAGGED = 0.1


def map_bench_scenario(folder: str | Path, *, width: float = 30.0, height: float = 50.0,
                       resolution: float = 0.03, seed: int = MAP_BENCH_SEED) -> Path:
    """Writes the bench's floor (``floor.pgm``, ``floor.yaml``) and its
    scenario (``floor_scenario.yaml``) into ``folder``; returns the scenario."""
    folder = Path(folder)
    rng = np.random.default_rng(seed)
    layout = office_floor_layout(width, height, resolution, rng)
    image = ragged_edges(layout.image(), rng, RAGGED)
    write_map(folder, "floor", image, resolution)
    spine, *corridors = layout.corridors
    sx = 0.5 * (spine[0] + spine[2])
    top = corridors[-1]
    gy = 0.5 * (top[1] + top[3])
    people = []
    for k, (x0, y0, x1, y1) in enumerate(corridors):
        for f in (0.35, 0.7):  # against the corridor's lower wall, facing across it
            people.append(f"  - {{x: {x0 + f * (x1 - x0):.3f}, y: {y0 + 0.6:.3f}, theta: 1.5708, radius: 0.25, "
                          f"name: \"corridor {k} {f}\"}}")
    text = "\n".join([
        f"description: \"bench floor: {width:g} x {height:g} m at {resolution:g} m, ragged walls\"",
        "world: {map: floor.yaml}",
        "people:", *people,
        "robot: {base_radius: 0.35, link_lengths: [0.6, 0.5], link_width: 0.08}",
        "object: !Bar {length: 1.5, thickness: 0.05}",
        f"start: [{sx:.3f}, {spine[1] + 1.5:.3f}, -1.2292, 2.8]",
        f"goal: [{top[2] - 1.5:.3f}, {gy:.3f}, -1.2292, 2.8]",
        "random_seed: 0",
        "planner: {planning_range: 2.5, near_radius: 3.0}",
        "execution: {time_limit: 600.0}",
        "",
    ])
    path = folder / "floor_scenario.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def _plan_time(scenario, checker, iterations: int, seed: int) -> dict:
    from drake_social.planning.algorithms import plan

    r = plan(scenario, checker, algorithm="social_rrt_star", iterations=iterations, seed=seed)
    return {"seed": seed, "planning_time": float(r.wall_time), "optimize_time": float(r.optimize_time),
            "success": bool(r.success), "cost": float(r.cost) if r.success else None,
            "base_length": float(r.base_length) if r.success else None, "waypoints": r.waypoints}


def run_map_bench(office_path: str | Path, *, iterations: int = 2000, seeds: int = 3, load_repeats: int = 5,
                  replay: bool = True, size: tuple[float, float] = (30.0, 50.0), resolution: float = 0.03,
                  progress: Callable[[str], None] | None = None) -> dict:
    """Measures the floor map (module docstring) against the scenario ``office_path``.

    ``size`` (width, height, metres) and ``resolution`` make a smaller floor
    for tests; the defaults are the issue's.

    Args:
        office_path: the scenario file whose plan time the map's is compared with.

    Returns:
        ``{"map": {...cells, boxes, load times}, "checker_seconds",
        "plan": {"map": runs, "office": runs, "office_scenario": its file name, "ratio"},
        "replay": {...} or None}``.
    """
    from drake_social.collision.drake_checker import make_checker
    from drake_social.people import people_model
    from drake_social.world import world_model

    tick = progress or (lambda label: None)
    with tempfile.TemporaryDirectory(prefix="drake_social_map_bench_") as folder:
        path = map_bench_scenario(folder, width=size[0], height=size[1], resolution=resolution)
        loads = []
        for _ in range(load_repeats):
            t0 = time.perf_counter()
            grid = read_map(Path(folder) / "floor.yaml")
            boxes = map_boxes(grid)
            loads.append(time.perf_counter() - t0)
        tick("map loaded")
        scenario = load_scenario(path)
        office = load_scenario(office_path)
        t0 = time.perf_counter()
        checker = make_checker(scenario, "planar", parallelism=1)
        checker_seconds = time.perf_counter() - t0
        office_checker = make_checker(office, "planar", parallelism=1)
        tick("checkers built")
        runs = {"map": [], "office": []}
        for seed in range(seeds):
            runs["map"].append(_plan_time(scenario, checker, iterations, seed))
            runs["office"].append(_plan_time(office, office_checker, iterations, seed))
            tick(f"plans seed {seed}")
        median = {k: float(np.median([r["planning_time"] for r in v])) for k, v in runs.items()}
        replay_entry = None
        ok = [r for r in runs["map"] if r["success"]]
        if replay and ok:
            replay_entry = _replay(scenario, checker, ok[0]["waypoints"])
            tick("replay recorded")
        for v in runs.values():
            for r in v:
                r.pop("waypoints")
        return {
            "map": {"width_m": grid.width_m, "height_m": grid.height_m, "resolution": grid.resolution,
                    "cells": int(grid.values.size), "boxes": len(boxes.yaws),
                    "boxes_in_world": world_model(scenario).map_box_count,
                    "load_seconds": {"median": float(np.median(loads)), "max": float(np.max(loads)),
                                     "n": len(loads)},
                    "people": people_model(scenario).state_at(0.0).count},
            "checker_seconds": checker_seconds,
            "plan": {"iterations": iterations, "map": runs["map"], "office": runs["office"],
                     "office_scenario": Path(office_path).name,
                     "median_map": median["map"], "median_office": median["office"],
                     "ratio": median["map"] / median["office"] if median["office"] > 0 else None},
            "replay": replay_entry,
        }


def _replay(scenario, checker, waypoints) -> dict:
    from drake_social.sim.replay import draw_overlays, make_meshcat, set_top_view, write_replay_html
    from drake_social.sim.run import simulate

    meshcat = make_meshcat()
    run = simulate(scenario, mode="kinematic", execution="synchronized", waypoints=waypoints, meshcat=meshcat,
                   checker=checker, analyze=False)
    draw_overlays(meshcat, scenario, waypoints)
    fit = set_top_view(meshcat, scenario)
    with tempfile.TemporaryDirectory() as folder:
        size = write_replay_html(meshcat, Path(folder) / "replay.html", fit=fit)
    return {"bytes": size, "simulated_seconds": float(run.time_to_goal) if run.reached else None,
            "reached": bool(run.reached), "realtime_factor": float(run.realtime_factor)}


def markdown(out: dict) -> list[str]:
    """The Markdown lines of the map section of ``bench.md``."""
    m, p, r = out["map"], out["plan"], out["replay"]
    office = Path(p["office_scenario"]).stem
    lines = ["", "## A building map (bench --map)", "",
             f"A generated {m['width_m']:g} x {m['height_m']:g} m office floor at {m['resolution']:g} m "
             f"({m['cells']:,} cells, ragged walls): {m['boxes']:,} boxes, {m['people']} people.", "",
             "| measurement | value | target |", "|---|---|---|",
             f"| read + boxes (median of {m['load_seconds']['n']}) | {m['load_seconds']['median']:.3f} s | < 2 s |",
             f"| planar checker built | {out['checker_seconds']:.2f} s | |",
             f"| plan K = {p['iterations']}, map (median of {len(p['map'])}; paths found "
             f"{sum(r['success'] for r in p['map'])}) | {p['median_map']:.3f} s | |",
             f"| plan K = {p['iterations']}, {office} (median of {len(p['office'])}; paths found "
             f"{sum(r['success'] for r in p['office'])}) | {p['median_office']:.3f} s | |",
             f"| ratio map / office | {p['ratio']:.2f} | < 2 |"]
    if r is not None:
        secs = "not reached" if r["simulated_seconds"] is None else f"{r['simulated_seconds']:.0f} s run"
        lines.append(f"| replay ({secs}) | {r['bytes'] / 1e6:.2f} MB | < 10 MB (2-minute run) |")
    lines.append("")
    return lines
