"""ReplanningPlannerSystem with a scripted test double of the replanner: its
ports, no feedthrough, the version and hold it keeps, the remainder it hands
the replanner, independent contexts; and the sequencer's version input."""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from drake_social.control import ReplanningPlannerSystem, WaypointSequencer, replanning_summary
from drake_social.control.replanner_system import MOVING_SPEED
from drake_social.people import StaticPeople
from drake_social.scenario import load_scenario

GOAL = np.array([3.0, 0.0, 0.1, 0.2])


@dc.dataclass(frozen=True)
class FakeResult:
    """The fields of drake_social.planning.replan.ReplanResult that the system reads."""

    t: float
    waypoints: np.ndarray
    cost: float
    changed: bool
    status: str
    reason: str
    plan_time: float
    iterations: int
    deadline_hit: bool
    replan_index: int
    searched: bool = True


class ScriptedReplanner:
    """Answers each replan with the status of its script (by replan index) and records the calls.

    ``"new"``: [q_now, a detour point, GOAL]; ``"kept"``: the remainder given;
    ``"wait"``: [q_now]; ``"initial"``: [q_now, GOAL].
    """

    def __init__(self, script: dict[int, str]):
        self.script = script
        self.calls: list[dict] = []

    def plan(self, q_now, t_now, prediction, previous=None, *, replan_index, deadline=True, commit=False,
             search=True, people=None):
        self.calls.append(dict(q=np.array(q_now), t=t_now, prediction=prediction,
                               previous=None if previous is None else np.array(previous),
                               replan_index=replan_index, deadline=deadline, commit=commit, search=search,
                               people=people))
        status = self.script.get(replan_index, "kept")
        q = np.asarray(q_now, float)
        if status == "initial":
            wp = np.array([q, GOAL])
        elif status == "new":
            wp = np.array([q, [1.0 + replan_index, 1.0, 0.0, 0.0], GOAL])
        elif status == "kept":
            wp = np.array(previous)
        elif status == "evade":
            wp = np.vstack([q, q + [0.0, 0.5, 0.0, 0.0], previous])
        else:
            wp = q[None]
        return FakeResult(t=t_now, waypoints=wp, cost=math.inf if status == "wait" else float(len(wp)),
                          changed=status in ("new", "evade"), status=status, reason="",
                          plan_time=0.001 * (replan_index + 1), iterations=10, deadline_hit=replan_index == 2,
                          replan_index=replan_index, searched=search)


@pytest.fixture(scope="module")
def scenario(tiny_scenario_path):
    return load_scenario(tiny_scenario_path)


PEOPLE = StaticPeople([[2.0, 1.0, 0.5]], [0.3], ["ann"])


def _system(scenario, script, rate=None):
    double = ScriptedReplanner(script)
    return ReplanningPlannerSystem(scenario, double, people=PEOPLE, rate=rate), double


def _context(dut, q=(0.0, 0.0, 0.0, 0.0), index=0.0):
    context = dut.CreateDefaultContext()
    dut.GetInputPort("q").FixValue(context, np.array(q, float))
    dut.GetInputPort("people_state").FixValue(context, PEOPLE.state_at(0.0))
    dut.GetInputPort("index").FixValue(context, [index])
    return context


def _replan(dut, context):
    scratch = context.Clone()
    dut.CalcForcedUnrestrictedUpdate(context, scratch.get_mutable_state())
    context.SetAbstractState(0, scratch.get_abstract_state(0).get_value())


def _outputs(dut, context):
    return (np.array(dut.GetOutputPort("waypoints").Eval(context)), dut.GetOutputPort("version").Eval(context)[0],
            dut.GetOutputPort("hold").Eval(context)[0])


def test_ports_and_no_feedthrough(scenario):
    dut, _ = _system(scenario, {0: "initial"})
    assert [dut.get_input_port(i).get_name() for i in range(dut.num_input_ports())] == ["q", "people_state", "index",
                                                                                       "velocity"]
    assert [dut.get_output_port(i).get_name() for i in range(dut.num_output_ports())] == [
        "waypoints", "version", "hold", "result", "replans"]
    for i in range(dut.num_input_ports()):
        for o in range(dut.num_output_ports()):
            assert not dut.HasDirectFeedthrough(i, o)


