"""A small study end to end: every file and figure, the same numbers on every
backend, seeds from the study seed, and claim lines computed from the data."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from drake_social.experiments.study.report import paired, paper_claims, report_markdown
from drake_social.experiments.study import (
    Group,
    Study,
    StudyResult,
    comparable,
    load_sweep,
    paper_study,
    run_study,
    study_tasks,
    write_study,
)
from drake_social.scenario import ScenarioError

# Studies: many plans per test.
pytestmark = pytest.mark.slow

_FILES = {"results.csv", "results.json", "REPORT.md", "boxplot_T.png", "cost_profile_T.png", "paths_T.png",
          "paths_single_algorithm_groups.png", "boxplot_single_algorithm_groups.png", "arena_T.log", "arena_W.log"}


def _study(tiny) -> Study:
    return Study("small", (Group("T", str(tiny), algorithms=("rrt_star", "social_rrt_star")),
                           Group("W", str(tiny), overrides=("social: {weights: [0.95, 0.05, 0.05, 0.05, 0.05]}",),
                                 algorithms=("social_rrt_star",))), runs=2, iterations=120, seed=7)


@pytest.fixture(scope="module")
def sequential(tiny_scenario_path):
    return run_study(_study(tiny_scenario_path), workers=1)


def test_seeds_come_from_the_study_seed_and_pair_runs(tiny_scenario_path):
    dut = _study(tiny_scenario_path)
    expected = [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(7).spawn(2)]
    assert dut.run_seeds() == expected
    tasks = study_tasks(dut)
    assert len(tasks) == 6 and [t["index"] for t in tasks] == list(range(6))
    assert {t["seed"] for t in tasks if t["run"] == 1} == {expected[1]}  # shared by every group and algorithm
    assert all(isinstance(t["scenario_text"], str) and "people" in t["scenario_text"] for t in tasks)


def test_small_study_writes_every_file(sequential, tmp_path):
    names = write_study(sequential, tmp_path)
    assert _FILES <= set(names)
    for name in names:
        assert (tmp_path / name).stat().st_size > 0, name
    data = json.loads((tmp_path / "results.json").read_text())
    assert len(data["runs"]) == 6 and data["seeds"] == sequential.study.run_seeds()
    rows = (tmp_path / "results.csv").read_text().splitlines()
    assert len(rows) == 7 and "min_dist_object_2" in rows[0] and "zone_personal_arm" in rows[0]
    report = (tmp_path / "REPORT.md").read_text()
    for figure in (n for n in names if n.endswith(".png")):
        assert f"]({figure})" in report
    ok = [r for r in sequential.records if r["success"]]
    assert ok, "tiny.yaml is solvable at K = 120"
    for r in ok:  # the record's F is the path's, recomputed
        assert r["F_multi"] >= r["F_base"] >= 0 and r["base_length"] > 5.4  # start and goal 5.5 m apart


def test_two_workers_and_dask_give_the_same_numbers(sequential, tiny_scenario_path):
    expected = [comparable(r) for r in sequential.records]
    pool = run_study(_study(tiny_scenario_path), workers=2)
    assert [comparable(r) for r in pool.records] == expected
    pytest.importorskip("distributed")
    dask = run_study(_study(tiny_scenario_path), workers=2, executor="dask")
    assert [comparable(r) for r in dask.records] == expected


def _fake(group: str, algorithm: str, values: dict[str, list[float]]) -> list[dict]:
    n = len(next(iter(values.values())))
    return [{"group": group, "algorithm": algorithm, "run": k, "success": True, **{m: v[k] for m, v in values.items()}}
            for k in range(n)]


def _paper_records(multi_beats_base: bool = True) -> list[dict]:
    rng = np.random.default_rng(3)
    records = []
    for g in ("A", "B"):
        base = 10 + rng.random(10)
        records += _fake(g, "rrt_star", {"F_multi": list(base + 10), "base_length": list(np.full(10, 10.0))})
        records += _fake(g, "social_rrt_star", {"F_multi": list(base + (-3 if multi_beats_base else 3)),
                                                "base_length": list(np.full(10, 12.0) + rng.random(10))})
        records += _fake(g, "base_rrt_star", {"F_multi": list(base)})
        records += _fake(g, "informed_social_rrt_star", {"F_multi": list(base - (4 if g == "A" else 1))})
        records += _fake(g, "informed_base_rrt_star", {"F_multi": list(base + 1)})
    far, near = list(2.0 + rng.random(10)), list(0.5 + 0.1 * rng.random(10))
    records += _fake("D_base", "social_rrt_star", {"min_dist_base": far, "min_dist_object": near,
                                                   "agf_mean_base": near, "agf_mean_object": far})
    records += _fake("D_object", "social_rrt_star", {"min_dist_base": near, "min_dist_object": far,
                                                     "agf_mean_base": far, "agf_mean_object": near})
    return records


def test_claims_follow_the_data_and_a_failing_claim_is_reported():
    claims = {c.source + c.statement[:20]: c for c in paper_claims(_paper_records())}
    assert all(c.verdict == "supported" for c in claims.values()), [c.markdown() for c in claims.values()]
    bad = paper_claims(_paper_records(multi_beats_base=False))
    multi = next(c for c in bad if c.statement.startswith("multi-point planners beat"))
    assert multi.verdict == "not supported"
    assert any("Risk-RRT* (multi-point) 13" in line and "not supported" in line for line in multi.lines)
    # The other claims do not depend on that pair and still hold.
    assert all(c.verdict == "supported" for c in bad if c.source == "V-D")
    result = StudyResult(paper_study(runs=10), _paper_records(multi_beats_base=False), 1.0)
    text = report_markdown(result, [], claims=bad)
    assert "- **NOT SUPPORTED**: multi-point planners beat" in text


def test_paired_comparison_numbers():
    records = _fake("G", "a", {"m": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]}) + _fake("G", "b", {"m": [2.0, 3.5, 3.0, 6.0,
                                                                                             5.5, 9.0]})
    records[2]["success"] = False  # run 2 drops out of the pairs
    dut = paired(records, ("G", "a"), ("G", "b"), "m")
    assert dut.n == 5 and dut.wins == 5
    assert dut.median_diff == pytest.approx(-1.5) and dut.median_a == 4.0 and dut.median_b == 5.5
    assert dut.p == pytest.approx(1 / 32) and dut.verdict == "supported"
    assert paired(records, ("G", "b"), ("G", "a"), "m").verdict == "not supported"


def test_paper_study_groups_and_weights():
    dut = paper_study(runs=10, iterations=2000)
    assert [g.name for g in dut.groups] == ["A", "B", "D_object", "D_base", "D_equal"]
    assert len(dut.groups[0].algorithms) == 5 and len(study_tasks(dut)) == 130
    d = {g.name: g for g in dut.groups}
    assert "!Bar {length: 1.5" in d["D_base"].overrides[0]
    assert "[0.05, 0.05, 0.05, 0.95, 0.95]" in d["D_object"].overrides[1]
    assert "[0.95, 0.05, 0.05, 0.05, 0.05]" in d["D_base"].overrides[1]


def test_sweep_file(tmp_path, tiny_scenario_path, repo_root):
    dut = load_sweep(repo_root / "studies" / "example_sweep.yaml")
    assert dut.runs >= 1 and len(dut.groups) >= 2
    bad = tmp_path / "bad.yaml"
    bad.write_text(f"scenarios: [{tiny_scenario_path}]\nalgorithms: [rrt]\n")
    with pytest.raises(ScenarioError, match="algorithms"):
        load_sweep(bad)
    bad.write_text(f"scenarios: [{tiny_scenario_path}]\nvariants: {{x: {{social: {{sigma_h: -1}}}}}}\n")
    with pytest.raises(ScenarioError, match="sigma_h"):
        load_sweep(bad)
    bad.write_text(f"scenarios: [{tiny_scenario_path}]\nrun: 3\n")
    with pytest.raises(ScenarioError, match="line 2: run: unknown field at the top level; allowed: name, runs"):
        load_sweep(bad)


def test_the_scenario_cache_reloads_when_the_people_file_changes(tmp_path, monkeypatch):
    """A study's scenario cache is keyed by the people_file's bytes too: a
    recording changed on disk is read and checked again (here it now puts
    someone inside the desk, an error) instead of reusing the old load."""
    import collections
    from pathlib import Path

    from drake_social.experiments.study import scenarios as study_scenarios
    from drake_social.scenario import ScenarioError

    monkeypatch.setattr(study_scenarios, "_loaded", collections.OrderedDict())
    tiny = Path(__file__).resolve().parents[2] / "scenarios" / "tiny.yaml"
    text = tiny.read_text() + "people_file: walkers.csv\n"
    source = str(tmp_path / "s.yaml")
    walkers = tmp_path / "walkers.csv"
    walkers.write_text("t,id,x,y\n0,1,6.0,4.0\n8,1,6.0,4.0\n")
    first = study_scenarios.load_cached(source, text, ())
    assert study_scenarios.load_cached(source, text, ()) is first  # unchanged file: cached
    walkers.write_text("t,id,x,y\n0,1,4.0,0.6\n8,1,4.0,0.6\n")  # the desk's centre
    with pytest.raises(ScenarioError, match=r"inside world\.obstacles\[0\]"):
        study_scenarios.load_cached(source, text, ())
    walkers.write_text("t,id,x,y\n0,1,6.0,4.5\n8,1,6.0,4.5\n")
    again = study_scenarios.load_cached(source, text, ())
    assert again is not first and again.people_file == str(walkers)
