"""The execution diagram as a station: its named ports, the parts a script can
leave out, Drake's config structs, and the example script that wires its own
controller (docs/examples/custom_controller.py)."""

from __future__ import annotations

import dataclasses as dc
import importlib.util
from pathlib import Path

import numpy as np
import pytest
from pydrake.multibody.plant import MultibodyPlantConfig
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from drake_social.collision.drake_checker import make_checker
from drake_social.people import people_model
from drake_social.planning.algorithms import plan
from drake_social.scenario import ScenarioError
from drake_social.sim.diagram import build_diagram, scenario_plant_config
from drake_social.sim.run import scenario_simulator_config, simulate

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "custom_controller.py"

OUTPUTS = {"robot_state", "target", "reference", "done", "index", "planned_path", "wheel_speeds", "people_state",
           "people_vector", "query_object"}


@pytest.fixture(scope="module")
def tiny_path(tiny_scenario):
    result = plan(tiny_scenario, make_checker(tiny_scenario, "numpy"))
    assert result.success
    return np.asarray(result.waypoints, float)


@pytest.mark.parametrize("mode", ["kinematic", "dynamic"])
@pytest.mark.parametrize("execution", ["synchronized", "paper"])
def test_the_station_exports_its_ports(tiny_scenario, tiny_path, mode, execution):
    built = build_diagram(tiny_scenario, mode=mode, execution=execution, waypoints=tiny_path)
    # tiny's person stands still: no safety monitor, no stop port (a walker's run exports it:
    # tests/sim/test_safety_stop.py).
    expected = OUTPUTS | ({"reference_feedforward"} if execution == "synchronized" else set())
    assert set(built.output_port_names()) == expected
    assert built.input_port_names() == []
    context = built.diagram.CreateDefaultContext()
    state = built.diagram.GetOutputPort("robot_state").Eval(context)
    np.testing.assert_array_equal(state, np.concatenate([tiny_path[0], np.zeros(4)]))
    np.testing.assert_array_equal(built.diagram.GetOutputPort("planned_path").Eval(context), tiny_path)
    np.testing.assert_array_equal(built.diagram.GetOutputPort("target").Eval(context), tiny_path[0])
    # The people at the context's time, as the people model answers.
    context.SetTime(2.5)
    people = built.diagram.GetOutputPort("people_state").Eval(context)
    model = people_model(tiny_scenario).state_at(2.5)
    assert people.t == 2.5 and people.names == model.names
    np.testing.assert_array_equal(people.positions, model.positions)
    rows = built.diagram.GetOutputPort("people_vector").Eval(context).reshape(-1, 6)
    np.testing.assert_array_equal(rows, [[p.x, p.y, p.theta, 0.0, 0.0, p.radius] for p in tiny_scenario.people])


def test_leaving_out_the_planner_and_controller_opens_input_ports(tiny_scenario):
    built = build_diagram(tiny_scenario, planner=False, controller=False)
    assert built.input_port_names() == ["path", "wheel_speeds"]
    assert not built.planner_included and not built.controller_included
    names = {system.get_name() for system in built.diagram.GetSystems()}
    assert {"sequencer", "drive", "people"} <= names
    assert "planner" not in names and "controller" not in names
    with pytest.raises(TypeError, match="planner"):
        build_diagram(tiny_scenario, planner="no")
    with pytest.raises(TypeError, match="plant_config"):
        build_diagram(tiny_scenario, plant_config={"time_step": 0.001})


def test_a_path_from_outside_runs_as_the_fixed_waypoints(tiny_scenario, tiny_path):
    """The sequencer reading the path from the station's ``path`` input gives
    the run of the same waypoints fixed in the builder, sample for sample."""
    reference = simulate(tiny_scenario, mode="kinematic", execution="paper", waypoints=tiny_path, analyze=False)
    built = build_diagram(tiny_scenario, mode="kinematic", execution="paper", planner=False)
    context = built.diagram.CreateDefaultContext()
    built.diagram.GetInputPort("path").FixValue(context, tiny_path)
    simulator = Simulator(built.diagram, context)
    simulator.get_mutable_integrator().set_maximum_step_size(tiny_scenario.execution.control_period)
    simulator.AdvanceTo(float(reference.times[-1]))
    log = built.loggers["q"].FindLog(context)
    n = len(reference.times)
    np.testing.assert_array_equal(log.sample_times()[:n], reference.times)
    np.testing.assert_array_equal(log.data().T[:n], reference.q)
    np.testing.assert_array_equal(built.diagram.GetOutputPort("planned_path").Eval(context), tiny_path)


