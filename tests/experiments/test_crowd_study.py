"""The closed-loop crowd study (``drake-social experiment crowd``): episode
perturbation, statistics on hand-made records, and a tiny study end to end."""

from __future__ import annotations

import dataclasses as dc
import json
import math
import re
import types
from pathlib import Path

import numpy as np
import pytest

from drake_social.cli_parser import build_parser
from drake_social.errors import ScenarioError
from drake_social.experiments.study.crowd import (JITTER_TAG, VARIANTS, CrowdStudy, crowd_tasks, episode_scenario,
                                                  episode_seeds, perturb, walker_delays)
from drake_social.experiments.study.crowd_episode import replan_stats
from drake_social.experiments.study.crowd_report import claim_line, compare, target_lines
from drake_social.people import people_model
from drake_social.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[2]

TINY_WALKER = """\
description: "tiny with a walker: an 8 x 5 m room, a desk, one person crossing, a 1.5 m bar"
world:
  bounds: [0.0, 0.0, 8.0, 5.0]
  obstacles:
    - {center: [4.0, 0.6], size: [1.6, 0.8], yaw: 0.0}
people:
  - {x: 7.0, y: 4.5, theta: 3.1416, radius: 0.25, name: "standing"}
  - name: "walker"
    x: 3.0
    y: 4.5
    theta: -1.5708
    radius: 0.25
    trajectory: [[1.0, 3.0, 4.5], [4.0, 3.5, 1.6], [7.0, 3.0, 4.5]]
    loop: true
robot:
  base_radius: 0.35
  link_lengths: [0.6, 0.5]
  link_width: 0.08
object: !Bar {length: 1.5, thickness: 0.05}
start: [1.0, 2.5, 0.0, 1.5708]
goal: [6.5, 2.5, 0.0, 1.5708]
random_seed: 1
planner: {iterations: 300}
execution: {time_limit: 20.0}
"""


@pytest.fixture
def tiny_walker(tmp_path) -> Path:
    path = tmp_path / "tiny_walker.yaml"
    path.write_text(TINY_WALKER)
    return path


def test_episode_seeds_are_the_study_run_seeds():
    seeds = episode_seeds(7, 3)
    assert seeds == [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(7).spawn(3)]
    assert CrowdStudy(scenarios=("a.yaml",), episodes=3, seed=7).run_seeds() == seeds


def test_jitter_shifts_the_walkers_times_by_their_delays(tiny_walker):
    scenario = load_scenario(tiny_walker)
    seed, jitter = 12345, 2.0
    # The delay by hand: the first uniform draw of the walker's own generator (index 1: the standing person is 0).
    u = np.random.default_rng(np.random.SeedSequence([seed, JITTER_TAG, 1])).random()
    episode, delays = perturb(scenario, seed, jitter)
    assert delays == {1: pytest.approx(2.0 * u, abs=0)}
    d = delays[1]
    assert 0.0 <= d <= jitter
    assert episode.random_seed == seed and scenario.random_seed == 1  # a copy; the loaded scenario unchanged
    assert episode.people[0] == scenario.people[0]  # a standing person is not delayed
    assert episode.people[1].trajectory == [[1.0 + d, 3.0, 4.5], [4.0 + d, 3.5, 1.6], [7.0 + d, 3.0, 4.5]]
    assert scenario.people[1].trajectory[0] == [1.0, 3.0, 4.5]
    # The walker stands at its first point d seconds longer, then walks the same route d seconds later.
    model = people_model(episode)
    np.testing.assert_allclose(model.state_at(0.0).positions[1], [3.0, 4.5])
    np.testing.assert_allclose(model.state_at(1.0 + d).positions[1], [3.0, 4.5], atol=1e-12)
    np.testing.assert_allclose(model.state_at(4.0 + d).positions[1], [3.5, 1.6], atol=1e-12)
    np.testing.assert_allclose(model.state_at(2.5 + d).positions[1], [3.25, 3.05], atol=1e-12)  # half way
    # The loop's period is kept: one period (6 s) later it is at the same point.
    np.testing.assert_allclose(model.state_at(10.0 + d).positions[1], [3.5, 1.6], atol=1e-12)
    # No jitter: the same trajectory.
    same, zero = perturb(scenario, seed, 0.0)
    assert zero == {1: 0.0} and same.people[1].trajectory == scenario.people[1].trajectory


