"""The replanner (drake_social.planning.replan) on a hand-built corridor.

The room (12 x 7 m) has a central block (x 4 .. 8, y 2 .. 5): two 2 m
corridors lead from the start (west) to the goal (east), one north, one
south. A person standing in the middle of a corridor blocks it for the
robot (0.95 m wide in its carrying pose) with a 0.05 m safety distance.
People are given as hand-made predictions (a scripted walker's timed
points, sampled at 0.1 s), with a horizon longer than any path here: the
scenario pins ``planner.prediction: constant_velocity``, under which the
replanner judges every path against the prediction it is given (the
interactive prediction's own tests: test_replan_interactive.py) and no time
or switching term (their tests: test_replan_commit.py).

Every returned path's distance to the people is checked again with an
independent computation: the people's surface distances
(:func:`drake_social.people.proximity.part_distances`) at 400 samples per
motion, the people placed by ``numpy.interp`` of the walker's own timed
points at the nominal times of the samples.
"""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest

from drake_social.collision.drake_checker import make_checker
from drake_social.kinematics import config_distance
from drake_social.scenario.geometry import arm_geometry
from drake_social.limits import MAX_REPLAN_BUDGET, MAX_REPLAN_ITERATIONS
from drake_social.people import PeopleState, constant_velocity, people_model, without_people
from drake_social.people.prediction import Prediction
from drake_social.people.proximity import part_distances
from drake_social.cost.social import SocialCost
from drake_social.planning.objective import SocialObjective
from drake_social.planning.replan import ReplanResult, Replanner
from drake_social.scenario.load import load_scenario_text

CORRIDOR = """
description: "corridor: two routes around a central block"
world:
  bounds: [0.0, 0.0, 12.0, 7.0]
  obstacles:
    - {center: [6.0, 3.5], size: [4.0, 3.0]}
robot: {base_radius: 0.35, link_lengths: [0.6, 0.5], link_width: 0.08}
object: !Bar {length: 1.5, thickness: 0.05}
start: [1.2, 3.5, -1.2292, 2.8]
goal: [10.8, 3.5, -1.2292, 2.8]
random_seed: 3
social: {length_weight: 1.0}
planner: {iterations: 1500, planning_range: 2.0, near_radius: 3.0, replan_iterations: 400, replan_length_weight: 0.0,
          prediction: constant_velocity, safety_horizon: 60.0, time_weight: 0.0, switch_weight: 0.0}
"""
NORTH_Y, SOUTH_Y = 6.0, 1.0  # corridor centre lines
HORIZON = 60.0  # seconds: longer than any path here


@pytest.fixture(scope="module")
def corridor():
    return load_scenario_text(CORRIDOR, "corridor")


@pytest.fixture(scope="module")
def room(corridor):
    return make_checker(without_people(corridor), "planar")


def replanner(scenario, room, **kw) -> Replanner:
    kw.setdefault("budget", 60.0)  # the iteration cap binds: reproducible
    return Replanner(scenario, room, **kw)


def walkers(t0: float, scripts: list[list[tuple[float, float, float]]], horizon: float = HORIZON,
            dt: float = 0.1) -> Prediction:
    """People walking timed points [(t, x, y), ...] (standing before the first and after the last)."""
    times = t0 + dt * np.arange(int(round(horizon / dt)) + 1)
    p = len(scripts)
    pos = np.zeros((len(times), p, 2))
    for i, script in enumerate(scripts):
        ts, xs, ys = np.asarray(script, float).T
        pos[:, i, 0], pos[:, i, 1] = np.interp(times, ts, xs), np.interp(times, ts, ys)
    step = np.hypot(*np.diff(pos, axis=0).transpose(2, 0, 1)) / dt if len(times) > 1 else np.zeros((1, p))
    now = step[0] if len(step) else np.zeros(p)
    return Prediction(t0=t0, dt=dt, positions=pos, headings=np.zeros((len(times), p)),
                      present=np.ones((len(times), p), bool), radii=np.full(p, 0.25), speeds=now,
                      max_speeds=step.max(axis=0) if len(step) else np.zeros(p),
                      names=tuple(f"walker {i}" for i in range(p)))


def nobody(t0: float) -> Prediction:
    return walkers(t0, [])


def min_distance(scenario, waypoints, t0, prediction, scripts, samples=400) -> float:
    """The robot's least surface distance to the walkers along the path driven
    from t0, sampled densely; the walkers placed by np.interp of their scripts."""
    ex = scenario.execution
    geometry = arm_geometry(scenario)
    wp = np.asarray(waypoints, float)
    best, t = math.inf, float(t0)
    for a, b in zip(wp[:-1], wp[1:]):
        d = b - a
        duration = max(math.hypot(d[0], d[1]) / ex.max_base_speed, abs(d[2]) / ex.arm_max_velocity[0],
                       abs(d[3]) / ex.arm_max_velocity[1])
        u = np.linspace(0.0, 1.0, samples)
        q = a + u[:, None] * d
        ts = t + u * duration
        centres = np.zeros((samples, len(scripts), 2))
        for i, script in enumerate(scripts):
            st, sx, sy = np.asarray(script, float).T
            centres[:, i, 0], centres[:, i, 1] = np.interp(ts, st, sx), np.interp(ts, st, sy)
        assert ts[-1] <= prediction.horizon  # the people are predicted all along
        best = min(best, float(part_distances(geometry, q, centres, np.full(len(scripts), 0.25))["robot"].min()))
        t += duration
    return best


