"""The slow-down's speed limit: the stopping law against Ruckig, monotone in distance, the hold."""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest
import ruckig

from drake_social.control import SpeedLimit
from drake_social.control.speed_limit import allowed_speed, ramp_speed, stopping_distance, stopping_time
from drake_social.scenario.geometry import arm_geometry
from drake_social.people import StaticPeople
from drake_social.scenario import ScenarioError, load_scenario, validate_scenario

SCENARIO = load_scenario("scenarios/tiny.yaml")
OPTS = SCENARIO.execution
GEOMETRY = arm_geometry(SCENARIO)
# tiny.yaml's start: the bar along x at y = 3 from x = 0.85 to 2.35; heading east along x.
Q = np.array([1.0, 2.5, 0.0, np.pi / 2])
EAST = Q + [4.0, 0.0, 0.0, 0.0]
STOP = OPTS.safety_distance + OPTS.stop_margin


def _ahead(gap: float, radius: float = 0.25) -> StaticPeople:
    """A person on the bar's line, ``gap`` metres beyond its tip (x = 2.35 + 0.025 capsule radius)."""
    return StaticPeople([[2.35 + 0.025 + radius + gap, 3.0, 0.0]], [radius])


@pytest.mark.parametrize("v", [0.02, 0.2, 0.5, 1.3])
def test_stopping_distance_and_time_are_ruckigs_shortest_stop(v):
    # Ruckig's velocity interface brakes from (v, 0) to rest as fast as A = 1, J = 5 allow.
    inp = ruckig.InputParameter(1)
    inp.control_interface = ruckig.ControlInterface.Velocity
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [v], [0.0]
    inp.target_velocity, inp.target_acceleration = [0.0], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [2.0], [1.0], [5.0]
    trajectory = ruckig.Trajectory(1)
    assert ruckig.Ruckig(1).calculate(inp, trajectory) == ruckig.Result.Working
    assert stopping_time(v, 1.0, 5.0) == pytest.approx(trajectory.duration, abs=1e-12)
    assert stopping_distance(v, 1.0, 5.0) == pytest.approx(trajectory.at_time(trajectory.duration)[0][0], abs=1e-12)


def test_allowed_speed_is_on_the_boundary_and_at_its_ends():
    kw = dict(decel=1.0, jerk=5.0, reaction=0.02, top=0.5)
    lead = 0.02 + 1.0 / 5.0
    # A person closing at 0.4 m/s needs 0.4 lead of gap even with the robot at rest: at it and below, 0.
    assert allowed_speed(0.4 * lead, 0.4, **kw) == 0.0
    assert allowed_speed(0.4 * lead * (1 + 1e-6), 0.4, **kw) > 0.0
    # The top speed needs 0.5 lead + D(0.5) = 0.285 m of gap (no one closing): at it the top, below it less.
    need = 0.5 * lead + stopping_distance(0.5, 1.0, 5.0)
    assert need == pytest.approx(0.285)
    assert allowed_speed(need, 0.0, **kw) == 0.5
    v = allowed_speed(need - 1e-3, 0.0, **kw)
    assert 0.49 < v < 0.5 and v * lead + stopping_distance(v, 1.0, 5.0) == pytest.approx(need - 1e-3, abs=1e-12)
    # A robot whose motion does not close the gap is limited only by a closing person: to be at rest
    # when they arrive, t(v) <= gap / c - lead; with nobody closing, not at all (even within the gap).
    assert allowed_speed(-1.0, 0.0, approach=0.0, **kw) == 0.5
    v = allowed_speed(0.5, 1.0, approach=0.0, **kw)
    assert stopping_time(v, 1.0, 5.0) == pytest.approx(0.5 / 1.0 - lead, abs=1e-12)


def test_the_ramp_at_its_ends_and_either_side():
    kw = dict(stop_distance=0.1, slow_distance=1.0, slow_speed=0.2, full_speed=0.5)
    assert ramp_speed(1.0, **kw) == math.inf
    assert ramp_speed(1.0 - 1e-9, **kw) == pytest.approx(0.5, abs=1e-8)
    assert ramp_speed(0.55, **kw) == pytest.approx(0.35)
    assert ramp_speed(0.1, **kw) == 0.2 and ramp_speed(0.05, **kw) == 0.2


@pytest.mark.parametrize("closing, approach", [(0.0, 1.0), (0.0, 0.4), (0.8, 1.0), (1.5, 0.2)])
def test_the_limit_is_monotone_in_distance_and_zero_at_the_stop_distance(closing, approach):
    dut = SpeedLimit(GEOMETRY, OPTS)
    braking = (0.5, 1.0, 5.0)  # a pure base motion: top speed, deceleration and jerk of its points
    distances = np.linspace(-0.1, 2.0, 2101)
    limits = np.array([dut.law(d, closing, approach, braking) for d in distances])
    assert np.all(limits[1:] >= limits[:-1])
    assert np.all(limits[distances <= STOP] == 0.0)
    assert np.all(limits[distances > STOP + 1e-9] > 0.0) or closing > 0.0
    assert np.isinf(limits[-1])  # far: no limit


