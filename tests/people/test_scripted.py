"""Scripted people against hand values: positions, velocities, loops, headings."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_social.people import StaticPeople, people_model
from drake_social.people.scripted import ScriptedPeople
from drake_social.people.tracks import TURN_RATE, heading_knots
from drake_social.scenario import Person, Scenario

# Walks east 2 m in 2 s, north 2 m in 2 s, pauses 1 s, west 2 m in 2 s, stops at t = 8.
ROUTE = [[1.0, 0.0, 0.0], [3.0, 2.0, 0.0], [5.0, 2.0, 2.0], [6.0, 2.0, 2.0], [8.0, 0.0, 2.0]]


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def _walker(**kw) -> Person:
    return Person(**{"theta": 0.3, "radius": 0.3, "name": "w", "trajectory": ROUTE, **kw})


@pytest.mark.parametrize("t, position, velocity", [
    (0.0, (0, 0), (0, 0)),     # standing at the first point before its time
    (1.0, (0, 0), (1, 0)),     # the first segment starts
    (2.0, (1, 0), (1, 0)),
    (2.5, (1.5, 0), (1, 0)),
    (4.0, (2, 1), (0, 1)),
    (5.5, (2, 2), (0, 0)),     # the pause
    (7.0, (1, 2), (-1, 0)),
    (7.9, (0.1, 2), (-1, 0)),
    (8.0, (0, 2), (0, 0)),     # at the last point
    (30.0, (0, 2), (0, 0)),
])
def test_positions_and_velocities_at_hand_chosen_times(t, position, velocity):
    state = ScriptedPeople([_walker()]).state_at(t)
    np.testing.assert_allclose(state.positions[0], position, atol=1e-12)
    np.testing.assert_allclose(state.velocities[0], velocity, atol=1e-12)
    assert state.t == t and state.names == ("w",) and state.radii[0] == 0.3 and state.present.all()


@pytest.mark.parametrize("t, heading", [
    (0.0, 0.3),                        # the given theta while standing
    (1.0, 0.3),                        # the turn toward east (0) starts with the motion
    (1.0 + 0.15 / TURN_RATE, 0.15),    # half of the 0.3 rad turn, at pi rad/s
    (2.0, 0.0),
    (3.0, 0.0),                        # the corner: turning north starts
    (3.25, math.pi / 4),               # 0.25 s at pi rad/s
    (4.0, math.pi / 2),
    (5.5, math.pi / 2),                # paused: the last walking heading
    (6.25, 3 * math.pi / 4),           # turning west, the shorter way (+pi/2)
    (7.0, math.pi),
    (20.0, math.pi),                   # after the end: the last walking heading
])
def test_heading_turns_at_the_bounded_rate_and_holds_while_standing(t, heading):
    state = ScriptedPeople([_walker()]).state_at(t)
    assert state.headings[0] == pytest.approx(heading, abs=1e-12)


def _max_heading_step(model, t_end: float, dt: float) -> float:
    h = np.array([model.state_at(k * dt).headings for k in range(int(t_end / dt) + 1)])
    return float(np.abs(_wrap(np.diff(h, axis=0))).max())


def test_heading_never_turns_faster_than_the_rate_at_corners_stops_and_u_turns():
    routes = [ROUTE,
              [[0, 1, 1], [2, 3, 1], [4, 1, 1], [5, 1, 1], [6, 1, 3]],          # a U-turn, a stop, a corner
              [[0, 0, 0], [0.2, 0.2, 0], [0.4, 0.2, 0.2], [0.6, 0, 0.2]]]       # turns cut short by the next
    model = ScriptedPeople([Person(trajectory=r, theta=2.0) for r in routes])
    dt = 1e-3
    assert _max_heading_step(model, 10.0, dt) <= TURN_RATE * dt + 1e-9
    # After each turn completes the heading is the direction of motion (the U-turn's half turn
    # is counter-clockwise: from 0 to pi).
    s = model.state_at(3.5)
    assert s.headings[1] == pytest.approx(math.pi, abs=1e-12)
    np.testing.assert_allclose(s.velocities[1], (-1, 0), atol=1e-12)


def test_a_loop_repeats_with_its_period():
    route = [[1.0, 0.0, 0.0], [3.0, 2.0, 0.0], [5.0, 2.0, 2.0], [7.0, 0.0, 0.0]]  # closed, period 6 s
    model = ScriptedPeople([Person(trajectory=route, loop=True, theta=1.0)])
    s0 = model.state_at(0.5)
    np.testing.assert_allclose(s0.positions[0], (0, 0), atol=1e-12)
    assert s0.headings[0] == 1.0 and not s0.velocities.any()
    for t, position, velocity in ((8.0, (1, 0), (1, 0)), (12.0, (1, 1), (-1, -1)), (13.0, (0, 0), (1, 0)),
                                  (604.0, (2, 1), (0, 1))):
        s = model.state_at(t)
        np.testing.assert_allclose(s.positions[0], position, atol=1e-9)
        np.testing.assert_allclose(s.velocities[0], velocity, atol=1e-12)
    for t in np.linspace(7.0, 13.0, 61):  # from the second period on the heading repeats
        for k in (1, 2, 17):
            assert _wrap(model.state_at(t + 6.0 * k).headings[0] - model.state_at(t).headings[0]) \
                == pytest.approx(0.0, abs=1e-9)
    assert _max_heading_step(model, 25.0, 1e-3) <= TURN_RATE * 1e-3 + 1e-9


def test_heading_knots_of_a_loop_start_repeating_after_the_first_period():
    t, h, steady = heading_knots(np.array([1.0, 3.0, 5.0, 7.0]), np.array([[0, 0], [2, 0], [2, 2], [0, 0.0]]),
                                 theta=1.0, loop=True)
    # The first period starts from theta; the second from the last segment's direction
    # (-3 pi / 4): from then on each period starts alike.
    assert steady == 7.0 and t[-1] == 13.0 and h[0] == 1.0
    assert _wrap(np.interp(7.0, t, h) - np.interp(13.0, t, h)) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("route", [[[0, 4.0, 3.8], [1, 4.0, 3.8]],                  # a pause in place
                                   [[2.5, 4.0, 3.8], [3, 4.0, 3.8], [7, 4.0, 3.8]]])  # three points, one place
def test_a_loop_without_motion_is_a_person_standing_there(route):
    dut = ScriptedPeople([Person(trajectory=route, loop=True, theta=-1.2, radius=0.3, name="p")])
    static = StaticPeople([[4.0, 3.8, -1.2]], [0.3], ["p"])
    for t in (0.0, 1.0, 2.75, 1e3, 1e9):
        a, b = dut.state_at(t), static.state_at(t)
        for field in ("positions", "headings", "velocities", "radii", "present"):
            assert np.array_equal(getattr(a, field), getattr(b, field)), (t, field)


def test_a_scenario_with_a_pause_in_place_on_a_loop_loads_and_its_person_stands(tmp_path):
    from drake_social.scenario import load_scenario

    path = tmp_path / "pause.yaml"
    path.write_text("world: {bounds: [0, 0, 8, 5]}\n"
                    "people: [{radius: 0.25, theta: 0.5, trajectory: [[0, 4.0, 3.8], [1, 4.0, 3.8]], loop: true}]\n"
                    "start: [1.0, 2.5, 0.0, 1.5708]\ngoal: [6.5, 2.5, 0.0, 1.5708]\n")
    dut = people_model(load_scenario(path))
    for t in (0.0, 0.5, 300.0):
        s = dut.state_at(t)
        np.testing.assert_array_equal(s.positions, [[4.0, 3.8]])
        assert s.headings[0] == 0.5 and not s.velocities.any()


def test_standing_people_are_exactly_the_static_model():
    standing = [Person(x=1.25, y=2.5, theta=-1.5708, radius=0.25, name="a"), Person(x=3.0, y=0.7, theta=4.0)]
    mixed = ScriptedPeople(standing + [_walker()])
    static = StaticPeople([[p.x, p.y, p.theta] for p in standing], [p.radius for p in standing], ["a", ""])
    for t in (0.0, 0.37, 2.0, 1e4):
        a, b = mixed.state_at(t), static.state_at(t)
        assert np.array_equal(a.positions[:2], b.positions) and np.array_equal(a.headings[:2], b.headings)
        assert np.array_equal(a.velocities[:2], b.velocities) and np.array_equal(a.radii[:2], b.radii)
    assert not mixed.static and ScriptedPeople(standing).static


def test_a_static_scenario_gives_todays_static_people():
    scenario = Scenario(people=[Person(x=1.0, y=2.0, theta=0.5, name="p"), Person(x=3.0, y=4.0, radius=0.3)])
    model = people_model(scenario)
    today = StaticPeople([[1.0, 2.0, 0.5], [3.0, 4.0, 0.0]], [0.25, 0.3], ["p", ""])
    assert model.static and len(model.open_loop) == 1 and isinstance(model.open_loop[0], StaticPeople)
    for t in (0.0, 12.5):
        a, b = model.state_at(t), today.state_at(t)
        for field in ("positions", "headings", "velocities", "radii", "present"):
            assert np.array_equal(getattr(a, field), getattr(b, field)), field
        assert a.names == b.names and a.t == b.t


def test_people_model_of_walkers_is_scripted():
    scenario = Scenario(people=[Person(x=1.0, y=2.0), _walker()])
    model = people_model(scenario)
    assert not model.static and isinstance(model.open_loop[0], ScriptedPeople)
    np.testing.assert_allclose(model.state_at(4.0).positions, [[1, 2], [2, 1]], atol=1e-12)


def test_state_at_refuses_a_time_that_is_not_finite():
    with pytest.raises(ValueError, match="finite time"):
        ScriptedPeople([_walker()]).state_at(math.nan)
