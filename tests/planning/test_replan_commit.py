"""Progress and commitment in the replanner (drake_social.planning.replan_commit).

* the time term: a judged path costs ``planner.time_weight`` per second it
  takes, by hand;
* :func:`route_deviation` against the distance to the route worked out by
  hand and, on random paths, against a dense brute-force sampling;
* waiting may beat a detour: a walker crossing just ahead of the robot makes
  it wait for the shortest pause after which the current path is safe
  (checked independently, densely); a walker who stops on the route leaves
  no pause, and the robot takes a new path;
* leaving the route costs: a cheaper route on the other side of the block
  replaces the current one only when it is cheaper by the margin with the
  switching cost added, either side of the weight at which they are equal;
* no side-step unless the predicted contact is real: a walker heading at the
  standing robot makes it step aside under the constant-velocity prediction,
  not under the interactive one, in which the walker steers round it (the
  rollout's distances checked independently).
"""

from __future__ import annotations

import dataclasses as dc
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from drake_social.collision.drake_checker import make_checker
from drake_social.kinematics import nominal_path_times
from drake_social.people import PeopleState, without_people
from drake_social.people.proximity import part_distances
from drake_social.planning.replan import Replanner
from drake_social.planning.replan_evade import standing_clear
from drake_social.planning.replan_commit import PAUSE_SHARES, SWITCH_STEP, pause_steps, route_deviation
from drake_social.scenario.geometry import arm_geometry
from drake_social.scenario.load import load_scenario_text

sys.path.insert(0, str(Path(__file__).parent))
from test_replan import CORRIDOR, SOUTH_Y, along, nobody, route, walkers  # noqa: E402  (the corridor's helpers)
from test_replan_interactive import OPEN as OPEN_ROOM  # noqa: E402

SAFETY_HORIZON = 2.0


def corridor_with(**planner):
    sc = load_scenario_text(CORRIDOR, "corridor")
    return dc.replace(sc, planner=dc.replace(sc.planner, **planner))


@pytest.fixture(scope="module")
def corridor():
    return corridor_with(safety_horizon=SAFETY_HORIZON, time_weight=0.1, switch_weight=0.1)


@pytest.fixture(scope="module")
def room(corridor):
    return make_checker(without_people(corridor), "planar")


@pytest.fixture(scope="module")
def first(corridor, room):
    return Replanner(corridor, room, budget=60.0).plan(np.asarray(corridor.start, float), 0.0, nobody(0.0),
                                                       replan_index=0)


def least_distance(scenario, waypoints, t0, t_end, scripts, pause=0.0, samples=400) -> float:
    """The robot's least surface distance to the walkers from ``t0`` to ``t_end``: standing at
    the first waypoint for ``pause`` seconds, then driving the path at the limits; the walkers
    placed by np.interp of their scripts."""
    geometry = arm_geometry(scenario)
    wp = np.asarray(waypoints, float)
    times = nominal_path_times(wp, scenario.execution.max_base_speed, scenario.execution.arm_max_velocity,
                               t0 + pause)
    ts = np.linspace(t0, t_end, samples * 10)
    q = np.column_stack([np.interp(ts, times, wp[:, j]) for j in range(4)])
    centres = np.zeros((len(ts), len(scripts), 2))
    for i, script in enumerate(scripts):
        st, sx, sy = np.asarray(script, float).T
        centres[:, i, 0], centres[:, i, 1] = np.interp(ts, st, sx), np.interp(ts, st, sy)
    return float(part_distances(geometry, q, centres, np.full(len(scripts), 0.25))["robot"].min())


# ---- the time term ---------------------------------------------------------------------------


def test_a_path_costs_its_seconds(room):
    """The judged cost with time_weight w is the cost without it plus w times the path's
    seconds; a straight base motion of L metres takes L / max_base_speed."""
    s = np.array([1.2, 3.5, -1.2292, 2.8])
    path = np.array([s, s + [2.0, 0.0, 0.0, 0.0]])  # 2 m east at 0.5 m/s: 4 s, the arm still
    costs = {}
    for w in (0.0, 0.25, 3.0):
        dut = Replanner(corridor_with(time_weight=w), room, budget=60.0)
        ev = dut.evaluate(path, 1.0, nobody(1.0))
        assert ev.times[-1] - ev.times[0] == pytest.approx(4.0, abs=1e-12)
        costs[w] = ev.cost
    assert costs[0.25] - costs[0.0] == pytest.approx(0.25 * 4.0, rel=1e-12)
    assert costs[3.0] - costs[0.0] == pytest.approx(3.0 * 4.0, rel=1e-12)