def route(waypoints) -> str:
    """'north' or 'south': the side of the block (x in 4 .. 8) the base passes
    along it (x in 4.5 .. 7.5: a path may turn back at a corridor's mouth)."""
    wp = np.asarray(waypoints, float)
    fine = np.concatenate([a + np.linspace(0, 1, 50)[:, None] * (b - a) for a, b in zip(wp[:-1], wp[1:])])
    inside = fine[(fine[:, 0] > 4.5) & (fine[:, 0] < 7.5)]
    assert len(inside) and (np.all(inside[:, 1] > 3.5) or np.all(inside[:, 1] < 3.5))
    return "north" if inside[0, 1] > 3.5 else "south"


def along(result: ReplanResult, t: float) -> tuple[np.ndarray, np.ndarray]:
    """Where the robot is at time t driving ``result``'s path (nominal times),
    and the remainder from there: [q(t)] + the later waypoints."""
    from drake_social.kinematics import nominal_path_times

    wp = result.waypoints
    times = nominal_path_times(wp, 0.5, [1.0, 1.0], result.t)
    k = int(np.searchsorted(times, t, side="right")) - 1
    k = min(max(k, 0), len(wp) - 2)
    u = (t - times[k]) / (times[k + 1] - times[k])
    q = wp[k] + min(max(u, 0.0), 1.0) * (wp[k + 1] - wp[k])
    return q, np.vstack([q[None], wp[k + 1:]])


@pytest.fixture(scope="module")
def first(corridor, room):
    return replanner(corridor, room).plan(np.asarray(corridor.start, float), 0.0, nobody(0.0), replan_index=0)


# ---- the initial plan and the result ------------------------------------------------


def test_initial_plan(corridor, room, first):
    assert first.status == "initial" and first.changed and first.replan_index == 0
    assert first.iterations == corridor.planner.iterations and not first.deadline_hit
    np.testing.assert_array_equal(first.waypoints[0], corridor.start)
    np.testing.assert_array_equal(first.waypoints[-1], corridor.goal)
    assert room.are_motions_valid(first.waypoints[:-1], first.waypoints[1:]).all()
    # Without people the cost is the length term alone: lambda * the weighted length.
    length = config_distance(first.waypoints[:-1], first.waypoints[1:]).sum()
    assert first.cost == pytest.approx(length, rel=1e-12)
    assert first.search_cost == first.cost and first.candidate_cost == math.inf
    assert not first.waypoints.flags.writeable
    assert first == dc.replace(first) and first != dc.replace(first, cost=first.cost + 1.0)
    assert first != dc.replace(first, waypoints=first.waypoints[::-1])
    record = first.to_record()
    assert record["status"] == "initial" and record["cost"] == first.cost


def test_replan_length_weight_adds_to_the_objective(corridor, room, first):
    """planner.replan_length_weight is added to social.length_weight: with
    nobody about a path's cost is (1.0 + 0.5) x its weighted length."""
    heavier = dc.replace(corridor, planner=dc.replace(corridor.planner, replan_length_weight=0.5))
    rp = replanner(heavier, room)
    assert rp.scenario.social.length_weight == 1.5 and corridor.social.length_weight == 1.0
    length = config_distance(first.waypoints[:-1], first.waypoints[1:]).sum()
    assert rp.evaluate(first.waypoints, 0.0, nobody(0.0)).cost == pytest.approx(1.5 * length, rel=1e-12)


def test_evaluate_times_and_safety(corridor, room, first):
    rp = replanner(corridor, room)
    wp = first.waypoints
    ev = rp.evaluate(wp, 2.0, nobody(2.0))
    d = np.diff(wp, axis=0)
    durations = np.maximum(np.hypot(d[:, 0], d[:, 1]) / 0.5, np.abs(d[:, 2:]).max(axis=1) / 1.0)
    np.testing.assert_allclose(ev.times, 2.0 + np.concatenate([[0.0], np.cumsum(durations)]), rtol=1e-12)
    assert ev.safe and ev.first_bad == -1
    # A person standing on the path's third waypoint: that motion (or an earlier one) is not safe.
    x, y = wp[2, :2]
    ev = rp.evaluate(wp, 0.0, walkers(0.0, [[(0.0, x, y)]]))
    assert not ev.safe and 0 <= ev.people_bad <= 2 and ev.static_bad == -1


def test_safety_is_hard_over_the_safety_horizon_only(corridor, room, first):
    """A walker who comes to stand on the path's third waypoint some seconds
    before the robot gets there: unsafe when the safety horizon reaches that
    time, safe (left to later replans; the cost still sees it) when it ends
    well before."""
    import dataclasses as dc

    wp = first.waypoints
    times = replanner(corridor, room).evaluate(wp, 0.0, nobody(0.0)).times
    x, y = wp[2, :2]
    arrive = max(times[2] - 1.0, 1.0)
    prediction = walkers(0.0, [[(0.0, 11.5, 0.3), (arrive, x, y)]])
    verdicts = {}
    for horizon in (60.0, min(arrive, times[1]) * 0.5):
        scenario = dc.replace(corridor, planner=dc.replace(corridor.planner, safety_horizon=horizon))
        judge = replanner(scenario, room).judge(prediction)
        assert judge.people_safety.prediction.samples == prediction.until(horizon).samples
        assert judge.prediction is prediction  # the cost looks over the whole horizon
        verdicts[horizon] = judge.evaluate(wp, 0.0)
    long, short = verdicts.values()
    assert not long.safe and long.people_bad >= 0
    assert short.safe
    assert short.social == long.social  # the same cost


def test_candidate_rows(corridor, room, first):
    """The candidate is ``previous`` from q_now: q_now put in front when
    missing, repeated rows dropped; a single row (a wait) is no candidate."""
    rp = replanner(corridor, room)
    rest = first.waypoints[1:]
    exact = rp.evaluate(rest, 1.0, nobody(1.0)).cost
    for previous in (rest, rest[1:], np.vstack([rest[:1], rest])):
        res = rp.plan(rest[0], 1.0, nobody(1.0), previous, replan_index=1)
        assert res.candidate_cost == exact
    res = rp.plan(rest[0], 1.0, nobody(1.0), rest[:1], replan_index=1)
    assert res.candidate_cost == math.inf and res.status == "new" and "no current path" in res.reason


