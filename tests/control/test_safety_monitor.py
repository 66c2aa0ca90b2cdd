"""The safety monitor against hand-placed people and the one distance home (part_distances)."""

from __future__ import annotations

import dataclasses as dc

import numpy as np
import pytest

from drake_social.control import SafetyMonitor, braking_travel
from drake_social.control.safety_monitor import robot_reach
from drake_social.kinematics import ArmGeometry
from drake_social.scenario.geometry import arm_geometry
from drake_social.people import PeopleState, StaticPeople
from drake_social.people.proximity import part_distances
from drake_social.scenario import load_scenario

PERIOD = 0.01
SAFETY = 0.05
# tiny.yaml's robot at its start: base disc (radius 0.35) at (1, 2.5), link 1
# along +x to (1.6, 2.5), link 2 along +y to (1.6, 3.0), the bar along x at y = 3.
Q = np.array([1.0, 2.5, 0.0, np.pi / 2])


@pytest.fixture(scope="module")
def geometry():
    return arm_geometry(load_scenario("scenarios/tiny.yaml"))


def _people(rows, radii, names=None, present=None, t=0.0):
    state = StaticPeople(rows, radii, names).state_at(t)
    return state if present is None else dc.replace(state, present=np.asarray(present, bool))


def _below_base(gap, radius=0.2):
    """A person straight below the base whose body is ``gap`` metres from the base disc."""
    return [[Q[0], Q[1] - 0.35 - radius - gap, 0.0]], [radius]


def _update(monitor, context, q=None, people=None, t=None):
    """Sets the inputs (when given) and time, then runs the monitor's update in place."""
    if t is not None:
        context.SetTime(t)
    if q is not None:
        monitor.GetInputPort("q").FixValue(context, np.asarray(q, float))
    if people is not None:
        monitor.GetInputPort("people_state").FixValue(context, people)
    scratch = context.Clone()
    monitor.CalcForcedUnrestrictedUpdate(context, scratch.get_mutable_state())
    context.SetAbstractState(0, scratch.get_abstract_state(0).get_value())
    return monitor.GetOutputPort("stop").Eval(context)[0]


def _monitor(geometry, safety=SAFETY):
    return SafetyMonitor(geometry, safety_distance=safety, period=PERIOD)


@pytest.mark.parametrize("gap, stops", [(0.04, True), (0.06, False)])
def test_flag_against_the_hand_distance_below_the_base(geometry, gap, stops):
    rows, radii = _below_base(gap)
    people = _people(rows, radii, ["ann"])
    # The one distance home agrees with the hand value, and the base is the nearest part.
    d = part_distances(geometry, Q[None], people.positions, people.radii)
    assert d["base"][0] == pytest.approx(gap, abs=1e-12)
    assert d["robot"][0] == pytest.approx(gap, abs=1e-12)
    monitor = _monitor(geometry)
    context = monitor.CreateDefaultContext()
    assert _update(monitor, context, Q, people, t=0.3) == (1.0 if stops else 0.0)
    stops_so_far = monitor.stops(context)
    if stops:
        (stop,) = stops_so_far
        assert (stop.start, stop.end, stop.person, stop.part) == (0.3, None, "ann", "base")
        assert stop.distance == pytest.approx(gap, abs=1e-12)
    else:
        assert stops_so_far == ()


def test_zero_safety_distance_stops_on_contact_only(geometry):
    monitor = _monitor(geometry, safety=0.0)
    context = monitor.CreateDefaultContext()
    for gap, expected in ((0.001, 0.0), (-1e-9, 1.0), (-0.02, 1.0), (0.001, 0.0)):  # -1e-9: touching
        rows, radii = _below_base(gap)
        assert _update(monitor, context, Q, _people(rows, radii)) == expected, gap


def test_absent_and_far_people_do_not_stop(geometry):
    rows, radii = _below_base(0.01)
    monitor = _monitor(geometry)
    context = monitor.CreateDefaultContext()
    assert _update(monitor, context, Q, _people(rows, radii, present=[False])) == 0.0
    assert _update(monitor, context, Q, _people([[7.5, 0.5, 0.0]], [0.3])) == 0.0
    assert _update(monitor, context, Q, _people(np.zeros((0, 3)), np.zeros(0))) == 0.0
    assert monitor.stops(context) == ()


