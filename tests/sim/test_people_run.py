"""A run logs the people at the executed samples' times, checks the room alone
when the people move, and ``simulate`` writes people.csv beside executed.csv."""

from __future__ import annotations

import csv
import dataclasses as dc
import json

import numpy as np
import pytest

from drake_social import app
from drake_social.io.paths import PEOPLE_HEADER, write_people_csv
from drake_social.people import PEOPLE_CSV_FIELDS, PeopleLog, PeopleState, ScenarioPeople, people_model
from drake_social.sim import diagram as diagram_module
from drake_social.sim.results import CHECKED_ROOM, CHECKED_ROOM_AND_PEOPLE
from drake_social.sim.run import simulate


class Walkers:
    """tiny's person walking west along y = 3.8 at 0.2 m/s, and one who is
    in the room only for 1 s <= t < 4 s, standing at (7, 1)."""

    count, static = 2, False

    def state_at(self, t):
        return PeopleState(t=t, positions=[[4.0 - 0.2 * t, 3.8], [7.0, 1.0]], headings=[np.pi, 0.5],
                           velocities=[[-0.2, 0.0], [0.0, 0.0]], radii=[0.25, 0.3], names=("standing", "visitor"),
                           present=[True, 1.0 <= t < 4.0])


@pytest.fixture
def walking(monkeypatch):
    model = ScenarioPeople([Walkers()])
    monkeypatch.setattr(diagram_module, "people_model", lambda scenario: model)
    return model