# ---- a walker steps into the route -------------------------------------------------------


def test_walker_steps_into_the_route(corridor, room, first):
    """At t = 2 s a walker is seen entering the corridor the plan goes through;
    it stops in its middle: the robot takes the other corridor."""
    rp = replanner(corridor, room)
    side = route(first.waypoints)
    yc = NORTH_Y if side == "north" else SOUTH_Y
    script = [(2.0, 9.0, yc), (5.0, 6.0, yc)]
    prediction = walkers(2.0, [script])
    q_now, previous = along(first, 2.0)
    res = rp.plan(q_now, 2.0, prediction, previous, replan_index=1)
    assert res.status == "new" and res.changed, res.reason
    assert "not safe" in res.reason and res.candidate_cost == math.inf
    assert route(res.waypoints) != side
    np.testing.assert_array_equal(res.waypoints[0], q_now)
    assert min_distance(corridor, res.waypoints, 2.0, prediction, [script]) > corridor.execution.safety_distance
    # The cost reported is the exact one.
    assert res.cost == rp.evaluate(res.waypoints, 2.0, prediction).cost == res.search_cost
    # ... and the path it left would have come within the safety distance.
    assert min_distance(corridor, previous, 2.0, prediction, [script]) <= corridor.execution.safety_distance


def test_both_routes_blocked_waits(corridor, room, first):
    rp = replanner(corridor, room)
    scripts = [[(2.0, 6.0, NORTH_Y)], [(2.0, 6.0, SOUTH_Y)]]
    q_now, previous = along(first, 2.0)
    res = rp.plan(q_now, 2.0, walkers(2.0, scripts), previous, replan_index=1)
    assert res.status == "wait" and res.waiting and not res.changed
    np.testing.assert_array_equal(res.waypoints, q_now[None])
    assert res.cost == math.inf and res.search_cost == math.inf and res.candidate_cost == math.inf
    assert res.reason.startswith("waiting") and "no safe path" in res.reason


def test_person_at_the_robot_waits(corridor, room, first):
    rp = replanner(corridor, room)
    q_now, previous = along(first, 2.0)
    # A person 0.02 m from the base disc's surface (0.35 + 0.25 + 0.02 from its centre, on the side away from the arm).
    person = [(2.0, q_now[0], q_now[1] + 0.62)]
    res = rp.plan(q_now, 2.0, walkers(2.0, [person]), previous, replan_index=1)
    assert res.status == "wait"
    near = part_distances(arm_geometry(corridor), q_now[None], np.array([person[0][1:]]),
                          np.array([0.25]))["robot"][0]
    assert near <= 0.02 + 1e-12
    assert f"{near:.3f} m from the robot now" in res.reason


# ---- people standing still: never dearer -------------------------------------------------


STANDING = CORRIDOR.replace("random_seed: 3", """random_seed: 3
people:
  - {x: 2.6, y: 5.6, theta: -1.0, radius: 0.25}
  - {x: 9.4, y: 1.4, theta: 2.0, radius: 0.25}
  - {x: 6.0, y: 6.6, theta: -1.5708, radius: 0.25}""")


def test_standing_people_never_a_dearer_path():
    """People standing still: every replan along the driven plan returns the
    current path or a cheaper one, under the static cost of today's planner
    (SocialCost.motion_cost with the people where they stand)."""
    scenario = load_scenario_text(STANDING, "corridor, standing people")
    room = make_checker(without_people(scenario), "planar")
    rp = replanner(scenario, room)
    state = people_model(scenario).state_at(0.0)
    static = SocialObjective(SocialCost.from_scenario(scenario), scenario.social.length_weight)

    def today(wp):
        return float(static.motion_cost(wp[:-1], wp[1:]).sum())

    res = rp.plan(np.asarray(scenario.start, float), 0.0, constant_velocity(state, HORIZON), replan_index=0)
    assert res.status == "initial"
    assert res.cost == pytest.approx(today(res.waypoints), rel=1e-9)
    statuses = []
    for k, t in enumerate([3.0, 6.0, 9.0, 12.0, 15.0], start=1):
        q_now, previous = along(res, t)
        prediction = constant_velocity(PeopleState(t, state.positions, state.headings, state.velocities,
                                                   state.radii, state.names), HORIZON)
        assert prediction.static
        new = rp.plan(q_now, t, prediction, previous, replan_index=k)
        statuses.append(new.status)
        assert new.status in ("kept", "new")
        assert new.cost == pytest.approx(today(new.waypoints), rel=1e-9)
        assert today(new.waypoints) <= today(previous) * (1 + 1e-9)
        if new.status == "kept":
            np.testing.assert_array_equal(new.waypoints, previous)
        else:
            assert new.cost < (1 - scenario.planner.replan_margin) * new.candidate_cost
        res = new
    assert "kept" in statuses


# ---- determinism, the budget, the margin ---------------------------------------------------


def _episode(scenario, room, seed):
    rp = replanner(scenario, room, seed=seed)
    res = rp.plan(np.asarray(scenario.start, float), 0.0, nobody(0.0), replan_index=0)
    out = [res]
    yc = NORTH_Y if route(res.waypoints) == "north" else SOUTH_Y
    script = [(2.0, 9.0, yc), (5.0, 6.0, yc)]
    for k, t in enumerate([2.0, 4.0, 6.0], start=1):
        q_now, previous = along(res, t)
        new = rp.plan(q_now, t, walkers(t, [script]), previous, replan_index=k)
        out.append(new)
        if new.status != "wait":
            res = new
    return out


