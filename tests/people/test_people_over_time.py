"""Consumers that know time read the people model at each sample's time.

A person walking past a robot that stands still: measured against the
people at each sample's time, the closest approach is where the walk passes
the robot; against the people at t = 0 it would be where the walk starts.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_social.cost.agf import PersonalSpace, agf_algorithm1
from drake_social.evaluation import metrics
from drake_social.people import PeopleModel, PeopleState, people_model
from drake_social.scenario import load_scenario

_ROOM = """
description: "a person walks past"
world: {bounds: [0.0, 0.0, 20.0, 6.0]}
people:
  - {x: 5.0, y: 3.8, theta: 0.0, radius: 0.25}
robot: {base_radius: 0.35, link_lengths: [0.6, 0.5], link_width: 0.08}
object: !Bar {length: 1.5, thickness: 0.05}
start: [10.0, 2.5, 0.0, 1.5707963267948966]
goal: [12.0, 2.5, 0.0, 1.5707963267948966]
"""

SPEED = 1.0  # m/s along +x


class WalkingPeople:
    """The scenario's people walking along +x at SPEED from their places at t = 0."""

    def __init__(self, scenario):
        self._start = people_model(scenario).state_at(0.0)

    @property
    def count(self) -> int:
        return self._start.count

    @property
    def static(self) -> bool:
        return False

    def state_at(self, t: float) -> PeopleState:
        s = self._start
        velocities = np.tile([SPEED, 0.0], (s.count, 1))
        return PeopleState(t=t, positions=s.positions + t * velocities, headings=s.headings, velocities=velocities,
                           radii=s.radii, names=s.names)


@pytest.fixture
def walk(tmp_path, monkeypatch):
    path = tmp_path / "walk.yaml"
    path.write_text(_ROOM)
    scenario = load_scenario(path)
    model = WalkingPeople(scenario)
    assert isinstance(model, PeopleModel)
    monkeypatch.setattr(metrics, "people_model", lambda s: model)
    return scenario


def test_metrics_of_a_trajectory_read_the_people_at_each_sample_time(walk):
    times = np.linspace(0.0, 10.0, 51)  # every 0.2 s; the person walks from x = 5 to x = 15, past x = 10 at t = 5
    q = np.tile(walk.start, (len(times), 1))  # the robot stands at (10, 2.5)
    dut = metrics.trajectory_metrics(walk, q, np.linspace(0.0, 1.0, len(times)), times)
    # Base disc (0.35) to body disc (0.25), 1.3 m apart when the person passes.
    assert dut["min_dist_base"] == pytest.approx(1.3 - 0.35 - 0.25, abs=1e-12)
    # The elbow at (10.6, 2.5): passed at t = 5.6, a sample time.
    assert dut["min_dist_link1_tip"] == pytest.approx(1.3 - 0.25, abs=1e-12)
    # AGF at the base: the largest over the samples, by Algorithm 1 line by line.
    space = PersonalSpace.from_options(walk.social)
    expected = max(agf_algorithm1(10.0, 2.5, (5.0 + SPEED * t, 3.8, 0.0), space) for t in times)
    assert expected > 0
    assert dut["agf_max_base"] == pytest.approx(expected, rel=1e-12, abs=1e-15)


def test_without_times_a_path_is_measured_against_the_people_at_t0(walk):
    q = np.tile(walk.start, (5, 1))
    dut = metrics.trajectory_metrics(walk, q, np.linspace(0.0, 1.0, 5))
    assert dut["min_dist_base"] == pytest.approx(math.hypot(5.0, 1.3) - 0.35 - 0.25, abs=1e-12)


def test_the_cost_and_the_figure_take_a_state_at_any_time(walk):
    from matplotlib.figure import Figure

    from drake_social.cost import SocialCost
    from drake_social.viz import draw_world

    state = WalkingPeople(walk).state_at(5.0)  # the person at (10, 3.8)
    cost = SocialCost.from_scenario(walk, people=state)
    np.testing.assert_array_equal(cost.people, [[10.0, 3.8, 0.0]])
    space = PersonalSpace.from_options(walk.social)
    assert cost(np.array([walk.start]))[0] == pytest.approx(
        sum(w * agf_algorithm1(x, y, (10.0, 3.8, 0.0), space)
            for w, (x, y) in zip(cost.weights, cost.geometry.interest_points(np.array(walk.start)))), rel=1e-12)
    # Without a state: the scenario's people at t = 0.
    np.testing.assert_array_equal(SocialCost.from_scenario(walk).people, [[5.0, 3.8, 0.0]])
    ax = Figure().add_subplot()
    drawn = draw_world(ax, walk, people=state)
    assert drawn["people"][0].center == (10.0, 3.8) and drawn["people"][0].radius == 0.25
    assert draw_world(Figure().add_subplot(), walk)["people"][0].center == (5.0, 3.8)


def test_executed_metrics_read_the_run_people_log_and_its_presence(walk):
    # The run's log, not the crowd without the robot: the person stood at (10, 3.3), facing +x,
    # and was in the room only from t = 5 s; the model's walker (passing 1.3 m away) is not used.
    from drake_social.people import PeopleLog

    times = np.linspace(0.0, 10.0, 51)
    q = np.tile(walk.start, (len(times), 1))  # the robot stands at (10, 2.5)
    states = [PeopleState(t=t, positions=[[10.0, 3.3]], headings=[0.0], velocities=[[0.0, 0.0]], radii=[0.25],
                          names=("p",), present=[t >= 5.0]) for t in times]
    log = PeopleLog.from_states(states)
    dut = metrics.executed_metrics(walk, times, q, log)
    assert dut["exec_min_dist_base"] == pytest.approx(0.8 - 0.35 - 0.25, abs=1e-12)
    # 0.2 m from t = 5 on: intimate for the last 5 s of 10; before, nobody is there (public; the
    # step into t = 5 has an end at +inf, so it is public too).
    assert dut["exec_zone_time_intimate_base"] == pytest.approx(0.5, abs=1e-12)
    assert dut["exec_zone_time_public_base"] == pytest.approx(0.5, abs=1e-12)
    space = PersonalSpace.from_options(walk.social)
    assert dut["exec_agf_max_base"] == pytest.approx(agf_algorithm1(10.0, 2.5, (10.0, 3.3, 0.0), space), rel=1e-12)
    # A log sampled at other times is read at the run's times (linear; presence from the sample before).
    coarse = PeopleLog.from_states(states[::5])
    assert metrics.executed_metrics(walk, times, q, coarse)["exec_zone_time_intimate_base"] == pytest.approx(0.5)