def _moving(dut, context, speed):
    dut.GetInputPort("velocity").FixValue(context, [0.0, 0.0, 0.0, speed])


@pytest.mark.parametrize("status", ["evade", "new"])
def test_a_new_path_not_starting_with_the_motion_waits_until_at_rest(scenario, status):
    """An evasion (or a new path after a wait) made from the robot's
    configuration while the reference moves: a wait (the robot stops on its
    path); the same decision from rest is taken."""
    script = {0: "initial", 1: "wait", 2: status, 3: status} if status == "new" else \
        {0: "initial", 1: status, 2: status}
    dut, double = _system(scenario, script)
    context = _context(dut)
    dut.ExecuteInitializationEvents(context)
    first, _, _ = _outputs(dut, context)
    _moving(dut, context, 0.3)
    if status == "new":
        _replan(dut, context)  # the wait: held, the next replan is not committed
    _replan(dut, context)
    waypoints, version, hold = _outputs(dut, context)
    np.testing.assert_array_equal(waypoints, first)
    assert (version, hold) == (0.0, 1.0)
    last = dut.GetOutputPort("result").Eval(context)
    assert last.status == "wait" and not last.changed and last.cost == math.inf
    assert last.reason.startswith(f"braking on the path before a new one ({status}: ")
    np.testing.assert_array_equal(last.waypoints, [[0.0, 0.0, 0.0, 0.0]])
    _moving(dut, context, 0.0)
    _replan(dut, context)
    waypoints, version, hold = _outputs(dut, context)
    assert (version, hold) == (1.0, 0.0)
    assert dut.GetOutputPort("result").Eval(context).status == status


def test_a_committed_new_path_is_taken_while_moving(scenario):
    """A new path that starts with the motion being driven (commit=True: the
    robot drives, no wait in force) is taken at once."""
    dut, double = _system(scenario, {0: "initial", 1: "new"})
    context = _context(dut)
    dut.ExecuteInitializationEvents(context)
    _moving(dut, context, 0.3)
    _replan(dut, context)
    assert double.calls[-1]["commit"] is True
    assert _outputs(dut, context)[1:] == (1.0, 0.0)


@pytest.mark.parametrize("speed, moving", [(MOVING_SPEED, False), (-MOVING_SPEED, False),
                                           (np.nextafter(MOVING_SPEED, 1.0), True),
                                           (-np.nextafter(MOVING_SPEED, 1.0), True), (0.0, False)])
def test_moving_is_a_speed_above_the_bound(scenario, speed, moving):
    dut, _ = _system(scenario, {0: "initial", 1: "evade"})
    context = _context(dut)
    dut.ExecuteInitializationEvents(context)
    _moving(dut, context, speed)
    _replan(dut, context)
    assert dut.GetOutputPort("result").Eval(context).status == ("wait" if moving else "evade")


def test_outputs_before_the_first_plan_say_so(scenario):
    dut, _ = _system(scenario, {0: "initial"})
    with pytest.raises(RuntimeError, match="initialization"):
        dut.GetOutputPort("waypoints").Eval(_context(dut))


def test_first_plan_is_initial_without_deadline(scenario):
    dut, double = _system(scenario, {0: "new"})  # a replanner that says "new" for the first plan: made "initial"
    context = _context(dut, q=(0.5, 0.0, 0.0, 0.0))
    dut.ExecuteInitializationEvents(context)
    waypoints, version, hold = _outputs(dut, context)
    np.testing.assert_array_equal(waypoints[0], [0.5, 0.0, 0.0, 0.0])
    assert (version, hold) == (0.0, 0.0)
    (first,) = dut.GetOutputPort("replans").Eval(context)
    assert first.status == "initial" and dut.GetOutputPort("result").Eval(context) is first
    call = double.calls[0]
    assert call["previous"] is None and call["replan_index"] == 0 and call["deadline"] is False
    # The prediction: the scenario's kind and horizon, from the people's state now.
    prediction = call["prediction"]
    assert prediction.t0 == 0.0 and prediction.horizon == pytest.approx(scenario.planner.replan_horizon)
    np.testing.assert_array_equal(prediction.positions[-1], [[2.0, 1.0]])


