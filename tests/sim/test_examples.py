"""The two "wire your own" scripts of docs/examples run, and do what they say:
custom_controller.py drives the station alone with its own controller (a P
law's lag is speed over gain, the feed-forward cancels it),
custom_path.py feeds the autonomy its own path (the run is simulate's with
those waypoints, sample for sample)."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from drake_social.scenario import load_scenario
from drake_social.sim import simulate

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"
#: A standing person across tiny's straight route (the straight motion and the first via point collide).
BLOCKING = ["people: [{x: 4.0, y: 2.9, radius: 0.25, name: blocking}]"]


def _example(name: str):
    spec = importlib.util.spec_from_file_location(f"{name}_example", EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def controller():
    return _example("custom_controller")


@pytest.fixture(scope="module")
def custom_path():
    return _example("custom_path")


# ---- custom_controller.py: the station alone, driven by the script's controller --------------------------------


@pytest.mark.parametrize("kp", [1.5, 6.0])
def test_a_proportional_law_lags_by_speed_over_gain(controller, tiny_scenario, kp):
    """Sampled every period T behind the station's hold, the error of a P law
    following a reference at speed v obeys |e_k+1| <= (1 - kp T) |e_k| + v T:
    it stays below v / kp and approaches it on a long straight segment."""
    straight = np.array([tiny_scenario.start, tiny_scenario.goal], float)
    result = controller.run(tiny_scenario, straight, kp=kp, feedforward=False)
    assert result["reached"]
    lag = result["speed"] / kp
    assert 0.9 * lag <= result["max_tracking_error"] <= lag * (1 + 1e-9)
    np.testing.assert_allclose(result["q"][-1, 2:], tiny_scenario.goal[2:], rtol=0, atol=1e-12)  # the arm: exact


def _corner_bound(follower, kp: float, period: float, end: float) -> float:
    """The largest |e_k| that |e_k+1| <= (1 - kp T) |e_k| + |v(t_k+1) - v(t_k)| T allows
    (with the feed-forward the error grows only where the reference's velocity changes)."""
    bound = worst = 0.0
    for k in range(int(np.ceil(end / period))):
        jump = np.linalg.norm(follower.reference((k + 1) * period)[1][:2] - follower.reference(k * period)[1][:2])
        bound = (1 - kp * period) * bound + jump * period
        worst = max(worst, bound)
    return worst


@pytest.mark.parametrize("kp", [1.5, 6.0])
def test_the_feedforward_leaves_only_the_corners_error(controller, tiny_scenario, kp):
    straight = np.array([tiny_scenario.start, tiny_scenario.goal], float)
    result = controller.run(tiny_scenario, straight, kp=kp)
    assert result["reached"] and result["max_tracking_error"] < 1e-12  # one segment ending on a sample: no lag
    # A path with turns between the samples: the error stays within the corners' bound.
    turns = np.array([tiny_scenario.start, [3.0037, 2.0, 0.0, 1.5708], [5.0, 2.2, 0.3, 1.2], tiny_scenario.goal])
    result = controller.run(tiny_scenario, turns, kp=kp)
    e = tiny_scenario.execution
    follower = controller.WaypointFollower(turns, base_speed=result["speed"], arm_speed=min(e.arm_max_velocity),
                                           kp=kp, max_speed=e.max_base_speed, wheel_radius=e.wheel_radius,
                                           max_wheel_speed=e.max_wheel_speed)
    bound = _corner_bound(follower, kp, e.control_period, follower.duration + e.control_period)
    assert result["reached"] and 0.3 * bound <= result["max_tracking_error"] <= bound * (1 + 1e-9)


def test_the_controller_script_says_when_the_goal_is_not_reached(controller, monkeypatch, capsys,
                                                                tiny_scenario_path):
    """A run that stops short has no time to goal (None): the script says so
    instead of formatting None as a number."""
    result = {"reached": False, "time_to_goal": None, "max_tracking_error": 0.25, "max_point_deviation": 0.125}
    monkeypatch.setattr(controller, "run", lambda scenario, waypoints, kp: result)
    controller.main([str(tiny_scenario_path)])
    lines = capsys.readouterr().out.splitlines()
    assert lines[1:] == [f"kp = {kp} 1/s: reached False, time to goal not reached, max tracking error 250.000 mm, "
                         "max point deviation 125.000 mm" for kp in ("1.5", "6")]


# ---- custom_path.py: the autonomy fed by the script's own path source ------------------------------------------


@pytest.mark.parametrize("people", [[], BLOCKING], ids=["straight", "detour"])
def test_the_scripts_path_runs_as_simulate_with_those_waypoints(custom_path, tiny_scenario_path, people):
    scenario = load_scenario(tiny_scenario_path, people)
    result = custom_path.run(scenario)
    expected = ([scenario.start, scenario.goal] if not people else
                [scenario.start, custom_path.VIA_POINTS[1], scenario.goal])  # the first via point collides too
    np.testing.assert_array_equal(result["path"], expected)
    reference = simulate(scenario, mode="kinematic", execution="synchronized", waypoints=result["path"],
                         analyze=False)
    assert result["reached"] and reference.reached and result["time_to_goal"] == reference.time_to_goal
    np.testing.assert_array_equal(result["times"], reference.times)
    np.testing.assert_array_equal(result["q"], reference.q)


def test_the_path_source_refuses_when_nothing_is_free(custom_path, tiny_scenario_path):
    from pydrake.systems.framework import DiagramBuilder
    from pydrake.systems.primitives import ConstantVectorSource

    from drake_social.collision.drake_checker import make_checker

    scenario = load_scenario(tiny_scenario_path, BLOCKING)
    dut = custom_path.ViaPointPath(scenario.goal, custom_path.VIA_POINTS[:1], make_checker(scenario, "planar"))
    builder = DiagramBuilder()
    state = builder.AddSystem(ConstantVectorSource(np.concatenate([scenario.start, np.zeros(4)])))
    builder.AddSystem(dut)
    builder.Connect(state.get_output_port(), dut.get_input_port(0))
    diagram = builder.Build()
    with pytest.raises(RuntimeError, match=r"^ViaPointPath: no free path from \[1.0, 2.5, 0.0, 1.5708\]: straight "
                                           r"and through 1 via points all collide"):
        diagram.ExecuteInitializationEvents(diagram.CreateDefaultContext())


# ---- both, as scripts -------------------------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("name, lines", [
    ("custom_controller", [r"\d+ waypoints planned",
                           r"kp = 1.5 1/s: reached True, time to goal \d+\.\d\d s, max tracking error \d+\.\d{3} mm, "
                           r"max point deviation \d+\.\d{3} mm",
                           r"kp = 6 1/s: reached True, .*"]),
    ("custom_path", [r"path of 2 waypoints: \[\[1.0, 2.5, 0.0, 1.571\], \[6.5, 2.5, 0.0, 1.571\]\]",
                     r"reached True, time to goal 11.71 s"]),
])
def test_the_scripts_run(repo_root, name, lines):
    done = subprocess.run([sys.executable, str(EXAMPLES / f"{name}.py")], cwd=repo_root, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    out = done.stdout.splitlines()
    assert len(out) == len(lines)
    for line, pattern in zip(out, lines):
        assert re.fullmatch(pattern, line), line
