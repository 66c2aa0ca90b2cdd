"""Slowing down near people in a whole run: brakes jerk-limited, stops before the safety distance, no chatter."""

from __future__ import annotations

import dataclasses as dc

import numpy as np
import pytest
from test_safety_stop import Walker

from drake_social.evaluation.time_series import derivative_magnitudes
from drake_social.scenario.geometry import arm_geometry
from drake_social.people import PeopleState
from drake_social.people.proximity import part_distances
from drake_social.scenario import load_scenario
from drake_social.sim import build_diagram, simulate

BASE = load_scenario("scenarios/tiny.yaml")
OPTS = BASE.execution
STOP = OPTS.safety_distance + OPTS.stop_margin


def _scenario(**execution):
    """tiny.yaml without its standing person, the robot driving east along y = 2.5 with its bar at y = 3."""
    return dc.replace(BASE, people=[], execution=dc.replace(OPTS, **execution))


def _distances(scenario, walker, run):
    geometry = arm_geometry(scenario)
    return np.array([part_distances(geometry, q[None], walker.position(t)[None], [walker.radius])["robot"][0]
                     for t, q in zip(run.times, run.q)])


class Pacer:
    """A person on the bar's line standing at ``x`` until ``t0``, then stepping 2 cm towards the
    robot and 15 cm away from it by turns, every ``period`` seconds."""

    count = 1
    static = False

    def __init__(self, x: float, t0: float, period: float, radius: float = 0.25):
        self.x, self.t0, self.period, self.radius = x, t0, period, radius

    def position(self, t: float) -> np.ndarray:
        if t < self.t0:
            return np.array([self.x, 3.0])
        return np.array([self.x + (0.15 if int((t - self.t0) / self.period) % 2 else -0.02), 3.0])

    def state_at(self, t: float) -> PeopleState:
        return PeopleState(t, self.position(t)[None], [np.pi], np.zeros((1, 2)), [self.radius], ("pacer",))


def test_the_robot_slows_and_stops_before_a_person_on_its_path():
    scenario = _scenario()
    person = Walker([5.0, 3.0], [5.0, 3.0], 0.0, 1.0)  # stands on the bar's line: a person who could move
    run = simulate(scenario, waypoints=np.array([scenario.start, scenario.goal]), people=person, mode="kinematic",
                   time_limit=30.0)
    d = _distances(scenario, person, run)
    assert not run.reached and run.stops == []  # it waits; the safety monitor never has to stop it
    assert len(run.slow_stops) == 1 and run.slow_stops[0]["end"] is None
    # At rest before the safety distance, about the stop distance (the stop planned there).
    assert OPTS.safety_distance < d.min() and d.min() == pytest.approx(STOP, abs=0.01)
    # The limit falls with the distance as the robot comes nearer.
    approach = np.flatnonzero(np.isfinite(run.speed_limit))
    order = np.argsort(-d[approach])
    assert np.all(np.diff(run.speed_limit[approach][order]) <= 1e-12)
    # Braking within the reference's limits: the base's sampled acceleration and jerk (a pure translation).
    xy = run.q[:, :2]
    assert derivative_magnitudes(run.times, xy, 2).max() <= OPTS.max_base_acceleration * (1 + 1e-6)
    assert derivative_magnitudes(run.times, xy, 3).max() <= OPTS.max_base_jerk * (1 + 1e-6)


def test_without_the_slow_down_the_safety_monitor_stops_the_robot():
    scenario = _scenario(slow_down=False)
    person = Walker([5.0, 3.0], [5.0, 3.0], 0.0, 1.0)
    built = build_diagram(scenario, waypoints=np.array([scenario.start, scenario.goal]), people=person)
    assert built.autonomy.speed_limit is None and "speed_limit" not in built.loggers
    run = simulate(scenario, waypoints=np.array([scenario.start, scenario.goal]), people=person, mode="kinematic",
                   time_limit=30.0)
    d = _distances(scenario, person, run)
    assert len(run.stops) == 1 and run.slow_stops == [] and np.all(np.isinf(run.speed_limit))
    assert d.min() < OPTS.safety_distance + 1e-9  # the monitor's stop, at the safety distance
    assert derivative_magnitudes(run.times, run.q[:, :2], 3).max() > 100 * OPTS.max_base_jerk  # a hard stop


@pytest.mark.parametrize("release, most", [(OPTS.release_time, 1), (0.0, None)])
def test_a_person_pacing_at_the_stop_distance_does_not_make_the_robot_chatter(release, most):
    # The bar's tip comes to rest about STOP from the person standing at x = 5 by t = 12 s; from then
    # on they step in (within the stop distance) and out (beyond the release margin) every 0.2 s.
    scenario = _scenario(release_time=release)
    pacer = Pacer(5.0, 12.0, 0.2)
    run = simulate(scenario, waypoints=np.array([scenario.start, scenario.goal]), people=pacer, mode="kinematic",
                   time_limit=30.0)
    if most is not None:
        assert run.stops == [] and len(run.slow_stops) <= most
    else:  # the hold is what keeps it still: without it the robot stops and goes many times
        assert len(run.slow_stops) > 5