def test_version_increments_only_on_a_change_and_hold_while_waiting(scenario):
    script = {0: "initial", 1: "kept", 2: "new", 3: "wait", 4: "wait", 5: "kept", 6: "new"}
    dut, double = _system(scenario, script)
    context = _context(dut)
    dut.ExecuteInitializationEvents(context)
    seen = []
    for k in range(1, 7):
        dut.GetInputPort("q").FixValue(context, [0.1 * k, 0.0, 0.0, 0.0])
        _replan(dut, context)
        seen.append(_outputs(dut, context)[1:])
    assert seen == [(0, 0), (1, 0), (1, 1), (1, 1), (1, 0), (2, 0)]
    log = dut.GetOutputPort("replans").Eval(context)
    assert [r.status for r in log] == [script[k] for k in range(7)]
    assert [c["replan_index"] for c in double.calls] == list(range(7))
    assert all(c["deadline"] for c in double.calls[1:])
    # Driving (no wait in force) commits the motion to the target; after a wait the robot starts from rest.
    assert [c["commit"] for c in double.calls[1:]] == [True, True, True, False, False, True]
    # All at t = 0 (forced updates): a search only after a wait, within replan_search_period of the first plan.
    assert [c["search"] for c in double.calls[1:]] == [False, False, False, True, True, False]
    # While waiting, the path to the goal is kept (the next candidate), not the wait's [q].
    waypoints = _outputs(dut, context)[0]
    np.testing.assert_allclose(waypoints, [[0.6, 0, 0, 0], [7.0, 1.0, 0, 0], GOAL], rtol=0, atol=1e-15)
    # The replan after the waits got the path of replan 2 from q: [q] + path[index:] (index 0 here).
    np.testing.assert_allclose(double.calls[5]["previous"], rtol=0, atol=1e-15, desired=
                                  [[0.5, 0, 0, 0], [0.2, 0, 0, 0], [3.0, 1.0, 0, 0], GOAL])


def test_an_escape_is_a_new_path_that_ends_the_wait(scenario):
    dut, double = _system(scenario, {0: "initial", 1: "wait", 2: "evade"})
    context = _context(dut)
    dut.ExecuteInitializationEvents(context)
    q = np.array([0.3, 0.2, 0.0, 0.0])
    dut.GetInputPort("q").FixValue(context, q)
    _replan(dut, context)
    assert _outputs(dut, context)[1:] == (0, 1)  # waiting: held, same version
    _replan(dut, context)
    waypoints, version, hold = _outputs(dut, context)
    assert (version, hold) == (1, 0)  # the escape is a new path, and the hold ends
    # [q, q stepped aside, then the path waited on from q]: the candidate of replan 2 was [q] + the first path.
    previous = double.calls[2]["previous"]
    np.testing.assert_array_equal(previous[0], q)
    np.testing.assert_array_equal(previous[-1], GOAL)
    np.testing.assert_array_equal(waypoints, np.vstack([q, q + [0.0, 0.5, 0.0, 0.0], previous]))
    assert double.calls[2]["commit"] is False and double.calls[2]["search"] is True  # from rest, after a wait
    np.testing.assert_array_equal(dut.followed(context), waypoints)  # replaced at index 0: nothing followed before


