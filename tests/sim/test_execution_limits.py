"""Executions at the robot's limits: a goal on a joint limit, a base speed beyond the wheels.

The joint-limit finding is measured on the executed trajectory itself (the
largest amount by which any logged configuration passes a limit), apart from
the geometry's collision verdict; the base's speed against the wheels' limit
computed by hand from the mecanum kinematics.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from drake_social.collision.drake_checker import make_checker
from drake_social.sim.diagram import build_diagram
from drake_social.planning.algorithms import plan
from drake_social.sim.execution_analysis import analyze_execution, limit_violations
from drake_social.sim.results import LimitViolation
from drake_social.sim.run import simulate

# Whole executions in Drake's Simulator.
pytestmark = pytest.mark.slow

#: Stated tolerances of "on the checked segments": every body point within
#: this distance (metres) of its planned curve.
ON_PATH_KINEMATIC = 1e-6
ON_PATH_DYNAMIC = 0.02


def _limits(scenario):
    b, r = scenario.world.bounds, scenario.robot
    return np.array([b[0], b[1], *r.joint_lower]), np.array([b[2], b[3], *r.joint_upper])


def _excess(scenario, q):
    """The largest amount (m or rad) by which any configuration passes a limit (<= 0: none)."""
    lower, upper = _limits(scenario)
    return float(np.max(np.maximum(q - upper, lower - q)))


@pytest.fixture(scope="module")
def at_the_limit(tiny_scenario):
    """tiny.yaml with the goal's psi1 on its upper limit pi, and its planned path."""
    scenario = copy.deepcopy(tiny_scenario)
    scenario.goal = [6.5, 2.5, math.pi, 1.5708]
    assert scenario.robot.joint_upper[0] == math.pi
    result = plan(scenario, make_checker(scenario, "planar"))
    assert result.success
    return scenario, result.waypoints


@pytest.mark.parametrize("goal", [[6.5, 2.5, -math.pi, 1.5708], [6.5, 2.5, 0.0, math.pi]])
@pytest.mark.parametrize("execution", ["synchronized", "paper"])
def test_other_goals_on_a_joint_limit_are_not_passed_in_dynamic_mode(tiny_scenario, goal, execution):
    scenario = copy.deepcopy(tiny_scenario)
    scenario.goal = goal
    result = plan(scenario, make_checker(scenario, "planar"))
    assert result.success
    dut = simulate(scenario, mode="dynamic", execution=execution, waypoints=result.waypoints)
    assert dut.reached, dut.message
    assert _excess(scenario, dut.q) <= 0.0
    assert dut.report.within_limits and dut.report.limit_violations == []


@pytest.mark.parametrize("mode", ["kinematic", "dynamic"])
@pytest.mark.parametrize("execution", ["synchronized", "paper"])
def test_a_goal_on_the_joint_limit_is_reached_without_passing_it(at_the_limit, mode, execution):
    # Before the inverse-dynamics servo, dynamic mode passed pi by 3.4e-5 rad
    # (synchronized) and 1.8e-4 rad (paper), and the run was called a collision.
    scenario, waypoints = at_the_limit
    dut = simulate(scenario, mode=mode, execution=execution, waypoints=waypoints)
    assert dut.reached, dut.message
    assert _excess(scenario, dut.q) <= 0.0
    assert _excess(scenario, dut.reference) <= 0.0
    assert dut.report.within_limits and dut.report.limit_violations == []
    assert dut.report.collision_free
    assert dut.report.min_clearance > 0
    assert dut.q[-1, 2] == pytest.approx(math.pi, abs=scenario.execution.joint_tolerance)


def test_a_limit_pass_is_its_own_finding_and_not_a_collision(tiny_scenario):
    # A hand-made execution in open space whose psi1 passes pi by 0.002 rad
    # between t = 0.2 s and 0.3 s (worst at 0.3 s): geometrically clear
    # (planar checker), so collision-free, and one psi1 finding.
    scenario = tiny_scenario
    psi1 = np.array([3.10, 3.13, 3.1426, 3.1435, 3.1420, 3.14])
    times = np.arange(len(psi1)) * 0.1
    q = np.column_stack([np.full(6, 2.0), np.full(6, 2.5), psi1, np.zeros(6)])
    planar = make_checker(scenario, "planar")
    assert np.min(planar.clearances(q)) > 0.05  # clear of everything
    report = analyze_execution(scenario, q, times, q)
    assert report.collision_free and report.first_collision_time is None
    assert not report.within_limits
    (violation,) = report.limit_violations
    assert violation.joint == "psi1" and violation.bound == "upper" and violation.limit == math.pi
    assert violation.first_time == pytest.approx(0.2) and violation.worst_time == pytest.approx(0.3)
    assert violation.max_excess == pytest.approx(3.1435 - math.pi, abs=1e-15)


