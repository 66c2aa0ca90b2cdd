"""bench --map on a small floor: what it measures adds up."""

from __future__ import annotations

import numpy as np
import pytest

from drake_social.experiments.bench import maps as dut
from drake_social.maps import map_boxes, read_map
from drake_social.scenario import load_scenario
from drake_social.world import world_model


def test_the_bench_scenario_is_valid_and_spans_the_floor(tmp_path):
    path = dut.map_bench_scenario(tmp_path, width=20.0, height=28.0, resolution=0.05)
    scenario = load_scenario(path)
    grid = read_map(tmp_path / "floor.yaml")
    assert scenario.world.bounds == pytest.approx([0.0, 0.0, 20.0, 28.0])
    assert world_model(scenario).map_box_count == len(map_boxes(grid))
    # From the bottom of the west corridor to the far east of the top one.
    assert scenario.start[1] < 4.0 and scenario.goal[0] > 15.0 and scenario.goal[1] > 18.0
    assert len(scenario.people) == 4  # two per horizontal corridor
    # The ragged edges give many more boxes than the clean floor's.
    assert len(map_boxes(grid)) > 300


@pytest.mark.slow
def test_a_small_map_bench(tiny_scenario_path):
    out = dut.run_map_bench(tiny_scenario_path, iterations=200, seeds=2, load_repeats=2, replay=False,
                            size=(16.0, 14.0), resolution=0.05)
    m, p = out["map"], out["plan"]
    assert m["cells"] == 280 * 320 and m["boxes"] == m["boxes_in_world"] > 50
    assert m["load_seconds"]["n"] == 2 and out["checker_seconds"] > 0
    assert len(p["map"]) == len(p["office"]) == 2
    assert p["median_map"] == pytest.approx(np.median([r["planning_time"] for r in p["map"]]))
    assert p["ratio"] == pytest.approx(p["median_map"] / p["median_office"])
    assert out["replay"] is None
    md = "\n".join(dut.markdown(out))
    assert "| ratio map / office |" in md and f"{m['boxes']:,} boxes" in md