def test_remainder_is_q_then_the_path_from_the_sequencers_index(scenario):
    dut, double = _system(scenario, {0: "initial", 1: "new", 2: "kept", 3: "new"})
    context = _context(dut)
    dut.ExecuteInitializationEvents(context)
    _replan(dut, context)  # path [q, (2, 1), GOAL]
    dut.GetInputPort("index").FixValue(context, [2.0])
    dut.GetInputPort("q").FixValue(context, [2.5, 0.5, 0.0, 0.0])
    _replan(dut, context)
    np.testing.assert_array_equal(double.calls[2]["previous"], [[2.5, 0.5, 0, 0], GOAL])
    # An index past the end (a stale one) is clamped to the last waypoint.
    dut.GetInputPort("index").FixValue(context, [9.0])
    _replan(dut, context)
    np.testing.assert_array_equal(double.calls[3]["previous"], [[2.5, 0.5, 0, 0], GOAL])
    # The path followed: the path of replan 1 (replacing the first at its index 0) up to its index 2
    # (start, (2, 1)), then the new one from q.
    followed = dut.followed(context)
    np.testing.assert_array_equal(followed, [[0, 0, 0, 0], [2.0, 1.0, 0, 0], [2.5, 0.5, 0, 0], [4.0, 1.0, 0, 0],
                                             GOAL])
    # The segments driven on keep the replaced path up to and including its target (index 2, the goal);
    # replan 1 replaced the first path at its index 0, the point it starts from: one row.
    np.testing.assert_array_equal(dut.judged(context), [[0, 0, 0, 0], [2.0, 1.0, 0, 0], GOAL, [2.5, 0.5, 0, 0],
                                                        [4.0, 1.0, 0, 0], GOAL])
    assert dut.state(context).judged_offset == 3 and dut.state(context).offset == 2


def test_no_path_at_first_waits_at_q_then_takes_the_first_path(scenario):
    dut, double = _system(scenario, {0: "wait", 1: "wait", 2: "new"})
    context = _context(dut, q=(0.2, 0.0, 0.0, 0.0))
    dut.ExecuteInitializationEvents(context)
    waypoints, version, hold = _outputs(dut, context)
    np.testing.assert_array_equal(waypoints, [[0.2, 0, 0, 0]])
    assert (version, hold) == (0, 1)
    _replan(dut, context)
    assert double.calls[1]["previous"] is None  # no path to the goal to offer as a candidate
    _replan(dut, context)
    waypoints, version, hold = _outputs(dut, context)
    assert (version, hold) == (1, 0) and len(waypoints) == 3


def test_two_contexts_run_on_their_own(scenario):
    dut, _ = _system(scenario, {0: "initial", 1: "new", 2: "wait"})
    a, b = _context(dut), _context(dut, q=(1.0, 0.0, 0.0, 0.0))
    dut.ExecuteInitializationEvents(a)
    dut.ExecuteInitializationEvents(b)
    _replan(dut, a)
    _replan(dut, a)
    assert _outputs(dut, a)[1:] == (1, 1) and len(dut.replans(a)) == 3
    assert _outputs(dut, b)[1:] == (0, 0) and len(dut.replans(b)) == 1
    np.testing.assert_array_equal(_outputs(dut, b)[0], [[1.0, 0, 0, 0], GOAL])
    clone = a.Clone()  # a clone shares the immutable state and goes on alone
    _replan(dut, clone)
    assert len(dut.replans(clone)) == 4 and len(dut.replans(a)) == 3


def test_periodic_replans_at_the_rate(scenario):
    dut, double = _system(scenario, {0: "initial"}, rate=5.0)
    simulator = Simulator(dut, _context(dut))
    simulator.Initialize()
    simulator.AdvanceTo(1.01)
    assert [c["t"] for c in double.calls] == pytest.approx([0.0, 0.2, 0.4, 0.6, 0.8, 1.0])
    assert dut.period == pytest.approx(0.2)


def test_bad_arguments_are_named(scenario):
    with pytest.raises(TypeError, match="replanner must have a plan"):
        ReplanningPlannerSystem(scenario, object())
    with pytest.raises(ValueError, match="rate"):
        ReplanningPlannerSystem(scenario, ScriptedReplanner({}), rate=0.0)


