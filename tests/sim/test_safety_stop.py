"""A walker crossing the robot's path: the safety monitor stops the robot, logs the stop, lets it go."""

from __future__ import annotations

import dataclasses as dc
import logging

import numpy as np
import pytest

from drake_social.control import braking_travel
from drake_social.evaluation.nav_metrics import execution_metrics
from drake_social.scenario.geometry import arm_geometry
from drake_social.people import PeopleState
from drake_social.people.proximity import part_distances
from drake_social.scenario import load_scenario
from drake_social.sim import simulate
from drake_social.sim.diagram import build_diagram


class Walker:
    """A test double of an open-loop PeopleModel: one person walking from a to b between t0 and t1."""

    count = 1
    static = False

    def __init__(self, a, b, t0: float, t1: float, radius: float = 0.25):
        self.a, self.b = np.asarray(a, float), np.asarray(b, float)
        self.t0, self.t1, self.radius = t0, t1, radius
        self.speed = float(np.linalg.norm(self.b - self.a)) / (t1 - t0)

    def position(self, t: float) -> np.ndarray:
        s = min(max((t - self.t0) / (self.t1 - self.t0), 0.0), 1.0)
        return self.a + s * (self.b - self.a)

    def state_at(self, t: float) -> PeopleState:
        walking = self.t0 < t < self.t1
        v = (self.b - self.a) / (self.t1 - self.t0) if walking else np.zeros(2)
        d = self.b - self.a
        return PeopleState(t, self.position(t)[None], [np.arctan2(d[1], d[0])], v[None], [self.radius],
                           ("walker",))


SAFETY = 0.05


@pytest.fixture(scope="module")
def setting():
    """tiny.yaml without its standing person and without the slow-down (the paper's stop and go: the
    monitor alone); the robot drives straight east along y = 2.5 (its 1.5 m bar along x at y = 3
    leads by 1.35 m) and a walker crosses its path southwards at x = 5.6 at 0.4 m/s, passing the
    bar's height y = 3 at t = 6.7 s, just when the bar's tip arrives."""
    base = load_scenario("scenarios/tiny.yaml")
    scenario = dc.replace(base, people=[], execution=dc.replace(base.execution, slow_down=False))
    waypoints = np.array([scenario.start, scenario.goal], float)
    walker = Walker([5.6, 4.8], [5.6, 0.3], 2.2, 2.2 + 4.5 / 0.4)
    return scenario, waypoints, walker


def _distances(scenario, walker, run):
    geometry = arm_geometry(scenario)
    return np.array([part_distances(geometry, q[None], walker.position(t)[None], [walker.radius])["robot"][0]
                     for t, q in zip(run.times, run.q)])


@pytest.mark.parametrize("execution", ["synchronized", "paper"])
def test_walker_crossing_stops_the_robot_which_goes_on_after(setting, execution, caplog):
    scenario, waypoints, walker = setting
    with caplog.at_level(logging.INFO, logger="drake_social.sim.run"):
        run = simulate(scenario, waypoints=waypoints, people=walker, analyze=False, mode="kinematic",
                       execution=execution)
    period = scenario.execution.control_period
    d = _distances(scenario, walker, run)
    assert run.reached
    (stop,) = run.stops
    assert (stop["person"], stop["part"]) == ("walker", "object")
    # The monitor decides from q and the people at each sample: the stop starts at the first sample
    # within the safety distance and ends release_time after the first one clear again (clear at
    # every sample between), with the distance of its start.
    close = np.flatnonzero(d <= SAFETY)
    k_start = close[0]
    k_clear = k_start + np.flatnonzero(d[k_start:] > SAFETY)[0]
    release = scenario.execution.release_time
    assert release == 0.5
    k_end = k_clear + int(round(release / period))
    assert np.all(d[k_clear:k_end + 1] > SAFETY)
    assert stop["start"] == pytest.approx(run.times[k_start], abs=1e-9)
    assert stop["end"] == pytest.approx(run.times[k_end], abs=1e-9)
    assert stop["duration"] == pytest.approx(stop["end"] - stop["start"], abs=1e-12)
    assert stop["duration"] > 0.5  # a real wait, many control periods
    assert stop["distance"] == pytest.approx(d[k_start], abs=1e-12)
    assert SAFETY - period * walker.speed - period * scenario.execution.max_base_speed < stop["distance"] <= SAFETY
    np.testing.assert_array_equal(run.stopped, (run.times >= stop["start"]) & (run.times < stop["end"]))
    # Held: the base does not move from the stop's start to its end: its sampled command is zero at once
    # (paper), or it follows the reference, held one period later (synchronized).
    lag = 1 if execution == "synchronized" else 0
    held = run.q[k_start + lag:k_end + 1]  # (the base's P term on the rounding of the reference: 1e-14 m)
    np.testing.assert_allclose(held, np.broadcast_to(run.q[k_start + lag], held.shape), rtol=0, atol=1e-12)
    # Only the robot's own motion counts against the field: wherever the robot moved into a sample, it
    # was clear one or two samples before, so it is within at most the braking travel of both.
    moved = np.r_[False, np.any(np.abs(run.q[1:] - run.q[:-1]) > 1e-12, axis=1)]
    opts = scenario.execution
    bound = SAFETY - braking_travel(arm_geometry(scenario), max_base_speed=opts.max_base_speed,
                                    arm_max_velocity=opts.arm_max_velocity, period=period,
                                    execution=execution) - (1 + lag) * period * walker.speed
    assert d[moved].min() >= bound
    # ... the arm stands still here, so the tight bound is one or two periods of the base and of the walker.
    assert d[moved].min() >= SAFETY - (1 + lag) * period * (opts.max_base_speed + walker.speed) - 1e-12
    # It goes on after the walker passed and reaches the goal.
    assert run.time_to_goal > stop["end"] + 1.0
    np.testing.assert_allclose(run.q[-1, :2], scenario.goal[:2], atol=opts.base_tolerance)
    record = run.to_json_dict()
    assert record["stops"] == [stop] and record["stopped_time"] == pytest.approx(stop["duration"])
    lines = [r.getMessage() for r in caplog.records if r.getMessage().startswith("safety stop")]
    assert len(lines) == 1 and "walker" in lines[0] and f"{stop['start']:.3f}" in lines[0]


