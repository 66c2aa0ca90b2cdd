"""The replanner under the interactive prediction (drake_social.planning.replan_interactive).

An open room (14 x 8 m): the robot drives straight east along y = 4 from
x = 1; a walker crosses its line northwards at 1.3 m/s from (x0, 1). Each
judged path is judged against the people it induces; a path that asks a
person to brake or step aside more than the courtesy bounds is not safe,
with the bound named in the reason; the people's effort is part of its cost.
"""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest

from drake_social.collision.drake_checker import make_checker
from drake_social.people import PeopleState, constant_velocity, without_people
from drake_social.people.interactive import InteractivePeople, demands, robot_samples
from drake_social.planning.replan import Replanner
from drake_social.planning.replan_interactive import InteractiveJudge
from drake_social.scenario.load import load_scenario_text

OPEN = """
description: "an open room"
world: {bounds: [0.0, 0.0, 14.0, 8.0]}
robot: {base_radius: 0.35, link_lengths: [0.6, 0.5], link_width: 0.08}
object: !Bar {length: 1.5, thickness: 0.05}
start: [1.0, 4.0, -1.2292, 2.8]
goal: [13.0, 4.0, -1.2292, 2.8]
random_seed: 3
planner: {iterations: 800, replan_iterations: 200, prediction: interactive}
"""
HORIZON = 5.0


@pytest.fixture(scope="module")
def scenario():
    return load_scenario_text(OPEN, "open")


@pytest.fixture(scope="module")
def room(scenario):
    return make_checker(without_people(scenario), "planar")


def walker(x0: float, t: float = 0.0) -> PeopleState:
    return PeopleState(t=t, positions=np.array([[x0, 1.0]]), headings=np.array([math.pi / 2]),
                       velocities=np.array([[0.0, 1.3]]), radii=np.array([0.25]), names=("walker",),
                       present=np.array([True]))


def straight(scenario) -> np.ndarray:
    return np.array([scenario.start, scenario.goal], float)


def judge_of(scenario, room, x0: float, **planner) -> InteractiveJudge:
    sc = dc.replace(scenario, planner=dc.replace(scenario.planner, **planner))
    r = Replanner(sc, room, budget=60.0)
    people = InteractivePeople(r.interactive, walker(x0), HORIZON)
    p = sc.planner
    return InteractiveJudge(r.judge, people, straight(sc)[:1], 0.0, p.courtesy_deceleration, p.courtesy_deviation,
                            p.courtesy_weight)


def asked(scenario, room, x0: float):
    """What the straight path asks of the walker, and what the robot standing at the start asks."""
    dut = judge_of(scenario, room, x0)
    return dut.induced(straight(scenario), 0.0)[1], dut.holding


def test_the_walker_yields_to_the_straight_path(scenario, room):
    """The straight path crosses the walker's line ahead of them: in the
    prediction it induces they give way (and come no nearer than the safety
    distance), where constant velocity walks them into the robot's line."""
    dut = judge_of(scenario, room, 3.0)
    induced, need = dut.induced(straight(scenario), 0.0)
    assert need.deviation[0] > 1.0 and need.effort > 1.0
    assert dut.holding.deviation[0] < 0.1  # the robot standing at x = 1: they pass by
    free = dut.reference.positions[:, 0]
    np.testing.assert_allclose(free[:, 0], 3.0, atol=1e-4)  # without the robot: straight on (the west wall 3 m away)
    assert np.abs(induced.positions[:, 0, 0] - 3.0).max() > 1.0
    # The basis (the robot holding still), over the safety horizon.
    np.testing.assert_array_equal(dut.people_safety.prediction.positions,
                                  dut.prediction.until(dut.safety_horizon).positions)


