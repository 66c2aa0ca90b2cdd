"""One run-record schema: plan's result.json, bench's runs and a study's runs name every quantity alike, and give
the same numbers for the same run."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from drake_social import app
from drake_social.io.json_numbers import finite_or_none as finite
from drake_social.io.records import (CONTEXT_FIELDS, PATH_FIELDS, PLANNER_FIELDS, RUN_FIELDS, SHARED_FIELDS, json_lines,
                                     write_json)
from drake_social.planning.result import PlannerResult

#: Names of one quantity that the schema replaced: no producer may use them.
RETIRED = ("wall_time", "wall_times", "reported_cost", "social_cost_full", "social_cost_planner")
K, SEED, ALGORITHM = 150, 0, "social_rrt_star"


def test_the_schema_names_each_field_once_and_documents_it():
    assert len(RUN_FIELDS) == len(CONTEXT_FIELDS) + len(PLANNER_FIELDS) + len(PATH_FIELDS)  # no name twice
    assert set(SHARED_FIELDS) <= set(RUN_FIELDS) and not set(RETIRED) & set(RUN_FIELDS)
    assert all(text and not text.endswith(".") for text in RUN_FIELDS.values())
    assert "seconds" in RUN_FIELDS["planning_time"] and "metres" in RUN_FIELDS["base_length"]


def test_to_record_gives_the_planner_fields_in_order_with_null_for_non_finite():
    dut = PlannerResult(algorithm="rrt_star", success=False, message="no path", waypoints=np.zeros((0, 4)),
                        cost=math.inf, raw_cost=math.inf, wall_time=0.25, seed=3, tree_size=9,
                        cost_history=np.array([math.inf, math.inf]), closest_distance_to_goal=1.5)
    record = dut.to_record()
    assert list(record) == list(PLANNER_FIELDS)
    assert record["planning_time"] == 0.25 and record["seed"] == 3 and record["tree_size"] == 9
    assert record["cost"] is None and record["raw_cost"] is None and record["cost_history"] == [None, None]
    assert record["waypoints"] == [] and record["num_waypoints"] == 0 and record["closest_distance_to_goal"] == 1.5
    json.dumps(record, allow_nan=False)


def test_json_is_strict_and_one_key_per_line(tmp_path):
    value = {"a": math.nan, "b": [1.0, math.inf, (2, -math.inf)], "c": {"d": np.float64("nan"), "e": 0.1}}
    assert finite(value) == {"a": None, "b": [1.0, None, [2, None]], "c": {"d": None, "e": 0.1}}
    text = json_lines(value)
    assert text.splitlines() == ["{", '  "a": null,', '  "b": [1.0, null, [2, null]],',
                                 '  "c": {"d": null, "e": 0.1}', "}"]
    write_json(tmp_path / "x.json", value, indent=1)
    assert json.loads((tmp_path / "x.json").read_text()) == finite(value)
    assert (tmp_path / "x.json").read_text().endswith("}\n")


@pytest.fixture(scope="module")
def three_records(tmp_path_factory, tiny_scenario_path):
    """The same run (tiny, social_rrt_star, seed 0, K = 150, the numpy checker) from plan, bench and a study."""
    from drake_social.experiments.bench.planners import run_bench
    from drake_social.experiments.study import Group, Study, run_task, study_tasks

    root = tmp_path_factory.mktemp("records")
    planned = app.run_plan(scenario=tiny_scenario_path, out=root / "plan", algorithm=ALGORITHM, iterations=K,
                           seed=SEED, checker="numpy").record
    bench = run_bench(scenario_paths=[tiny_scenario_path], algorithms=[ALGORITHM], iterations=K, seeds=1,
                      checker="numpy", include_ompl=False, include_checker=False, sim_runs=0, out_dir=root / "bench")
    benched = bench["scenarios"][tiny_scenario_path.name]["algorithms"][ALGORITHM]["runs"][0]
    study = Study("records", (Group("tiny", str(tiny_scenario_path), algorithms=(ALGORITHM,)),), runs=1,
                  iterations=K, checker="numpy")
    (task,) = study_tasks(study)
    task["seed"] = SEED  # the run of the other two
    studied = run_task(task)
    return {"plan": planned, "bench": benched, "study": studied}


def test_plan_bench_and_study_records_share_names_and_numbers(three_records):
    for name, record in three_records.items():
        missing = [f for f in SHARED_FIELDS if f not in record]
        assert not missing, f"{name} lacks {missing}"
        assert not set(RETIRED) & set(record), f"{name} uses a retired name"
    plan, others = three_records["plan"], (three_records["bench"], three_records["study"])
    assert plan["success"] is True and plan["seed"] == SEED and plan["iterations"] == K
    for record in others:
        for field in SHARED_FIELDS:
            if field == "planning_time":  # the machine's: only its kind and sign
                assert isinstance(record[field], float) and record[field] > 0
            elif isinstance(plan[field], float):
                assert record[field] == pytest.approx(plan[field], rel=1e-12), field
            else:
                assert record[field] == plan[field], field
    # The path measures are those of the waypoints, recomputed here by hand for the lengths.
    wp = np.array(plan["waypoints"])
    assert plan["path_length"] == pytest.approx(float(np.linalg.norm(np.diff(wp, axis=0), axis=1).sum()), rel=1e-12)
    assert plan["base_length"] == pytest.approx(sum(math.dist(a[:2], b[:2]) for a, b in zip(wp, wp[1:])), rel=1e-12)
    # Every field plan and bench write is documented in the schema.
    assert set(plan) <= set(RUN_FIELDS)
    assert set(three_records["bench"]) <= set(RUN_FIELDS)