def test_limit_violations_name_each_joint_and_bound_by_hand(tiny_scenario):
    # The room is [0, 8] x [0, 5]; joints in [-pi, pi].
    q = np.array([[-0.1, 2.0, 0.0, -3.2], [1.0, 5.3, 0.0, 0.0], [8.0, 2.0, 0.0, 0.0]])
    found = limit_violations(tiny_scenario, np.array([0.0, 0.5, 1.0]), q)
    assert found == [
        LimitViolation("base_x", "lower", 0.0, 0.0, 0.0, pytest.approx(0.1)),
        LimitViolation("base_y", "upper", 5.0, 0.5, 0.5, pytest.approx(0.3)),
        LimitViolation("psi2", "lower", -math.pi, 0.0, 0.0, pytest.approx(3.2 - math.pi)),
    ]
    assert "base_x 0.1 m beyond its lower limit 0 at t = 0.00 s" in str(found[0])
    assert [v.kind for v in found] == ["a room bound", "a room bound", "a joint limit"]
    assert limit_violations(tiny_scenario, np.array([0.0]), np.array([[8.0, 5.0, math.pi, -math.pi]])) == []


@pytest.fixture(scope="module")
def tiny_path(tiny_scenario):
    result = plan(tiny_scenario, make_checker(tiny_scenario, "planar"))
    assert result.success
    return result.waypoints


@pytest.mark.parametrize("max_base_speed, wheel_radius, max_wheel_speed", [
    (1.0, 0.05, 20.0),   # r w_max = 1 m/s: the fastest any direction allows
    (2.0, 0.05, 20.0),   # beyond every direction
    (0.5, 0.03, 15.0),   # the default speed on small wheels: r w_max = 0.45 m/s
    (0.3, 0.05, 20.0),   # slow: Ruckig's 4-DoF phase synchronization fell back to time sync, off the line
])
@pytest.mark.parametrize("mode", ["kinematic", "dynamic"])
def test_synchronized_execution_stays_on_the_checked_segments_at_the_wheels_limit(
        tiny_scenario, tiny_path, max_base_speed, wheel_radius, max_wheel_speed, mode):
    # Wheels: |w_i| = |vx +- vy| / r <= w_max, so |vx| + |vy| <= r w_max:
    # r w_max along an axis, r w_max / sqrt(2) on a diagonal. Before the
    # reference knew the wheels' limit, the kinematic run at 2.0 m/s (r =
    # 0.05 m, 20 rad/s) left the checked segments by 0.095 m, at 1.0 m/s by 0.061 m.
    scenario = copy.deepcopy(tiny_scenario)
    e = scenario.execution
    e.max_base_speed, e.wheel_radius, e.max_wheel_speed = max_base_speed, wheel_radius, max_wheel_speed
    wheels = wheel_radius * max_wheel_speed
    dut = simulate(scenario, mode=mode, execution="synchronized", waypoints=tiny_path)
    assert dut.reached, dut.message
    tolerance = ON_PATH_KINEMATIC if mode == "kinematic" else ON_PATH_DYNAMIC
    assert dut.report.max_point_deviation["max"] < tolerance
    assert dut.report.collision_free
    # The reference's base speed on each segment is within what the wheels
    # allow along it: s (|dx| + |dy|) / |d| <= r w_max.
    d = np.diff(tiny_path[:, :2], axis=0)
    along = wheels * np.linalg.norm(d, axis=1) / np.maximum(np.abs(d).sum(axis=1), 1e-300)
    reference_speed = np.hypot(*np.gradient(dut.reference[:, :2], dut.times, axis=0).T)
    assert np.max(reference_speed) <= np.max(np.minimum(max_base_speed, along)) * (1 + 1e-3)
    if mode == "kinematic":
        assert np.max(np.abs(dut.wheel_speeds)) <= e.max_wheel_speed * (1 + 1e-9)
        # Near the wheels' diagonal limit at least: they, not a lower cap, hold the speed.
        assert np.max(np.hypot(dut.v[:, 0], dut.v[:, 1])) > 0.95 * min(max_base_speed, wheels / np.sqrt(2))


def test_fixed_waypoints_outside_the_limits_are_refused_before_execution(tiny_scenario):
    start, goal = tiny_scenario.start, tiny_scenario.goal
    with pytest.raises(ValueError, match=r"^build_diagram: waypoints: waypoint 1: psi2: 3.5 is outside the joint range "
                                         r"\[-3.141592653589793, 3.141592653589793\] \(robot.joint_lower/joint_upper\)$"):
        build_diagram(tiny_scenario, waypoints=np.array([start, [3.0, 2.5, 0.0, 3.5], goal]))
    with pytest.raises(ValueError, match=r"^build_diagram: waypoints: waypoint 1: x: 8.5 is outside the room \[0.0, 8.0\] "):
        build_diagram(tiny_scenario, waypoints=np.array([start, [8.5, 2.5, 0.0, 0.0], goal]))