@pytest.mark.parametrize("bound", ["courtesy_deceleration", "courtesy_deviation"])
def test_the_courtesy_bound_at_its_value_and_either_side(scenario, room, bound):
    """A demand exactly at the bound passes; a bound a hair below it refuses
    the path with a reason naming the bound; above it passes."""
    x0 = 2.0 if bound == "courtesy_deceleration" else 3.0  # the walker's braking / turning binds
    need, held = asked(scenario, room, x0)
    value = float(need.deceleration[0] if bound == "courtesy_deceleration" else need.deviation[0])
    assert value > (held.deceleration[0] if bound == "courtesy_deceleration" else held.deviation[0])
    other = "courtesy_deviation" if bound == "courtesy_deceleration" else "courtesy_deceleration"
    for scale, safe in ((1.0, True), (1.0 - 1e-9, False), (1.0 + 1e-9, True)):
        dut = judge_of(scenario, room, x0, **{bound: value * scale, other: 20.0})
        ev = dut.evaluate(straight(scenario), 0.0)
        assert ev.safe is safe, (scale, ev.courtesy)
        if not safe:
            assert ev.courtesy.startswith("courtesy: walker would ") and f"planner.{bound}" in ev.courtesy
            assert dut.unsafe_words(ev) == ev.courtesy
            assert ev.static_bad < 0 and ev.people_bad < 0


def test_holding_still_asks_as_much_passes(scenario, room):
    """A demand above the bound that the robot standing still asks as well is not the path's: it passes."""
    need, held = asked(scenario, room, 2.0)
    assert held.deviation[0] > 1.0 > need.deviation[0]  # the robot at the start is in their way
    dut = judge_of(scenario, room, 2.0, courtesy_deviation=0.5 * float(need.deviation[0]), courtesy_deceleration=20.0)
    assert dut.evaluate(straight(scenario), 0.0).courtesy == ""
    dut = judge_of(scenario, room, 3.0, courtesy_deviation=0.5 * float(need.deviation[0]), courtesy_deceleration=20.0)
    assert dut.evaluate(straight(scenario), 0.0).courtesy != ""


def test_effort_weighs_in_the_cost(scenario, room):
    free = judge_of(scenario, room, 3.0, courtesy_weight=0.0, courtesy_deviation=100.0)
    heavy = judge_of(scenario, room, 3.0, courtesy_weight=2.5, courtesy_deviation=100.0)
    a, b = (j.evaluate(straight(scenario), 0.0) for j in (free, heavy))
    need = free.induced(straight(scenario), 0.0)[1]
    assert a.effort == b.effort == pytest.approx(need.effort, rel=1e-15) and need.effort > 1.0
    assert b.cost - a.cost == pytest.approx(2.5 * need.effort, rel=1e-12)
    # The cost without the effort is PathJudge's against the induced prediction.
    induced = free.induced(straight(scenario), 0.0)[0]
    assert a.cost == pytest.approx(free.make_judge(induced).evaluate(straight(scenario), 0.0).cost, rel=1e-15)


def test_a_path_the_walker_must_brake_hard_for_is_refused(scenario, room):
    """The robot's current path cuts in front of the walker: the replan finds
    it not safe by courtesy, says so, and drives another path (or waits)."""
    r = Replanner(dc.replace(scenario, planner=dc.replace(scenario.planner, courtesy_deviation=20.0)), room,
                  budget=60.0)
    state = walker(2.0)
    q = np.asarray(scenario.start, float)
    dut = r.plan(q, 0.0, constant_velocity(state, HORIZON), straight(scenario), replan_index=1, search=False,
                 people=state)
    assert dut.status in ("new", "wait") and dut.candidate_cost == math.inf
    assert "courtesy: walker would have to brake at" in dut.reason and "planner.courtesy_deceleration 1.5" in \
        dut.reason
    # The replay's culprit is the walker the reason names.
    from drake_social.control.replan_culprit import culprit
    ex = scenario.execution
    assert culprit(dut, constant_velocity(state, HORIZON), straight(scenario), q, room.compiled_scene(),
                   ex.max_base_speed, ex.arm_max_velocity) == 0
    if dut.status == "new":
        judge = r.interactive_judge(state, 0.0, constant_velocity(state, HORIZON), q[None])
        ev = judge.evaluate(dut.waypoints, 0.0)
        assert ev.safe and ev.cost == pytest.approx(dut.cost, rel=1e-12)
    # Under constant velocity the same path is judged without courtesy.
    cv = Replanner(dc.replace(scenario, planner=dc.replace(scenario.planner, prediction="constant_velocity")),
                   room, budget=60.0)
    assert "courtesy" not in cv.plan(q, 0.0, constant_velocity(state, HORIZON), straight(scenario),
                                     replan_index=1, search=False).reason


