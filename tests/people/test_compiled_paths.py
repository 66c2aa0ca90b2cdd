"""The compiled per-step paths of the people give their references' numbers.

The safety monitor's robot distance (:func:`drake_social.people.proximity.robot_distance`)
against :func:`~drake_social.people.proximity.part_distances`, the tracks'
evaluation against :meth:`~drake_social.people.tracks.Tracks.evaluate_reference`,
and the models' states (built without the constructor's copies) against
states built by the constructor: seeded random cases, exact equality.
"""

from __future__ import annotations

import numpy as np
import pytest

from drake_social.scenario.geometry import arm_geometry
from drake_social.people import PeopleState, StaticPeople
from drake_social.people.compose import ScenarioPeople, concat_states, people_model
from drake_social.people.proximity import part_distances, robot_distance, robot_distance_args
from drake_social.people.tracks import Tracks
from drake_social.scenario import load_scenario

SCENARIOS = ("tiny", "office_bar", "office_walkers", "lobby_crowd")


@pytest.mark.parametrize("name", SCENARIOS)
def test_robot_distance_is_part_distances_robot(name):
    geometry = arm_geometry(load_scenario(f"scenarios/{name}.yaml"))
    args = robot_distance_args(geometry)
    rng = np.random.default_rng(20)
    for _ in range(500):
        p = int(rng.integers(0, 8))
        q = np.r_[rng.uniform(0.0, 5.0, 2), rng.uniform(-7.0, 7.0, 2)]
        centres, radii = rng.uniform(-1.0, 6.0, (p, 2)), rng.uniform(0.1, 0.4, p)
        present = rng.random(p) < 0.8
        ref = part_distances(geometry, q[None], centres, radii, present)["robot"][0]
        got = robot_distance(args, q, centres, radii, present)
        assert got == ref if np.isinf(ref) else abs(got - ref) <= 1e-12
        assert got == ref  # the same operations, in fact
    assert robot_distance(geometry, q, np.zeros((0, 2)), np.zeros(0)) == np.inf


def test_robot_distance_touching_and_overlapping():
    geometry = arm_geometry(load_scenario("scenarios/tiny.yaml"))
    q = np.array([1.0, 2.5, 0.0, np.pi / 2])  # base disc of radius 0.35 at (1, 2.5)
    for gap in (0.0, -0.1, 0.03):
        d = robot_distance(geometry, q, [[1.0, 2.5 - 0.35 - 0.2 - gap]], [0.2])
        assert d == pytest.approx(gap, abs=1e-12)
        assert d == part_distances(geometry, q[None], [[1.0, 2.5 - 0.35 - 0.2 - gap]], [0.2])["robot"][0]
    with pytest.raises(ValueError, match="one of each per person"):
        robot_distance(geometry, q, [[1.0, 1.0]], [0.2, 0.3])


def _random_tracks(rng):
    times, points, headings, loops, steady = [], [], [], [], []
    for _ in range(int(rng.integers(1, 6))):
        t = np.unique(rng.uniform(0.0, 20.0, int(rng.integers(1, 6))))
        loop = bool(rng.random() < 0.5) and len(t) > 1
        times.append(t)
        points.append(rng.uniform(-5.0, 5.0, (len(t), 2)))
        headings.append((t, rng.uniform(-3.0, 3.0, len(t))))
        loops.append(loop)
        steady.append(float(t[0]) if loop else np.inf)
    return Tracks(times, points, headings, loops, steady)


def test_tracks_evaluate_is_the_reference():
    rng = np.random.default_rng(7)
    cases = [(people_model(load_scenario("scenarios/office_walkers.yaml")).open_loop[0]._tracks,
              np.r_[np.arange(-1.0, 130.0, 0.01), rng.uniform(-10.0, 1e4, 500), [0.0, -0.0]])]
    cases += [(_random_tracks(rng), rng.uniform(-5.0, 100.0, 50)) for _ in range(100)]
    for tracks, times in cases:
        for t in times:
            got, ref = tracks.evaluate(t), tracks.evaluate_reference(t)
            for a, b in zip(got, ref):
                assert np.array_equal(a, b) and a.flags.c_contiguous


def _constructed(state: PeopleState) -> PeopleState:
    return PeopleState(t=state.t, positions=state.positions, headings=state.headings, velocities=state.velocities,
                       radii=state.radii, names=state.names, present=state.present)


def _same(a: PeopleState, b: PeopleState) -> None:
    assert a.t == b.t and a.names == b.names
    for field in ("positions", "headings", "velocities", "radii", "present"):
        x, y = getattr(a, field), getattr(b, field)
        assert x.dtype == y.dtype and np.array_equal(x, y) and not x.flags.writeable, field


@pytest.mark.parametrize("name", ["office_walkers", "lobby_crowd", "office_bar"])
def test_model_states_are_checked_states(name):
    model = people_model(load_scenario(f"scenarios/{name}.yaml"))
    for t in (0.0, 1.25, 7.5, 33.3):
        state = model.state_at(t)
        _same(state, _constructed(state))
        assert model.open_loop_state(t) is model.open_loop_state(t)  # the same time asked twice: one state
        _same(model.open_loop_state(t), _constructed(model.open_loop_state(t)))


def test_concat_and_static_states_are_checked_states():
    a = StaticPeople([[1.0, 2.0, 0.5]], [0.2], ["a"])
    b = StaticPeople([[3.0, 4.0, -0.5], [5.0, 1.0, 0.0]], [0.25, 0.3])
    s = concat_states([a.state_at(2.0), b.state_at(2.0)], 2.0)
    _same(s, _constructed(s))
    assert s.positions.tolist() == [[1.0, 2.0], [3.0, 4.0], [5.0, 1.0]] and s.names == ("a", "", "")
    _same(a.state_at(3.0), _constructed(a.state_at(3.0)))
    assert a.state_at(3.0).t == 3.0
    joined = ScenarioPeople([a, b])
    assert joined.open_loop_state(1.0).t == 1.0 and joined.open_loop_state(2.0).t == 2.0


def test_joined_crowd_states_reused_only_while_their_parts_stay():
    from drake_social.control import PeopleSource

    model = people_model(load_scenario("scenarios/lobby_crowd.yaml"))
    source, crowd = PeopleSource(model), model.crowd
    row = source.initial_crowd_state()
    for k in range(12):
        t = 0.01 * k
        if k % 5 == 0 and k:  # a crowd step: new numbers
            n = (len(row) - 1) // 2
            row = np.concatenate([[t], row[1 + n:], crowd.step(row[1 + n:], t, model.open_loop_state(t), None)])
        got = source.people_at(t, row)
        n = (len(row) - 1) // 2
        x = row[1 + n:] if t >= row[0] + crowd.time_step - 1e-9 else row[1:1 + n]
        pos, vel, heading, _ = crowd.unpack(x)
        fresh = PeopleState(t=t, positions=pos, headings=heading, velocities=vel, radii=crowd.people_state(x, t).radii,
                            names=crowd.people_state(x, t).names)
        _same(got, _constructed(concat_states([model.open_loop_state(t), fresh], t)))
