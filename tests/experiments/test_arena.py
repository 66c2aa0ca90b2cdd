"""The Planner Arena export: our log, parsed by OMPL's own script, gives our numbers."""

from __future__ import annotations

import math
import sqlite3

import pytest

from drake_social.experiments.study.arena import build_database, statistics_script, write_logs
from drake_social.experiments.study import Group, Study, run_study

# A study exported to Planner Arena: many plans.
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def small(tiny_scenario_path):
    study = Study("arena", (Group("T", str(tiny_scenario_path), algorithms=("rrt_star", "base_rrt_star")),
                            Group("U", str(tiny_scenario_path), algorithms=("social_rrt_star",))),
                  runs=2, iterations=80, seed=3)
    return run_study(study)


def test_ompl_script_reads_our_log_into_rows_equal_to_the_records(small, tmp_path):
    if statistics_script() is None:
        pytest.skip("ompl (the bench extra) is not installed")
    logs = write_logs(small, tmp_path)
    assert logs == ["arena_T.log", "arena_U.log"]
    db = build_database([tmp_path / n for n in logs], tmp_path / "arena.db")
    con = sqlite3.connect(db)
    con.row_factory = sqlite3.Row
    experiments = {r["id"]: r["name"] for r in con.execute("SELECT id, name FROM experiments")}
    assert sorted(experiments.values()) == ["T", "U"]
    rows = con.execute("SELECT runs.*, plannerConfigs.name AS planner FROM runs JOIN plannerConfigs "
                       "ON runs.plannerid = plannerConfigs.id").fetchall()
    assert len(rows) == len(small.records) == 6
    by_key = {(experiments[r["experimentid"]], r["planner"], r["run"]): r for r in rows}
    for rec in small.records:
        row = by_key[(rec["group"], rec["algorithm"], rec["run"])]
        assert row["solved"] == int(rec["success"]) and row["seed"] == rec["seed"]
        assert row["time"] == pytest.approx(rec["planning_time"], rel=1e-12)
        for column in ("F_multi", "base_length", "min_dist_object_2", "zone_personal_base", "agf_max_arm"):
            if rec["success"]:
                assert row[column] == pytest.approx(rec[column], rel=1e-12, abs=1e-300), column
            else:
                assert row[column] is None
        assert (row["best_cost"] is None) == (not rec["success"])
    # The anytime curve: one progress row per kept iteration, costs as recorded.
    rec = small.records[0]
    runid = by_key[(rec["group"], rec["algorithm"], rec["run"])]["id"]
    progress = con.execute("SELECT time, best_cost, iterations FROM progress WHERE runid = ? ORDER BY iterations",
                           (runid,)).fetchall()
    assert len(rec["progress"]) >= 2 and rec["progress"][-1][0] == rec["iterations"]  # a real curve
    assert [p["iterations"] for p in progress] == [k for k, _ in rec["progress"]]
    for p, (_, c) in zip(progress, rec["progress"]):
        assert (p["best_cost"] is None and c is None) or math.isclose(p["best_cost"], c, rel_tol=1e-12)
    # OMPL's views (Planner Arena's best-planner tables) were computed.
    views = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type = 'view'")}
    assert "bestPlannerConfigsPerExperiment" in views