def test_the_people_now_are_required(scenario, room):
    r = Replanner(scenario, room, budget=60.0)
    with pytest.raises(TypeError, match="people must be a drake_social.people.PeopleState"):
        r.plan(np.asarray(scenario.start, float), 0.0, constant_velocity(walker(3.0), HORIZON), replan_index=0)


def test_same_inputs_same_replan(scenario, room):
    state = walker(3.0)
    runs = [Replanner(scenario, room, budget=60.0).plan(np.asarray(scenario.start, float), 0.0,
                                                          constant_velocity(state, HORIZON), straight(scenario),
                                                          replan_index=2, people=state) for _ in range(2)]
    a, b = runs
    np.testing.assert_array_equal(a.waypoints, b.waypoints)
    assert (a.cost, a.status, a.reason, a.iterations) == (b.cost, b.status, b.reason, b.iterations)


def test_judging_stops_at_the_deadline(scenario, room, monkeypatch):
    """Each rollout costs 0.1 s of a fake clock and the search runs
    to its deadline: the judging after it starts no rollout past the
    replan's deadline (the budget less FINISH_RESERVE), however many
    candidates there are."""
    import time

    from drake_social.planning import replan as replan_module
    from drake_social.planning.replan import FINISH_RESERVE, INTERACTIVE_VERIFY_RESERVE

    clock = {"now": 1000.0, "rollouts": [], "after": False, "budget": 1.0}
    monkeypatch.setattr(time, "perf_counter", lambda: clock["now"])
    search, driving = replan_module.run_search, InteractivePeople.driving

    def to_its_deadline(setup, social, q, t_now, prediction, candidate, iterations, stop, rng):
        out = search(setup, social, q, t_now, prediction, candidate, iterations, stop, rng)
        assert len(out.paths) >= 4
        if stop is not None:  # the search leaves the interactive judging its share of the budget
            assert stop == pytest.approx(1000.0 + clock["budget"] * (1.0 - INTERACTIVE_VERIFY_RESERVE), abs=1e-9)
            clock["now"] = max(clock["now"], stop)
        clock["after"] = True
        return out

    def costly(self, waypoints, times):
        if clock["after"]:
            clock["rollouts"].append(clock["now"])
        clock["now"] += 0.1
        return driving(self, waypoints, times)

    monkeypatch.setattr(replan_module, "run_search", to_its_deadline)
    monkeypatch.setattr(InteractivePeople, "driving", costly)
    state = walker(20.0)  # nobody in the way: every path is safe
    r = Replanner(scenario, room, budget=1.0)
    dut = r.plan(np.asarray(scenario.start, float), 0.0, constant_velocity(state, HORIZON), None, replan_index=3,
                 people=state)
    stop = 1000.0 + 1.0 * (1.0 - FINISH_RESERVE)
    assert dut.deadline_hit and dut.status == "new"
    assert clock["rollouts"] and max(clock["rollouts"]) <= stop
    assert len(clock["rollouts"]) <= 3  # 0.25 s after the search's deadline, 0.1 s per rollout
    # With time to spare the same replan judges more.
    clock.update(now=1000.0, rollouts=[], after=False, budget=60.0)
    Replanner(scenario, room, budget=60.0).plan(np.asarray(scenario.start, float), 0.0,
                                                 constant_velocity(state, HORIZON), None, replan_index=3,
                                                 people=state)
    assert len(clock["rollouts"]) > 3