# ---- the dynamic mode's plant step ------------------------------------------------------------

_STEP_RULE = ("execution.plant_time_step: must be <= 0.00833333 s in dynamic mode (the servo's damping gain 120 /s "
              "times the step must be <= 1 for the plant to stay stable), got {}")


@pytest.mark.parametrize("step", [0.02, 0.0084, 0.5])
def test_a_dynamic_plant_step_beyond_the_servos_stability_is_refused(tiny_scenario_path, tmp_path, capsys, step):
    """In the scenario, by --mode dynamic on a kinematic scenario, and by the
    API's mode argument; the same step is fine for a kinematic run (no plant)."""
    import dataclasses as dc

    from drake_social.cli import load_with_overrides, main
    from drake_social.scenario import ScenarioError

    setting = f"execution: {{plant_time_step: {step}, control_period: {max(step, 0.01)}}}"
    with pytest.raises(ScenarioError) as info:
        load_with_overrides(tiny_scenario_path, [setting.replace("{", "{mode: dynamic, ", 1)])
    assert str(info.value).endswith(_STEP_RULE.format(step))
    kinematic = load_with_overrides(tiny_scenario_path, [setting])
    assert kinematic.execution.plant_time_step == step
    out = tmp_path / "out"
    assert main(["simulate", str(tiny_scenario_path), "--mode", "dynamic", "--set", setting, "--no-replay",
                 "--out", str(out)]) == 2
    captured = capsys.readouterr()
    assert captured.err == (f"drake-social: error: {tiny_scenario_path} (--mode dynamic): "
                            f"{_STEP_RULE.format(step)}\n")
    assert captured.out == "" and not out.exists()
    with pytest.raises(ScenarioError) as info:
        simulate(kinematic, mode="dynamic", analyze=False)
    assert str(info.value) == f"simulate: scenario: {_STEP_RULE.format(step)}"
    # Exactly at the rule it is accepted.
    at = dc.replace(kinematic.execution, mode="dynamic", plant_time_step=1 / 120, control_period=0.01)
    ok = copy.deepcopy(kinematic)
    ok.execution = at
    from drake_social.scenario import validate_scenario

    validate_scenario(ok)


def test_a_diverging_dynamic_run_is_reported_as_such(tiny_scenario):
    """A run past the validation (run_checked takes its arguments as checked)
    with the reviewer's 0.02 s step: the state blows up within a second, and
    the run stops there with the error naming it and the step."""
    import dataclasses as dc

    from drake_social.sim.results import SimulationDiverged
    from drake_social.sim.run import run_checked

    scenario = copy.deepcopy(tiny_scenario)
    scenario.execution = dc.replace(scenario.execution, mode="dynamic", plant_time_step=0.02, control_period=0.02)
    with pytest.raises(SimulationDiverged) as info:
        run_checked(scenario, "dynamic", "synchronized", None, make_checker(scenario, "numpy"), None, 60.0, True,
                    None, None)
    assert 0 < info.value.time <= 2.0
    assert str(info.value) == (f"the dynamic simulation diverged by t = {info.value.time:.2f} s ({info.value.what}): "
                               "execution.plant_time_step 0.02 s is too large for this scenario's dynamics; use a "
                               "smaller one")


@pytest.mark.parametrize("q, v, what", [
    ([1, 1, np.nan, 0], [0, 0, 0, 0], "non-finite position of psi1"),
    ([1, 1, 0, 0], [0, np.inf, 0, 0], "non-finite speed of base_y"),
    ([1, -20, 0, 0], [0, 0, 0, 0], "base_y = -20 m, more than the room's diagonal outside the room"),
    ([1, 1, 0, -150], [0, 0, 0, 0], "psi2 = -150 rad"),
    ([1, 1, 0, 0], [0, 0, 2e3, 0], "speed 2e+03 of psi1"),
    ([-5, 9, 3, -3], [10, -10, 50, 50], None),  # outside the room, fast: a motion, not a divergence
])
def test_divergence_is_named_by_what_is_absurd(q, v, what):
    from drake_social.sim.run import _divergence

    lower, upper = np.array([0.0, 0.0, -3.2, -3.2]), np.array([8.0, 6.0, 3.2, 3.2])  # a diagonal of 10 m
    assert _divergence(q, v, lower, upper) == what
