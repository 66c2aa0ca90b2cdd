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


@pytest.mark.slow
def test_bench_map_from_another_folder_compares_with_the_first_scenario(tiny_scenario_path, tmp_path, monkeypatch):
    """bench --map from a folder that is not the checkout's root: the floor's
    plans are compared with the first of --scenarios (here tiny), whose name
    the table gives; nothing is looked up in the working folder."""
    import functools
    import json

    from drake_social.app import run_bench

    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    small = functools.partial(dut.run_map_bench, seeds=1, load_repeats=1, replay=False, size=(16.0, 14.0),
                              resolution=0.05)
    monkeypatch.setattr(dut, "run_map_bench", small)
    run_bench(scenario_paths=[tiny_scenario_path], out=tmp_path / "out", algorithms=["social_rrt_star"],
              iterations=50, seeds=1, include_ompl=False, include_checker=False, map_bench=True)
    bench = json.loads((tmp_path / "out" / "bench.json").read_text())
    plan = bench["map_bench"]["plan"]
    assert plan["office_scenario"] == "tiny.yaml" and len(plan["office"]) == 1
    assert "| plan K = 50, tiny (median of 1;" in (tmp_path / "out" / "bench.md").read_text()
    assert sorted(p.name for p in elsewhere.iterdir()) == []


def test_the_bench_defaults_are_the_shipped_scenarios_whatever_the_folder(tmp_path, monkeypatch, repo_root):
    from drake_social.cli_parser import build_parser
    from drake_social.experiments.bench.replanning import REPLAN_SCENARIO

    monkeypatch.chdir(tmp_path)
    shipped = repo_root / "scenarios"
    assert build_parser().parse_args(["bench", "--map"]).scenarios == [shipped / "office_bar.yaml",
                                                                       shipped / "generic_L.yaml"]
    assert REPLAN_SCENARIO == shipped / "office_walkers.yaml" and REPLAN_SCENARIO.is_file()
