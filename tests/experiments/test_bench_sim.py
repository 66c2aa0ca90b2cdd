"""The execution benchmark on tiny.yaml: its figures are those of simulate()."""

from __future__ import annotations

import pytest

from drake_social.experiments.bench.execution import run_sim_bench, sim_markdown
from drake_social.collision.drake_checker import make_checker
from drake_social.planning.algorithms import plan
from drake_social.sim.run import simulate

# Simulation benchmark runs in Drake's Simulator.
pytestmark = pytest.mark.slow


def test_sim_bench_reports_what_simulate_measures(tiny_scenario_path, tiny_scenario):
    labels = []
    dut = run_sim_bench(scenario_paths=[tiny_scenario_path], runs=2, modes=["kinematic"],
                        executions=["synchronized", "paper"], progress=labels.append)
    entry = dut["tiny.yaml"]
    assert entry["path"]["success"]
    assert sorted(entry["pairs"]) == ["kinematic/paper", "kinematic/synchronized"]
    assert labels.count("tiny kinematic/paper") == 2 and labels.count("tiny kinematic/paper recorded") == 1
    # The bench's path is the planner's, and its figures are simulate()'s on that path.
    path = plan(tiny_scenario, make_checker(tiny_scenario, "planar")).waypoints
    for pair, e in entry["pairs"].items():
        mode, execution = pair.split("/")
        run = simulate(tiny_scenario, mode=mode, execution=execution, waypoints=path)
        assert e["time_to_goal"] == run.time_to_goal
        assert e["executed_social_cost"] == pytest.approx(run.report.executed_social_cost, rel=1e-12)
        assert e["max_point_deviation"] == pytest.approx(run.report.max_point_deviation["max"], rel=1e-9, abs=1e-12)
        assert e["realtime_factor"]["n"] == 2
        assert e["realtime_factor"]["min"] <= e["realtime_factor"]["median"] <= e["realtime_factor"]["max"]
        assert 2e6 < e["replay_bytes"] < 5e6
    text = "\n".join(sim_markdown(dut))
    assert "| kinematic/synchronized |" in text and "| kinematic/paper |" in text
