"""The replay colours the robot's base by the slow-down: free, under a speed limit, held for a person."""

from __future__ import annotations

import dataclasses as dc

import numpy as np
import pytest
from test_safety_stop import Walker

import browser
from drake_social.scenario import load_scenario
from drake_social.sim import simulate
from drake_social.sim.replay import make_meshcat, write_replay_html
from drake_social.sim.replay_speed import BASE_NODE, SLOW_DOWN_COLOURS, animate_slow_down, slow_down_states


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """tiny.yaml's straight drive towards a person standing on the bar's line, recorded: the robot
    slows down and stops for them (a person who could walk: the slow-down is built)."""
    base = load_scenario("scenarios/tiny.yaml")
    scenario = dc.replace(base, people=[])
    meshcat = make_meshcat()
    run = simulate(scenario, waypoints=np.array([scenario.start, scenario.goal]), meshcat=meshcat, analyze=False,
                   people=Walker([5.0, 3.0], [5.0, 3.0], 0.0, 1.0), mode="kinematic", time_limit=12.0)
    keys = animate_slow_down(meshcat, run, float(scenario.execution.replay_fps))
    html = tmp_path_factory.mktemp("replay") / "replay.html"
    write_replay_html(meshcat, html)
    return run, keys, html


def test_the_states_follow_the_limit_and_the_stops(recorded):
    run, keys, _ = recorded
    dut = slow_down_states(run)
    t_limit = run.times[np.flatnonzero(np.isfinite(run.speed_limit))[0]]
    t_stop = run.slow_stops[0]["start"]
    assert np.all(dut[run.times < t_limit] == 0)
    assert np.all(dut[(run.times >= t_limit) & (run.times < t_stop)] == 1)
    assert np.all(dut[run.times >= t_stop + 0.01] == 2)
    assert keys == 1 + 2 * 2  # the first colour, then two changes of two keyframes each


def test_a_run_that_was_never_slowed_is_left_alone():
    scenario = load_scenario("scenarios/tiny.yaml")
    run = simulate(scenario, waypoints=np.array([scenario.start, scenario.goal]), analyze=False, time_limit=1.0)
    assert not slow_down_states(run).any()
    assert animate_slow_down(make_meshcat(), run, 30.0) == 0


@pytest.mark.browser
def test_the_page_shows_the_base_coloured_by_the_slow_down(recorded):
    browser.require_chromium()
    run, _, html = recorded
    t_limit = float(run.times[np.flatnonzero(np.isfinite(run.speed_limit))[0]])
    t_stop = float(run.slow_stops[0]["start"])
    times = [1.0, 0.5 * (t_limit + t_stop), t_stop + 1.0]
    colours = browser.probe(html, times, path=BASE_NODE)["colours"]
    assert [c[0] for c in colours] == pytest.approx(times)
    for (_, *rgb), expected in zip(colours, SLOW_DOWN_COLOURS):
        assert rgb == pytest.approx(expected, abs=1e-6)