def test_summary_counts_the_periodic_replans(scenario):
    dut, _ = _system(scenario, {0: "initial", 1: "new", 2: "wait", 3: "evade", 4: "kept"})
    context = _context(dut)
    dut.ExecuteInitializationEvents(context)
    for _ in range(4):
        _replan(dut, context)
    summary = replanning_summary(dut.replans(context), 10.0, 0.08)
    times = [0.002, 0.003, 0.004, 0.005]
    # All at t = 0: only the replan after the wait (replan 3) searched.
    assert summary == {"count": 4, "changed": 2, "waits": 1, "evasions": 1, "searches": 1, "search_time_median": 0.004,
                       "plan_time_median": pytest.approx(np.median(times)),
                       "plan_time_p95": pytest.approx(np.percentile(times, 95)),
                       "plan_time_p99": pytest.approx(np.percentile(times, 99)), "plan_time_max": 0.005,
                       "deadline_hits": 1, "rate": 10.0, "budget": 0.08, "first_plan_time": 0.001}
    empty = replanning_summary((), 10.0, 0.08)
    assert empty["count"] == 0 and empty["plan_time_median"] is None and empty["first_plan_time"] is None


def test_summary_plan_time_percentiles_by_hand():
    """100 replans taking 1, 2, ..., 100 ms (in a shuffled order) after a
    first plan of 3 s: the p-th percentile of the linear interpolation
    between the sorted times lies at rank p / 100 x 99, so the median is
    50.5 ms, p95 95 + 0.05 = 95.05 ms, p99 99 + 0.01 = 99.01 ms, max 100 ms;
    the first plan is left out. With 3 replans (10, 20, 40 ms): rank 1.9
    for p95 (20 + 0.9 x 20 = 38 ms) and 1.98 for p99 (39.6 ms)."""
    from drake_social.planning.replan import ReplanResult
    from drake_social.sim.results import replanning_line

    def result(index, plan_time, deadline_hit=False):
        return ReplanResult(0.1 * index, np.zeros((1, 4)), 0.0, False, "initial" if index == 0 else "kept", "",
                            plan_time, 0, deadline_hit, 0.0, math.inf, index)

    order = np.random.default_rng(5).permutation(100)
    replans = [result(0, 3.0)] + [result(i + 1, (k + 1) * 1e-3, deadline_hit=k >= 98) for i, k in enumerate(order)]
    dut = replanning_summary(replans, 10.0, 0.08)
    assert dut["count"] == 100 and dut["first_plan_time"] == 3.0 and dut["deadline_hits"] == 2
    assert dut["plan_time_median"] == pytest.approx(0.0505, abs=1e-12)
    assert dut["plan_time_p95"] == pytest.approx(0.09505, abs=1e-12)
    assert dut["plan_time_p99"] == pytest.approx(0.09901, abs=1e-12)
    assert dut["plan_time_max"] == 0.1
    assert "median 50.5 ms, p95 95.0 ms, p99 99.0 ms, max 100.0 ms (budget 80 ms, 2 deadline hits)" in \
        replanning_line(dut)
    few = replanning_summary([result(0, 1.0), result(1, 0.04), result(2, 0.01), result(3, 0.02)], 10.0, 0.08)
    assert (few["plan_time_median"], few["plan_time_p95"], few["plan_time_p99"], few["plan_time_max"]) == \
        pytest.approx((0.02, 0.038, 0.0396, 0.04), abs=1e-12)
    assert replanning_summary([result(0, 1.0)], 10.0, 0.08)["plan_time_p99"] is None


# ---- the sequencer's version input ---------------------------------------------

WAYPOINTS = np.array([[0.0, 0, 0, 0], [1.0, 0, 0, 0], [2.0, 0, 0, 0]])


def _sequencer_step(dut, context):
    update = dut.AllocateDiscreteVariables()
    dut.CalcForcedDiscreteVariableUpdate(context, update)
    context.SetDiscreteState(update)