def test_the_plant_config_follows_the_scenario(tiny_scenario, tiny_path):
    scenario = dc.replace(tiny_scenario, execution=dc.replace(tiny_scenario.execution, plant_time_step=0.0015))
    config = scenario_plant_config(scenario)
    assert config.time_step == 0.0015 and config.discrete_contact_approximation == "tamsi"
    lagged = dc.replace(scenario, execution=dc.replace(scenario.execution, contact_approximation="lagged"))
    assert scenario_plant_config(lagged).discrete_contact_approximation == "lagged"
    built = build_diagram(scenario, mode="dynamic", waypoints=tiny_path)
    assert built.plant.time_step() == 0.0015
    assert built.plant.get_discrete_contact_approximation().name == "kTamsi"
    # A config given by the script wins over the scenario's.
    mine = MultibodyPlantConfig(time_step=0.001, discrete_contact_approximation="lagged")
    built = build_diagram(scenario, mode="dynamic", waypoints=tiny_path, plant_config=mine)
    assert built.plant.time_step() == 0.001
    assert built.plant.get_discrete_contact_approximation().name == "kLagged"


def test_the_simulator_config_follows_the_scenario(tiny_scenario):
    config = scenario_simulator_config(tiny_scenario)
    assert config.max_step_size == tiny_scenario.execution.control_period
    assert (config.integration_scheme, config.accuracy, config.use_error_control) == ("runge_kutta3", 1e-4, True)
    assert config.target_realtime_rate == 0.0
    execution = dc.replace(tiny_scenario.execution, integration_scheme="runge_kutta5", accuracy=1e-6,
                           target_realtime_rate=1.0, control_period=0.02)
    config = scenario_simulator_config(dc.replace(tiny_scenario, execution=execution))
    assert (config.integration_scheme, config.accuracy, config.target_realtime_rate, config.max_step_size) == (
        "runge_kutta5", 1e-6, 1.0, 0.02)
    with pytest.raises(TypeError, match="simulator_config"):
        simulate(tiny_scenario, simulator_config={"max_step_size": 0.01})


@pytest.mark.parametrize("field, value, rule", [
    ("integration_scheme", "rk9", "unknown scheme 'rk9'; allowed: .*runge_kutta3"),
    ("contact_approximation", "soft", "unknown approximation 'soft'; allowed: tamsi, sap, similar, lagged"),
    ("accuracy", 0.0, "must be > 0"),
    ("target_realtime_rate", -1.0, "must be >= 0"),
    ("accuracy", float("nan"), "must be a finite number"),
])
def test_bad_drake_settings_are_refused_by_name(tiny_scenario, field, value, rule):
    scenario = dc.replace(tiny_scenario, execution=dc.replace(tiny_scenario.execution, **{field: value}))
    with pytest.raises(ScenarioError, match=f"build_diagram: scenario: execution.{field}: {rule}"):
        build_diagram(scenario)


def _example():
    spec = importlib.util.spec_from_file_location("custom_controller_example", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_example_with_the_stations_law_reproduces_simulate(tiny_scenario, tiny_path):
    """The script's controller with the feed-forward is the station's own law
    (numpy instead of plain floats): the same run as simulate()."""
    example = _example()
    mine = example.run(tiny_scenario, tiny_path, kp=tiny_scenario.execution.kp, feedforward=True)
    theirs = simulate(tiny_scenario, mode="kinematic", execution="synchronized", waypoints=tiny_path, analyze=False)
    assert mine["reached"] and theirs.reached
    assert mine["time_to_goal"] == pytest.approx(theirs.time_to_goal, abs=1e-9)
    np.testing.assert_allclose(mine["q"], theirs.q, atol=1e-9)


@pytest.mark.parametrize("kp", [1.5, 6.0])
def test_the_example_without_feedforward_lags_by_speed_over_gain(tiny_scenario, tiny_path, kp):
    """A proportional law following a reference that cruises at the base
    speed limit v lags it by v / kp at most (the error obeys e' = v - kp e
    between the samples), and reaches that lag on a long straight stretch."""
    result = _example().run(tiny_scenario, tiny_path, kp=kp)
    assert result["reached"]
    lag = tiny_scenario.execution.max_base_speed / kp
    assert 0.9 * lag <= result["max_tracking_error"] <= lag * (1 + 1e-6)


def test_the_example_says_when_the_goal_is_not_reached(monkeypatch, capsys, tiny_scenario_path):
    """A run that stops short has no time to goal (None): the script says so
    instead of formatting None as a number."""
    example = _example()
    result = {"reached": False, "time_to_goal": None, "max_tracking_error": 0.25, "max_point_deviation": 0.125}
    monkeypatch.setattr(example, "run", lambda scenario, waypoints, kp: result)
    example.main([str(tiny_scenario_path)])
    lines = capsys.readouterr().out.splitlines()
    assert lines[1:] == [f"kp = {kp} 1/s: reached False, time to goal not reached, max tracking error 250.000 mm, "
                         "max point deviation 125.000 mm" for kp in ("1.5", "6")]
