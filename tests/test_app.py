"""drake_social.app called from Python: each command's work, its record and files, checked against independent
computations."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from drake_social import app
from drake_social.collision.geometric import GeometricChecker
from drake_social.cost.social import SocialCost
from drake_social.io.records import PLANNER_FIELDS, SHARED_FIELDS
from drake_social.scenario.geometry import arm_geometry
from drake_social.planning.algorithms import make_objective, plan
from drake_social.scenario import PREDICTIONS, ScenarioError, load_scenario


def _edges(wp: np.ndarray):
    return [(wp[i:i + 1], wp[i + 1:i + 2]) for i in range(len(wp) - 1)]


@pytest.fixture(scope="module")
def planned(tmp_path_factory, tiny_scenario_path):
    """One run_plan of tiny: base_rrt_star, seed 4 (by --set), K = 300, the numpy checker."""
    out = tmp_path_factory.mktemp("plan") / "tiny"
    dut = app.run_plan(scenario=tiny_scenario_path, out=out, overrides=["random_seed: 4"], iterations=300,
                       checker="numpy", algorithm="base_rrt_star")
    return dut, out


def test_run_plan_record_is_the_written_path_measured_independently(planned, tiny_scenario_path):
    dut, out = planned
    record, result = dut.record, dut.result
    scenario = load_scenario(tiny_scenario_path)
    assert record["success"] is True and record["algorithm"] == "base_rrt_star"
    assert record["seed"] == 4 and record["iterations"] == 300 and record["checker"] == "numpy"
    assert record["overrides"] == ["random_seed: 4"] and record["scenario"] == str(tiny_scenario_path)
    assert dut.files == list(app.PLAN_OUTPUTS) and all((out / name).stat().st_size > 0 for name in dut.files)
    assert json.loads((out / "result.json").read_text()) == record
    wp = np.array(record["waypoints"])
    assert np.array_equal(wp, result.waypoints) and len(wp) == record["num_waypoints"] >= 2
    np.testing.assert_array_equal(wp[0], scenario.start)
    np.testing.assert_array_equal(wp[-1], scenario.goal)
    # The cost is the algorithm's objective along the path, summed edge by edge.
    objective = make_objective(scenario, "base_rrt_star")
    by_edge = sum(float(objective.motion_cost(a, b)[0]) for a, b in _edges(wp))
    assert record["cost"] == pytest.approx(by_edge, rel=1e-9)
    assert record["raw_cost"] >= record["cost"] - 1e-9  # optimisation never makes the path worse
    # F_multi: weight 1 on every interest point; F_base: the base alone; F_planner: base-only (this planner).
    n = arm_geometry(scenario).num_interest_points
    ones = SocialCost.from_scenario(scenario, np.ones(n))
    base = SocialCost.from_scenario(scenario, np.eye(n)[0])
    assert record["F_multi"] == pytest.approx(sum(float(ones.motion_cost(a, b)[0]) for a, b in _edges(wp)), rel=1e-9)
    assert record["F_base"] == pytest.approx(sum(float(base.motion_cost(a, b)[0]) for a, b in _edges(wp)), rel=1e-9)
    assert record["F_planner"] == pytest.approx(record["F_base"], rel=1e-12)
    assert record["F_base"] <= record["F_multi"]  # the base is one of the points weighted 1
    assert record["path_length"] == pytest.approx(float(np.linalg.norm(np.diff(wp, axis=0), axis=1).sum()), rel=1e-12)
    assert record["base_length"] == pytest.approx(sum(math.dist(a[:2], b[:2]) for a, b in zip(wp, wp[1:])), rel=1e-12)
    assert record["planning_time"] == result.wall_time > 0
    assert len(record["cost_history"]) == 300 and record["drake_verified"] is True and dut.rejected_segment is None
    assert set(PLANNER_FIELDS) | set(SHARED_FIELDS) <= set(record)
    # The planner's own run, outside the app: the same path.
    again = plan(scenario, GeometricChecker(scenario), algorithm="base_rrt_star", iterations=300, seed=4)
    assert np.array_equal(again.waypoints, wp) and again.cost == record["cost"]


WALLED = """\
description: "tiny with the goal walled off"
world:
  bounds: [0.0, 0.0, 8.0, 5.0]
  obstacles:
    - {center: [4.0, 0.6], size: [1.6, 0.8]}
    - {center: [5.2, 2.5], size: [0.2, 5.0]}