def test_the_weights_are_checked():
    from drake_social.errors import ScenarioError

    for field in ("time_weight", "switch_weight"):
        for bad in (-1e-9, 1e6 * (1 + 1e-9), math.nan):
            with pytest.raises(ScenarioError, match=f"planner.{field}"):
                load_scenario_text(CORRIDOR.replace(f"{field}: 0.0", f"{field}: {bad!r}"), "corridor")
        for good in (0.0, 1e6):
            sc = load_scenario_text(CORRIDOR.replace(f"{field}: 0.0", f"{field}: {good!r}"), "corridor")
            assert getattr(sc.planner, field) == good


# ---- the distance from the route --------------------------------------------------------------


def q(x, y):
    return [x, y, 0.0, 0.0]


def test_deviation_of_a_parallel_path_by_hand():
    """A path 1 m beside a straight route: 1 m everywhere; one leaving it at right angles
    at a constant speed: the mean of its distances, the window's and the whole path's."""
    current = np.array([q(0, 0), q(10, 0)])
    beside = np.array([q(0, 1), q(10, 1)])
    assert route_deviation(beside, np.array([0.0, 20.0]), current, 5.0) == pytest.approx(1.0, abs=1e-15)
    away = np.array([q(2, 0), q(2, 2)])  # 2 m north in 4 s: 0.5 m/s
    # Samples every SWITCH_STEP from 0 to 4 s: y = 0.125 k, k = 0 .. 16: mean 1.0.
    assert route_deviation(away, np.array([0.0, 4.0]), current, 5.0) == pytest.approx(1.0, abs=1e-15)
    # A 2 s window: y = 0 .. 1 in 9 samples: mean 0.5; a window between samples ends on its own sample.
    assert route_deviation(away, np.array([0.0, 4.0]), current, 2.0) == pytest.approx(0.5, abs=1e-15)
    ys = np.append(np.arange(0.0, 2.1, SWITCH_STEP), 2.1) * 0.5
    assert route_deviation(away, np.array([0.0, 4.0]), current, 2.1) == pytest.approx(ys.mean(), abs=1e-15)
    # Beyond the route's end the distance is to its end point.
    past = np.array([q(13, 4), q(13, 4.0 + 1e-9)])
    assert route_deviation(past, np.array([0.0, 1e-9]), current, 5.0) == pytest.approx(5.0, abs=1e-8)
    # A route of one waypoint is a point.
    assert route_deviation(beside[:1], np.array([0.0]), np.array([q(3, 5)]), 5.0) == pytest.approx(5.0, abs=1e-15)


def test_deviation_against_brute_force():
    """Random paths and routes: the mean distance over the samples against the distance to
    100,000 points along the route (an upper bound within the spacing)."""
    rng = np.random.default_rng(7)
    for _ in range(40):
        current = np.column_stack([rng.uniform(0, 10, (5, 2)), np.zeros((5, 2))])
        path = np.column_stack([rng.uniform(0, 10, (4, 2)), np.zeros((4, 2))])
        times = np.concatenate([[0.0], np.cumsum(rng.uniform(0.5, 3.0, 3))])
        window = float(rng.uniform(0.3, 12.0))
        dut = route_deviation(path, times, current, window)
        end = min(times[-1], window)
        at = np.append(np.arange(0.0, end, SWITCH_STEP), end)
        pts = np.column_stack([np.interp(at, times, path[:, 0]), np.interp(at, times, path[:, 1])])
        u = np.linspace(0, 1, 25_000)[:, None]
        dense = np.concatenate([a[:2] + u * (b[:2] - a[:2]) for a, b in zip(current[:-1], current[1:])])
        spacing = max(np.hypot(*(b[:2] - a[:2])) for a, b in zip(current[:-1], current[1:])) / 25_000
        brute = np.array([np.hypot(*(dense - p).T).min() for p in pts]).mean()
        assert brute - spacing <= dut <= brute + 1e-12


