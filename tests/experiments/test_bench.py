"""The planner benchmark and its OMPL baseline: numbers consistent with the runs, deterministic, same cost code."""

from __future__ import annotations

import json
import math
import platform

import numpy as np
import pytest

from drake_social.cost.social import SocialCost
from drake_social.experiments.bench.planners import run_bench
from drake_social.io.json_numbers import finite_or_none
from drake_social.collision.geometric import GeometricChecker
from drake_social.planning.space import ConfigurationSpace
from drake_social.planning.algorithms import evaluate_path, make_objective
from drake_social.scenario import ALGORITHMS, load_scenario

# Benchmark runs: many plans per test.
pytestmark = pytest.mark.slow

ALGOS = ["rrt_star", "social_rrt_star"]


def _small(path, out_dir, **kw):
    args = dict(scenario_paths=[path], algorithms=ALGOS, iterations=200, seeds=2, checker="numpy",
                include_ompl=False, include_checker=False, out_dir=out_dir)
    args.update(kw)
    return run_bench(**args)


def test_small_bench_reports_its_runs(tiny_scenario_path, tiny_scenario, tmp_path):
    calls = []
    dut = _small(tiny_scenario_path, tmp_path / "a", include_checker=True,
                 progress=lambda done, total, label: calls.append((done, total, label)))
    # Progress: one call per run plus the checker bench, counting up to the total.
    assert [c[0] for c in calls] == list(range(1, 6)) and {c[1] for c in calls} == {5}
    assert calls[-1][2] == "checker bench"

    on_disk = json.loads((tmp_path / "a" / "bench.json").read_text())
    assert on_disk["settings"] == {"scenario_paths": [str(tiny_scenario_path)], "algorithms": ALGOS,
                                   "iterations": 200, "seeds": [0, 1], "checker": "numpy", "ompl_checker": "drake",
                                   "sim_runs": 0, "repeats": 1}
    assert on_disk["machine"]["cpu_count"] >= 1 and on_disk["machine"]["numpy"] == np.__version__
    for key in ("load_average_start", "load_average_end"):  # what os.getloadavg gives here
        assert len(on_disk["machine"][key]) == 3 and min(on_disk["machine"][key]) >= 0.0
    from drake_social.experiments.bench import planners as bench

    assert on_disk["machine"]["cpu_model"] == bench.cpu_model()
    assert on_disk["checker_bench"]["scenarios"]["tiny.yaml"]["configs_per_s"]["numpy_batched"] > 0
    md = (tmp_path / "a" / "bench.md").read_text()
    assert "## Checkers" in md

    full = SocialCost.from_scenario(tiny_scenario)
    checker = GeometricChecker(tiny_scenario)
    for algorithm in ALGOS:
        data = dut["scenarios"]["tiny.yaml"]["algorithms"][algorithm]
        runs, summary = data["runs"], data["summary"]
        assert [r["seed"] for r in runs] == [0, 1] and all(r["success"] for r in runs)
        assert data["vs_ompl"] is None
        planning_times = [r["planning_time"] for r in runs]
        social = [r["F_multi"] for r in runs]
        assert summary["planning_time"]["median"] == pytest.approx(np.median(planning_times), rel=1e-12)
        assert summary["F_multi"]["median"] == pytest.approx(np.median(social), rel=1e-12)
        assert summary["F_multi"]["iqr"] == pytest.approx(
            np.percentile(social, 75) - np.percentile(social, 25), rel=1e-12, abs=1e-12)
        assert summary["F_multi"]["min"] == min(social) and summary["F_multi"]["max"] == max(social)
        assert summary["median_first_solution_iteration"] == np.median([r["first_solution_iteration"] for r in runs])
        assert summary["success_rate"] == 1.0 and summary["paths_valid"]
        for run in runs:
            wp = np.array(run["waypoints"])
            np.testing.assert_array_equal(wp[0], tiny_scenario.start)
            np.testing.assert_array_equal(wp[-1], tiny_scenario.goal)
            # Independent recomputation: the social integral edge by edge, the base length by hand.
            by_edge = sum(float(full.motion_cost(wp[i:i + 1], wp[i + 1:i + 2])[0]) for i in range(len(wp) - 1))
            assert run["F_multi"] == pytest.approx(by_edge, rel=1e-9)
            assert run["base_length"] == pytest.approx(sum(math.dist(a[:2], b[:2]) for a, b in zip(wp, wp[1:])))
            # The planner's own cost is the objective recomputed from the path.
            assert run["cost"] == pytest.approx(run["objective"], rel=1e-9)
            assert checker.are_valid(wp).all() and checker.are_motions_valid(wp[:-1], wp[1:]).all()
            assert run["path_valid"]
            # One configuration check per sample, but for goal samples once the goal is a node.
            assert run["tree_size"] <= 201 and 150 <= run["num_config_checks"] <= 200
        # The Markdown row carries the same medians.
        row = next(line for line in md.splitlines() if line.startswith(f"| tiny | {algorithm} |"))
        assert f"{summary['F_multi']['median']:.3g}" in row and "| 2 | 100% |" in row

    # Same seeds, same paths and costs (times may differ).
    again = _small(tiny_scenario_path, tmp_path / "b")
    for algorithm in ALGOS:
        first = dut["scenarios"]["tiny.yaml"]["algorithms"][algorithm]["runs"]
        second = again["scenarios"]["tiny.yaml"]["algorithms"][algorithm]["runs"]
        assert [r["F_multi"] for r in first] == [r["F_multi"] for r in second]
        assert [r["waypoints"] for r in first] == [r["waypoints"] for r in second]
    # Different seeds gave different paths.
    runs = dut["scenarios"]["tiny.yaml"]["algorithms"]["social_rrt_star"]["runs"]
    assert runs[0]["waypoints"] != runs[1]["waypoints"]