def test_episodes_are_deterministic_and_paired_across_variants(tiny_walker):
    study = CrowdStudy(scenarios=(str(tiny_walker),), variants=("plan_once", "replan_multi", "replan_speed"),
                       episodes=3, seed=4, jitter=3.0)
    tasks = crowd_tasks(study)
    assert len(tasks) == 9
    assert [(t["variant"], t["episode"]) for t in tasks[:4]] == [("plan_once", 0), ("plan_once", 1),
                                                                 ("plan_once", 2), ("replan_multi", 0)]
    by = {(t["variant"], t["episode"]): t for t in tasks}
    for k, seed in enumerate(study.run_seeds()):
        scenarios = {v: episode_scenario(by[(v, k)]) for v in study.variants}
        walkers = {v: [p.trajectory for p in s.people] for v, (s, _) in scenarios.items()}
        assert walkers["plan_once"] == walkers["replan_multi"] == walkers["replan_speed"]
        assert {s.random_seed for s, _ in scenarios.values()} == {seed}
        assert scenarios["plan_once"][1] == walker_delays(load_scenario(tiny_walker), seed, 3.0)
        again = episode_scenario(dict(by[("replan_speed", k)]))
        assert [p.trajectory for p in again[0].people] == walkers["replan_speed"]
        # The variants differ only by their overrides.
        s_once, s_speed = scenarios["plan_once"][0], scenarios["replan_speed"][0]
        assert (s_once.planner.replan, s_speed.planner.replan) == (False, True)
        assert (s_once.social.speed_scaling, s_speed.social.speed_scaling) == (False, True)
    delays = [episode_scenario(by[("plan_once", k)])[1][1] for k in range(3)]
    assert len(set(delays)) == 3  # the episodes differ


def test_variants_are_the_issue_s():
    from drake_social.limits import CROWD_VARIANTS

    assert list(VARIANTS) == list(CROWD_VARIANTS) == ["plan_once", "replan_base", "replan_multi", "replan_speed"]


@pytest.mark.parametrize("settings, error, message", [
    ({"episodes": 0}, ValueError, "CrowdStudy: episodes must be an integer >= 1 and <= 10,000, got 0"),
    ({"episodes": 10_001}, ValueError, "CrowdStudy: episodes must be an integer >= 1 and <= 10,000, got 10001"),
    ({"episodes": True}, TypeError, "CrowdStudy: episodes must be an integer >= 1 and <= 10,000, got bool True"),
    ({"jitter": -1.0}, ValueError, "CrowdStudy: jitter must be a finite number >= 0 and <= 600 seconds, got -1.0"),
    ({"jitter": 600.0000000000001}, ValueError,
     "CrowdStudy: jitter must be a finite number >= 0 and <= 600 seconds, got 600.0000000000001"),
    ({"jitter": "1"}, TypeError, "CrowdStudy: jitter must be a finite number >= 0 and <= 600 seconds, got str '1'"),
    ({"variants": ("nope",)}, ValueError, "CrowdStudy: unknown variants[0] 'nope'; allowed: plan_once, "
                                          "replan_base, replan_multi, replan_speed"),
    ({"variants": ("plan_once", "plan_once")}, ValueError, "CrowdStudy: variants must name each of plan_once, "
                                                           "replan_base, replan_multi, replan_speed at most once"),
    ({"variants": ()}, ValueError, "CrowdStudy: variants must be a non-empty list or tuple"),
    ({"scenarios": ("a/x.yaml", "b/x.yaml")}, ScenarioError, "crowd study: scenarios: the file names ['x', 'x'] "
                                                             "must be distinct"),
    ({"scenarios": "a.yaml"}, TypeError, "CrowdStudy: scenarios must be a list or tuple of file names"),
    ({"seed": -1}, ValueError, "CrowdStudy: seed must be an integer >= 0, got -1"),
    ({"time_limit": 0.0}, ValueError, "CrowdStudy: time_limit must be a finite number > 0 and <= 600 seconds, got 0.0"),
    ({"time_limit": 600.0000000000001}, ValueError,
     "CrowdStudy: time_limit must be a finite number > 0 and <= 600 seconds, got 600.0000000000001"),
    ({"time_limit": "5"}, TypeError,
     "CrowdStudy: time_limit must be a finite number > 0 and <= 600 seconds or None, got str '5'"),
    ({"trace_episode": -1}, ValueError, "CrowdStudy: trace_episode must be an integer >= 0, got -1"),
    ({"trace_episode": 3, "episodes": 3}, ValueError,
     "CrowdStudy: trace_episode must be one of the 3 episodes, in [0, 2], or None, got 3"),
])
def test_study_settings_are_checked(settings, error, message):
    with pytest.raises(error) as info:
        CrowdStudy(**{"scenarios": ("a.yaml",), **settings})
    assert str(info.value).startswith(message) and type(info.value) is error