def test_pause_steps():
    assert PAUSE_SHARES == (0.25, 0.5, 0.75)
    assert pause_steps(2.0) == (0.5, 1.0, 1.5)
    assert pause_steps(5.0) == (1.25, 2.5, 3.75)


# ---- waiting may beat a detour ----------------------------------------------------------------


def crossing(q_now: np.ndarray, t: float, stop_at: float | None = None, ahead: float = 2.0
             ) -> list[tuple[float, float, float]]:
    """A walker crossing the robot's way ``ahead`` metres east of it, northwards at 1.3 m/s
    from y = 0.3 (stopping at y = ``stop_at`` for good)."""
    x = float(q_now[0]) + ahead
    if stop_at is None:
        return [(t, x, 0.3), (t + 6.5 / 1.3, x, 6.8)]
    return [(t, x, 0.3), (t + (stop_at - 0.3) / 1.3, x, stop_at)]


def test_a_walker_crossing_ahead_makes_the_robot_wait(corridor, room, first):
    """The current path, driven now, comes within the safety distance of the walker within
    the safety horizon; after the first pause step it does not (both checked densely and
    independently): the robot waits, with the pause, its cost and the search's in the reason."""
    t = 2.0
    q_now, previous = along(first, t)
    script = crossing(q_now, t)
    safety = corridor.execution.safety_distance
    horizon_end = t + SAFETY_HORIZON
    w = pause_steps(SAFETY_HORIZON)[0]
    assert least_distance(corridor, previous, t, horizon_end, [script]) <= safety
    assert least_distance(corridor, previous, t, horizon_end, [script], pause=w) > safety
    dut = Replanner(corridor, room, budget=60.0)
    res = dut.plan(q_now, t, walkers(t, [script]), previous, replan_index=1)
    assert res.status == "wait" and res.waiting and not res.changed, res.reason
    np.testing.assert_array_equal(res.waypoints, q_now[None])
    assert f"after a pause of {w:.2g} s it is" in res.reason and "less than the search's path" in res.reason
    # The pause's cost: the path driven from t + w, and w seconds at time_weight.
    delayed = dut.evaluate(previous, t + w, walkers(t, [script]))
    assert f"costs {delayed.cost + 0.1 * w:.4g}" in res.reason


def test_a_walker_stopping_on_the_route_leaves_no_pause(corridor, room, first):
    """The same walker stops on the route ahead: no pause makes the current path safe,
    and the robot takes the search's path (clear of the walker over the safety horizon)."""
    t = 2.0
    q_now, previous = along(first, t)
    x = float(q_now[0]) + 0.8
    on_route = float(np.interp(x, previous[:2, 0], previous[:2, 1]))  # the first motion goes east (south-east)
    assert previous[1, 0] > x
    script = crossing(q_now, t, stop_at=on_route, ahead=0.8)
    safety = corridor.execution.safety_distance
    for w in (0.0, *pause_steps(SAFETY_HORIZON)):
        assert least_distance(corridor, previous, t, t + SAFETY_HORIZON, [script], pause=w) <= safety
    res = Replanner(corridor, room, budget=60.0).plan(q_now, t, walkers(t, [script]), previous, replan_index=1)
    assert res.status == "new" and res.changed, res.reason
    assert "waiting" not in res.reason
    assert least_distance(corridor, res.waypoints, t, t + SAFETY_HORIZON, [script]) > safety


# ---- leaving the route costs ------------------------------------------------------------------


def via(scenario, y):
    s, g = np.asarray(scenario.start, float), np.asarray(scenario.goal, float)
    return np.array([s, [3.4, y, *s[2:]], [8.6, y, *s[2:]], g])


