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
from drake_social.kinematics import ArmGeometry
from drake_social.planning.algorithms import make_objective, plan
from drake_social.scenario import ScenarioError, load_scenario


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
    n = ArmGeometry.from_scenario(scenario).num_interest_points
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
    assert dut.files == ["executed.csv", "people.csv", "tracking.png", "sim.json"] and dut.replay_bytes is None
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
