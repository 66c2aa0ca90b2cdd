"""The checker benchmark: its report is complete, consistent and deterministic where it should be."""

from __future__ import annotations

import numpy as np
import pytest

from drake_social.experiments.bench.checkers import random_edges, run_checker_bench
from drake_social.kinematics import config_distance


@pytest.mark.slow
def test_bench_report_on_tiny(tiny_scenario_path):
    dut = run_checker_bench(scenario_paths=[tiny_scenario_path], num_configs=400, num_edges=60, seed=5, repeats=1)
    assert dut["machine"]["cpu_count"] >= 1
    report = dut["scenarios"]["tiny.yaml"]
    for kind in ("configs_per_s", "edges_per_s"):
        assert set(report[kind]) == {
            "drake_single", "drake_parallel", "drake_per_call", "numpy_batched", "numpy_per_call",
        }
        assert all(v > 0 and np.isfinite(v) for v in report[kind].values())
    # Items / seconds: the rates are the counts over the wall times.
    s = report["seconds"]
    assert report["configs_per_s"]["drake_single"] == pytest.approx(400 / s["drake_configs_single"]["wall"])
    assert s["numpy_edges_per_call"]["items"] == 12
    fractions = report["python_fraction"]
    assert fractions["edges_per_call"] is None  # no single Drake call does is_motion_valid's search
    for key in ("configs_batched", "configs_per_call", "edges_batched"):
        assert fractions[key] < 1.0
    agreement = report["agreement"]
    assert agreement["configs_total"] == 400 and agreement["edges_total"] == 60
    assert agreement["configs"] >= 399 and agreement["configs_max_margin_m"] < 1e-3
    assert agreement["edges"] >= 58
    assert 0.0 < report["valid_fraction"]["configs"] < 1.0
    # Drake's steps bound sqrt(3) times the weighted norm, numpy's the L1-type bound: never more.
    assert report["steps_per_edge"]["numpy"] <= report["steps_per_edge"]["drake"]
    assert report["steps_per_edge"]["drake"] <= np.sqrt(3) * report["steps_per_edge"]["numpy"] + 1


def test_bench_inputs_are_checked(tiny_scenario_path):
    with pytest.raises(ValueError, match="num_configs, num_edges and repeats must be >= 1"):
        run_checker_bench(scenario_paths=[tiny_scenario_path], num_configs=0, num_edges=10, seed=0)


def test_random_edges_have_the_steer_length_inside_the_limits(rng):
    lower, upper = np.array([0.0, 0.0, -np.pi, -np.pi]), np.array([8.0, 5.0, np.pi, np.pi])
    w = np.array([1.0, 1.0, 0.5, 0.25])
    q_a, q_b = random_edges(rng, lower, upper, 1.5, w, 500)
    assert np.all((q_b >= lower) & (q_b <= upper)) and np.all((q_a >= lower) & (q_a <= upper))
    d = config_distance(q_a, q_b, w)
    assert np.all(d <= 1.5 + 1e-12)
    # Clipping only shortens; most motions keep the full length.
    assert np.isclose(d, 1.5, rtol=1e-12).mean() > 0.3
