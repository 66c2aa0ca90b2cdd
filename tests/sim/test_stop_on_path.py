"""A stop stays on the planned segment: base and arm stop together, on it."""

from __future__ import annotations

import dataclasses as dc

import numpy as np
import pytest

from drake_social.scenario import load_scenario
from drake_social.sim import simulate
from test_safety_stop import Walker


@pytest.fixture(scope="module")
def crossing():
    """tiny.yaml without its standing person; a path whose first segment turns the arm as the base
    drives east, and a walker crossing it southwards at x = 3.6 while the robot is on that segment."""
    scenario = dc.replace(load_scenario("scenarios/tiny.yaml"), people=[])
    waypoints = np.array([scenario.start, [4.5, 2.5, 0.8, 0.9], scenario.goal], float)
    walker = Walker([3.6, 4.8], [3.6, 0.3], 2.0, 2.0 + 4.5 / 0.4)
    return scenario, waypoints, walker


def test_a_safety_stop_mid_segment_stays_on_the_segment(crossing):
    scenario, waypoints, walker = crossing
    run = simulate(scenario, waypoints=waypoints, people=walker, mode="kinematic", execution="synchronized")
    assert run.reached and run.report.collision_free
    (stop,) = run.stops
    k = int(np.argmin(np.abs(run.times - stop["start"])))
    # Mid-segment, with base and arm moving when the monitor stops the robot.
    assert np.linalg.norm(run.q[k, :2] - waypoints[0, :2]) > 1.0 and np.linalg.norm(run.q[k, :2] - waypoints[1, :2]) > 0.5
    assert np.abs(run.v[k - 1, :2]).max() > 0.1 and np.abs(run.v[k - 1, 2:]).max() > 0.05
    assert stop["duration"] > 1.0
    # Every executed configuration on the planned segments, every body point on its planned curve.
    assert run.report.max_config_deviation <= 1e-9
    assert run.report.max_point_deviation["max"] <= 1e-9