@pytest.mark.parametrize("time_limit, ok", [(0.05, True), (0.05 * (1 - 2e-9), False), (300.0, True),
                                            (300.0 * (1 + 2e-9), False)])
def test_the_study_time_limit_keeps_to_each_scenarios_rules_of_a_run(tmp_path, time_limit, ok):
    # 10 to 60,000 control periods (and at most 300,000 plant steps): tiny.yaml with a 0.005 s control
    # period and a 0.001 s plant step runs 0.05 .. 300 s, whole periods up to a relative 1e-9 (period_count).
    path = tmp_path / "fine.yaml"
    path.write_text((ROOT / "scenarios" / "tiny.yaml").read_text()
                    + "execution: {control_period: 0.005, plant_time_step: 0.001}\n")
    study = CrowdStudy(scenarios=(str(path),), variants=("plan_once",), episodes=1, time_limit=time_limit)
    if ok:
        assert [t["time_limit"] for t in crowd_tasks(study)] == [time_limit]
    else:
        with pytest.raises(ScenarioError, match=rf"^{re.escape(str(path))}: the crowd study's time_limit "
                                                rf"\(--time-limit\) must be"):
            crowd_tasks(study)


def test_study_settings_at_their_bounds_are_accepted():
    dut = CrowdStudy(scenarios=("a.yaml",), episodes=10_000, jitter=600.0, time_limit=600.0, trace_episode=9_999)
    assert (dut.episodes, dut.jitter, dut.time_limit, dut.trace_episode) == (10_000, 600.0, 600.0, 9_999)
    dut = CrowdStudy(scenarios=("a.yaml",), episodes=1, jitter=0.0, time_limit=5e-324, trace_episode=None)
    assert (dut.episodes, dut.jitter, dut.trace_episode) == (1, 0.0, None)


def test_replan_stats_by_hand():
    def r(status, changed, plan_time, hit=False, searched=True):
        return types.SimpleNamespace(status=status, changed=changed, plan_time=plan_time, deadline_hit=hit,
                                     searched=searched)

    log = [r("initial", True, 0.5), r("new", True, 0.01), r("kept", False, 0.04, True), r("wait", False, 0.02),
           r("kept", False, 0.03, searched=False), r("evade", True, 0.001, searched=False)]
    s = replan_stats(log)
    # The periodic replans: 0.01, 0.04, 0.02, 0.03, 0.001 -> sorted 0.001 0.01 0.02 0.03 0.04: median 0.02,
    # 95th percentile at rank 0.95 * 4 = 3.8: 0.03 + 0.8 * 0.01; those that searched: 0.01 0.04 0.02.
    assert s == {"replans": 5.0, "replan_changes": 2.0, "replan_waits": 1.0, "replan_evasions": 1.0,
                 "replan_searches": 3.0, "replan_time_median": pytest.approx(0.02),
                 "replan_time_p95": pytest.approx(0.038), "replan_time_max": 0.04,
                 "replan_search_time_median": pytest.approx(0.02), "replan_deadline_hits": 1.0}
    assert all(math.isnan(v) for v in replan_stats(None).values())