def test_a_new_route_pays_for_leaving_the_current_one(room):
    """The robot at the start on the south route; a person standing beside the south
    corridor (not in it) makes it dearer, and the search's north path is cheaper by more
    than the margin. It replaces the south route for a switching weight below the one at
    which the two are equal, and not above it."""
    base = corridor_with(safety_horizon=SAFETY_HORIZON, time_weight=0.1, switch_weight=0.0)
    start = np.asarray(base.start, float)
    south = via(base, SOUTH_Y)
    beside = walkers(0.0, [[(0.0, 3.0, 0.3)]])  # by the south corridor's mouth, near the wall
    free = Replanner(base, room, budget=60.0)
    res = free.plan(start, 0.0, beside, south, replan_index=1)
    assert res.status == "new" and route(res.waypoints) == "north", res.reason
    times = free.evaluate(res.waypoints, 0.0, beside).times
    deviation = route_deviation(res.waypoints, times, south, base.planner.replan_horizon)
    assert deviation > 1.0
    margin = base.planner.replan_margin
    equal = ((1.0 - margin) * res.candidate_cost - res.search_cost) / deviation  # the weight of a tie
    assert equal > 0.0
    below = Replanner(dc.replace(base, planner=dc.replace(base.planner, switch_weight=equal * (1 - 1e-6))), room,
                      budget=60.0).plan(start, 0.0, beside, south, replan_index=1)
    above = Replanner(dc.replace(base, planner=dc.replace(base.planner, switch_weight=equal * (1 + 1e-6))), room,
                      budget=60.0).plan(start, 0.0, beside, south, replan_index=1)
    assert below.status == "new" and "for leaving the current route" in below.reason, below.reason
    np.testing.assert_array_equal(below.waypoints, res.waypoints)
    assert above.status == "kept" and "for leaving the current route" in above.reason, above.reason
    np.testing.assert_array_equal(above.waypoints, south)


# ---- no side-step unless the predicted contact is real -------------------------------------------

# test_replan_interactive.py's open room, the task north from (3, 4), the safety horizon 2 s.
OPEN = (OPEN_ROOM.replace("start: [1.0, 4.0,", "start: [3.0, 4.0,").replace("goal: [13.0, 4.0,", "goal: [3.0, 7.0,")
        .replace("prediction: interactive}", "safety_horizon: 2.0}"))


@pytest.mark.parametrize("prediction", ["constant_velocity", "interactive"])
def test_a_walker_heading_at_the_standing_robot(prediction):
    """A walker 2.5 m east of the robot walks west at it at 1.3 m/s; the robot's path (north,
    away from the walker's line) is blocked by a person standing on it. At constant
    velocity the walker walks through the standing robot: it steps aside. In the
    interactive prediction the walker steers round the robot standing there, which stays
    beyond the safety distance of them (the rollout's positions checked against the robot
    independently): the robot does not step aside."""
    sc = load_scenario_text(OPEN.replace("safety_horizon: 2.0", f"safety_horizon: 2.0, prediction: {prediction}"),
                            "open")
    assert sc.start[:2] == [3.0, 4.0] and sc.goal[:2] == [3.0, 7.0] and sc.planner.prediction == prediction
    room = make_checker(without_people(sc), "planar")
    dut = Replanner(sc, room, budget=60.0)
    start = np.asarray(sc.start, float)
    people = PeopleState(t=0.0, positions=np.array([[5.5, 4.0], [3.0, 5.6]]), headings=np.array([math.pi, 0.0]),
                         velocities=np.array([[-1.3, 0.0], [0.0, 0.0]]), radii=np.array([0.25, 0.25]),
                         names=("walker", "standing"), present=np.array([True, True]))
    prediction_cv = walkers(0.0, [[(0.0, 5.5, 4.0), (5.5 / 1.3, 0.0, 4.0)], [(0.0, 3.0, 5.6)]], horizon=5.0)
    path = np.array([start, sc.goal], float)
    until = dut.lookahead
    if prediction == "constant_velocity":
        judge = dut.judge(prediction_cv)
        assert not standing_clear(judge, start, 0.0, until)
        res = dut.plan(start, 0.0, prediction_cv, path, replan_index=1)
        assert res.status in ("evade", "new") and res.changed, res.reason  # out of the walker's way
        return
    judge = dut.interactive_judge(people, 0.0, prediction_cv, start[None])
    assert standing_clear(judge, start, 0.0, until)
    res = dut.plan(start, 0.0, prediction_cv, path, replan_index=1, people=people)
    assert res.status != "evade" and "evading" not in res.reason, res.reason
    rolled = judge.prediction  # the people with the robot standing at the start
    times = rolled.t0 + rolled.dt * np.arange(len(rolled.positions))
    ahead = times <= until + 1e-9
    d = part_distances(arm_geometry(sc), np.repeat(start[None], ahead.sum(), axis=0), rolled.positions[ahead],
                       rolled.radii)["robot"]
    assert d.min() > sc.execution.safety_distance