def test_a_new_version_restarts_the_sequencer_at_waypoint_1():
    dut = WaypointSequencer(base_tolerance=0.05, joint_tolerance=0.05, period=0.01, versioned=True)
    assert [dut.get_input_port(i).get_name() for i in range(dut.num_input_ports())] == [
        "waypoints", "q", "hold", "version"]
    context = dut.CreateDefaultContext()
    dut.GetInputPort("waypoints").FixValue(context, WAYPOINTS)
    dut.GetInputPort("version").FixValue(context, [0.0])
    for q in WAYPOINTS:  # to the end: done
        dut.GetInputPort("q").FixValue(context, q)
        _sequencer_step(dut, context)
    assert dut.GetOutputPort("done").Eval(context)[0] == 1.0
    new = np.array([[2.0, 0, 0, 0], [2.0, 1.0, 0, 0], [3.0, 1.0, 0, 0]])
    dut.GetInputPort("waypoints").FixValue(context, new)
    dut.GetInputPort("version").FixValue(context, [1.0])
    # At once, before any update: the new path's waypoint 1, not done.
    np.testing.assert_array_equal(dut.GetOutputPort("target").Eval(context), new[1])
    assert dut.GetOutputPort("index").Eval(context)[0] == 1.0 and dut.GetOutputPort("done").Eval(context)[0] == 0.0
    dut.GetInputPort("hold").FixValue(context, [1.0])  # the reset happens while held too
    _sequencer_step(dut, context)
    np.testing.assert_array_equal(context.get_discrete_state_vector().value(), [1.0, 0.0, 1.0])
    dut.GetInputPort("hold").FixValue(context, [0.0])
    dut.GetInputPort("q").FixValue(context, new[1])
    _sequencer_step(dut, context)
    np.testing.assert_array_equal(dut.GetOutputPort("target").Eval(context), new[2])
    # A path of one row (a wait at q) clamps the index to 0.
    dut.GetInputPort("waypoints").FixValue(context, new[:1])
    dut.GetInputPort("version").FixValue(context, [2.0])
    assert dut.GetOutputPort("index").Eval(context)[0] == 0.0


def test_an_unconnected_version_changes_nothing():
    dut = WaypointSequencer(WAYPOINTS, base_tolerance=0.05, joint_tolerance=0.05, period=0.01, versioned=True)
    context = dut.CreateDefaultContext()
    dut.GetInputPort("q").FixValue(context, WAYPOINTS[0])
    _sequencer_step(dut, context)
    np.testing.assert_array_equal(context.get_discrete_state_vector().value(), [1.0, 0.0, 0.0])
    np.testing.assert_array_equal(dut.GetOutputPort("target").Eval(context), WAYPOINTS[1])


@pytest.mark.parametrize("kind", ["interactive", "constant_velocity"])
def test_the_interactive_prediction_passes_the_people_now(scenario, kind):
    """Under the interactive prediction the replanner is given the people now
    (it rolls them out per judged path) and, as the prediction, their rollout
    without the robot (the default); under the others no people argument."""
    from drake_social.people.interactive import InteractiveModel, predict_interactive

    sc = dc.replace(scenario, planner=dc.replace(scenario.planner, prediction=kind))
    double = ScriptedReplanner({0: "initial"})
    dut = ReplanningPlannerSystem(sc, double, people=PEOPLE)
    context = _context(dut)
    dut.ExecuteInitializationEvents(context)
    context.SetTime(0.3)
    _replan(dut, context)
    assert [c["replan_index"] for c in double.calls] == [0, 1]
    for call, t in zip(double.calls, (0.0, 0.3)):
        if kind == "constant_velocity":
            assert call["people"] is None
            continue
        now = call["people"]
        assert now.t == t and now.names == ("ann",)
        np.testing.assert_array_equal(now.positions, [[2.0, 1.0]])
        expected = predict_interactive(now, None, sc.planner.replan_horizon, InteractiveModel.from_scenario(sc))
        np.testing.assert_array_equal(call["prediction"].positions, expected.positions)
        assert call["prediction"].t0 == t
