"""What the replanning system keeps of its predictions (ReplanState.predicted):
for the replans that changed the path or began a wait, the prediction's
positions at the kept times (checked against constant velocity computed by
hand), within MAX_PREDICTED_REPLANS; the replans themselves are called
exactly as without (the test double records the calls)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_replanner_system import PEOPLE, ScriptedReplanner, _context, _replan

from drake_social.control import ReplanningPlannerSystem
from drake_social.control.replanner_system import KEPT_PREDICTIONS, MAX_PREDICTED_REPLANS
from drake_social.people import PeopleState
from drake_social.scenario import load_scenario

SCRIPT = {0: "initial", 1: "kept", 2: "new", 3: "wait", 4: "wait", 5: "kept", 6: "wait", 7: "evade", 8: "kept"}
#: The replans whose prediction is kept: the first plan, the changes and the first of each wait.
KEPT = [0, 2, 3, 6, 7]
P0 = np.array([[2.0, 1.0], [-1.0, 3.0]])
V = np.array([[0.0, 0.5], [1.2, -0.3]])


@pytest.fixture(scope="module")
def scenario(tiny_scenario_path):
    # Constant velocity: the kept positions are checked against it by hand.
    return load_scenario(tiny_scenario_path, ["planner: {prediction: constant_velocity}"])


def _walkers(t: float) -> PeopleState:
    """Two people walking straight at V from P0 at t = 0, as the people input sees them at ``t``."""
    return PeopleState(t=t, positions=P0 + t * V, headings=np.array([math.pi / 4, 0.0]), velocities=V,
                       radii=np.array([0.25, 0.3]), names=("ann", "bob"))


def _run(scenario, max_predicted=None):
    double = ScriptedReplanner(SCRIPT)
    kwargs = {} if max_predicted is None else {"max_predicted": max_predicted}
    dut = ReplanningPlannerSystem(scenario, double, people=PEOPLE, **kwargs)
    context = _context(dut)
    dut.GetInputPort("people_state").FixValue(context, _walkers(0.0))
    dut.ExecuteInitializationEvents(context)
    for k in range(1, len(SCRIPT)):
        t = 0.1 * k
        context.SetTime(t)
        dut.GetInputPort("people_state").FixValue(context, _walkers(t))
        _replan(dut, context)
    return dut, context, double


def test_kept_for_the_changes_and_waits_equal_to_the_prediction(scenario):
    assert KEPT_PREDICTIONS == ("initial", "new", "evade", "wait")
    dut, context, double = _run(scenario)
    log = dut.replans(context)
    assert [r.status for r in log] == list(SCRIPT.values())
    kept = dut.predictions(context)
    assert [p.replan for p in kept] == KEPT
    horizon = float(scenario.planner.replan_horizon)
    for p in kept:
        t0 = 0.1 * p.replan
        assert p.t == pytest.approx(t0, abs=1e-12)
        # Every 0.6 s over a 5 s horizon at 0.1 s (9 times); the horizon's end at most.
        assert len(p.times) == int(horizon / 0.6 + 1e-9) + 1 <= 10
        np.testing.assert_allclose(p.times, t0 + 0.6 * np.arange(len(p.times)), atol=1e-12)
        for j, t in enumerate(p.times):  # constant velocity by hand: P0 + t V
            np.testing.assert_allclose(p.positions[j], P0 + t * V, rtol=0, atol=1e-9)
        assert p.names == ("ann", "bob") and p.culprit == -1  # the test double has no checker: no culprit named
        # ... and the prediction the replanner was given, at the kept times.
        given = double.calls[p.replan]["prediction"]
        for j, t in enumerate(p.times):
            np.testing.assert_allclose(p.positions[j], given.state_at(float(t)).positions, rtol=0, atol=1e-12)


def test_the_replanner_is_called_as_without(scenario):
    _, _, with_kept = _run(scenario)
    _, _, without = _run(scenario, max_predicted=0)
    for a, b in zip(with_kept.calls, without.calls, strict=True):
        assert a.keys() == b.keys()
        for key in a:
            if key == "prediction":
                np.testing.assert_array_equal(a[key].positions, b[key].positions)
            elif isinstance(a[key], np.ndarray):
                np.testing.assert_array_equal(a[key], b[key])
            else:
                assert a[key] == b[key]


@pytest.mark.parametrize(("cap", "kept"), [(len(KEPT) - 1, KEPT[:-1]), (len(KEPT), KEPT), (len(KEPT) + 1, KEPT),
                                           (0, [])])
def test_at_most_max_predicted_the_first_kept(scenario, cap, kept):
    dut, context, _ = _run(scenario, max_predicted=cap)
    assert [p.replan for p in dut.predictions(context)] == kept
    assert [r.status for r in dut.replans(context)] == list(SCRIPT.values())


def test_the_bound_is_refused_beyond_max_predicted_replans(scenario):
    assert MAX_PREDICTED_REPLANS == 1000
    ReplanningPlannerSystem(scenario, ScriptedReplanner({}), people=PEOPLE, max_predicted=MAX_PREDICTED_REPLANS)
    with pytest.raises(ValueError, match="max_predicted"):
        ReplanningPlannerSystem(scenario, ScriptedReplanner({}), people=PEOPLE,
                                max_predicted=MAX_PREDICTED_REPLANS + 1)
    with pytest.raises(ValueError, match="max_predicted"):
        ReplanningPlannerSystem(scenario, ScriptedReplanner({}), people=PEOPLE, max_predicted=-1)


def test_under_the_interactive_prediction_the_people_react_to_the_plan_chosen(tiny_scenario_path):
    """The kept positions are those of the people reacting to the robot
    driving the plan chosen (rolled out here from the people now with the
    plan's nominal times), not the robot-free reference the replanner is
    given; a wait keeps the people reacting to the robot standing."""
    from drake_social.kinematics import nominal_path_times
    from drake_social.people.interactive import InteractiveModel, predict_interactive

    scenario = load_scenario(tiny_scenario_path, ["planner: {prediction: interactive}"])
    dut, context, double = _run(scenario)
    model = InteractiveModel.from_scenario(scenario)
    ex, horizon = scenario.execution, float(scenario.planner.replan_horizon)
    kept = dut.predictions(context)
    assert [p.replan for p in kept] == KEPT
    differs = 0
    for p in kept:
        result, now = dut.replans(context)[p.replan], _walkers(0.1 * p.replan)
        wp = np.asarray(result.waypoints, float)
        induced = predict_interactive(now, (wp, nominal_path_times(wp, ex.max_base_speed, ex.arm_max_velocity,
                                                                   now.t)), horizon, model)
        reference = double.calls[p.replan]["prediction"]
        for j, t in enumerate(p.times):
            np.testing.assert_allclose(p.positions[j], induced.state_at(float(t)).positions, rtol=0, atol=1e-12)
        differs += not np.allclose(p.positions, [reference.state_at(float(t)).positions for t in p.times],
                                   rtol=0, atol=1e-3)
    assert differs >= 2  # the robot's plans come near the walkers: they react