def test_the_pauses_keep_within_the_prediction(corridor, room, first):
    """A safety horizon longer than the prediction checks paths over the whole prediction and no
    further, so the replan is the one with the safety horizon equal to the prediction's length:
    the same pause (a quarter of the prediction), not one after which the resumed path starts
    beyond the prediction and is checked over nothing."""
    t = 2.0
    q_now, previous = along(first, t)
    script = crossing(q_now, t)
    people = walkers(t, [script], horizon=SAFETY_HORIZON)
    assert people.horizon == pytest.approx(t + SAFETY_HORIZON, abs=1e-12)
    reference = Replanner(corridor, room, budget=60.0).plan(q_now, t, people, previous, replan_index=1)
    assert "waiting 0.5 s for the current path" in reference.reason, reference.reason
    longer = dc.replace(corridor, planner=dc.replace(corridor.planner, safety_horizon=4.0 * SAFETY_HORIZON))
    dut = Replanner(longer, room, budget=60.0).plan(q_now, t, people, previous, replan_index=1)
    assert dut.status == reference.status and dut.reason == reference.reason, dut.reason
    np.testing.assert_array_equal(dut.waypoints, reference.waypoints)


def test_a_pause_cut_by_the_deadline_is_recorded(corridor, room, first, monkeypatch):
    """The deadline passes as the pauses are about to be judged: none is (the robot takes the
    search's path), and the replan says that the deadline cut it."""
    import time

    t = 2.0
    q_now, previous = along(first, t)
    people = walkers(t, [crossing(q_now, t)])
    clock = {"now": 1000.0}
    monkeypatch.setattr(time, "perf_counter", lambda: clock["now"])
    pause = Replanner._pause

    def late(self, *args, **kwargs):
        clock["now"] += 10.0
        return pause(self, *args, **kwargs)

    full = Replanner(corridor, room, budget=1.0).plan(q_now, t, people, previous, replan_index=1)
    assert full.status == "wait" and not full.deadline_hit, full.reason
    monkeypatch.setattr(Replanner, "_pause", late)
    dut = Replanner(corridor, room, budget=1.0).plan(q_now, t, people, previous, replan_index=1)
    assert dut.status == "new" and "waiting" not in dut.reason, dut.reason
    assert dut.deadline_hit


def test_a_pause_from_the_end_of_a_committed_motion_leaves_a_quarter_checked(corridor, room, first):
    """From a later time than the prediction's start (the end of the motion being driven), the
    pauses tried are shares of what is left of the safety horizon there: each resumed path is
    checked over a quarter of it at least; none is tried once it is spent."""
    from drake_social.planning.replan_deadline import Deadline

    t = 2.0
    q_now, previous = along(first, t)
    people = nobody(t)
    dut = Replanner(corridor, room, budget=60.0)
    judge = dut.judge(people)
    starts = []
    evaluate = judge.evaluate

    def recorded(waypoints, t0):  # every resumed path judged not safe: each pause is tried
        starts.append(t0)
        return evaluate(waypoints, t0)._replace(people_bad=0)

    judge.evaluate = recorded
    for later in (0.0, 0.8, 1.6):
        starts.clear()
        assert dut._pause(judge, q_now, t + later, people, previous, Deadline()) is None
        left = SAFETY_HORIZON - later
        np.testing.assert_allclose(starts, t + later + np.array(PAUSE_SHARES) * left, rtol=0, atol=1e-12)
        assert t + SAFETY_HORIZON - max(starts) >= 0.25 * left - 1e-12
    for spent in (SAFETY_HORIZON, SAFETY_HORIZON + 0.5):
        starts.clear()
        assert dut._pause(judge, q_now, t + spent, people, previous, Deadline()) is None and starts == []