def test_same_seed_bit_for_bit(corridor, room):
    a, b = _episode(corridor, room, 7), _episode(corridor, room, 7)
    for x, y in zip(a, b):
        assert x.waypoints.tobytes() == y.waypoints.tobytes()
        assert (x.status, x.cost, x.iterations, x.candidate_cost, x.search_cost, x.reason) == \
               (y.status, y.cost, y.iterations, y.candidate_cost, y.search_cost, y.reason)
        assert not x.deadline_hit
    c = _episode(corridor, room, 8)
    assert any(x.waypoints.tobytes() != y.waypoints.tobytes() for x, y in zip(a, c))


def test_over_budget_returns_the_best_found(corridor, room, first):
    """A budget far too small for the iteration cap: the search stops at the
    deadline and the replan returns a safe path (the candidate, or better)."""
    rp = Replanner(corridor, room, budget=0.002, iterations=MAX_REPLAN_ITERATIONS)
    yc = NORTH_Y if route(first.waypoints) == "north" else SOUTH_Y
    script = [(2.0, 6.0, 3.5 + 3 * (yc - 3.5))]  # a person far outside the room: nothing blocked
    prediction = walkers(2.0, [script])
    q_now, previous = along(first, 2.0)
    res = rp.plan(q_now, 2.0, prediction, previous, replan_index=1)
    assert res.deadline_hit and 0 < res.iterations < MAX_REPLAN_ITERATIONS
    assert res.status in ("kept", "new")
    assert res.cost <= res.candidate_cost
    assert min_distance(corridor, res.waypoints, 2.0, prediction, [script]) > corridor.execution.safety_distance
    # Without a candidate: the best path found by the deadline, or a wait; never an unsafe path.
    blocked = [(2.0, 6.0, yc)]
    res = rp.plan(q_now, 2.0, walkers(2.0, [blocked]), None, replan_index=2)
    assert res.deadline_hit and res.status in ("new", "wait")
    if res.status == "new":
        assert min_distance(corridor, res.waypoints, 2.0, walkers(2.0, [blocked]), [blocked]) > 0.05


def test_margin_keeps_one_of_two_equal_routes(corridor, room):
    """Two routes of exactly equal cost (mirror images, arm fixed, no people):
    the current one is kept at every replan, whichever it is."""
    s = np.asarray(corridor.start, float)
    g = np.asarray(corridor.goal, float)

    def via(y):
        return np.array([s, [3.4, y, *s[2:]], [8.6, y, *s[2:]], g])

    north, south = via(NORTH_Y), via(SOUTH_Y)
    rp = replanner(corridor, room, margin=0.05)
    assert rp.evaluate(north, 0.0, nobody(0.0)).cost == rp.evaluate(south, 0.0, nobody(0.0)).cost
    for candidate in (north, south):
        for k in range(1, 5):
            res = rp.plan(s, 0.0, nobody(0.0), candidate, replan_index=k)
            assert res.status == "kept", res.reason
            np.testing.assert_array_equal(res.waypoints, candidate)
            assert res.search_cost >= 0.95 * res.candidate_cost


def test_margin_stops_changes_for_small_gains(corridor, room, first):
    """Driving the first plan with a replan every second and nobody about:
    with the margin a path changes only for a gain of 5 % or more; without it
    the path changes again and again, for gains below 5 % too."""
    changes = {}
    for margin in (0.05, 0.0):
        rp = replanner(corridor, room, margin=margin)
        res, out = first, []
        for k, t in enumerate(np.arange(1.0, 16.0), start=1):
            q_now, previous = along(res, t)
            res = rp.plan(q_now, t, nobody(t), previous, replan_index=k)
            assert res.status in ("kept", "new")
            assert res.cost <= res.candidate_cost
            out.append(res)
        changes[margin] = [r for r in out if r.status == "new"]
    assert all(r.search_cost < 0.95 * r.candidate_cost for r in changes[0.05])
    assert len(changes[0.05]) < len(changes[0.0])
    assert len(changes[0.0]) >= 3
    assert any(0.95 * r.candidate_cost <= r.search_cost < r.candidate_cost for r in changes[0.0])


# ---- committing to the motion being driven, searching less often, stepping aside ---------------


def test_committed_motion_starts_every_path(corridor, room, first):
    """With ``commit`` the motion to the next waypoint is kept: a walker
    stepping into the route beyond it makes a new path that still starts
    [q_now, that waypoint], timed from there; the robot drives exactly the
    judged segments."""
    rp = replanner(corridor, room)
    side = route(first.waypoints)
    yc = NORTH_Y if side == "north" else SOUTH_Y
    script = [(2.0, 9.0, yc), (5.0, 6.0, yc)]
    prediction = walkers(2.0, [script])
    q_now, previous = along(first, 2.0)
    res = rp.plan(q_now, 2.0, prediction, previous, replan_index=1, commit=True)
    assert res.status == "new" and res.searched, res.reason
    np.testing.assert_array_equal(res.waypoints[:2], previous[:2])
    assert route(res.waypoints) != side
    assert min_distance(corridor, res.waypoints, 2.0, prediction, [script]) > corridor.execution.safety_distance
    # Its cost: the committed motion's plus the rest's, from the time the robot reaches the motion's end.
    assert res.cost == pytest.approx(rp.evaluate(res.waypoints, 2.0, prediction).cost, rel=1e-9)
    # Nobody about: the committed candidate is kept as it is.
    kept = rp.plan(q_now, 2.0, nobody(2.0), previous, replan_index=1, commit=True)
    assert kept.status in ("kept", "new") and np.array_equal(kept.waypoints[:2], previous[:2])
    # The margin compares the whole paths from the robot (the committed motion's cost in both).
    whole = rp.evaluate(previous, 2.0, nobody(2.0)).cost
    assert kept.candidate_cost == pytest.approx(whole, rel=1e-9)
    assert kept.searched  # a replan after the first searches (replan_index=1, no search yet)
    if kept.status == "new":
        assert kept.search_cost < 0.95 * kept.candidate_cost
    else:
        assert 0.95 * kept.candidate_cost <= kept.search_cost < np.inf


