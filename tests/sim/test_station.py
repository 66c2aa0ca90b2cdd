"""The station (the robot and its world), the autonomy (the stack that drives
it) and build_diagram, which wires the two by port name: each system alone
against a hand computation, the composed diagram's ports and handles, the
path source from outside, Drake's config structs and the checks at the door."""

from __future__ import annotations

import dataclasses as dc

import numpy as np
import pytest
from pydrake.multibody.plant import MultibodyPlantConfig
from pydrake.systems.analysis import Simulator

from drake_social.collision.drake_checker import make_checker
from drake_social.control import base_velocity
from drake_social.people import people_model
from drake_social.planning.algorithms import plan
from drake_social.scenario import ScenarioError
from drake_social.sim.autonomy import (ExternalPath, GivenWaypoints, PlanAtInit, Replan, make_autonomy,
                                       path_source)
from drake_social.sim.diagram import build_diagram
from drake_social.sim.run import scenario_simulator_config, simulate
from drake_social.sim.station import make_station, scenario_plant_config, servo_gains

OUTPUTS = {"robot_state", "target", "reference", "done", "index", "planned_path", "wheel_speeds", "people_state",
           "people_vector", "query_object"}


@pytest.fixture(scope="module")
def tiny_path(tiny_scenario):
    result = plan(tiny_scenario, make_checker(tiny_scenario, "numpy"))
    assert result.success
    return np.asarray(result.waypoints, float)


# ---- the station alone ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("mode", ["kinematic", "dynamic"])
def test_the_station_starts_where_it_is_told_and_reports_the_people(tiny_scenario, mode):
    start = np.array([2.0, 2.4, 0.3, 1.2])
    dut = make_station(tiny_scenario, mode=mode, start=start)
    assert dut.input_port_names() == ["wheel_speeds", "arm_command"]
    assert sorted(dut.output_port_names()) == sorted(
        ["robot_state", "wheel_speeds", "people_state", "people_vector", "query_object"])
    assert dut.diagram.get_name() == "station" and dut.mode == mode
    context = dut.diagram.CreateDefaultContext()
    dut.diagram.GetInputPort("wheel_speeds").FixValue(context, np.zeros(4))
    dut.diagram.GetInputPort("arm_command").FixValue(context, np.concatenate([start[2:], np.zeros(4)]))
    np.testing.assert_array_equal(dut.diagram.GetOutputPort("robot_state").Eval(context),
                                  np.concatenate([start, np.zeros(4)]))
    # The people at the context's time, as the people model answers.
    context.SetTime(2.5)
    people = dut.diagram.GetOutputPort("people_state").Eval(context)
    model = people_model(tiny_scenario).state_at(2.5)
    assert people.t == 2.5 and people.names == model.names
    np.testing.assert_array_equal(people.positions, model.positions)
    rows = dut.diagram.GetOutputPort("people_vector").Eval(context).reshape(-1, 6)
    np.testing.assert_array_equal(rows, [[p.x, p.y, p.theta, 0.0, 0.0, p.radius] for p in tiny_scenario.people])