def _records(values_a, values_b, metric="nav_time_intimate_object"):
    out = []
    for variant, values in (("replan_multi", values_a), ("replan_base", values_b)):
        for k, v in enumerate(values):
            out.append({"scenario": "s", "variant": variant, "episode": k, "reached": 1.0, metric: v})
    return out


def test_paired_statistics_on_hand_made_records():
    # Differences multi - base: -1, -2, 0, -3, -4. Wilcoxon drops the zero: 4 negative
    # differences, so W+ = 0, whose one-sided exact probability is 1 / 2^4.
    records = _records([1.0, 2.0, 3.0, 4.0, 5.0], [2.0, 4.0, 3.0, 7.0, 9.0])
    c = compare(records, "s", "replan_multi", "replan_base", "nav_time_intimate_object", "lower")
    assert (c.n, c.wins) == (5, 4)
    assert (c.median_a, c.median_b, c.median_diff) == (3.0, 4.0, -2.0)
    assert c.p == pytest.approx(1 / 16)
    assert c.verdict == "not significant"
    line = claim_line(c, "s")
    assert line == ("- **NOT SIGNIFICANT**: s: replanning multi-point vs replanning base-only: object intimate-zone "
                    "time lower in 4/5 paired episodes (median 3 s vs 4 s, median difference -2 s, one-sided "
                    "Wilcoxon p = 0.0625)")
    # Five negative differences: p = 1 / 2^5 < 0.05; a NaN leaves its pair out.
    records = _records([1.0, 2.0, 3.0, 4.0, 5.0, float("nan")], [2.0, 4.0, 3.5, 7.0, 9.0, 1.0])
    c = compare(records, "s", "replan_multi", "replan_base", "nav_time_intimate_object", "lower")
    assert (c.n, c.wins, c.p, c.verdict) == (5, 5, pytest.approx(1 / 32), "supported")
    # The other way round: not supported.
    c = compare(records, "s", "replan_base", "replan_multi", "nav_time_intimate_object", "lower")
    assert c.verdict == "not supported" and c.wins == 0


def test_target_lines_on_hand_made_records():
    records = []
    for k in range(20):
        records.append({"scenario": "s", "variant": "replan_multi", "episode": k, "reached": float(k != 3),
                        "nav_collisions_robot": 0.0, "nav_stop_count": float(k % 2),
                        "replan_times": [0.01, 0.02, 0.09, 0.1] if k == 0 else [0.03], "replan_deadline_hits": float(k == 0)})
    lines = target_lines(records, ["s"], ["replan_multi"], {"s": 0.08})
    assert lines[0].startswith("- **MET** (target): s, replanning multi-point: collisions with people: 0 contact(s) "
                               "in 0/20 episodes, 0 begun with the robot commanded to move, 0 by a person appearing "
                               "in contact, the rest walked into the held robot (safety stops: 10 in all")
    # Contacts in episodes 5 (3: one moving, one appearing) and 7 (1, walked into); a record without
    # a stop flag (moving null) counts no moving contact.
    records[5].update(nav_collisions_robot=3.0, nav_collisions_moving_robot=1.0, nav_collisions_appeared_robot=1.0)
    records[7].update(nav_collisions_robot=1.0, nav_collisions_moving_robot=None, nav_collisions_appeared_robot=0.0)
    touched = target_lines(records, ["s"], ["replan_multi"], {"s": 0.08})[0]
    assert touched.startswith("- **MISSED** (target): s, replanning multi-point: collisions with people: 4 "
                              "contact(s) in 2/20 episodes, 1 begun with the robot commanded to move, 1 by a person "
                              "appearing in contact, the rest walked into the held robot (safety stops: 10 in all")
    assert lines[1] == ("- **MET** (target): s, replanning multi-point: success 19/20 = 95.0 % (target >= 95 %)")
    # 23 replan times, sorted 0.01, 0.02, 0.03 x 19 (ranks 2..20), 0.09, 0.1: median 0.03; the 95th
    # percentile at rank 0.95 * 22 = 20.9: 0.03 + 0.9 * (0.09 - 0.03) = 0.084 > the budget 0.08.
    assert lines[2].startswith("- **MISSED** (target): s, replanning multi-point: replan time over 23 replans: "
                               "median 0.03 s (target <= 0.05 s), 95th percentile 0.084 s")
    assert lines[2].endswith("max 0.1 s, 1 deadline hits")