def test_bench_rejects_bad_arguments(tiny_scenario_path, tmp_path):
    with pytest.raises(ValueError, match="allowed: rrt_star, social_rrt_star"):
        _small(tiny_scenario_path, tmp_path, algorithms=["rrt"])
    with pytest.raises(ValueError, match="checker 'fcl' not allowed; allowed: planar, drake, numpy"):
        _small(tiny_scenario_path, tmp_path, checker="fcl")
    with pytest.raises(ValueError, match="iterations, seeds and repeats must be >= 1, got 200, 0, 1"):
        _small(tiny_scenario_path, tmp_path, seeds=0)
    with pytest.raises(ValueError, match="repeats must be >= 1, got 200, 2, 0"):
        _small(tiny_scenario_path, tmp_path, repeats=0)
    assert not (tmp_path / "bench.json").exists()


# ---- OMPL -------------------------------------------------------------------


def test_radius_formula_by_hand(extra):
    ompl_baseline = extra("ompl", "drake_social.experiments.bench.ompl_baseline")
    assert ompl_baseline.unit_ball_measure(2) == pytest.approx(math.pi)
    assert ompl_baseline.unit_ball_measure(3) == pytest.approx(4 * math.pi / 3)
    assert ompl_baseline.unit_ball_measure(4) == pytest.approx(math.pi**2 / 2)
    # d = 4, measure 10, factor 1: r_rrt = (2.5 * 10 / (pi^2 / 2))^(1/4); n = 100.
    r_rrt = (25 / (math.pi**2 / 2)) ** 0.25
    assert ompl_baseline.ompl_radius(1.0, 10.0, 4, 100, 99.0) == pytest.approx(r_rrt * (math.log(100) / 100) ** 0.25)
    assert ompl_baseline.ompl_radius(1.0, 10.0, 4, 100, 0.3) == 0.3  # clipped at the range
    # The chosen factor reaches the radius at every tree size up to max_n, exactly at the binding end.
    dut = ompl_baseline.rewire_factor_for_radius(1.5, 1239.2, 4, 2002)
    radii = [ompl_baseline.ompl_radius(dut, 1239.2, 4, n, np.inf) for n in range(2, 2003)]
    assert min(radii) == pytest.approx(1.5, rel=1e-12) and radii[-1] == pytest.approx(1.5, rel=1e-12)
    small = ompl_baseline.rewire_factor_for_radius(1.0, 5.0, 4, 3)  # ln 2 / 2 < ln 3 / 3: n = 2 binds
    assert ompl_baseline.ompl_radius(small, 5.0, 4, 2, np.inf) == pytest.approx(1.0, rel=1e-12)