def test_the_people_are_logged_at_the_executed_times(tiny_scenario, walking):
    run = simulate(tiny_scenario, mode="kinematic", time_limit=6.0)
    log = run.people
    np.testing.assert_array_equal(log.times, run.times)
    assert log.names == ("standing", "visitor") and len(run.times) > 100
    np.testing.assert_allclose(log.positions[:, 0, 0], 4.0 - 0.2 * run.times, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(log.present[:, 1], (run.times >= 1.0) & (run.times < 4.0))
    # The people moved: the collision check covered the room alone.
    assert run.report.collision_checked == list(CHECKED_ROOM)
    assert run.to_json_dict()["collision_checked"] == ["obstacles", "walls"]


def test_a_static_scenario_logs_its_standing_people_and_checks_them(tiny_scenario):
    run = simulate(tiny_scenario, mode="kinematic", time_limit=2.0)
    person = tiny_scenario.people[0]
    np.testing.assert_array_equal(run.people.times, run.times)
    np.testing.assert_array_equal(run.people.positions, np.broadcast_to([[person.x, person.y]], (len(run.times), 1, 2)))
    assert run.report.collision_checked == list(CHECKED_ROOM_AND_PEOPLE)


def test_a_dynamic_run_with_a_walker_through_the_robot_runs(tiny_scenario, monkeypatch):
    # A walker crossing the robot's start: the plant must neither crash nor push on them. The
    # safety monitor holds the robot while the walker walks through it, then lets it go.
    start = np.asarray(tiny_scenario.start, float)

    class Crossing:
        count, static = 1, False

        def state_at(self, t):
            return PeopleState(t=t, positions=[[start[0], start[1] - 1.0 + t]], headings=[np.pi / 2],
                               velocities=[[0.0, 1.0]], radii=[0.25], names=("crossing",))

    monkeypatch.setattr(diagram_module, "people_model", lambda scenario: ScenarioPeople([Crossing()]))
    waypoints = np.array([start, start + [0.5, 0.0, 0.0, 0.0]])
    near = dc.replace(tiny_scenario, goal=waypoints[1].tolist())
    run = simulate(near, mode="dynamic", waypoints=waypoints, time_limit=5.0)
    assert run.reached and np.isfinite(run.q).all()
    assert len(run.stops) == 1 and run.stops[0]["end"] is not None
    np.testing.assert_allclose(run.people.positions[:, 0, 1], start[1] - 1.0 + run.times, atol=1e-12)
    # The robot went where the servo took it, through the person (no contact force from them).
    assert run.q[-1, 0] == pytest.approx(start[0] + 0.5, abs=0.06)


def test_simulate_writes_people_csv(tiny_scenario_path, walking, tmp_path, monkeypatch):
    from drake_social.viz import path as viz_path

    drawn = []
    original = viz_path.draw_people_tracks
    monkeypatch.setattr(viz_path, "draw_people_tracks",
                        lambda ax, people, **kw: drawn.append((people, kw)) or original(ax, people, **kw))
    dut = app.run_simulate(scenario=tiny_scenario_path, out=tmp_path, mode="kinematic", checker="numpy",
                           replay=False)
    assert dut.files == ["executed.csv", "people.csv", "path.png", "tracking.png", "motion.png", "sim.json"]
    # path.png: the run's own log and executed trajectory, marked at 5 common times over the run.
    from matplotlib.image import imread

    assert imread(tmp_path / "path.png").shape[0] > 500
    ((people, kw),) = drawn
    assert people is dut.run.people and kw["robot"][0] is dut.run.times and kw["robot"][1] is dut.run.q
    np.testing.assert_allclose(kw["marks"], np.linspace(0.0, dut.run.times[-1], 5), rtol=0, atol=1e-12)
    executed = np.loadtxt(tmp_path / "executed.csv", delimiter=",", skiprows=1)
    with open(tmp_path / "people.csv", newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0] == list(PEOPLE_CSV_FIELDS)
    times = executed[:, 0]
    # One row per present person per logged time, equal to the model's state there.
    expected = []
    for t in times:
        state = walking.state_at(float(t))
        for i in np.flatnonzero(state.present):
            expected.append([t, state.names[i], *state.positions[i], state.headings[i], np.hypot(*state.velocities[i])])
    assert len(rows) - 1 == len(expected) == len(times) + int(((times >= 1.0) & (times < 4.0)).sum())
    for got, want in zip(rows[1:], expected):
        assert got[1] == want[1]
        np.testing.assert_allclose([float(v) for v in got[:1] + got[2:]], [want[0], *want[2:]], rtol=0, atol=1e-12)
    record = json.loads((tmp_path / "sim.json").read_text())
    assert record["collision_checked"] == ["obstacles", "walls"]


def test_people_csv_quotes_odd_ids_and_keeps_17_digits(tmp_path):
    assert PEOPLE_HEADER == ",".join(PEOPLE_CSV_FIELDS)
    log = PeopleLog(times=[0.0, 0.1], positions=[[[1 / 3, 2.0]], [[0.5, 2.0]]], headings=[[0.1], [0.2]],
                    velocities=[[[3.0, 4.0]], [[0.0, 0.0]]], present=[[True], [True]], radii=[0.3],
                    names=('ann, "the" walker',))
    write_people_csv(tmp_path / "people.csv", log)
    with open(tmp_path / "people.csv", newline="") as f:
        rows = list(csv.reader(f))
    assert rows[1][1] == 'ann, "the" walker' and float(rows[1][2]) == 1 / 3 and float(rows[1][5]) == 5.0
    assert len(rows) == 3


def test_people_model_of_a_scenario_without_people_gives_no_log(tiny_scenario):
    empty = dc.replace(tiny_scenario, people=[])
    assert people_model(empty).count == 0
    run = simulate(empty, mode="kinematic", time_limit=1.0)
    assert run.people is None


@pytest.mark.parametrize("kind", ["numpy", "planar"])
def test_a_given_checker_of_the_people_at_t0_is_replaced_by_the_room_alone_when_people_move(tiny_scenario, kind):
    # The base drives through where tiny's person stood at t = 0; the planning checker
    # (people at t = 0) rejects it, the room alone (the person has walked off) accepts it.
    from drake_social.collision.drake_checker import make_checker
    from drake_social.people import without_people
    from drake_social.sim.execution_analysis import analyze_execution

    q = np.array([[x, 3.4, 0.0, 1.5708] for x in np.linspace(3.0, 5.0, 41)])
    times = np.linspace(0.0, 4.0, len(q))
    planning = make_checker(tiny_scenario, kind)
    assert not planning.are_valid(q).all()
    assert make_checker(without_people(tiny_scenario), kind).are_valid(q).all()
    moving = analyze_execution(tiny_scenario, q[[0, -1]], times, q, planning, people_move=True)
    assert moving.collision_free and moving.first_collision_time is None
    assert moving.collision_checked == list(CHECKED_ROOM)
    standing = analyze_execution(tiny_scenario, q[[0, -1]], times, q, planning, people_move=False)
    assert not standing.collision_free and standing.collision_checked == list(CHECKED_ROOM_AND_PEOPLE)