people:
  - {x: 4.0, y: 3.8, theta: -1.5708, radius: 0.25}
object: !Bar {length: 1.5, thickness: 0.05}
start: [1.0, 2.5, 0.0, 1.5708]
goal: [6.5, 2.5, 0.0, 1.5708]
random_seed: 1
"""


def test_run_plan_without_a_path_records_nulls(tmp_path):
    walled = tmp_path / "walled.yaml"
    walled.write_text(WALLED)
    out = tmp_path / "out"
    dut = app.run_plan(scenario=walled, out=out, iterations=100, checker="numpy")
    assert dut.record["success"] is False and dut.record["drake_verified"] is None
    assert all(dut.record[k] is None for k in ("cost", "raw_cost", "F_multi", "F_base", "F_planner", "path_length"))
    assert dut.record["waypoints"] == [] and dut.record["num_waypoints"] == 0
    assert (out / "path.csv").read_text() == "x,y,psi1,psi2\n"
    assert json.loads((out / "result.json").read_text())["success"] is False


def test_run_plan_reports_progress_over_its_iterations(tmp_path, tiny_scenario_path):
    calls = []
    app.run_plan(scenario=tiny_scenario_path, out=tmp_path, iterations=50, checker="numpy",
                 progress=lambda done, total, status: calls.append((done, total, status)))
    done = [c[0] for c in calls]
    assert done[-1] == 50 and done == sorted(done) and {c[1] for c in calls} == {50}
    assert all(c[2] == "no path yet" or c[2].startswith("best ") for c in calls)
    assert calls[-1][2] == f"best {json.loads((tmp_path / 'result.json').read_text())['cost_history'][-1]:.4g}"


def test_run_plan_refuses_bad_input_naming_the_option(tmp_path, tiny_scenario_path):
    with pytest.raises(ScenarioError, match="must be a YAML mapping"):
        app.run_plan(scenario=tiny_scenario_path, out=tmp_path, overrides=["[1, 2]"], checker="numpy")
    with pytest.raises(ScenarioError, match=r"\(--iterations\)"):
        app.run_plan(scenario=tiny_scenario_path, out=tmp_path, iterations=10**9, checker="numpy")
    assert not any(tmp_path.iterdir())  # refused before the output set was opened


def test_load_with_overrides_applies_each_set_in_turn(tiny_scenario_path):
    dut = app.load_with_overrides(tiny_scenario_path, ["random_seed: 3", "social: {sigma_h: 1.5}",
                                                       "social: {threshold: 0.1}"])
    plain = load_scenario(tiny_scenario_path)
    assert dut.random_seed == 3 and dut.social.sigma_h == 1.5 and dut.social.threshold == 0.1
    assert dut.social.side_ratio == plain.social.side_ratio and dut.start == plain.start


def test_run_simulate_follows_a_planned_path_csv(planned, tmp_path, tiny_scenario_path):
    _, out = planned
    path = out / "path.csv"
    calls = []
    dut = app.run_simulate(scenario=tiny_scenario_path, out=tmp_path, overrides=["random_seed: 4"], path=path,
                           mode="kinematic", checker="numpy", replay=False,
                           progress=lambda done, total, status: calls.append((done, total)))
    record = dut.record
    # tiny has a person: people.csv beside executed.csv.
    assert dut.files == ["executed.csv", "people.csv", "tracking.png", "motion.png", "sim.json"] and dut.replay_bytes is None
    assert record["path"] == str(path) and record["mode"] == "kinematic" and "planner" not in record
    assert json.loads((tmp_path / "sim.json").read_text()) == record
    np.testing.assert_array_equal(np.array(record["waypoints"]), np.loadtxt(path, delimiter=",", skiprows=1))
    assert record["reached"] is True and record["collision_free"] is True
    executed = np.loadtxt(tmp_path / "executed.csv", delimiter=",", skiprows=1)
    assert executed.shape == (len(dut.run.times), 9)
    np.testing.assert_array_equal(executed[:, 0], dut.run.times)
    # The run ends at the goal, within the sequencer's tolerances.
    scenario = load_scenario(tiny_scenario_path)
    assert np.linalg.norm(executed[-1, 1:3] - np.asarray(scenario.goal)[:2]) <= scenario.execution.base_tolerance
    assert np.abs(executed[-1, 3:5] - np.asarray(scenario.goal)[2:]).max() <= scenario.execution.joint_tolerance
    limit = scenario.execution.time_limit
    assert calls and {total for _, total in calls} == {int(round(limit * 10))}
    assert all(0 <= done <= total for done, total in calls)


def test_run_simulate_refuses_planner_options_with_a_path(tmp_path, tiny_scenario_path):
    with pytest.raises(ScenarioError, match=r"--seed: only for planning; with --path"):
        app.run_simulate(scenario=tiny_scenario_path, out=tmp_path, path=tmp_path / "p.csv", seed=3)


def test_run_show_writes_the_scene(tmp_path, tiny_scenario_path):
    dut = app.run_show(scenario=tiny_scenario_path, out=tmp_path / "show")
    assert dut == tmp_path / "show" / "scene.png" and dut.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_check_scheduler_names_what_is_wrong():
    app.check_scheduler("process", None)
    with pytest.raises(ScenarioError, match="--scheduler needs --executor dask"):
        app.check_scheduler("process", "tcp://127.0.0.1:8786")


def test_run_plan_takes_a_scenario_object_as_it_takes_the_file(tmp_path, tiny_scenario_path):
    scenario = load_scenario(tiny_scenario_path)
    scenario.random_seed = 2
    dut = app.run_plan(scenario=scenario, out=tmp_path / "object", iterations=100, checker="numpy").record
    by_file = app.run_plan(scenario=tiny_scenario_path, out=tmp_path / "file", overrides=["random_seed: 2"],
                           iterations=100, checker="numpy").record
    assert dut["scenario"] is None and by_file["scenario"] == str(tiny_scenario_path)
    for field in SHARED_FIELDS:
        if field != "planning_time":
            assert dut[field] == by_file[field], field
    with pytest.raises(ValueError, match="run_plan: overrides apply to a scenario file"):
        app.run_plan(scenario=scenario, out=tmp_path / "x", overrides=["random_seed: 3"])
    scenario.planner.iterations = 0
    with pytest.raises(ScenarioError, match=r"run_plan: scenario.*planner\.iterations"):
        app.run_plan(scenario=scenario, out=tmp_path / "y", checker="numpy")


# ---- the arguments of every public function are checked at the door (issue 29, item 14)

NONE = "no-such-scenario.yaml"  # never read: the door comes first


@pytest.mark.parametrize("function, arguments, error, message", [
    ("run_simulate", dict(scenario=NONE, replan="no"), TypeError,
     "run_simulate: replan must be True, False or None, got str 'no'"),
    ("run_simulate", dict(scenario=NONE, mode="Dynamic"), ValueError,
     "run_simulate: unknown mode 'Dynamic'; allowed: kinematic, dynamic"),
    ("run_simulate", dict(scenario=NONE, execution="Paper"), ValueError,
     "run_simulate: unknown execution 'Paper'; allowed: synchronized, paper"),
    ("run_simulate", dict(scenario=NONE, iterations=50.5), TypeError,
     "run_simulate: iterations must be an integer >= 1 or None, got float 50.5"),
    ("run_simulate", dict(scenario=NONE, replay=1), TypeError, "run_simulate: replay must be True or False, got int 1"),
    ("run_simulate", dict(scenario=NONE, path=3), TypeError,
     "run_simulate: path must be a file name (a str or pathlib.Path) or None, got int 3"),
    ("run_plan", dict(scenario=NONE, iterations=True), TypeError,
     "run_plan: iterations must be an integer >= 1 or None, got bool True"),
    ("run_plan", dict(scenario=NONE, iterations=0), ValueError, "run_plan: iterations must be an integer >= 1, got 0"),
    ("run_plan", dict(scenario=NONE, seed=-1), ValueError, "run_plan: seed must be an integer >= 0, got -1"),
    ("run_plan", dict(scenario=NONE, checker="Planar"), ValueError,
     "run_plan: unknown checker 'Planar'; allowed: planar, drake, numpy"),
    ("run_plan", dict(scenario=NONE, algorithm=1), TypeError, "run_plan: algorithm must be one of rrt_star"),
    ("run_plan", dict(scenario=NONE, overrides="random_seed: 3"), TypeError,
     "run_plan: overrides must be a list or tuple of strings, got str 'random_seed: 3' (a list of one: "
     "['random_seed: 3'])"),
    ("run_plan", dict(scenario=NONE, overrides=["random_seed: 3", 4]), TypeError,
     "run_plan: overrides[1] must be a string, got int 4"),
    ("run_plan", dict(scenario=3), TypeError, "run_plan: scenario must be a scenario file name (a str or "
                                              "pathlib.Path) or a drake_social.scenario.Scenario, got int 3"),
    ("run_plan", dict(scenario=NONE, progress=5), TypeError, "run_plan: progress must be a callable or None, got int 5"),
    ("run_show", dict(scenario=NONE, out=None), TypeError,
     "run_show: out must be a file name (a str or pathlib.Path), got NoneType None"),
    ("run_crowd_experiment", dict(jitter="1"), TypeError,
     "run_crowd_experiment: jitter must be a finite number >= 0 and <= 600 seconds, got str '1'"),
    ("run_crowd_experiment", dict(time_limit="5"), TypeError,
     "run_crowd_experiment: time_limit must be a finite number > 0 and <= 600 seconds or None, got str '5'"),
    ("run_crowd_experiment", dict(jitter=10**400), ValueError,
     "run_crowd_experiment: jitter must be a finite number >= 0 and <= 600 seconds, got 1000000000"),
    ("run_crowd_experiment", dict(episodes=True), TypeError,
     "run_crowd_experiment: episodes must be an integer >= 1 and <= 10,000, got bool True"),
    ("run_crowd_experiment", dict(trace_episode=-1), ValueError,
     "run_crowd_experiment: trace_episode must be an integer >= 0, got -1"),
    ("run_crowd_experiment", dict(workers=0), ValueError,
     "run_crowd_experiment: workers must be an integer >= 1 and <= 64, got 0"),
    ("run_crowd_experiment", dict(executor="threads"), ValueError,
     "run_crowd_experiment: unknown executor 'threads'; allowed: process, dask"),
    ("run_crowd_experiment", dict(episode=3), TypeError, "run_crowd_experiment: unexpected argument 'episode'; "
                                                         "allowed: name, scenarios, variants, episodes, seed"),
    ("run_bench", dict(scenario_paths=[NONE], iterations=10_000_001), ValueError,
     "run_bench: iterations must be an integer >= 1 and <= 10,000,000, got 10000001"),
    ("run_bench", dict(scenario_paths=[NONE], sim_runs=101), ValueError,
     "run_bench: sim_runs must be an integer >= 0 and <= 100, got 101"),
    ("run_bench", dict(scenario_paths=[NONE], replan_count=60_001), ValueError,
     "run_bench: replan_count must be an integer >= 1 and <= 60,000, got 60001"),
    ("run_bench", dict(scenario_paths=NONE), TypeError, "run_bench: scenario_paths must be a list or tuple of file names"),
    ("run_bench", dict(scenario_paths=[]), ValueError, "run_bench: scenario_paths must be a non-empty list or tuple"),
    ("run_bench", dict(scenario_paths=[NONE], algorithms=["RRT*"]), ValueError,
     "run_bench: unknown algorithms[0] 'RRT*'; allowed: rrt_star"),
    ("run_bench", dict(scenario_paths=[NONE], include_ompl="no"), TypeError,
     "run_bench: include_ompl must be True or False, got str 'no'"),
    ("run_bench", dict(scenario_paths=[NONE], ompl=True), TypeError, "run_bench: unexpected argument 'ompl'"),
    ("run_study", dict(study="sweep.yaml"), TypeError,
     "run_study: study must be a drake_social.experiments.study.Study (paper_experiment(...) or load_sweep(file)), "
     "CrowdStudy or RecordedCrowdStudy, got str 'sweep.yaml'"),
    ("run_recorded_experiment", dict(recording=NONE, windows=0), ValueError,
     "run_recorded_experiment: windows must be an integer >= 1 and <= 1,000, got 0"),
    ("run_recorded_experiment", dict(recording=NONE, window_length=0.5), ValueError,
     "run_recorded_experiment: window_length must be a finite number >= 1 and <= 600 seconds, got 0.5"),
    ("run_recorded_experiment", dict(recording=NONE, sets="planner: {}"), TypeError,
     "run_recorded_experiment: sets must be a list or tuple of strings, got str 'planner: {}'"),
    ("run_recorded_experiment", dict(recording=NONE, prediction="oracle"), ValueError,
     "run_recorded_experiment: unknown prediction 'oracle'; allowed: " + ", ".join(PREDICTIONS)),
    ("run_recorded_experiment", dict(recording=NONE, jitter=1.0), TypeError,
     "run_recorded_experiment: unexpected argument 'jitter'; allowed: name, recording, layout"),
    ("run_recorded_experiment", dict(recording=NONE, executor="threads"), ValueError,
     "run_recorded_experiment: unknown executor 'threads'; allowed: process, dask"),
    ("run_recorded_experiment", dict(windows=1), TypeError,
     "run_recorded_experiment: recording (the ETH/UCY file) is required"),
    ("run_people_import", dict(file=NONE, fps="25"), TypeError,
     "run_people_import: fps must be a finite number > 0 frames per second, got str '25'"),
    ("run_people_import", dict(file=NONE, fps=0.0), ValueError,
     "run_people_import: fps must be a finite number > 0 frames per second, got 0.0"),
    ("run_people_import", dict(file=NONE, offset=(1.0,)), ValueError,
     "run_people_import: offset: must be a (2,) array of [dx, dy], metres, got shape (1,)"),
    ("run_people_import", dict(file=NONE, layout="yx"), ValueError,
     "run_people_import: unknown layout 'yx'; allowed: xy, xzy"),
    ("run_people_import", dict(file=NONE, ids="3"), TypeError, "run_people_import: ids must be a list or tuple of "
                                                               "strings or None, got str '3'"),
    ("run_people_import", dict(file=NONE, theta="yes"), TypeError,
     "run_people_import: theta must be True or False, got str 'yes'"),
    ("paper_experiment", dict(runs=1, iterations=10, seed=0, simulate="yes", scenario_dir="scenarios"), TypeError,
     "paper_experiment: simulate must be True or False, got str 'yes'"),
    ("paper_experiment", dict(runs=7693, iterations=10, seed=0, simulate=False, scenario_dir="scenarios"), ValueError,
     "paper_experiment: runs must be an integer >= 1 and <= 7,692, got 7693"),
])
def test_public_functions_refuse_arguments_of_the_wrong_kind_or_value_at_the_door(tmp_path, function, arguments,
                                                                                  error, message):
    out = tmp_path / "out"
    if function not in ("paper_experiment",):
        arguments = {"out": out, **arguments}
    if function == "run_crowd_experiment":
        arguments = {"scenarios": (NONE,), **arguments}
    with pytest.raises(error) as info:
        getattr(app, function)(**arguments)
    assert type(info.value) is error and str(info.value).startswith(message)
    assert not out.exists()  # refused before anything was read or written


def test_the_positional_helpers_check_their_arguments_too(tiny_scenario_path):
    with pytest.raises(TypeError, match=r"^load_with_overrides: sets must be a list or tuple of strings or None, "
                                        r"got str 'random_seed: 3'"):
        app.load_with_overrides(tiny_scenario_path, "random_seed: 3")
    with pytest.raises(TypeError, match=r"^read_path_csv: scenario must be a drake_social.scenario.Scenario, got "
                                        r"str .* \(load the file first"):
        app.read_path_csv("path.csv", str(tiny_scenario_path))
    with pytest.raises(ValueError, match=r"^check_scheduler: unknown executor 'threads'; allowed: process, dask$"):
        app.check_scheduler("threads", None)


def test_run_bench_passes_its_options_at_their_bounds_and_just_within(tmp_path, monkeypatch, tiny_scenario_path):
    import sys
    import types

    calls = []
    fake = types.ModuleType("drake_social.experiments.bench.planners")
    fake.run_bench = lambda **kwargs: calls.append(kwargs)
    monkeypatch.setitem(sys.modules, "drake_social.experiments.bench.planners", fake)
    at = dict(iterations=10_000_000, seeds=10_000, repeats=100, sim_runs=100, replan_runs=100, replan_count=60_000)
    within = dict(iterations=9_999_999, seeds=9_999, repeats=99, sim_runs=99, replan_runs=99, replan_count=59_999)
    floor = dict(iterations=1, seeds=1, repeats=1, sim_runs=0, replan_runs=0, replan_count=1)
    for i, options in enumerate((at, within, floor)):
        app.run_bench(scenario_paths=[tiny_scenario_path], out=tmp_path / str(i), algorithms=["rrt_star"],
                      include_ompl=False, **options)
        assert {k: calls[-1][k] for k in options} == options
    for name, below in (("iterations", 0), ("seeds", 0), ("repeats", 0), ("sim_runs", -1), ("replan_runs", -1),
                        ("replan_count", 0)):
        with pytest.raises(ValueError, match=rf"^run_bench: {name} must be an integer >= {below + 1}"):
            app.run_bench(scenario_paths=[tiny_scenario_path], out=tmp_path / "x", **{name: below})