def test_a_committed_replan_counts_the_peoples_effort_once(scenario, room):
    """Driving on along its current path (committed to the motion to (4, 4)),
    the replan's cost is that of the whole path judged from the robot at
    rest (:meth:`InteractiveJudge.evaluate`'s cost: the same motion), the people's effort over it counted once (the
    committed motion's cost adds no effort of its own)."""
    r = Replanner(scenario, room, budget=60.0)
    q = np.asarray(scenario.start, float)
    path = np.array([q, [4.0, 4.0, q[2], q[3]], scenario.goal])
    state = walker(3.0)  # steps aside for the robot driving on: a large effort
    prediction = constant_velocity(state, HORIZON)
    dut = r.plan(q, 0.0, prediction, path, replan_index=1, commit=True, search=False, people=state)
    assert dut.status == "kept"
    np.testing.assert_array_equal(dut.waypoints, path)
    whole = r.interactive_judge(state, 0.0, prediction, q[None]).evaluate(path, 0.0)
    committed = r.interactive_judge(state, 0.0, prediction, path[:2])
    assert scenario.planner.courtesy_weight * whole.effort > 1.0  # (its courtesy is not the question here)
    assert dut.cost == pytest.approx(whole.cost, rel=1e-12)
    # The committed motion alone: its cost against the basis, no effort, nothing asked beyond holding.
    head = committed.evaluate(path[:2], 0.0)
    assert head.effort == 0.0 and head.courtesy == ""
    assert head.cost == pytest.approx(committed.make_judge(committed.prediction).evaluate(path[:2], 0.0).cost,
                                      rel=1e-15)


def test_a_path_after_a_pause_at_the_end_of_the_committed_motion(scenario, room):
    """A path from the committed motion's end that starts later than the motion ends (a
    pause there): the robot drives the motion, stands at its end until the path starts,
    then drives it; a path starting when the motion ends has no pause, and one starting
    elsewhere is the path alone."""
    r = Replanner(scenario, room, budget=60.0)
    q = np.asarray(scenario.start, float)
    end = np.array([4.0, 4.0, q[2], q[3]])
    state = walker(9.0)
    dut = r.interactive_judge(state, 0.0, constant_velocity(state, HORIZON), np.array([q, end]))
    t_end = float(dut.prefix_times[-1])
    assert t_end == pytest.approx(3.0 / scenario.execution.max_base_speed, rel=1e-12)
    rest = np.array([end, scenario.goal], float)
    for pause in (0.0, 0.5):
        wp, times = dut.motion(rest, np.array([t_end + pause, t_end + pause + 18.0]))
        rows = 3 if pause == 0.0 else 4
        assert len(wp) == rows and len(times) == rows
        np.testing.assert_array_equal(wp[0], q)
        np.testing.assert_array_equal(wp[-1], scenario.goal)
        at = np.array([t_end - 1.0, t_end, t_end + pause / 2, t_end + pause, t_end + pause + 9.0])
        placed = robot_samples(wp, times, at)
        np.testing.assert_allclose(placed[0, :2], [3.5, 4.0], atol=1e-12)  # 1 s before the end: 0.5 m short
        np.testing.assert_allclose(placed[1:4], np.repeat(end[None], 3, axis=0), atol=1e-12)  # standing there
        np.testing.assert_allclose(placed[4, :2], [8.5, 4.0], atol=1e-12)  # half-way along the rest
    elsewhere = np.array([q + [0.0, 1.0, 0.0, 0.0], scenario.goal])
    wp, times = dut.motion(elsewhere, np.array([0.0, 20.0]))
    np.testing.assert_array_equal(wp, elsewhere)