def test_a_robot_heading_at_a_person_is_limited_and_one_heading_away_is_not():
    dut = SpeedLimit(GEOMETRY, OPTS)
    people = _ahead(0.3).state_at(0.0)
    towards, who = dut.limit_of(Q, people, EAST)
    assert who == 0 and 0.0 < towards < OPTS.max_base_speed
    # The ramp (approach 1 along x) at 0.3 m: 0.2 + 0.3 (0.2 / 0.9); the stopping law allows 0.37 m/s there.
    assert towards == pytest.approx(0.2 + 0.3 * (0.3 - STOP) / (1.0 - STOP), rel=1e-9)
    away, _ = dut.limit_of(Q, people, Q - [4.0, 0.0, 0.0, 0.0])
    assert away == math.inf
    assert dut.limit_of(Q, people, Q) == (math.inf, -1)  # not moving


def _updates(dut, context, people_at, count, target=EAST):
    """Runs ``count`` updates every control period with the people of ``people_at(k)``; the outputs."""
    out = []
    for k in range(count):
        context.SetTime(round(k * OPTS.control_period, 10))
        dut.GetInputPort("q").FixValue(context, Q)
        dut.GetInputPort("target").FixValue(context, target)
        dut.GetInputPort("people_state").FixValue(context, people_at(k).state_at(context.get_time()))
        scratch = context.Clone()
        dut.CalcForcedUnrestrictedUpdate(context, scratch.get_mutable_state())
        context.SetAbstractState(0, scratch.get_abstract_state(0).get_value())
        out.append(dut.GetOutputPort("speed_limit").Eval(context)[0])
    return np.array(out)


def test_the_limit_falls_at_once_and_rises_after_the_hold():
    dut = SpeedLimit(GEOMETRY, OPTS)
    context = dut.CreateDefaultContext()
    near, far = _ahead(0.2), _ahead(0.6)
    limits = _updates(dut, context, lambda k: near if 10 <= k < 20 else far, 120)
    low, high = dut.limit_of(Q, near.state_at(0.0), EAST)[0], dut.limit_of(Q, far.state_at(0.0), EAST)[0]
    assert low < high
    np.testing.assert_array_equal(limits[:10], high)
    np.testing.assert_array_equal(limits[10:20], low)  # at once
    # The person is far again from k = 20 (t = 0.2 s); the low value of t = 0.19 s is held for
    # release_time = 0.5 s and up to a sixteenth more (the hold's buckets of 1/32 s).
    rise = 20 + int(np.flatnonzero(limits[20:] == high)[0])
    assert 0.19 + 0.5 <= rise * OPTS.control_period <= 0.19 + 0.5 + 0.5 / 16 + 1e-9


@pytest.mark.parametrize("release, stops", [(0.5, 1), (0.0, 50)])
def test_a_person_stepping_in_and_out_at_the_stop_distance_makes_one_stop(release, stops):
    # Within the stop distance every other period for 1 s (the limit 0), then 0.4 m ahead.
    options = dc.replace(OPTS, release_time=release)
    dut = SpeedLimit(GEOMETRY, options)
    context = dut.CreateDefaultContext()
    limits = _updates(dut, context, lambda k: _ahead(STOP - 0.01 - 0.0) if k % 2 == 0 else _ahead(0.4), 100)
    assert len(dut.stops(context)) == stops
    if release > 0:
        assert np.all(limits == 0.0)
        assert dut.stops(context)[0].part == "object" and dut.stops(context)[0].distance == pytest.approx(STOP - 0.01)


def test_limit_has_no_direct_feedthrough():
    dut = SpeedLimit(GEOMETRY, OPTS)
    for name in ("q", "target", "people_state"):
        assert not dut.HasDirectFeedthrough(dut.GetInputPort(name).get_index(),
                                            dut.GetOutputPort("speed_limit").get_index())


@pytest.mark.parametrize("field, value, message", [
    ("slow_distance", STOP, "execution.slow_distance: must be > execution.safety_distance + execution.stop_margin"),
    ("slow_distance", float("nan"), "execution.slow_distance: must be finite"),
    ("slow_speed", OPTS.max_base_speed * (1 + 1e-9), "execution.slow_speed: must be <= execution.max_base_speed"),
    ("slow_speed", 0.0, "execution.slow_speed: must be > 0"),
    ("stop_margin", -1e-9, "execution.stop_margin: must be >= 0"),
    ("release_time", -1e-9, "execution.release_time: must be >= 0"),
    ("release_time", float("inf"), "execution.release_time: must be finite"),
    ("slow_down", 1, "execution.slow_down: must be true or false, got 1"),
])
def test_bad_slow_down_options_are_named(field, value, message):
    scenario = dc.replace(SCENARIO, execution=dc.replace(OPTS, **{field: value}))
    with pytest.raises(ScenarioError, match=message.replace("+", r"\+").replace(".", r"\.")):
        validate_scenario(scenario, source="x.yaml")


@pytest.mark.parametrize("field, value", [("slow_distance", STOP + 1e-9), ("slow_speed", OPTS.max_base_speed),
                                          ("stop_margin", 0.0), ("release_time", 0.0), ("slow_down", False)])
def test_slow_down_options_at_their_bounds_are_valid(field, value):
    validate_scenario(dc.replace(SCENARIO, execution=dc.replace(OPTS, **{field: value})), source="x.yaml")
