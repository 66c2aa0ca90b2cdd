"""The scaling benchmark: exponent fit, far people, optimisation against the reference."""

from __future__ import annotations

import numpy as np
import pytest

from drake_social.experiments.bench import scaling as dut
from drake_social.collision.drake_checker import make_checker


def test_fit_exponent_recovers_a_power_law():
    ks = [2000, 5000, 20000, 50000]
    assert dut.fit_exponent(ks, [3e-5 * k**1.27 for k in ks]) == pytest.approx(1.27, abs=1e-12)
    assert dut.fit_exponent([2000], [0.1]) is None


def test_far_people_stand_outside_the_room_and_are_in_the_checker(tiny_scenario):
    far = dut.far_people_scenario(tiny_scenario, 7)
    x0, y0, x1, y1 = tiny_scenario.world.bounds
    extra = far.people[len(tiny_scenario.people):]
    assert len(extra) == 7 and all(p.x >= x1 + 10.0 and y0 <= p.y <= y1 for p in extra)
    assert len(tiny_scenario.people) + 7 == len(far.people)  # the input is not changed
    a, b = make_checker(tiny_scenario, "planar"), make_checker(far, "planar")
    assert len(b.env) == len(a.env) + 7


def test_far_boxes_stand_outside_the_room_and_are_in_the_checker(tiny_scenario):
    far = dut.far_boxes_scenario(tiny_scenario, 30)
    x0, y0, x1, y1 = tiny_scenario.world.bounds
    extra = far.world.obstacles[len(tiny_scenario.world.obstacles):]
    assert len(extra) == 30 and all(b.center[0] >= x1 + 10.0 and y0 <= b.center[1] <= y1 for b in extra)
    assert len(tiny_scenario.world.obstacles) + 30 == len(far.world.obstacles)  # the input is not changed
    a, b = make_checker(tiny_scenario, "planar"), make_checker(far, "planar")
    assert len(b.env) == len(a.env) + 30


@pytest.mark.slow
def test_small_scaling_bench(tiny_scenario_path):
    out = dut.run_scaling_bench(scenario_paths=[tiny_scenario_path], ks=(100, 200), reference_k=200,
                                reference_seeds=2, seeds=2, far_people=5, far_repeats=1,
                                obstacle_counts=(10, 300), obstacle_iterations=300)
    e = out["scenarios"]["tiny.yaml"]
    runs = e["scaling"]["runs"]
    assert [r["iterations"] for r in runs] == [100, 200]
    assert e["scaling"]["exponent"] is None  # no K >= 2000 here
    o = e["optimized"]
    assert o["reference"][0] == runs[1]  # the K = 200 scaling run is the first reference run
    assert len(o["reference"]) == 2 and len(o["runs"]) == 2
    for r in o["runs"]:
        assert r["optimized"] and r["cost"] <= r["raw_cost"]  # optimisation never raises the cost
    assert o["ratio_to_reference"] == pytest.approx(o["median_cost"] / o["reference_median_cost"])
    assert o["median_cost"] == pytest.approx(np.median([r["cost"] for r in o["runs"]]))
    f = e["far_people"]
    assert f["same_trees"] and len(f["times_with"]) == 2
    assert f["time_ratio"] == pytest.approx(np.median(f["times_with"]) / np.median(f["times_without"]))
    ob = e["obstacles"]
    assert ob["same_trees"] and [r["extra_boxes"] for r in ob["rows"]] == [10, 300]
    assert ob["rows"][1]["environment_shapes"] == ob["rows"][0]["environment_shapes"] + 290
    assert ob["rows"][0]["time_ratio"] == 1.0 and len(ob["rows"][1]["times"]) == 2
    md = "\n".join(dut.markdown(out))
    assert "| tiny |" in md and "same trees" in md and "| tiny | 300 |" in md


def test_kernel_times_compare_the_grid_with_every_shape(tiny_scenario):
    far = dut.far_boxes_scenario(tiny_scenario, 200)
    out = dut.kernel_times(make_checker(far, "planar"), count=200, repeats=1)
    assert out["same"] is True
    assert set(out) == {f"{n}_{k}" for n in ("clearance", "valid", "motion") for k in ("grid", "plain")} | {"same"}
    assert all(v > 0 for k, v in out.items() if k != "same")