def test_ompl_path_is_valid_and_costed_by_our_code(tiny_scenario, extra):
    ompl_baseline = extra("ompl", "drake_social.experiments.bench.ompl_baseline")
    objective = make_objective(tiny_scenario, "social_rrt_star")
    p = tiny_scenario.planner

    def run(seed):
        return ompl_baseline.plan_ompl(
            ConfigurationSpace.from_scenario(tiny_scenario), GeometricChecker(tiny_scenario), objective,
            np.asarray(tiny_scenario.start), np.asarray(tiny_scenario.goal), iterations=200,
            planning_range=p.planning_range, near_radius=p.near_radius, goal_bias=p.goal_bias, seed=seed,
        )

    dut, settings = run(3)
    assert dut.success and dut.first_solution_iteration is not None
    wp = dut.waypoints
    np.testing.assert_allclose(wp[0], tiny_scenario.start, atol=1e-12)
    np.testing.assert_allclose(wp[-1], tiny_scenario.goal, atol=1e-12)
    checker = GeometricChecker(tiny_scenario)
    assert checker.are_valid(wp).all() and checker.are_motions_valid(wp[:-1], wp[1:]).all()
    # No edge longer than OMPL's range (Steer).
    assert np.all(np.linalg.norm(np.diff(wp, axis=0), axis=1) <= p.planning_range + 1e-9)
    parts = evaluate_path(tiny_scenario, wp, objective)
    assert np.isfinite(parts["social_cost_full"]) and parts["objective"] == pytest.approx(dut.cost, rel=1e-9)
    # Anytime curve: never increases, ends at the returned cost, infinite before the first solution.
    h = dut.cost_history
    assert len(h) == 200 and np.all(np.diff(h[np.isfinite(h)]) <= 1e-12) and h[-1] == pytest.approx(dut.cost)
    assert np.isinf(h[dut.first_solution_iteration - 2]) and np.isfinite(h[dut.first_solution_iteration - 1])
    assert dut.num_config_checks == 1 and dut.num_motion_checks >= dut.tree_size - 1
    assert settings.radius == pytest.approx(min(p.planning_range, p.near_radius))
    # Deterministic per seed; another seed explores differently.
    again, _ = run(3)
    np.testing.assert_array_equal(again.waypoints, wp)
    assert again.cost == dut.cost
    other, _ = run(4)
    assert other.tree_size != dut.tree_size or not np.array_equal(other.waypoints, wp)


def test_objective_adapter_equals_our_motion_cost(tiny_scenario_path, rng, extra):
    ompl_baseline = extra("ompl", "drake_social.experiments.bench.ompl_baseline")
    from ompl import base as ob
    from ompl import geometric as og

    # Non-unit distance weights and a length term: OMPL states are W q.
    scenario = load_scenario(tiny_scenario_path, "planner: {distance_weights: [1.0, 2.0, 0.5, 0.8]}\n"
                                                 "social: {length_weight: 0.3}")
    objective = make_objective(scenario, "social_rrt_star")
    space = ConfigurationSpace.from_scenario(scenario)
    w = space.weights
    state_space = ob.RealVectorStateSpace(4)
    bounds = ob.RealVectorBounds(4)
    for i in range(4):
        bounds.setLow(i, float(space.lower[i] * w[i]))
        bounds.setHigh(i, float(space.upper[i] * w[i]))
    state_space.setBounds(bounds)
    si = ob.SpaceInformation(state_space)
    si.setStateValidityChecker(lambda s: True)
    si.setup()
    dut = ompl_baseline.ObjectiveAdapter(si, objective, w)

    q_a = space.sample_uniform(rng, 20)
    q_b = q_a + rng.normal(scale=0.5, size=(20, 4))
    expected = objective.motion_cost(q_a, q_b)
    assert np.all(expected > 0)
    for a, b, e in zip(q_a, q_b, expected):
        path = og.PathGeometric(si)
        for q in (a, b):
            s = si.allocState()
            for i in range(4):
                s[i] = float(q[i] * w[i])
            path.append(s)
        # path.cost goes through OMPL's C++ (initial + motion + terminal cost).
        assert path.cost(dut).value() == pytest.approx(e, rel=1e-12)
    assert dut.num_motion_costs == 20