def test_cli_parses_experiment_crowd():
    args = build_parser().parse_args(["experiment", "crowd", "--episodes", "3", "--variants", "plan_once",
                                      "replan_multi", "--jitter", "2.5", "--workers", "2", "--out", "x"])
    assert (args.study, args.episodes, args.variants, args.jitter, args.workers) == \
        ("crowd", 3, ["plan_once", "replan_multi"], 2.5, 2)
    for bad in (["--episodes", "0"], ["--jitter", "-1"], ["--variants", "nope"]):
        with pytest.raises(SystemExit):
            build_parser().parse_args(["experiment", "crowd", *bad])


def test_the_default_scenarios_are_the_shipped_ones_whatever_the_folder(tmp_path, monkeypatch):
    """``experiment crowd`` and a CrowdStudy without scenarios find the
    shipped office_walkers.yaml and lobby_crowd.yaml beside the package, run
    from any folder."""
    monkeypatch.chdir(tmp_path)
    shipped = ROOT / "scenarios"
    args = build_parser().parse_args(["experiment", "crowd"])
    assert args.scenarios == [shipped / "office_walkers.yaml", shipped / "lobby_crowd.yaml"]
    dut = CrowdStudy(variants=("plan_once",), episodes=1)
    assert dut.scenarios == tuple(str(p) for p in args.scenarios)
    tasks = crowd_tasks(dut)  # read and loaded from here
    assert [(t["scenario"], t["source"]) for t in tasks] == [("office_walkers", str(shipped / "office_walkers.yaml")),
                                                            ("lobby_crowd", str(shipped / "lobby_crowd.yaml"))]
    assert tasks[0]["scenario_text"] == (shipped / "office_walkers.yaml").read_text()


_MACHINE = ("wall_time", "plan_time_initial", "replan_time_median", "replan_time_p95", "replan_time_max",
            "replan_search_time_median",
            "replan_times")


@pytest.mark.slow
def test_tiny_study_writes_its_outputs_and_does_not_depend_on_the_workers(tiny_walker, tmp_path):
    from drake_social.app import run_crowd_experiment

    settings = dict(scenarios=(str(tiny_walker),), variants=("plan_once",), episodes=2, seed=3, jitter=2.0,
                    time_limit=12.0)
    study = CrowdStudy(**settings)
    done = run_crowd_experiment(out=tmp_path / "one", workers=1, **settings)
    one, names = done.result, done.files
    assert done.failure is None and not done.interrupted and done.runs == "2 episodes"
    assert names == ["records.csv", "records.json", "boxplots_tiny_walker.png", "snapshots_tiny_walker.png",
                     "REPORT.md"]
    for n in names:
        assert (tmp_path / "one" / n).stat().st_size > 0
    csv = (tmp_path / "one" / "records.csv").read_text().splitlines()
    assert len(csv) == 3 and csv[0].startswith("index,scenario,variant,episode,seed,jitter,")
    saved = json.loads((tmp_path / "one" / "records.json").read_text())
    assert saved["seeds"] == study.run_seeds() and len(saved["episodes"]) == 2
    assert saved["study"] == json.loads(json.dumps(dc.asdict(study)))
    assert set(saved) == {"study", "seeds", "wall_time", "executor", "workers", "episodes"}
    report = (tmp_path / "one" / "REPORT.md").read_text()
    assert "tiny_walker, plan-once (paper): success" in report and "![snapshots_tiny_walker.png]" in report
    for r in one.records:
        assert r["sim_time"] <= 12.0 + 1e-9 and r["nav_people_count"] == 2.0 and "nav_time_intimate_object" in r
        assert math.isnan(r["replans"])
    assert "trace" in one.records[0] and "trace" not in one.records[1]
    two = run_crowd_experiment(out=tmp_path / "two", workers=2, **settings).result

    def same(r):
        return json.dumps({k: v for k, v in r.items() if k not in _MACHINE}, sort_keys=True, default=str)

    assert [same(r) for r in one.records] == [same(r) for r in two.records]