def test_the_kinematic_station_follows_its_commands_exactly(tiny_scenario):
    """The arm is where arm_command puts it at once; the base moves with the
    mecanum velocity of the wheel speeds held at t = 0 ((r/4) M w)."""
    dut = make_station(tiny_scenario, mode="kinematic")
    context = dut.diagram.CreateDefaultContext()
    wheels = np.array([2.0, -1.0, 3.0, 0.5])
    command = np.array([0.4, 1.1, 0.2, -0.3, 0.0, 0.0])
    dut.diagram.GetInputPort("wheel_speeds").FixValue(context, wheels)
    dut.diagram.GetInputPort("arm_command").FixValue(context, command)
    simulator = Simulator(dut.diagram, context)
    simulator.AdvanceTo(1.0)
    state = dut.diagram.GetOutputPort("robot_state").Eval(context)
    velocity = base_velocity(wheels, tiny_scenario.execution.wheel_radius)
    np.testing.assert_allclose(state[:2], np.asarray(tiny_scenario.start[:2]) + velocity * 1.0, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(state[2:4], command[:2])
    np.testing.assert_allclose(state[4:6], velocity, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(state[6:], command[2:4])
    np.testing.assert_array_equal(dut.diagram.GetOutputPort("wheel_speeds").Eval(context), wheels)


def test_the_dynamic_station_servos_the_arm_to_its_command(tiny_scenario):
    """A constant arm command is a step for the critically damped servo (60
    rad/s): after 0.5 s (30 time constants) the arm stands on it, within the
    TAMSI plant's residue; the base, commanded still, does not move."""
    dut = make_station(tiny_scenario, mode="dynamic")
    context = dut.diagram.CreateDefaultContext()
    target = np.array([0.3, 1.4])
    dut.diagram.GetInputPort("wheel_speeds").FixValue(context, np.zeros(4))
    dut.diagram.GetInputPort("arm_command").FixValue(context, np.concatenate([target, np.zeros(4)]))
    Simulator(dut.diagram, context).AdvanceTo(0.5)
    state = dut.diagram.GetOutputPort("robot_state").Eval(context)
    np.testing.assert_allclose(state[2:4], target, atol=1e-6)
    np.testing.assert_allclose(state[:2], tiny_scenario.start[:2], atol=1e-9)
    np.testing.assert_allclose(state[4:], 0.0, atol=1e-5)
    kp, kd = servo_gains()
    assert kd[2] ** 2 == pytest.approx(4 * kp[2])  # critically damped


def test_make_station_checks_its_arguments_at_the_door(tiny_scenario):
    with pytest.raises(ValueError, match=r"^make_station: start: must be a \(4,\) array"):
        make_station(tiny_scenario, start=[1.0, 2.5, 0.0])
    with pytest.raises(ValueError, match=r"^make_station: start: must lie within the room and the joint limits"):
        make_station(tiny_scenario, start=[9.0, 2.5, 0.0, 0.0])
    with pytest.raises(TypeError, match="^make_station: people must be a drake_social.people.PeopleModel"):
        make_station(tiny_scenario, people="nobody")
    with pytest.raises(TypeError, match="make_station: plant_config"):
        make_station(tiny_scenario, plant_config={"time_step": 0.001})
    with pytest.raises(ValueError, match="^make_station: unknown mode 'fast'; allowed: kinematic, dynamic"):
        make_station(tiny_scenario, mode="fast")


# ---- the autonomy alone -----------------------------------------------------------------------------------------


@pytest.mark.parametrize("execution", ["synchronized", "paper"])
def test_the_autonomy_commands_the_start_until_it_moves(tiny_scenario, tiny_path, execution):
    """At rest at the start the autonomy's arm command is the start's arm
    [psi, 0, 0], its target the first waypoint, its base command zero."""
    dut = make_autonomy(tiny_scenario, execution=execution, path=GivenWaypoints(tiny_path))
    assert dut.input_port_names() == ["robot_state"]
    assert dut.planner is None and dut.safety is None and not dut.replanning
    np.testing.assert_array_equal(dut.waypoints, tiny_path)
    context = dut.diagram.CreateDefaultContext()
    dut.diagram.GetInputPort("robot_state").FixValue(context, np.concatenate([tiny_path[0], np.zeros(4)]))
    np.testing.assert_array_equal(dut.diagram.GetOutputPort("arm_command").Eval(context),
                                  np.concatenate([tiny_path[0][2:], np.zeros(4)]))
    np.testing.assert_array_equal(dut.diagram.GetOutputPort("target").Eval(context), tiny_path[0])
    np.testing.assert_array_equal(dut.diagram.GetOutputPort("wheel_speeds").Eval(context), np.zeros(4))
    np.testing.assert_array_equal(dut.diagram.GetOutputPort("planned_path").Eval(context), tiny_path)


def test_the_path_sources_give_the_planner_they_name(tiny_scenario):
    from drake_social.control import PlannerSystem, ReplanningPlannerSystem

    assert isinstance(make_autonomy(tiny_scenario, path=PlanAtInit()).planner, PlannerSystem)
    replanning = make_autonomy(tiny_scenario, path=Replan())
    assert isinstance(replanning.planner, ReplanningPlannerSystem) and replanning.replanning
    external = make_autonomy(tiny_scenario, path=ExternalPath())
    assert external.planner is None and external.input_port_names() == ["robot_state", "path"]
    # None: the scenario's word (planner.replan).
    on = dc.replace(tiny_scenario, planner=dc.replace(tiny_scenario.planner, replan=True))
    assert make_autonomy(on).replanning and not make_autonomy(tiny_scenario).replanning
    assert path_source(None, True, "mine") == Replan("mine") and path_source(None, False) == PlanAtInit()


def test_make_autonomy_checks_its_arguments_at_the_door(tiny_scenario):
    with pytest.raises(TypeError, match="^make_autonomy: path must be a PlanAtInit, Replan, GivenWaypoints or "
                                        "ExternalPath of drake_social.sim.autonomy or None, got str 'external'"):
        make_autonomy(tiny_scenario, path="external")
    with pytest.raises(ScenarioError, match=r"^make_autonomy: waypoints: .*must be an \(N, 4\) array"):
        make_autonomy(tiny_scenario, path=GivenWaypoints(np.zeros((0, 4))))
    with pytest.raises(ValueError, match="^make_autonomy: unknown execution 'smooth'; allowed: synchronized, paper"):
        make_autonomy(tiny_scenario, execution="smooth")
    with pytest.raises(TypeError, match="^make_autonomy: people must be"):
        make_autonomy(tiny_scenario, people=[])
    fast = dc.replace(tiny_scenario, planner=dc.replace(tiny_scenario.planner, replan_rate=1000.0))
    with pytest.raises(ValueError, match="^make_autonomy: replan=True: the scenario's planner.replan_rate must be"):
        make_autonomy(fast, path=Replan())


# ---- the two wired: build_diagram -------------------------------------------------------------------------------


@pytest.mark.parametrize("mode", ["kinematic", "dynamic"])
@pytest.mark.parametrize("execution", ["synchronized", "paper"])
def test_the_diagram_exports_the_station_and_the_autonomy(tiny_scenario, tiny_path, mode, execution):
    built = build_diagram(tiny_scenario, mode=mode, execution=execution, waypoints=tiny_path)
    # tiny's person stands still: no safety monitor, no stop port (a walker's run exports it:
    # tests/sim/test_safety_stop.py).
    expected = OUTPUTS | ({"reference_feedforward"} if execution == "synchronized" else set())
    assert set(built.output_port_names()) == expected
    assert built.input_port_names() == []
    assert {s.get_name() for s in built.diagram.GetSystems()} >= {"station", "autonomy"}
    context = built.diagram.CreateDefaultContext()
    state = built.diagram.GetOutputPort("robot_state").Eval(context)
    np.testing.assert_array_equal(state, np.concatenate([tiny_path[0], np.zeros(4)]))
    np.testing.assert_array_equal(built.diagram.GetOutputPort("planned_path").Eval(context), tiny_path)
    np.testing.assert_array_equal(built.diagram.GetOutputPort("target").Eval(context), tiny_path[0])
    # The records and the convenience lookup through the parts.
    np.testing.assert_array_equal(built.waypoints, tiny_path)
    assert built.subsystem("sequencer") is built.autonomy.sequencer
    assert built.subsystem("people") is built.station.people and built.plant is built.station.plant
    with pytest.raises(RuntimeError, match="no subsystem named 'planner'"):
        built.subsystem("planner")


def test_a_path_from_outside_runs_as_the_fixed_waypoints(tiny_scenario, tiny_path):
    """The sequencer reading the path from the diagram's ``path`` input gives
    the run of the same waypoints fixed in the builder, sample for sample."""
    reference = simulate(tiny_scenario, mode="kinematic", execution="paper", waypoints=tiny_path, analyze=False)
    built = build_diagram(tiny_scenario, mode="kinematic", execution="paper", path=ExternalPath())
    assert built.input_port_names() == ["path"] and built.waypoints is None
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


def test_build_diagram_takes_the_path_once(tiny_scenario, tiny_path):
    with pytest.raises(ValueError, match="^build_diagram: path: the path source says where the path comes from; "
                                         "leave out waypoints, replan"):
        build_diagram(tiny_scenario, path=ExternalPath(), waypoints=tiny_path, replan=False)
    with pytest.raises(TypeError, match="^build_diagram: path must be a PlanAtInit"):
        build_diagram(tiny_scenario, path=False)
    with pytest.raises(TypeError, match="planner"):  # the flag of the one-piece builder is gone
        build_diagram(tiny_scenario, planner=False)
    with pytest.raises(TypeError, match="plant_config"):
        build_diagram(tiny_scenario, plant_config={"time_step": 0.001})
    built = build_diagram(tiny_scenario, path=GivenWaypoints(tiny_path))  # the same as waypoints=
    np.testing.assert_array_equal(built.waypoints, tiny_path)


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
    assert make_station(scenario, mode="dynamic", plant_config=mine).plant.time_step() == 0.001


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
@pytest.mark.parametrize("who", ["build_diagram", "make_station", "make_autonomy"])
def test_bad_drake_settings_are_refused_by_name(tiny_scenario, field, value, rule, who):
    scenario = dc.replace(tiny_scenario, execution=dc.replace(tiny_scenario.execution, **{field: value}))
    function = {"build_diagram": build_diagram, "make_station": make_station, "make_autonomy": make_autonomy}[who]
    with pytest.raises(ScenarioError, match=f"{who}: scenario: execution.{field}: {rule}"):
        function(scenario)


@pytest.mark.parametrize("count", [1999, 2000, 2001])
def test_a_dynamic_station_holds_at_most_the_bound_of_map_boxes(tiny_scenario, monkeypatch, count):
    """MAX_DYNAMIC_MAP_BOXES (docs/limits.md): a map of that many boxes builds, one more is refused by
    name in dynamic mode; the kinematic station, which does not register them, takes any number."""
    import types

    import drake_social.sim.station as station_module

    assert station_module.MAX_DYNAMIC_MAP_BOXES == 2000
    monkeypatch.setattr(station_module, "world_model", lambda scenario: types.SimpleNamespace(map_box_count=count))
    make_station(tiny_scenario, mode="kinematic")
    if count <= 2000:
        assert make_station(tiny_scenario, mode="dynamic").mode == "dynamic"
    else:
        with pytest.raises(ScenarioError, match="^world.map: 2,001 boxes are too many for a dynamic run .* at most "
                                                "2,000: run it kinematic"):
            make_station(tiny_scenario, mode="dynamic")