def test_nearest_person_part_and_unnamed_index(geometry):
    # Person 0 (unnamed) 0.03 m below the base, person 1 ("bob") 0.01 m above the bar (y = 3, radius 0.025).
    rows = [[Q[0], Q[1] - 0.35 - 0.2 - 0.03, 0.0], [2.0, 3.0 + 0.025 + 0.3 + 0.01, 0.0]]
    people = _people(rows, [0.2, 0.3], ["", "bob"])
    monitor = _monitor(geometry)
    context = monitor.CreateDefaultContext()
    assert _update(monitor, context, Q, people, t=1.0) == 1.0
    (stop,) = monitor.stops(context)
    assert (stop.person, stop.part) == ("bob", "object")
    assert stop.distance == pytest.approx(0.01, abs=1e-12)
    # Without bob the unnamed person 0 is reported by index, by the base.
    assert monitor.nearest(Q, _people(rows[:1], [0.2], [""]))[1:] == (0, "base")


def test_stops_are_recorded_with_start_and_end(geometry):
    monitor = _monitor(geometry)
    context = monitor.CreateDefaultContext()
    near, far = _people(*_below_base(0.02)), _people(*_below_base(0.2))
    flags = [_update(monitor, context, Q, people, t=t)
             for t, people in ((0.0, far), (0.01, near), (0.02, near), (0.03, far), (0.04, near))]
    assert flags == [0.0, 1.0, 1.0, 0.0, 1.0]
    first, second = monitor.stops(context)
    assert (first.start, first.end, second.start, second.end) == (0.01, 0.03, 0.04, None)
    assert first.to_dict()["duration"] == pytest.approx(0.02)
    assert second.to_dict(end_time=0.1) == pytest.approx(
        {"start": 0.04, "end": None, "duration": 0.06, "person": "0", "part": "base", "distance": 0.02})


@pytest.mark.parametrize("release, ends", [
    (0.0, [0.03]),            # no hold: released at the first clear sample
    (0.05, [0.08]),           # clear at 0.03 ... 0.08: 0.05 s clear, released at 0.08
    (0.05 + 1e-6, [None]),    # just longer than the run stays clear: still stopped
])
def test_a_stop_is_released_after_release_time_clear(geometry, release, ends):
    monitor = SafetyMonitor(geometry, safety_distance=SAFETY, period=PERIOD, release_time=release)
    context = monitor.CreateDefaultContext()
    near, far = _people(*_below_base(0.02)), _people(*_below_base(0.2))
    for k, people in enumerate([far, near, near] + [far] * 6):
        _update(monitor, context, Q, people, t=round(0.01 * k, 10))
    assert [stop.end for stop in monitor.stops(context)] == pytest.approx(ends)


def test_a_person_lingering_at_the_boundary_does_not_make_the_robot_stop_and_go(geometry):
    # In and out of the safety distance every other period for 2 s: one stop with the hold, 100 without.
    near, far = _people(*_below_base(SAFETY - 0.005)), _people(*_below_base(SAFETY + 0.005))
    counts = []
    for release in (0.5, 0.0):
        monitor = SafetyMonitor(geometry, safety_distance=SAFETY, period=PERIOD, release_time=release)
        context = monitor.CreateDefaultContext()
        for k in range(200):
            _update(monitor, context, Q, near if k % 2 == 0 else far, t=round(0.01 * k, 10))
        counts.append(len(monitor.stops(context)))
    assert counts == [1, 100]


def test_clone_and_reset_keep_their_own_record(geometry):
    monitor = _monitor(geometry)
    context = monitor.CreateDefaultContext()
    assert _update(monitor, context, Q, _people(*_below_base(0.02)), t=0.5) == 1.0
    clone = context.Clone()
    assert _update(monitor, clone, Q, _people(*_below_base(0.2)), t=0.6) == 0.0
    assert monitor.GetOutputPort("stop").Eval(context)[0] == 1.0
    assert monitor.stops(context)[0].end is None and monitor.stops(clone)[0].end == 0.6
    monitor.SetDefaultContext(context)
    assert monitor.GetOutputPort("stop").Eval(context)[0] == 0.0 and monitor.stops(context) == ()


