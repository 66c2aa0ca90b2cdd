"""drake-social plan and bench: outputs, exit codes, progress bar, argument wiring."""

from __future__ import annotations

import io
import json
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from drake_social.cli import EXIT_NO_PATH, ProgressBar, build_parser, main
from drake_social.collision.geometric import GeometricChecker
from drake_social.planning.algorithms import evaluate_path, make_objective, plan
from drake_social.scenario import ALGORITHMS, load_scenario

SCENARIO_DIR = Path(__file__).resolve().parent.parent / "scenarios"
TINY = SCENARIO_DIR / "tiny.yaml"
OUTPUTS = ("path.csv", "result.json", "path.png", "cost_profile.png", "convergence.png")

# tiny.yaml with a full-height wall at x = 5.2 between the start (x = 1) and the goal (x = 6.5).
WALLED = """\
description: "tiny with the goal walled off"
world:
  bounds: [0.0, 0.0, 8.0, 5.0]
  obstacles:
    - {center: [4.0, 0.6], size: [1.6, 0.8]}
    - {center: [5.2, 2.5], size: [0.2, 5.0]}
people:
  - {x: 4.0, y: 3.8, theta: -1.5708, radius: 0.25}
object: !Bar {length: 1.5, thickness: 0.05}
start: [1.0, 2.5, 0.0, 1.5708]
goal: [6.5, 2.5, 0.0, 1.5708]
random_seed: 1
"""


def _read_csv(path: Path) -> np.ndarray:
    lines = path.read_text().splitlines()
    assert lines[0] == "x,y,psi1,psi2"
    return np.array([[float(v) for v in line.split(",")] for line in lines[1:]]).reshape(-1, 4)


@pytest.mark.slow
def test_plan_tiny_writes_a_path_from_start_to_goal(tmp_path, capsys):
    out = tmp_path / "tiny"
    assert main(["plan", str(TINY), "--iterations", "300", "--checker", "numpy", "--out", str(out)]) == 0
    stdout = capsys.readouterr().out.splitlines()
    scenario = load_scenario(TINY)
    expected = plan(scenario, GeometricChecker(scenario), iterations=300)  # the file's algorithm and seed
    assert stdout[0].startswith("social_rrt_star: ") and "waypoints" in stdout[0]
    assert stdout[0][: stdout[0].rindex(",")] == expected.summary()[: expected.summary().rindex(",")]  # wall time differs
    assert stdout[1] == f"wrote {out}/: " + ", ".join(OUTPUTS)
    for name in OUTPUTS:
        assert (out / name).stat().st_size > 0

    dut = _read_csv(out / "path.csv")
    assert np.array_equal(dut[0], scenario.start) and np.array_equal(dut[-1], scenario.goal)
    assert np.array_equal(dut, expected.waypoints)  # 17 significant digits: an exact round trip
    record = json.loads((out / "result.json").read_text())
    assert record["success"] is True
    assert record["scenario"] == str(TINY) and record["algorithm"] == "social_rrt_star"
    assert record["seed"] == 1 and record["iterations"] == 300 and record["checker"] == "numpy"
    assert np.array_equal(np.array(record["waypoints"]), dut)
    assert len(record["cost_history"]) == 300 and record["cost_history"][-1] == pytest.approx(record["cost"])
    # The costs in the file are those of the written waypoints, recomputed independently.
    parts = evaluate_path(scenario, dut, make_objective(scenario, "social_rrt_star"))
    assert record["F_multi"] == pytest.approx(parts["social_cost_full"], rel=1e-12)
    assert record["cost"] == pytest.approx(parts["objective"], rel=1e-9)
    assert record["base_length"] == pytest.approx(parts["base_length"], rel=1e-12)


