"""``plan``'s path.png draws the walkers over the plan's nominal duration."""

from __future__ import annotations

import numpy as np
import pytest

from drake_social import app
from drake_social.people import PeopleState
from drake_social.viz import path as viz_path
from drake_social.viz.path import nominal_times, planned_people


class Walker:
    """One person walking west along y = 4.5 at 0.25 m/s (tiny's room)."""

    count, static = 1, False

    def state_at(self, t):
        return PeopleState(t=t, positions=[[7.0 - 0.25 * t, 4.5]], headings=[np.pi], velocities=[[-0.25, 0.0]],
                           radii=[0.25], names=("walker",))


def test_nominal_times_by_hand(tiny_scenario):
    # max_base_speed 0.5 m/s, arm_max_velocity 1 rad/s (tiny's defaults): 5 m of base take 10 s;
    # then a turn of 2 rad and 0.5 rad with the base still takes 2 s; then 1 m of base and 1 rad: 2 s.
    assert tiny_scenario.execution.max_base_speed == 0.5 and tiny_scenario.execution.arm_max_velocity == [1.0, 1.0]
    wp = np.array([[0.0, 0.0, 0.0, 0.0], [3.0, 4.0, 0.0, 0.0], [3.0, 4.0, 2.0, 0.5], [4.0, 4.0, 1.0, 0.5]])
    np.testing.assert_allclose(nominal_times(tiny_scenario, wp), [0.0, 10.0, 12.0, 14.0], rtol=0, atol=1e-12)


def test_planned_people_samples_the_walkers_over_the_nominal_duration(tiny_scenario, monkeypatch):
    assert planned_people(tiny_scenario, [tiny_scenario.start, tiny_scenario.goal]) is None  # tiny's person stands
    monkeypatch.setattr(viz_path, "people_model", lambda scenario: Walker())
    # start (1, 2.5) to goal (6.5, 2.5), arm unchanged: 5.5 m at 0.5 m/s = 11 s, 10 samples a second.
    log = planned_people(tiny_scenario, np.array([tiny_scenario.start, tiny_scenario.goal], float))
    np.testing.assert_allclose(log.times, np.linspace(0.0, 11.0, 111), rtol=0, atol=1e-12)
    np.testing.assert_allclose(log.positions[:, 0, 0], 7.0 - 0.25 * log.times, rtol=0, atol=1e-12)
    # Without a path (a failed plan): the start-to-goal line's duration.
    assert planned_people(tiny_scenario, np.zeros((0, 4))).times[-1] == pytest.approx(11.0)


def test_plan_draws_the_walkers_tracks_on_path_png(tiny_scenario_path, tmp_path, monkeypatch):
    drawn = []
    original = viz_path.draw_people_tracks
    monkeypatch.setattr(viz_path, "draw_people_tracks",
                        lambda ax, people, **kw: drawn.append(people) or original(ax, people, **kw))
    monkeypatch.setattr(viz_path, "people_model", lambda scenario: Walker())
    dut = app.run_plan(scenario=tiny_scenario_path, out=tmp_path, checker="numpy")
    assert dut.result.success and "path.png" in dut.files
    (people,) = drawn
    duration = nominal_times(app.load_scenario(tiny_scenario_path), dut.result.waypoints)[-1]
    assert people.times[-1] == pytest.approx(duration, abs=1e-12)
    assert people.times[-1] > 11.0  # the planned path is longer than the straight line
