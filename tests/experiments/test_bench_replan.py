"""The replanning benchmark (drake_social.experiments.bench.replanning).

Its statistics are checked on a hand-made log (records with the documented
fields of a ReplanResult) against numpy; the rollout and the simulated runs
on tiny.yaml against the replanner's own records.
"""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest

from drake_social.experiments.bench import replanning as dut
from drake_social.experiments.bench.machine import cpu_model
from drake_social.kinematics import nominal_path_times


@dc.dataclass(frozen=True)
class Replan:
    t: float
    plan_time: float
    status: str
    deadline_hit: bool = False
    changed: bool = False
    cost: float = 1.0
    iterations: int = 500
    searched: bool = True


def log() -> list[Replan]:
    rng = np.random.default_rng(3)
    out = [Replan(0.0, 0.9, "initial", changed=True)]
    for k in range(1, 41):
        status = "wait" if k in (7, 8) else ("new" if k % 10 == 0 else "kept")
        out.append(Replan(0.1 * k, float(rng.uniform(0.02, 0.09)), status, deadline_hit=k % 9 == 0,
                          changed=status == "new", cost=math.inf if status == "wait" else 1.0,
                          searched=k % 4 == 0 or status != "kept"))
    return out


def test_replan_time_stats_leave_the_first_plan_apart():
    replans = log()
    times = np.array([r.plan_time for r in replans[1:]])
    s = dut.replan_time_stats(replans, 0.08)
    assert s["n"] == 40 and s["initial_plan_time"] == 0.9
    assert s["median"] == np.median(times) and s["p95"] == np.percentile(times, 95) and s["max"] == times.max()
    assert s["mean"] == pytest.approx(times.mean(), rel=1e-15)
    assert s["deadline_hits"] == 4 and s["over_budget"] == int(np.sum(times > 0.08))
    assert s["path_changes"] == 4 and s["waits"] == 2
    searched = np.array([r.plan_time for r in replans[1:] if r.searched])
    assert s["searches"] == len(searched) == 13  # k a multiple of 4 (10 of them), the waits 7, 8 and the new 10, 30
    assert s["search_median"] == np.median(searched) and s["search_p95"] == np.percentile(searched, 95)
    empty = dut.replan_time_stats(replans[:1], 0.08)
    assert empty["n"] == 0 and empty["median"] is None and empty["initial_plan_time"] == 0.9


def test_position_at_follows_the_time_model():
    wp = np.array([[0.0, 0.0, 0.0, 0.0], [2.0, 0.0, 0.0, 0.0], [2.0, 0.0, 1.0, 0.0], [2.0, 3.0, 1.0, 0.0]])
    times = nominal_path_times(wp, 0.5, [0.5, 0.5], 1.0)  # 4 s, 2 s, 6 s from t = 1
    np.testing.assert_allclose(times, [1.0, 5.0, 7.0, 13.0])
    q, k = dut.position_at(wp, times, 3.0)
    np.testing.assert_allclose(q, [1.0, 0.0, 0.0, 0.0])
    assert k == 1
    q, k = dut.position_at(wp, times, 6.0)
    np.testing.assert_allclose(q, [2.0, 0.0, 0.5, 0.0])
    assert k == 2
    q, k = dut.position_at(wp, times, 5.0)  # at a waypoint: the next one is ahead
    np.testing.assert_allclose(q, wp[1])
    assert k == 2
    q, k = dut.position_at(wp, times, 20.0)
    np.testing.assert_array_equal(q, wp[-1])
    assert k == 4
    q, k = dut.position_at(wp, times, 0.0)
    np.testing.assert_array_equal(q, wp[0])
    assert k == 1