def _no_space(*args, **kwargs):
    raise OSError(28, "No space left on device")


def _interrupt(*args, **kwargs):
    raise KeyboardInterrupt


@pytest.mark.slow
@pytest.mark.parametrize("where, failure", [("write_figures", _no_space), ("report_markdown", _no_space),
                                            ("write_figures", _interrupt)])
def test_an_output_error_or_ctrl_c_after_the_episodes_keeps_their_records(tiny_walker, tmp_path, monkeypatch, capsys,
                                                                          where, failure):
    """As for every study: when a figure or REPORT.md fails, or Ctrl-C comes
    while they are written, the finished episodes' records are committed
    alone and the message names them (exit 1, or 130 for Ctrl-C)."""
    from drake_social.cli import main
    from drake_social.experiments.study import crowd_report
    from drake_social.io.outputs import current_set

    out = tmp_path / "out"
    monkeypatch.setattr(crowd_report, where, failure)
    rc = main(["experiment", "crowd", "--scenarios", str(tiny_walker), "--variants", "plan_once", "--episodes", "2",
               "--time-limit", "1", "--out", str(out)])
    err = capsys.readouterr().err
    records = f"{out / 'records.json'} and {out / 'records.csv'} (the figures and REPORT.md were not written)\n"
    if failure is _interrupt:
        assert rc == 130
        assert err == f"drake-social: experiment interrupted after its 2 episodes: their records were written to {records}"
    else:
        assert rc == 1
        assert err == (f"drake-social: error: writing the study's outputs into {out} failed: [Errno 28] No space left "
                       f"on device; the records of its 2 episodes are in {records}")
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == ["records.csv", "records.json"]
    assert current_set(out, "experiment").files == ("records.csv", "records.json")
    episodes = json.loads((out / "records.json").read_text())["episodes"]
    assert [(r["variant"], r["episode"], r["sim_time"]) for r in episodes] == [("plan_once", 0, 1.0), ("plan_once", 1, 1.0)]


def test_a_replanning_variant_needs_a_simulator_that_replans(tiny_walker, monkeypatch):
    from drake_social.experiments.study import crowd

    study = CrowdStudy(scenarios=(str(tiny_walker),), variants=("plan_once", "replan_multi"), episodes=1)
    monkeypatch.setattr(crowd, "replanning_available", lambda: False)
    with pytest.raises(ScenarioError, match=r"crowd study: variants \['plan_once', 'replan_multi'\]: the replanning "
                       r"variants need simulate\(\.\.\., replan=True\)"):
        crowd.check_crowd_study(study)
    assert len(crowd.check_crowd_study(dc.replace(study, variants=("plan_once",)))) == 1


def test_a_claim_without_pairs_says_so():
    records = _records([1.0, float("nan")], [float("nan"), 2.0], metric="nav_time_to_goal")
    c = compare(records, "s", "replan_multi", "replan_base", "nav_time_to_goal", "lower")
    assert c.n == 0
    assert claim_line(c, "s") == ("- **NOT SUPPORTED**: s: replanning multi-point vs replanning base-only: time to "
                                  "goal lower: no paired episode has a value on both sides")


