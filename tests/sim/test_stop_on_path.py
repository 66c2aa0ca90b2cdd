"""A stop stays on the planned segment: base and arm stop together, on it."""

from __future__ import annotations

import dataclasses as dc

import numpy as np
import pytest
from test_safety_stop import Walker

from drake_social.scenario import load_scenario
from drake_social.sim import simulate


def _crossing(slow_down: bool):
    """tiny.yaml without its standing person; a path whose first segment turns the arm as the base
    drives east, and a walker crossing it southwards at x = 3.6 while the robot is on that segment."""
    base = load_scenario("scenarios/tiny.yaml")
    scenario = dc.replace(base, people=[], execution=dc.replace(base.execution, slow_down=slow_down))
    waypoints = np.array([scenario.start, [4.5, 2.5, 0.8, 0.9], scenario.goal], float)
    walker = Walker([3.6, 4.8], [3.6, 0.3], 2.0, 2.0 + 4.5 / 0.4)
    return scenario, waypoints, walker


def _mid_segment_stop(run, waypoints, start: float) -> int:
    """The sample of a stop's start, checked to be mid-segment with base and arm moving just before."""
    k = int(np.argmin(np.abs(run.times - start)))
    assert np.linalg.norm(run.q[k, :2] - waypoints[0, :2]) > 1.0
    assert np.linalg.norm(run.q[k, :2] - waypoints[1, :2]) > 0.5
    return k


def test_a_safety_stop_mid_segment_stays_on_the_segment():
    # Without the slow-down the monitor stops the robot at full speed (the hard stop).
    scenario, waypoints, walker = _crossing(slow_down=False)
    run = simulate(scenario, waypoints=waypoints, people=walker, mode="kinematic", execution="synchronized")
    assert run.reached and run.report.collision_free
    (stop,) = run.stops
    k = _mid_segment_stop(run, waypoints, stop["start"])
    assert np.abs(run.v[k - 1, :2]).max() > 0.1 and np.abs(run.v[k - 1, 2:]).max() > 0.05
    assert stop["duration"] > 1.0
    # Every executed configuration on the planned segments, every body point on its planned curve.
    assert run.report.max_config_deviation <= 1e-9
    assert run.report.max_point_deviation["max"] <= 1e-9


def test_a_slow_down_stop_mid_segment_stays_on_the_segment():
    # With it the robot brakes along the segment before the walker comes near and rests on it.
    scenario, waypoints, walker = _crossing(slow_down=True)
    run = simulate(scenario, waypoints=waypoints, people=walker, mode="kinematic", execution="synchronized")
    assert run.reached and run.report.collision_free
    stop = run.slow_stops[0]
    k = _mid_segment_stop(run, waypoints, stop["start"])
    assert np.all(run.speed_limit[k + 1:k + 20] == 0.0)
    at_rest = np.flatnonzero(np.abs(run.v[k:]).max(axis=1) < 1e-9)  # (the base's P term on rounding)
    assert len(at_rest) > 10  # it comes to rest there
    assert run.report.max_config_deviation <= 1e-9
    assert run.report.max_point_deviation["max"] <= 1e-9