def test_markdown_rows():
    stats = dut.replan_time_stats(log(), 0.08)
    entry = {"scenario": "office_walkers.yaml", "processor": "a CPU", "load_average_start": [0.5, 0.4, 0.3],
             "load_average_end": [1.25, 0.5, 0.4],
             "settings": {"algorithm": "social_rrt_star", "replan_rate": 10.0, "replan_budget": 0.08,
                          "replan_iterations": 500, "replan_horizon": 5.0, "prediction": "constant_velocity"},
             "rollout": {"replans": 40, **stats},
             "simulation": {"runs": 2, "reached": True, "time_to_goal": 118.3, "sim_time": 118.4, "stopped_time": 1.5,
                            "realtime_factor": {"median": 7.25, "min": 7.0, "max": 7.5, "n": 2},
                            "replan_time": stats}}
    text = "\n".join(dut.replan_markdown(entry))
    assert "## Replanning (office_walkers)" in text
    assert "processor: a CPU (1-minute load average 0.50 at the start, 1.25 at the end)." in text
    row = (f"| 40 | {1e3 * stats['median']:.1f} | {1e3 * stats['p95']:.1f} | {1e3 * stats['max']:.1f} | 13 "
           f"| {1e3 * stats['search_median']:.1f} / {1e3 * stats['search_p95']:.1f} | 4 "
           f"| {stats['over_budget']} | 4 | 2 | 0.90 |")
    assert f"| kinematic rollout (first replans) {row}" in text
    assert f"| simulated run (kinematic) {row}" in text
    assert "realtime factor 7.2x [7.0, 7.5] over 2 run(s) (target >= 5x); goal at 118.3 s" in text


@pytest.mark.slow
def test_rollout_is_the_replanners_log(tiny_scenario_path, tiny_scenario):
    labels = []
    entry = dut.run_replan_bench(tiny_scenario_path, count=5, runs=0, progress=labels.append)
    assert labels == ["tiny rollout of 5 replans"] and entry["simulation"] is None
    assert entry["processor"] == cpu_model() and entry["scenario"] == "tiny.yaml"
    assert len(entry["load_average_start"]) == 3 and len(entry["load_average_end"]) == 3
    p = tiny_scenario.planner
    assert entry["settings"]["replan_budget"] == p.replan_budget and entry["settings"]["count"] == 5
    r = entry["rollout"]
    assert r["replans"] == r["n"] == 5 and set(r) >= {"median", "p95", "max", "deadline_hits", "initial_plan_time"}
    replans = dut.rollout_replans(tiny_scenario, 5, warm=False)
    assert [x.replan_index for x in replans] == list(range(6))
    np.testing.assert_allclose([x.t for x in replans], np.arange(6) / p.replan_rate)
    assert replans[0].status == "initial" and all(x.status in ("new", "kept", "wait", "evade") for x in replans[1:])
    # Each replan starts where the path decided before it had brought the robot.
    ex = tiny_scenario.execution
    for before, now in zip(replans, replans[1:]):
        if before.waiting:
            continue
        q, _ = dut.position_at(before.waypoints, nominal_path_times(before.waypoints, ex.max_base_speed,
                                                                      ex.arm_max_velocity, before.t), now.t)
        np.testing.assert_allclose(now.waypoints[0], q, atol=1e-12)


@pytest.mark.slow
def test_bench_with_replanning_runs(tiny_scenario_path, tmp_path):
    from drake_social.experiments.bench.planners import run_bench

    out = run_bench(scenario_paths=[tiny_scenario_path], algorithms=["social_rrt_star"], iterations=100, seeds=1,
                    checker="planar", include_ompl=False, include_checker=False, replan_runs=1, replan_count=3,
                    replan_scenario=tiny_scenario_path, out_dir=tmp_path)
    rb = out["replan_bench"]
    assert rb["rollout"]["n"] == 3 and rb["simulation"]["runs"] == 1
    sim = rb["simulation"]
    assert set(sim) == {"runs", "reached", "time_to_goal", "sim_time", "stopped_time", "realtime_factor",
                        "replan_time"}
    assert sim["realtime_factor"]["n"] == 1 and sim["realtime_factor"]["median"] > 0
    assert sim["replan_time"]["n"] >= 1 and sim["replan_time"]["initial_plan_time"] is not None
    md = (tmp_path / "bench.md").read_text()
    assert "## Replanning (tiny)" in md and "| simulated run (kinematic) |" in md


def test_rollout_under_the_interactive_prediction(tiny_scenario):
    """The benchmark gives the replanner the people now when it predicts them interactively."""
    import dataclasses as dc

    sc = dc.replace(tiny_scenario, planner=dc.replace(tiny_scenario.planner, prediction="interactive"))
    replans = dut.rollout_replans(sc, 3, warm=False)
    assert [x.replan_index for x in replans] == [0, 1, 2, 3] and replans[0].status == "initial"
    assert all(x.status in ("new", "kept", "wait", "evade") for x in replans[1:])