def test_committed_motion_unsafe_holds(corridor, room, first):
    """A person standing on the committed motion: the robot holds at once."""
    rp = replanner(corridor, room)
    q_now, previous = along(first, 2.0)
    mid = 0.5 * (previous[0] + previous[1])
    res = rp.plan(q_now, 2.0, walkers(2.0, [[(2.0, mid[0], mid[1])]]), previous, replan_index=1, commit=True)
    assert res.status == "wait" and not res.searched and res.iterations == 0
    assert "motion being driven is not safe" in res.reason
    np.testing.assert_array_equal(res.waypoints, q_now[None])


def test_no_search_keeps_a_safe_candidate_and_searches_an_unsafe_one(corridor, room, first):
    rp = replanner(corridor, room)
    q_now, previous = along(first, 2.0)
    res = rp.plan(q_now, 2.0, nobody(2.0), previous, replan_index=1, search=False)
    assert res.status == "kept" and not res.searched and res.iterations == 0
    np.testing.assert_array_equal(res.waypoints, previous)
    assert res.cost == rp.evaluate(previous, 2.0, nobody(2.0)).cost
    yc = NORTH_Y if route(first.waypoints) == "north" else SOUTH_Y
    blocked = walkers(2.0, [[(2.0, 6.0, yc)]])
    res = rp.plan(q_now, 2.0, blocked, previous, replan_index=1, search=False)
    assert res.searched and res.iterations == corridor.planner.replan_iterations
    assert res.status == "new" and res.candidate_cost == math.inf


def clear_until(scenario, q_a, q_b, t0, horizon, scripts) -> float:
    """The least distance to the walkers driving q_a -> q_b from t0 (nominal
    time), then standing at q_b until ``horizon``; independent of the kernel."""
    geometry = arm_geometry(scenario)
    arrive = t0 + math.hypot(*(q_b[:2] - q_a[:2])) / scenario.execution.max_base_speed
    u = np.linspace(0.0, 1.0, 400)
    ts = np.concatenate([t0 + u * (arrive - t0), np.linspace(arrive, horizon, 400)])
    qs = np.concatenate([q_a + u[:, None] * (q_b - q_a), np.repeat(q_b[None], 400, axis=0)])
    centres = np.stack([np.stack([np.interp(ts, *np.asarray(sc, float)[:, [0, 1]].T),
                                  np.interp(ts, *np.asarray(sc, float)[:, [0, 2]].T)], axis=1) for sc in scripts],
                       axis=1)
    return min(float(part_distances(geometry, qs[k][None], centres[k][None], np.full(len(scripts), 0.25))
                     ["robot"].min()) for k in range(len(ts)))


def test_steps_aside_from_a_walker_coming_at_it(corridor, room, first):
    """Both corridors blocked by standing people and a walker heading
    straight for the robot: standing still is not safe. Driving on to the
    next waypoint gets out of the way, so the path is kept; with a next
    waypoint in the walker's way, the robot steps aside. Either way the
    motion and the robot standing at its end are clear of every person until
    the horizon (checked densely and independently), where standing still
    was not."""
    rp = replanner(corridor, room, lookahead=8.0)  # the whole prediction
    q_now, previous = along(first, 2.0)
    x, y = q_now[:2]
    walker = [(2.0, x, 6.7), (2.0 + (6.7 - 0.3) / 1.1, x, 0.3)]  # north to south through the base, 1.1 m/s
    scripts = [[(2.0, 6.0, NORTH_Y)], [(2.0, 6.0, SOUTH_Y)], walker]
    prediction = walkers(2.0, scripts, horizon=8.0)
    safety = corridor.execution.safety_distance
    assert clear_until(corridor, q_now, q_now, 2.0, prediction.horizon, scripts) <= safety
    res = rp.plan(q_now, 2.0, prediction, previous, replan_index=1)
    assert res.status == "kept" and "driving on to the next waypoint" in res.reason and "(clear)" in res.reason
    np.testing.assert_array_equal(res.waypoints, previous)
    assert clear_until(corridor, q_now, previous[1], 2.0, prediction.horizon, scripts) > safety
    # A next waypoint in the walker's way: the base steps aside, then comes back to the path.
    blocked = np.vstack([q_now[None], q_now + [0.0, -1.5, 0.0, 0.0], previous[1:]])
    res = rp.plan(q_now, 2.0, prediction, blocked, replan_index=1)
    assert res.status == "evade" and res.changed and not res.waiting, res.reason
    assert "evading" in res.reason and "(clear)" in res.reason
    wp = res.waypoints
    np.testing.assert_array_equal(wp[0], q_now)
    np.testing.assert_array_equal(wp[1, 2:], q_now[2:])  # the arm as it is
    np.testing.assert_array_equal(wp[2:], blocked)
    assert room.are_motions_valid(wp[:1], wp[1:2]).all()
    assert clear_until(corridor, q_now, wp[1], 2.0, prediction.horizon, scripts) > safety