@pytest.mark.parametrize("mode", ["kinematic", "dynamic"])
def test_a_walker_walking_into_the_held_robot_makes_no_moving_contact(setting, mode):
    # The walker comes head-on along the base's line y = 2.5 and walks on through the robot: the
    # monitor holds the robot from the walker's first sample within the safety distance (no contact
    # force in either mode: the walker passes through). The robot did not drive into them.
    scenario, waypoints, _ = setting
    walker = Walker([7.5, 2.5], [0.5, 2.5], 0.0, 7.0 / 0.5)
    run = simulate(scenario, waypoints=waypoints, people=walker, analyze=False, mode=mode, time_limit=8.0)
    d = _distances(scenario, walker, run)
    (stop,) = run.stops
    k0 = int(np.flatnonzero(d <= 0.0)[0])  # the contact's first sample, by hand
    assert stop["start"] < run.times[k0 - 1] and stop["end"] is None
    dut = execution_metrics(scenario, run)
    assert dut["nav_collisions_robot"] == 1.0 and dut["nav_collisions_arm"] == 1.0
    assert dut["nav_collisions_moving_robot"] == 0.0 and dut["nav_collisions_appeared_robot"] == 0.0
    assert dut["nav_collisions_moving_arm"] == 0.0 and dut["nav_collisions_moving_base"] == 0.0
    if mode == "dynamic":  # the held robot still creeps (the servo's residue) as the contact begins
        assert np.any(run.q[k0] != run.q[k0 - 1])


def test_stop_port_and_logger_only_with_people(setting):
    scenario, waypoints, walker = setting
    with_people = build_diagram(scenario, waypoints=waypoints, people=walker)
    without = build_diagram(scenario, waypoints=waypoints)
    assert "stop" in with_people.output_port_names() and "stop" in with_people.loggers
    assert "stop" not in without.output_port_names() and "stop" not in without.loggers
    context = with_people.diagram.CreateDefaultContext()
    assert with_people.diagram.GetOutputPort("stop").Eval(context)[0] == 0.0


def test_no_people_no_stops(setting):
    scenario, waypoints, _ = setting
    run = simulate(scenario, waypoints=waypoints, analyze=False, mode="kinematic", time_limit=2.0)
    assert run.stops == [] and not run.stopped.any() and len(run.stopped) == len(run.times)
    assert run.to_json_dict()["stopped_time"] == 0.0


def test_a_standing_person_closer_than_the_safety_distance_does_not_hold_the_robot():
    # A static scenario whose straight path passes a standing person 1 cm away (< SAFETY: link 2's
    # capsule, radius 4 cm, ends at the gripper, 0.5 m above the base's y = 2.5): no
    # monitor (the people do not move), so the robot goes by instead of waiting for ever.
    base = load_scenario("scenarios/tiny.yaml")
    person = dc.replace(base.people[0], x=4.0, y=3.3)
    scenario = dc.replace(base, people=[person])
    waypoints = np.array([scenario.start, scenario.goal], float)
    s = np.linspace(0.0, 1.0, 2001)[:, None]
    q = waypoints[0] + s * (waypoints[1] - waypoints[0])
    d = part_distances(arm_geometry(scenario), q, np.array([[4.0, 3.3]]), [person.radius])["robot"]
    assert 0.0 < d.min() < SAFETY and d.min() == pytest.approx(3.3 - 0.25 - 3.0 - 0.04, abs=1e-5)
    built = build_diagram(scenario, waypoints=waypoints)
    assert "stop" not in built.output_port_names() and "stop" not in built.loggers
    run = simulate(scenario, waypoints=waypoints, analyze=False, mode="kinematic", time_limit=40.0)
    assert run.reached and run.stops == [] and not run.stopped.any()
    np.testing.assert_allclose(run.q[-1], scenario.goal, atol=1e-6)
