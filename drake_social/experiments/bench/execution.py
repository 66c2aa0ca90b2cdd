"""Execution benchmark: how fast the diagrams simulate, and what they execute.

For each scenario one path is planned (the scenario's algorithm and seed, the
planar checker), then executed in every (mode, execution) pair ``runs``
times without recording and once more recorded to Meshcat and exported as
HTML. Reported per pair: the realtime factor (simulated seconds per wall
second of ``Simulator.AdvanceTo``; median and range over the runs), the same
with recording, the replay's size, the time to goal, the planned and executed
social cost and the largest body-point and configuration deviation.
"""

from __future__ import annotations

import logging
import tempfile
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from drake_social.scenario import EXECUTIONS, SIM_MODES, load_scenario

__all__ = ["run_sim_bench", "sim_markdown"]

_log = logging.getLogger(__name__)


def run_sim_bench(
    *,
    scenario_paths: Sequence[str | Path],
    runs: int = 3,
    modes: Sequence[str] = SIM_MODES,
    executions: Sequence[str] = EXECUTIONS,
    checker: str = "planar",
    record: bool = True,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """Simulates each scenario's planned path in every mode and execution.

    Args:
        scenario_paths: scenario files.
        runs: timed runs per (mode, execution), without recording (>= 1).
        modes, executions: which pairs.
        checker: the planner's checker (see ``drake_social.collision.drake_checker.CHECKERS``).
        record: also time one recorded run and measure its replay size.
        progress: optional ``progress(label)`` after each simulation.

    Returns:
        ``{file name: {"path": {...}, "pairs": {"mode/execution": {...}}}}``.
    """
    from drake_social.collision.drake_checker import make_checker
    from drake_social.planning.algorithms import plan
    from drake_social.sim.replay import draw_overlays, make_meshcat, set_top_view, write_replay_html
    from drake_social.sim.run import simulate

    if runs < 1:
        raise ValueError(f"runs must be >= 1, got {runs}")
    out = {}
    for path in map(Path, scenario_paths):
        scenario = load_scenario(path)
        planning_checker = make_checker(scenario, checker, source=str(path))
        result = plan(scenario, planning_checker)
        if not result.success:
            out[path.name] = {"path": {"success": False, "message": result.message}, "pairs": {}}
            continue
        waypoints = result.waypoints
        pairs = {}
        for mode in modes:
            for execution in executions:
                factors = []
                for i in range(runs):  # the first run is also analysed
                    run = simulate(scenario, mode=mode, execution=execution, waypoints=waypoints,
                                   checker=planning_checker, analyze=i == 0)
                    factors.append(run.realtime_factor)
                    if i == 0:
                        report, reached, time_to_goal = run.report, run.reached, run.time_to_goal
                    if progress:
                        progress(f"{path.stem} {mode}/{execution}")
                entry = {
                    "reached": reached,
                    "time_to_goal": time_to_goal,
                    "realtime_factor": {"median": float(np.median(factors)), "min": float(np.min(factors)),
                                        "max": float(np.max(factors)), "n": len(factors)},
                    "planned_social_cost": report.planned_social_cost,
                    "executed_social_cost": report.executed_social_cost,
                    "max_point_deviation": report.max_point_deviation["max"],
                    "max_config_deviation": report.max_config_deviation,
                    "min_clearance": report.min_clearance,
                    "collision_free": report.collision_free,
                    "within_limits": report.within_limits,
                }
                if record:
                    meshcat = make_meshcat()
                    run = simulate(scenario, mode=mode, execution=execution, waypoints=waypoints, meshcat=meshcat,
                                   checker=planning_checker, analyze=False)
                    draw_overlays(meshcat, scenario, waypoints)
                    fit = set_top_view(meshcat, scenario)
                    with tempfile.TemporaryDirectory() as folder:
                        size = write_replay_html(meshcat, Path(folder) / "replay.html", fit=fit)
                    entry["recorded_realtime_factor"] = run.realtime_factor
                    entry["replay_bytes"] = size
                    if progress:
                        progress(f"{path.stem} {mode}/{execution} recorded")
                pairs[f"{mode}/{execution}"] = entry
        out[path.name] = {
            "path": {"success": True, "algorithm": result.algorithm, "seed": result.seed,
                     "waypoints": int(len(waypoints)), "base_length": result.base_length},
            "pairs": pairs,
        }
    return out


def sim_markdown(sim: dict) -> list[str]:
    """The Markdown lines of the execution section of ``bench.md``."""
    lines = ["", "## Execution (Simulator)", "",
             "Realtime factor: simulated seconds per wall second of `Simulator.AdvanceTo` (median [min, max] "
             "over the runs without recording; one recorded run beside it).", ""]
    for name, entry in sim.items():
        p = entry["path"]
        if not p["success"]:
            lines += [f"### {name}: no path ({p['message']})", ""]
            continue
        lines += [f"### {name} ({p['algorithm']}, seed {p['seed']}, {p['waypoints']} waypoints, "
                  f"base path {p['base_length']:.2f} m)", "",
                  "| mode / execution | realtime factor | recorded | replay MB | time to goal s | "
                  "social cost planned / executed | max point deviation m | max C-space deviation | "
                  "min clearance m | collision-free |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for pair, e in entry["pairs"].items():
            rf = e["realtime_factor"]
            recorded = f"{e['recorded_realtime_factor']:.0f}x" if "recorded_realtime_factor" in e else "n/a"
            size = f"{e['replay_bytes'] / 1e6:.2f}" if "replay_bytes" in e else "n/a"
            ttg = "not reached" if e["time_to_goal"] is None else f"{e['time_to_goal']:.1f}"
            lines.append(
                f"| {pair} | {rf['median']:.0f}x [{rf['min']:.0f}, {rf['max']:.0f}] | {recorded} | {size} | {ttg} | "
                f"{e['planned_social_cost']:.4g} / {e['executed_social_cost']:.4g} | "
                f"{e['max_point_deviation']:.2g} | {e['max_config_deviation']:.2g} | {e['min_clearance']:.3f} | "
                f"{'yes' if e['collision_free'] else 'NO'} |")
        lines.append("")
    return lines