def test_shortcut_straightens_a_zigzag_and_keeps_clear(corridor, room):
    """A zigzag through the west part of the corridor room: with nobody about
    the shortcut reaches farther waypoints directly (fewer waypoints, lower
    exact cost, every motion valid); with a person standing near, it never
    comes within the safety distance (checked independently) and never costs
    more than the path it was given."""
    from drake_social.planning.replan_shortcut import shortcut

    s = np.asarray(corridor.start, float)
    zig = np.array([s, [1.7, 4.4, *s[2:]], [2.1, 2.6, *s[2:]], [2.5, 4.4, *s[2:]], [2.9, 3.5, *s[2:]]])
    assert room.are_motions_valid(zig[:-1], zig[1:]).all()
    rp = replanner(corridor, room)
    judge = rp.judge(nobody(0.0))
    ev = judge.evaluate(zig, 0.0)
    short, sev = shortcut(judge, zig, 0.0, ev)
    assert len(short) < len(zig) and sev.cost < ev.cost and sev.safe
    np.testing.assert_array_equal(short[[0, -1]], zig[[0, -1]])
    assert all(any(np.array_equal(w, z) for z in zig) for w in short)  # waypoints of the path, in order
    assert room.are_motions_valid(short[:-1], short[1:]).all()
    assert sev.cost == rp.evaluate(short, 0.0, nobody(0.0)).cost
    # A person standing south-east of the path.
    person = [(0.0, 3.3, 2.2)]
    blocked = walkers(0.0, [person])
    judge = rp.judge(blocked)
    ev = judge.evaluate(zig, 0.0)
    assert ev.safe
    short, sev = shortcut(judge, zig, 0.0, ev)
    assert sev.safe and sev.cost <= ev.cost
    assert min_distance(corridor, short, 0.0, blocked, [person]) > corridor.execution.safety_distance


# ---- the anytime budget: every stage after the search stops at the deadline --------------------------


class WorkClock:
    """A stand-in for ``time.perf_counter``: time passes only in the people's
    checks, ``tick`` seconds per motion or configuration checked (the work
    whose amount grows with the people and the candidates), and in the search,
    which runs until its deadline (as a loaded one does). A replan's time is
    then its count of checks, the same on every machine; reading the clock is
    free. ``work`` counts the checks made inside the search for a way out
    (``escape``) and elsewhere; ``search_stop`` is the search's deadline."""

    def __init__(self, tick: float):
        self.now, self.tick = 1000.0, float(tick)
        self.work = {"escape": 0, "other": 0}
        self.inside = False
        self.search_stop = None

    def __call__(self) -> float:
        return self.now

    def spend(self, checks: int = 1) -> None:
        self.now += self.tick * checks
        self.work["escape" if self.inside else "other"] += checks

    def restart(self) -> None:
        self.now, self.work, self.search_stop = 1000.0, {"escape": 0, "other": 0}, None


@pytest.fixture
def work_clock(monkeypatch):
    """Installs a WorkClock as time.perf_counter, ticking in PeopleSafety's checks and the search."""
    import time

    from drake_social.collision.people_safety import PeopleSafety
    from drake_social.planning import replan as replan_module

    clock = WorkClock(1e-4)
    monkeypatch.setattr(time, "perf_counter", clock)
    motion, one, many = PeopleSafety._motion, PeopleSafety.clearance, PeopleSafety.clearances
    search, escape = replan_module.run_search, replan_module.escape

    def counted_motion(self, *args):
        clock.spend()
        return motion(self, *args)

    def counted_one(self, q, t):
        clock.spend()
        return one(self, q, t)

    def counted_many(self, q, t):
        clock.spend(len(q))
        return many(self, q, t)

    def until_its_deadline(setup, social, q, t_now, prediction, candidate, iterations, stop, rng):
        out = search(setup, social, q, t_now, prediction, candidate, iterations, stop, rng)
        if stop is not None:
            clock.search_stop, clock.now = stop, max(clock.now, stop)
        return out

    def counted_escape(*args, **kwargs):
        clock.inside = True
        try:
            return escape(*args, **kwargs)
        finally:
            clock.inside = False

    monkeypatch.setattr(PeopleSafety, "_motion", counted_motion)
    monkeypatch.setattr(PeopleSafety, "clearance", counted_one)
    monkeypatch.setattr(PeopleSafety, "clearances", counted_many)
    monkeypatch.setattr(replan_module, "run_search", until_its_deadline)
    monkeypatch.setattr(replan_module, "escape", counted_escape)
    return clock