def test_stop_has_no_direct_feedthrough(geometry):
    monitor = _monitor(geometry)
    for name in ("q", "people_state"):
        assert not monitor.HasDirectFeedthrough(monitor.GetInputPort(name).get_index(),
                                                monitor.GetOutputPort("stop").get_index())


def test_flag_equals_part_distances_on_random_scenes(geometry):
    """The reach pre-check never changes the verdict of the full distance (seeded scenes)."""
    rng = np.random.default_rng(20)
    monitor = _monitor(geometry)
    reach = robot_reach(geometry)
    agree = stopped = 0
    for _ in range(300):
        q = np.array([rng.uniform(2, 6), rng.uniform(1, 4), rng.uniform(-np.pi, np.pi), rng.uniform(-2.5, 2.5)])
        n = int(rng.integers(0, 4))
        angle = rng.uniform(-np.pi, np.pi, n)
        dist = rng.uniform(0.2, reach + 0.6, n)
        rows = np.column_stack([q[0] + dist * np.cos(angle), q[1] + dist * np.sin(angle), np.zeros(n)])
        radii = rng.uniform(0.15, 0.3, n)
        present = rng.random(n) < 0.8
        people = _people(rows, radii, present=present)
        d = part_distances(geometry, q[None], people.positions, people.radii, people.present)["robot"][0]
        assert monitor.too_close(q, people) == (d <= SAFETY)
        agree += 1
        stopped += d <= SAFETY
    assert agree == 300 and 20 < stopped < 280  # both verdicts occur


def test_robot_reach_and_braking_travel_by_hand(geometry):
    # tiny.yaml: l1 = 0.6, l2 = 0.5; the 1.5 m bar is held at its middle: farthest point 0.75, radius 0.025.
    assert robot_reach(geometry) == pytest.approx(0.6 + 0.5 + 0.775)
    arm = 1.0 * (1.1 + 0.775) + 2.0 * (0.5 + 0.775)
    travel = braking_travel(geometry, max_base_speed=0.5, arm_max_velocity=[1.0, 2.0], period=0.01, execution="paper")
    assert travel == pytest.approx(0.01 * (0.5 + 2 * arm))
    # Synchronized: the base follows the held reference, one period after the paper's base command.
    travel = braking_travel(geometry, max_base_speed=0.5, arm_max_velocity=[1.0, 2.0], period=0.01)
    assert travel == pytest.approx(2 * 0.01 * (0.5 + arm))
    with pytest.raises(ValueError, match="execution must be 'synchronized' or 'paper', got 'fast'"):
        braking_travel(geometry, max_base_speed=0.5, arm_max_velocity=[1.0, 2.0], period=0.01, execution="fast")


@pytest.mark.parametrize("kwargs, match", [
    ({"safety_distance": -0.01, "period": PERIOD}, "safety_distance"),
    ({"safety_distance": float("nan"), "period": PERIOD}, "safety_distance"),
    ({"safety_distance": SAFETY, "period": 0.0}, "period"),
    ({"safety_distance": SAFETY, "period": PERIOD, "release_time": -0.1}, "release_time"),
    ({"safety_distance": SAFETY, "period": PERIOD, "release_time": float("inf")}, "release_time"),
])
def test_bad_arguments_are_named(geometry, kwargs, match):
    with pytest.raises(ValueError, match=match):
        SafetyMonitor(geometry, **kwargs)
    with pytest.raises(TypeError, match="ArmGeometry"):
        SafetyMonitor("robot", safety_distance=SAFETY, period=PERIOD)


def test_people_state_port_accepts_the_people_source_value(geometry):
    state = PeopleState(0.0, [[1.0, 1.0]], [0.0], [[0.0, 0.0]], [0.25], ("x",))
    monitor = _monitor(geometry)
    context = monitor.CreateDefaultContext()
    assert _update(monitor, context, Q, state) == 0.0


def test_scenario_validation_names_a_negative_safety_distance():
    from drake_social.scenario import ScenarioError, validate_scenario

    scenario = load_scenario("scenarios/tiny.yaml")
    scenario.execution.safety_distance = -0.1
    with pytest.raises(ScenarioError, match=r"execution\.safety_distance: must be >= 0"):
        validate_scenario(scenario, source="tiny")
    scenario.execution.safety_distance = 0.0  # stop on contact only: allowed
    validate_scenario(scenario, source="tiny")