def test_bench_with_ompl_reports_ratios(tiny_scenario_path, tmp_path, extra):
    extra("ompl")
    dut = _small(tiny_scenario_path, tmp_path, algorithms=["informed_social_rrt_star"], iterations=150, include_ompl=True,
                 ompl_checker="planar", repeats=3)
    entry = dut["scenarios"]["tiny.yaml"]
    once = _small(tiny_scenario_path, tmp_path / "once", algorithms=["informed_social_rrt_star"], iterations=150,
                  include_ompl=True, ompl_checker="planar")["scenarios"]["tiny.yaml"]
    # Repeats: each run's time is the median of its three, the paths those of single runs.
    for field, key in (("algorithms", "informed_social_rrt_star"), ("ompl", "social_rrt_star"),
                       ("ompl_same_checker", "social_rrt_star")):
        for run, single in zip(entry[field][key]["runs"], once[field][key]["runs"]):
            assert len(run["planning_times"]) == 3 and len(single["planning_times"]) == 1
            assert run["planning_time"] == np.median(run["planning_times"])
            assert single["planning_time"] == single["planning_times"][0]
            assert run["waypoints"] == single["waypoints"] and run["objective"] == single["objective"]
    assert list(entry["ompl"]) == ["social_rrt_star"]  # the informed variant's objective
    assert entry["ompl"]["social_rrt_star"]["checker"] == "planar"
    same = entry["ompl_same_checker"]["social_rrt_star"]  # OMPL with our checker too
    assert same["checker"] == "numpy" and same["summary"]["runs"] == 2
    vs_same = entry["algorithms"]["informed_social_rrt_star"]["vs_ompl_same_checker"]
    assert vs_same["ompl_checker"] == "numpy"
    ours = entry["algorithms"]["informed_social_rrt_star"]["summary"]
    ompl = entry["ompl"]["social_rrt_star"]
    assert ompl["summary"]["runs"] == 2 and ompl["summary"]["paths_valid"]
    for run in ompl["runs"]:
        assert run["cost"] == pytest.approx(run["objective"], rel=1e-9)
    vs = entry["algorithms"]["informed_social_rrt_star"]["vs_ompl"]
    assert vs["time"] == pytest.approx(ours["planning_time"]["median"] / ompl["summary"]["planning_time"]["median"])
    assert vs_same["time"] == pytest.approx(ours["planning_time"]["median"] / same["summary"]["planning_time"]["median"])
    assert vs["social_cost"] == pytest.approx(
        ours["F_multi"]["median"] / ompl["summary"]["F_multi"]["median"])
    md = (tmp_path / "bench.md").read_text()
    assert "| tiny | ompl_rrt_star[social_rrt_star] (planar) | 2 |" in md and "rewire factor" in md
    assert "| tiny | ompl_rrt_star[social_rrt_star] (numpy) | 2 |" in md


def test_bench_without_ompl_says_so(tiny_scenario_path, tmp_path, monkeypatch):
    import drake_social.experiments.bench.planners as bench

    monkeypatch.setattr(bench, "ompl_available", lambda: False)
    dut = _small(tiny_scenario_path, tmp_path, algorithms=["rrt_star"], seeds=1, iterations=50, include_ompl=True)
    assert dut["ompl"] == {"requested": True, "available": False, "objectives": []}
    assert dut["scenarios"]["tiny.yaml"]["ompl"] == {}
    assert dut["scenarios"]["tiny.yaml"]["algorithms"]["rrt_star"]["vs_ompl"] is None
    md = (tmp_path / "bench.md").read_text()
    assert "OMPL was not importable" in md and "| tiny | rrt_star | 1 |" in md


def test_ratios_where_a_median_is_zero_are_not_defined():
    """A scenario where every social planner finds a path of cost 0: the
    social-cost and objective ratios are n/a, not 0; the time ratio stays."""
    from drake_social.experiments.bench import planners as bench

    def summary(time, cost):
        stat = lambda m: {"n": 2, "median": m, "q25": m, "q75": m, "iqr": 0.0, "min": m, "max": m}  # noqa: E731
        return {"runs": 2, "success_rate": 1.0, "planning_time": stat(time), "F_multi": stat(cost),
                "objective": stat(cost), "median_first_solution_iteration": 3.0}

    ours, ompl = summary(0.5, 0.0), summary(2.0, 1.5)
    assert bench._ratio(ours, ompl, "planning_time") == pytest.approx(0.25)
    assert bench._ratio(ours, ompl, "F_multi") is None  # 0 / 1.5
    assert bench._ratio(ompl, ours, "F_multi") is None  # 1.5 / 0
    assert bench._ratio(summary(0.5, 0.0), summary(2.0, 0.0), "objective") is None  # 0 / 0
    vs = {"ompl": "ompl_rrt_star[social_rrt_star]",
          **{f: bench._ratio(ours, ompl, g)
             for f, g in (("time", "planning_time"), ("social_cost", "F_multi"), ("objective", "objective"))}}
    out = {"settings": {"iterations": 10, "seeds": [0, 1], "checker": "numpy"},
           "machine": {"platform": "p", "cpu_count": 2, "numpy": "n", "drake": "d", "ompl": None},
           "ompl": {"requested": False}, "checker_bench": None,
           "scenarios": {"tiny.yaml": {"algorithms": {"social_rrt_star": {"summary": ours, "vs_ompl": vs}},
                                       "ompl": {}}}}
    row = next(line for line in bench._markdown(out).splitlines() if line.startswith("| tiny | social_rrt_star"))
    assert row.endswith("| 0.25 | n/a | n/a | n/a |")  # time, time with the same checks (none), costs
    assert json.loads(json.dumps(finite_or_none(vs)))["social_cost"] is None