@pytest.mark.slow
def test_replanning_episodes_are_paired_and_do_not_depend_on_the_workers(tmp_path):
    """With a budget no replan reaches (the iteration cap binds), replanning
    episodes are the same on 1 and 2 workers, bit for bit but for the wall clock."""
    from drake_social.experiments.study import run_study
    from drake_social.experiments.study.crowd import replanning_available

    if not replanning_available():
        pytest.skip("simulate(..., replan=True) is not in this tree yet")
    path = tmp_path / "tiny_walker.yaml"
    path.write_text(TINY_WALKER.replace("planner: {iterations: 300}", "planner: {iterations: 300, replan_rate: 2.0, "
                                        "replan_iterations: 60, replan_budget: 30.0}"))
    study = CrowdStudy(scenarios=(str(path),), variants=("replan_multi",), episodes=2, seed=5, jitter=2.0,
                       time_limit=8.0)
    one = run_study(study, workers=1)
    two = run_study(study, workers=2)
    for r in one.records:
        assert r["replans"] >= 10 and r["replan_deadline_hits"] == 0.0  # 2 Hz over 8 s, none over the budget
        assert r["replan_changes"] <= r["replans"] and len(r["replan_times"]) == r["replans"]

    def same(r):
        return json.dumps({k: v for k, v in r.items() if k not in _MACHINE}, sort_keys=True, default=str)

    assert [same(r) for r in one.records] == [same(r) for r in two.records]


def test_the_crowd_study_is_a_kind_of_the_one_study_framework(tiny_walker):
    """A CrowdStudy goes through the studies' framework: its kind's tasks,
    per-task function, record files and outputs; anything else is no study."""
    from drake_social.experiments.study import KINDS, Study, kind_of, output_names, run_task
    from drake_social.experiments.study.crowd_episode import run_episode
    from drake_social.experiments.study.recorded import RecordedCrowdStudy

    study = CrowdStudy(scenarios=(str(tiny_walker),), variants=("plan_once", "replan_multi"), episodes=2)
    dut = kind_of(study)
    assert set(KINDS) == {Study, CrowdStudy, RecordedCrowdStudy} and dut is KINDS[CrowdStudy]
    assert (dut.run, KINDS[Study].run) == (run_episode, run_task)
    assert dut.tasks(study) == crowd_tasks(study)
    assert output_names(study) == ["records.csv", "records.json", "boxplots_tiny_walker.png",
                                   "snapshots_tiny_walker.png", "REPORT.md"]
    assert output_names(dc.replace(study, trace_episode=None)) == ["records.csv", "records.json",
                                                                   "boxplots_tiny_walker.png", "REPORT.md"]
    assert dut.describe({"scenario": "s", "variant": "plan_once", "episode": 3}) == "s plan_once episode 3"
    with pytest.raises(TypeError, match=r"^not a study: dict; a study is one of Study, CrowdStudy, RecordedCrowdStudy$"):
        kind_of({"name": "crowd"})


def test_a_crowd_result_loads_its_scenarios_from_the_text_its_episodes_read(tiny_walker):
    """StudyResult.scenario of a crowd study: the text read before the
    episodes with a variant's overrides, whatever the file holds since."""
    from drake_social.experiments.study import StudyResult

    study = CrowdStudy(scenarios=(str(tiny_walker),), variants=("plan_once", "replan_speed"), episodes=1)
    text = tiny_walker.read_text()
    tiny_walker.write_text(text.replace("random_seed: 1", "random_seed: 2"))
    dut = StudyResult(study, [], 0.0, scenario_texts={"tiny_walker": text})
    assert (dut.scenario("tiny_walker").random_seed, dut.scenario("tiny_walker").planner.replan) == (1, False)
    speed = dut.scenario("tiny_walker", variant="replan_speed")
    assert (speed.planner.replan, speed.social.speed_scaling) == (True, True)
    assert study.scenario("tiny_walker").random_seed == 2  # without the text: the file as it is now