@pytest.mark.slow
def test_algorithm_and_seed_options_reach_the_planner(tmp_path, capsys):
    assert main(["plan", str(TINY), "--algorithm", "rrt_star", "--seed", "5", "--iterations", "120",
                 "--checker", "numpy", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    record = json.loads((tmp_path / "result.json").read_text())
    scenario = load_scenario(TINY)
    expected = plan(scenario, GeometricChecker(scenario), algorithm="rrt_star", iterations=120, seed=5)
    assert record["algorithm"] == "rrt_star" and record["seed"] == 5
    assert np.array_equal(_read_csv(tmp_path / "path.csv"), expected.waypoints)
    # rrt_star minimises length: its cost is the configuration path length.
    assert record["cost"] == pytest.approx(record["path_length"], rel=1e-9)


@pytest.mark.slow
def test_walled_off_goal_exits_3_and_still_writes_the_result(tmp_path, capsys):
    scenario = tmp_path / "walled.yaml"
    scenario.write_text(WALLED)
    out = tmp_path / "out"
    assert main(["plan", str(scenario), "--iterations", "300", "--checker", "numpy", "--out", str(out)]) == EXIT_NO_PATH
    captured = capsys.readouterr()
    assert captured.out.startswith("social_rrt_star: no path")
    assert "no path from start to goal in 300 iterations" in captured.err and "success: false" in captured.err
    record = json.loads((out / "result.json").read_text())
    assert record["success"] is False and record["cost"] is None and record["waypoints"] == []
    assert record["closest_distance_to_goal"] > 0.5  # the tree stays on the start side
    assert _read_csv(out / "path.csv").shape == (0, 4)
    for name in OUTPUTS:
        assert (out / name).stat().st_size > 0


@pytest.mark.parametrize("checker", ["numpy", "drake"])
def test_start_in_collision_exits_2_naming_start(tmp_path, capsys, checker):
    argv = ["plan", str(TINY), "--set", "start: [4.0, 0.6, 0.0, 1.5708]", "--iterations", "20",
            "--checker", checker, "--out", str(tmp_path)]
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith("drake-social: error: ") and str(TINY) in captured.err
    assert "start" in captured.err and "[4.0, 0.6, 0.0, 1.5708]" in captured.err and "collision" in captured.err
    if checker == "drake":  # the Drake checker names the touching bodies (the base sits in the desk)
        assert "base with obstacle[0]" in captured.err
    assert not (tmp_path / "result.json").exists()


def test_goal_in_collision_exits_2_naming_goal(tmp_path, capsys):
    argv = ["plan", str(TINY), "--set", "goal: [4.0, 3.8, 0.0, 1.5708]", "--checker", "numpy", "--out", str(tmp_path)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "goal" in err and "collision" in err


def test_bad_options_are_usage_errors(tmp_path, capsys):
    assert main(["plan", str(TINY), "--iterations", "0", "--out", str(tmp_path)]) == 2
    assert "--iterations: must be an integer >= 1, got 0" in capsys.readouterr().err
    assert main(["plan", str(TINY), "--iterations", "many"]) == 2
    assert "--iterations: must be an integer >= 1, got 'many'" in capsys.readouterr().err
    assert main(["plan", str(TINY), "--algorithm", "dijkstra"]) == 2
    assert "invalid choice: 'dijkstra'" in capsys.readouterr().err
    assert main(["plan", str(TINY), "--checker", "fcl"]) == 2
    assert "invalid choice: 'fcl'" in capsys.readouterr().err


@pytest.mark.slow
def test_progress_bar_only_when_asked_or_on_a_terminal(tmp_path, capsys):
    base = ["plan", str(TINY), "--iterations", "40", "--checker", "numpy"]
    assert main(base + ["--out", str(tmp_path / "a")]) == 0
    assert "\r" not in capsys.readouterr().err  # captured stderr is not a TTY
    assert main(base + ["--out", str(tmp_path / "b"), "--progress"]) == 0
    err = capsys.readouterr().err
    assert err.startswith("\rplanning [") and err.endswith("\n")
    assert err.rstrip().split("\r")[-1].startswith("planning [" + "#" * 30 + "] 40/40, best ")


def test_progress_bar_draws_fraction_and_best_cost():
    stream = io.StringIO()
    dut = ProgressBar(300, stream, width=10, interval=0.0)
    dut(1, float("inf"))
    dut(150, 12.345)
    dut.close()
    frames = stream.getvalue().split("\r")[1:]
    assert frames[0].startswith("planning [..........] 0/300")  # drawn when made
    assert frames[1].startswith("planning [..........] 1/300, no path yet")
    assert frames[2].startswith("planning [#####.....] 150/300, best 12.35")
    assert stream.getvalue().endswith("\n")
    quiet = io.StringIO()
    slow = ProgressBar(10, quiet, interval=3600.0)
    for k in range(1, 11):
        slow(k, 1.0)
    slow.close()
    # Throttled: drawn when made, then not again until the end (close draws the last state).
    assert quiet.getvalue().count("\r") <= 3
    assert quiet.getvalue().rstrip().split("\r")[-1].startswith("planning [" + "#" * 30 + "] 10/10, best 1")


class _CutStream(io.StringIO):
    """Raises KeyboardInterrupt right after the n-th write (Ctrl-C mid-redraw)."""

    def __init__(self, n):
        super().__init__()
        self.n = n

    def write(self, text):
        out = super().write(text)
        self.n -= 1
        if self.n == 0:
            raise KeyboardInterrupt
        return out


@pytest.mark.parametrize("cut", [1, 2, 3, 4])
def test_a_ctrl_c_mid_redraw_still_ends_the_bars_line(cut):
    """Whether Ctrl-C lands while the bar is made, in a redraw or after, the
    line ends once: the one message after it starts on a line of its own."""
    stream = _CutStream(cut)
    try:
        bar = ProgressBar(300, stream, width=10, interval=0.0)
        try:
            for k in range(1, 4):
                bar(k, 1.0)
        finally:
            bar.close()
    except KeyboardInterrupt:
        pass
    text = stream.getvalue()
    assert text.startswith("\rplanning [") and text.endswith("\n") and not text.endswith("\n\n")


def test_bench_parses_and_calls_run_bench_with_keywords(tmp_path, monkeypatch, capsys):
    calls = []
    fake = types.ModuleType("drake_social.experiments.bench.planners")

    def fake_run_bench(**kwargs):
        calls.append(kwargs)
        (kwargs["out_dir"] / "bench.md").write_text("| table |\n")

    fake.run_bench = fake_run_bench
    monkeypatch.setitem(sys.modules, "drake_social.experiments.bench.planners", fake)
    argv = ["bench", "--scenarios", str(TINY), "--algorithms", "rrt_star", "social_rrt_star", "--iterations", "50",
            "--seeds", "3", "--repeats", "2", "--checker", "numpy", "--no-ompl", "--out", str(tmp_path)]
    assert main(argv) == 0
    # run_bench writes into the output set's staging folder inside --out, moved into --out as a whole.
    staging = calls[0].pop("out_dir")
    assert staging.parent == tmp_path and staging.name.startswith(".staging-bench-") and not staging.exists()
    assert calls == [dict(scenario_paths=[TINY], algorithms=["rrt_star", "social_rrt_star"], iterations=50, seeds=3,
                          checker="numpy", ompl_checker="drake", include_ompl=False, include_checker=True,
                          sim_runs=3, scaling=False, repeats=2, replan_runs=0, replan_count=200, map_bench=False,
                          progress=None)]
    assert (tmp_path / "bench.md").read_text() == "| table |\n" and "| table |" in capsys.readouterr().out
    defaults = build_parser().parse_args(["bench"])
    assert defaults.scenarios == [SCENARIO_DIR / "office_bar.yaml", SCENARIO_DIR / "generic_L.yaml"]
    assert defaults.algorithms == list(ALGORITHMS) and defaults.iterations == 2000 and defaults.seeds == 10
    assert defaults.checker == "planar" and defaults.ompl_checker == "drake" and defaults.scaling is False
    assert defaults.no_ompl is False and defaults.out == Path("out/bench") and defaults.repeats == 1
    assert main(["bench", "--scenarios", str(tmp_path / "none.yaml")]) == 2
    assert "none.yaml: no such scenario file" in capsys.readouterr().err


@pytest.mark.slow
def test_bench_runs_on_tiny_and_prints_its_table(tmp_path, capsys):
    argv = ["bench", "--scenarios", str(TINY), "--algorithms", "social_rrt_star", "rrt_star", "--iterations", "40",
            "--seeds", "2", "--checker", "numpy", "--no-ompl", "--no-checker-bench", "--sim-runs", "0",
            "--out", str(tmp_path), "--progress"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert captured.out.rstrip().endswith(f"wrote {tmp_path}/: bench.json, bench.md")
    assert "| tiny | social_rrt_star | 2 |" in captured.out and "| tiny | rrt_star | 2 |" in captured.out
    assert captured.err.rstrip().split("\r")[-1].startswith("bench [" + "#" * 30 + "] 4/4, tiny rrt_star seed 1")
    record = json.loads((tmp_path / "bench.json").read_text())
    runs = record["scenarios"]["tiny.yaml"]["algorithms"]["social_rrt_star"]["runs"]
    scenario = load_scenario(TINY)
    for seed, run in enumerate(runs):  # the bench's runs are the planner's, seed by seed
        expected = plan(scenario, GeometricChecker(scenario), algorithm="social_rrt_star", iterations=40, seed=seed)
        assert run["seed"] == seed and run["F_multi"] == pytest.approx(expected.social_cost_full, rel=1e-12)


def test_cli_offers_exactly_the_library_checkers():
    from drake_social import cli
    from drake_social.collision.drake_checker import CHECKERS

    assert cli.CHECKERS == CHECKERS


@pytest.mark.parametrize("name", ["path.csv", "result.json", "path.png", "cost_profile.png", "convergence.png"])
def test_a_folder_named_like_an_output_is_refused_before_planning(tmp_path, capsys, name):
    out = tmp_path / "out"
    (out / name).mkdir(parents=True)
    rc = main(["plan", str(TINY), "--checker", "numpy", "--iterations", "50", "--out", str(out)])
    captured = capsys.readouterr()
    assert rc == 1 and captured.out == ""  # nothing planned
    assert captured.err == (f"drake-social: error: {out / name} is a folder in the way of plan's output {name}; "
                            "remove or rename it, or choose another --out\n")
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == [name]