def test_repeats_pool_only_identical_runs():
    """_repeated: the median of the repeats' times on the first result; a
    repeat with another path is refused, not averaged in."""
    from types import SimpleNamespace

    from drake_social.experiments.bench import planners as bench

    def run(times, costs):
        it = iter(zip(times, costs))

        def once():
            t, c = next(it)
            return (SimpleNamespace(algorithm="a", seed=3, wall_time=t, cost=c, waypoints=np.zeros((2, 4))), "x")
        return once

    (result, extra), times = bench._repeated(run([0.3, 0.1, 0.2], [1.0, 1.0, 1.0]), 3)
    assert times == [0.3, 0.1, 0.2] and result.wall_time == 0.2 and extra == "x"
    with pytest.raises(RuntimeError, match="a: a repeat of seed 3 returned another path .cost 1.5, first 1.0."):
        bench._repeated(run([0.3, 0.1], [1.0, 1.5]), 2)


def test_cpu_model_and_the_machine_line(tmp_path):
    """The processor is read from cpuinfo's first non-empty "model name"; the
    Markdown says it and the load averages around the run."""
    from drake_social.experiments.bench import planners as bench

    info = tmp_path / "cpuinfo"
    info.write_text("processor\t: 0\nvendor_id\t: X\nmodel name\t:   \nmodel name\t: AMD EPYC 9B45\n"
                    "model name\t: other\n")
    assert bench.cpu_model(info) == "AMD EPYC 9B45"
    info.write_text("processor\t: 0\n")
    assert bench.cpu_model(info) == (platform.processor() or None)
    assert bench.cpu_model(tmp_path / "missing") == (platform.processor() or None)

    m = {"cpu_model": "AMD EPYC", "load_average_start": [0.5, 0.25, 0.125], "load_average_end": [1.0, 0.5, 0.0]}
    assert bench._machine_line(m) == [
        "Processor: AMD EPYC; load average (1, 5, 15 min) at the start: 0.50, 0.25, 0.12; "
        "load average (1, 5, 15 min) at the end: 1.00, 0.50, 0.00.", ""]
    assert bench._machine_line({"cpu_model": None, "load_average_start": [2.0, 1.0, 1.0]}) == [
        "Load average (1, 5, 15 min) at the start: 2.00, 1.00, 1.00.", ""]
    assert bench._machine_line({"cpu_model": None}) == []


def test_bench_plans_with_the_papers_planner_whatever_the_file_says(tiny_scenario_path, tmp_path):
    """A file asking for the shrinking radius and the optimiser is benched
    as OMPL's RRTstar plans: fixed radius, raw path (limits.PAPER_PLANNER)."""
    text = tiny_scenario_path.read_text()
    old = "planner: {near_radius_mode: fixed, optimize: false,"
    assert text.count(old) == 1
    path = tmp_path / "optimised.yaml"
    path.write_text(text.replace(old, "planner: {near_radius_mode: shrinking, optimize: true,"))
    assert load_scenario(path).planner.optimize is True  # the file's own setting
    dut = run_bench(scenario_paths=[path], algorithms=["rrt_star"], iterations=300, seeds=1, checker="numpy",
                    include_ompl=False, include_checker=False, out_dir=tmp_path / "out")
    entry = dut["scenarios"]["optimised.yaml"]
    assert entry["planner_options"]["near_radius_mode"] == "fixed"
    assert entry["planner_options"]["optimize"] is False
    (run,) = entry["algorithms"]["rrt_star"]["runs"]
    assert run["success"] is True  # a found path the file's settings would have optimised
    assert run["optimized"] is False
    table = (tmp_path / "out" / "bench.md").read_text()
    assert ("Planner options (the paper's, set over every scenario file): optimised.yaml: near radius fixed, "
            "optimize off.") in table


def test_each_algorithm_is_compared_with_ompl_as_the_uniform_one_of_its_objective():
    from drake_social.experiments.bench.planners import ompl_counterpart

    assert {a: ompl_counterpart(a) for a in ALGORITHMS} == {
        "rrt_star": "rrt_star", "social_rrt_star": "social_rrt_star", "base_rrt_star": "base_rrt_star",
        "informed_social_rrt_star": "social_rrt_star", "informed_base_rrt_star": "base_rrt_star"}
    with pytest.raises(ValueError, match="unknown"):
        ompl_counterpart("informed_rrt_star")