def crowd(q, kind: str, n: int = 120) -> list:
    """Scripts of ``n`` people about the robot at q from t = 2 s, and the two
    corridors blocked by people standing in them (no path to the goal).
    "column": half walk in a column at 1 m/s from the east through the robot,
    half stand on a ring 5 m away (ways out to the side stay clear);
    "converging": each walks at 0.8 to 1.4 m/s from 1.5 to 4 m away straight
    through the robot (no way out is clear)."""
    x, y = q[:2]
    scripts = [[(2.0, 6.0, NORTH_Y)], [(2.0, 6.0, SOUTH_Y)]]
    if kind == "column":
        scripts += [[(2.0, x + 2.0 + 0.7 * k, y), (32.0, x - 28.0 + 0.7 * k, y)] for k in range(n // 2)]
        scripts += [[(2.0, x + 5.0 * math.cos(a), y + 5.0 * math.sin(a))]
                    for a in 2.0 * math.pi * np.arange(n - n // 2) / (n - n // 2)]
        return scripts
    rng = np.random.default_rng(1)
    for _ in range(n):
        a, r, s = rng.uniform(0.0, 2.0 * math.pi), rng.uniform(1.5, 4.0), rng.uniform(0.8, 1.4)
        sx, sy = x + r * math.cos(a), y + r * math.sin(a)
        scripts.append([(2.0, sx, sy), (2.0 + r / s, x, y), (2.0 + 2.0 * r / s, 2.0 * x - sx, 2.0 * y - sy)])
    return scripts


def _same_but_time(a: ReplanResult, b: ReplanResult) -> bool:
    return a == dc.replace(b, plan_time=a.plan_time)


@pytest.mark.parametrize("kind, tick", [("column", 6e-4), ("converging", 8e-5)])
def test_loaded_evasion_stops_at_the_deadline(corridor, room, first, work_clock, kind, tick):
    """120 people about the robot, both corridors blocked: the search finds
    nothing, standing still is not safe, and the robot looks for a way out
    among up to 64 escape motions. Given a search that runs to its deadline
    (brought forward by EVADE_RESERVE) and checks costly enough that the
    evasion cannot judge every candidate in the 80 ms budget, the evasion
    stops at the deadline (fewer checks than with the whole budget, the
    replan's time within the budget, deadline_hit), and the way out is still
    one the rules allow: a clear one, checked again independently, or a best
    effort that beats standing still and is no better than the one found with
    every candidate judged."""
    from drake_social.planning.replan import EVADE_RESERVE, VERIFY_RESERVE
    from drake_social.planning.replan_evade import BETTER_BY, _least_clearance

    work_clock.tick = tick
    q_now, previous = along(first, 2.0)
    scripts = crowd(q_now, kind)
    prediction = walkers(2.0, scripts, horizon=5.0)
    safety = corridor.execution.safety_distance
    full = replanner(corridor, room).plan(q_now, 2.0, prediction, previous, replan_index=1)
    full_work = dict(work_clock.work)
    assert full.status == "evade" and not full.deadline_hit, full.reason
    work_clock.restart()
    rp = Replanner(corridor, room)
    assert rp.budget == 0.08  # the default
    dut = rp.plan(q_now, 2.0, prediction, previous, replan_index=1)
    assert dut.plan_time <= rp.budget
    assert dut.deadline_hit and "the search for a way out stopped at the deadline" in dut.reason, dut.reason
    assert work_clock.work["other"] == full_work["other"]  # the same judging before the evasion
    assert 0 < work_clock.work["escape"] < full_work["escape"]
    assert full_work["escape"] * tick > rp.budget * EVADE_RESERVE  # more than the evasion's share
    assert work_clock.search_stop == pytest.approx(1000.0 + rp.budget * (1 - VERIFY_RESERVE - EVADE_RESERVE),
                                                   abs=1e-12)
    assert dut.status == "evade", dut.reason
    wp = dut.waypoints
    np.testing.assert_array_equal(wp[0], q_now)
    np.testing.assert_array_equal(wp[1, 2:], q_now[2:])  # the arm as it is
    np.testing.assert_array_equal(wp[2:], previous)
    assert room.are_motions_valid(wp[:1], wp[1:2]).all()
    judge = Replanner(corridor, room).judge(prediction)
    until = min(prediction.horizon, 2.0 + 2.0)
    if kind == "column":
        assert "(clear)" in dut.reason
        assert clear_until(corridor, q_now, wp[1], 2.0, until, scripts) > safety
    else:
        assert "the best effort" in dut.reason and "the best effort" in full.reason
        t_end = float(judge.times(wp[:2], 2.0)[1])
        least = _least_clearance(judge, q_now, wp[1], 2.0, t_end, until)
        assert least > _least_clearance(judge, q_now, q_now, 2.0, 2.0, until) + BETTER_BY
        t_full = float(judge.times(full.waypoints[:2], 2.0)[1])
        assert least <= _least_clearance(judge, q_now, full.waypoints[1], 2.0, t_full, until)


def test_evasion_after_the_deadline_holds(corridor, room, first, work_clock):
    """The budget spent before the evasion starts: no escape is tried and the
    robot holds (the documented fallback), saying so."""
    q_now, previous = along(first, 2.0)
    prediction = walkers(2.0, crowd(q_now, "column"), horizon=5.0)
    work_clock.tick = 1.0  # the first check spends the budget
    dut = Replanner(corridor, room).plan(q_now, 2.0, prediction, previous, replan_index=1)
    assert dut.status == "wait" and dut.deadline_hit and not dut.changed
    assert "the search for a way out stopped at the deadline with none found" in dut.reason
    np.testing.assert_array_equal(dut.waypoints, q_now[None])
    assert work_clock.work["escape"] == 0


def test_judging_and_shortcut_stop_at_the_deadline(corridor, room, first, monkeypatch):
    """The search's paths are judged, and the best one shortened, within the
    budget: the clock past the deadline right after the search, no path of it
    is judged (the current path is not safe: the robot waits); past it after
    the first judgement, that path is returned as judged, not shortened."""
    import time

    from drake_social.planning import replan as replan_module
    from drake_social.planning.replan_eval import PathJudge

    yc = NORTH_Y if route(first.waypoints) == "north" else SOUTH_Y
    prediction = walkers(2.0, [[(2.0, 6.0, yc)]])  # the route being driven blocked, the other one free
    q_now, previous = along(first, 2.0)
    full = replanner(corridor, room).plan(q_now, 2.0, prediction, previous, replan_index=1)
    assert full.status == "new" and not full.deadline_hit, full.reason

    clock = {"now": 1000.0, "jump_after_search": True, "jump_after_judging": False, "judged": []}
    monkeypatch.setattr(time, "perf_counter", lambda: clock["now"])
    search, evaluate = replan_module.run_search, PathJudge.evaluate

    def searched(*args, **kwargs):
        out = search(*args, **kwargs)
        if clock["jump_after_search"]:
            clock["now"] += 10.0
        clock["after"] = True
        return out

    def judged(self, waypoints, t0):
        ev = evaluate(self, waypoints, t0)
        if clock.get("after"):
            clock["judged"].append(np.array(waypoints))
            if clock["jump_after_judging"]:
                clock["now"] += 10.0
        return ev

    monkeypatch.setattr(replan_module, "run_search", searched)
    monkeypatch.setattr(PathJudge, "evaluate", judged)
    dut = Replanner(corridor, room, budget=1.0).plan(q_now, 2.0, prediction, previous, replan_index=1)
    assert dut.status == "wait" and dut.deadline_hit and dut.search_cost == math.inf, dut.reason
    assert clock["judged"] == [] and dut.iterations == full.iterations
    # Past the deadline after the first judgement: that path, as judged (it was safe), not shortened.
    clock.update(now=1000.0, jump_after_search=False, jump_after_judging=True, judged=[], after=False)
    dut = Replanner(corridor, room, budget=1.0).plan(q_now, 2.0, prediction, previous, replan_index=1)
    assert dut.status == "new" and dut.deadline_hit, dut.reason
    assert len(clock["judged"]) == 1
    np.testing.assert_array_equal(dut.waypoints, clock["judged"][0])
    assert len(dut.waypoints) > len(full.waypoints)  # the shortcut would have shortened it
    assert dut.search_cost == Replanner(corridor, room).evaluate(dut.waypoints, 2.0, prediction).cost
    assert min_distance(corridor, dut.waypoints, 2.0, prediction, [[(2.0, 6.0, yc)]]) > \
        corridor.execution.safety_distance


def test_shortcut_with_a_passed_deadline_returns_its_input(corridor, room):
    from drake_social.planning.replan_deadline import Deadline
    from drake_social.planning.replan_shortcut import shortcut

    s = np.asarray(corridor.start, float)
    zig = np.array([s, [1.7, 4.4, *s[2:]], [2.1, 2.6, *s[2:]], [2.5, 4.4, *s[2:]], [2.9, 3.5, *s[2:]]])
    judge = replanner(corridor, room).judge(nobody(0.0))
    ev = judge.evaluate(zig, 0.0)
    passed = Deadline(-math.inf)
    short, sev = shortcut(judge, zig, 0.0, ev, passed)
    assert short is zig and sev is ev and passed.hit
    kept = Deadline(math.inf)
    short, sev = shortcut(judge, zig, 0.0, ev, kept)
    assert len(short) < len(zig) and not kept.hit
    assert short.tobytes() == shortcut(judge, zig, 0.0, ev)[0].tobytes()


def test_a_budget_that_is_not_reached_changes_nothing(corridor, room, first):
    """With a budget far above the work, a replan with its deadline checks is
    the replan without a deadline, bit for bit (the loaded evasion included)."""
    q_now, previous = along(first, 2.0)
    rp = replanner(corridor, room)
    for kind in ("column", "converging"):
        prediction = walkers(2.0, crowd(q_now, kind), horizon=5.0)
        a = rp.plan(q_now, 2.0, prediction, previous, replan_index=1, deadline=True)
        b = rp.plan(q_now, 2.0, prediction, previous, replan_index=1, deadline=False)
        assert a.status == "evade" and not a.deadline_hit
        assert _same_but_time(a, b) and a.waypoints.tobytes() == b.waypoints.tobytes()


# ---- arguments ----------------------------------------------------------------------------------


def test_arguments_are_checked(corridor, room, first):
    with pytest.raises(TypeError, match="checker"):
        Replanner(corridor, "planar")
    with pytest.raises(ValueError, match="without people"):
        Replanner(load_scenario_text(STANDING, "standing"), make_checker(load_scenario_text(STANDING, "s"), "planar"))
    with pytest.raises(ValueError, match="margin"):
        Replanner(corridor, room, margin=1.0)
    with pytest.raises(ValueError, match="safety"):
        Replanner(corridor, room, safety=-0.1)
    with pytest.raises(ValueError, match="iterations"):
        Replanner(corridor, room, iterations=0)
    with pytest.raises(ValueError, match="budget"):
        Replanner(corridor, room, budget=0.0)
    # The bounds of planner.replan_iterations and replan_budget, at them and just beyond.
    dut = Replanner(corridor, room, iterations=MAX_REPLAN_ITERATIONS, budget=MAX_REPLAN_BUDGET)
    assert (dut.iterations, dut.budget) == (10_000, 60.0)
    with pytest.raises(ValueError, match=r"^Replanner: iterations must be an integer >= 1 and <= 10,000, got 10001$"):
        Replanner(corridor, room, iterations=MAX_REPLAN_ITERATIONS + 1)
    with pytest.raises(ValueError, match=r"^Replanner: budget must be in \(0, 60\] seconds, got 60.00000000000001$"):
        Replanner(corridor, room, budget=math.nextafter(MAX_REPLAN_BUDGET, math.inf))
    rp = replanner(corridor, room)
    assert (rp.iterations, rp.budget, rp.margin, rp.safety, rp.seed) == (
        corridor.planner.replan_iterations, 60.0, corridor.planner.replan_margin,
        corridor.execution.safety_distance, corridor.random_seed)
    with pytest.raises(ValueError, match="previous must end at the goal"):
        rp.plan(first.waypoints[0], 0.0, nobody(0.0), first.waypoints[:-1], replan_index=1)
    with pytest.raises(TypeError, match="prediction"):
        rp.plan(first.waypoints[0], 0.0, None, replan_index=1)
    with pytest.raises(ValueError, match="replan_index"):
        rp.plan(first.waypoints[0], 0.0, nobody(0.0), replan_index=-1)
    with pytest.raises(ValueError, match="q_now"):
        rp.plan([1.0, 2.0, 3.0], 0.0, nobody(0.0), replan_index=1)
    with pytest.raises(ValueError, match="ReplanResult.status"):
        ReplanResult(0.0, first.waypoints, 1.0, True, "maybe", "", 0.0, 0, False, 1.0, 1.0, 1)
