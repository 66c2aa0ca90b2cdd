"""Replanning in the execution diagram: the hand-over to a new path keeps the
reference continuous, a wait holds the robot, and (with the real replanner) a
walker stepping into the route of a corridor is never met within the safety
distance, the same seed giving the same episode bit for bit."""

from __future__ import annotations

import dataclasses as dc
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from drake_social.scenario.geometry import arm_geometry
from drake_social.people.proximity import part_distances
from drake_social.scenario import load_scenario
from drake_social.scenario.load import load_scenario_text
from drake_social.sim import simulate
from drake_social.sim.diagram import build_diagram
from drake_social.sim.run import run_checked

sys.path.insert(0, str(Path(__file__).parents[1] / "control"))
from test_replanner_system import FakeResult  # noqa: E402  (the replanner's test double's result)

DETOUR = [3.5, 1.8, 0.3, 1.2]


class Detour:
    """A scripted replanner: straight to the goal; at replan ``turn`` a detour
    through DETOUR; waits at the replans in ``waits``; else keeps the path."""

    def __init__(self, goal, turn: int = 8, waits=()):
        self.goal, self.turn, self.waits = np.asarray(goal, float), turn, set(waits)

    def plan(self, q_now, t_now, prediction, previous=None, *, replan_index, deadline=True, commit=False,
             search=True, people=None):
        q = np.asarray(q_now, float)
        if replan_index in self.waits:
            wp, status = q[None], "wait"
        elif replan_index == self.turn:
            wp, status = np.array([q, DETOUR, self.goal]), "new"
        elif previous is None:
            wp, status = np.array([q, self.goal]), "initial"
        else:
            wp, status = np.array(previous), "kept"
        return FakeResult(t_now, wp, math.inf if status == "wait" else 1.0, status == "new", status, "", 0.0, 1,
                          False, replan_index)


@pytest.fixture(scope="module")
def tiny(tiny_scenario_path):
    return load_scenario(tiny_scenario_path)


def _reference_log(built, until: float):
    """The reference's position and velocity and the planner's version at every control period up to ``until``."""
    period = built.scenario.execution.control_period
    simulator = Simulator(built.diagram)
    simulator.Initialize()
    root = simulator.get_context()
    reference = built.autonomy.reference
    context = reference.GetMyContextFromRoot(root)
    planner = built.autonomy.planner
    planner_context = planner.GetMyContextFromRoot(root)
    times, p, v, version = [], [], [], []
    for k in range(1, int(round(until / period)) + 1):
        simulator.AdvanceTo(k * period)
        times.append(root.get_time())
        p.append(reference.GetOutputPort("position").Eval(context).copy())
        v.append(reference.GetOutputPort("velocity").Eval(context).copy())
        version.append(planner.GetOutputPort("version").Eval(planner_context)[0])
    return np.array(times), np.array(p), np.array(v), np.array(version), root


def test_handover_keeps_the_reference_continuous_in_position_and_velocity(tiny):
    built = build_diagram(tiny, replan=True, replanner=Detour(tiny.goal))
    assert built.replanning and not built.autonomy.diagram.HasSubsystemNamed("held")
    times, p, v, version, _ = _reference_log(built, 2.0)
    change = int(np.flatnonzero(np.diff(version) > 0)[0]) + 1
    # Replan 8 runs at t = 0.8 s; AdvanceTo(0.8) stops before the events of t = 0.8 s, so the first
    # sample that shows it is that of 0.81 s.
    assert times[change] == pytest.approx(0.81)
    ex = tiny.execution
    period = ex.control_period
    # One period moves the reference by at most its speed limit times the period, and changes its
    # velocity by at most the acceleration limit times the period (the base's norm-limited pair may
    # exceed its limit by sqrt(2) on a change of target mid-motion: RuckigTrajectorySource).
    vmax = np.array([ex.max_base_speed * math.sqrt(2)] * 2 + list(ex.arm_max_velocity))
    amax = np.array([ex.max_base_acceleration * math.sqrt(2)] * 2 + list(ex.arm_max_acceleration))
    window = slice(change - 10, change + 10)
    dp = np.abs(np.diff(p[window], axis=0))
    dv = np.abs(np.diff(v[window], axis=0))
    assert np.all(dp <= vmax * period * (1 + 1e-9) + 1e-12)
    assert np.all(dv <= amax * period * (1 + 1e-9) + 1e-12)
    # It was moving at the change, and turns towards the detour after it.
    assert np.linalg.norm(v[change - 1, :2]) > 0.1
    assert abs(v[change - 1, 1]) < 1e-12 and v[change + 30, 1] < 0  # heading south-east towards (3.5, 1.8), off the straight line y = 2.5


def test_a_wait_brakes_the_robot_on_its_path_and_the_path_resumes(tiny):
    waits = range(5, 20)  # t = 0.5 .. 1.9 s
    built = build_diagram(tiny, replan=True, replanner=Detour(tiny.goal, turn=-1, waits=waits))
    times, p, v, version, root = _reference_log(built, 3.2)
    # The wait brakes the reference on its path, jerk-limited: no jump in velocity ...
    ex = tiny.execution
    amax = np.array([ex.max_base_acceleration] * 2 + list(ex.arm_max_acceleration))
    assert np.all(np.abs(np.diff(v, axis=0)) <= amax * ex.control_period * (1 + 1e-9) + 1e-12)
    assert np.linalg.norm(v[np.searchsorted(times, 0.52), :2]) > 0.05  # moving when the wait began
    # ... to rest, where it stands while waiting
    held = (times > 1.5) & (times < 2.0)
    np.testing.assert_array_equal(v[held], 0.0)
    assert np.ptp(p[held], axis=0).max() == 0.0
    assert np.max(np.abs(p[:, 1] - 2.5)) < 1e-9  # on the straight segment throughout
    assert np.all(version == 0)  # a wait keeps the path
    assert np.linalg.norm(v[-1, :2]) > 0.1  # and goes on along it after
    assert abs(p[-1, 1] - 2.5) < 1e-9  # on the straight segment to the goal
    planner = built.autonomy.planner
    statuses = [r.status for r in planner.replans(planner.GetMyContextFromRoot(root))]
    assert statuses[5:20] == ["wait"] * 15 and statuses[20] == "kept"


def test_replan_with_given_waypoints_is_refused(tiny):
    with pytest.raises(ValueError, match="replan=True"):
        build_diagram(tiny, replan=True, waypoints=np.array([tiny.start, tiny.goal]))
    with pytest.raises(TypeError, match="replan"):
        build_diagram(tiny, replan="yes")


def test_a_replanning_run_reports_its_replans(tiny):
    scenario = dc.replace(tiny, people=[])
    run = run_checked(scenario, "kinematic", "synchronized", None, None, None, 30.0, False, None, None,
                      replan=True, replanner=Detour(scenario.goal))
    assert run.reached and run.planner is None
    statuses = [r.status for r in run.replans]
    assert statuses[0] == "initial" and statuses[8] == "new" and all(r.t <= run.times[-1] for r in run.replans)
    summary = run.replanning
    assert summary["count"] == len(run.replans) - 1 and summary["changed"] == 1 and summary["waits"] == 0
    # The path followed: the first path up to the target it headed for (the goal: none of its rows but
    # the start), then the detour from where the robot was at t = 0.8 s.
    assert len(run.waypoints) == 4
    np.testing.assert_array_equal(run.waypoints[0], scenario.start)
    np.testing.assert_array_equal(run.waypoints[2:], [DETOUR, scenario.goal])
    assert run.to_json_dict()["replanning"] == summary
    assert "replans at 10 Hz: 1 changed the path, 0 waited" in run.summary()


def test_a_replanning_run_records_when_the_replanner_held_the_robot(tiny):
    # Replans 5 .. 14 wait: replan k runs at t = k / 10 s (summed apart from the log's 0.01 s steps).
    scenario = dc.replace(tiny, people=[])
    run = run_checked(scenario, "kinematic", "synchronized", None, None, None, 3.0, False, None, None,
                      replan=True, replanner=Detour(scenario.goal, turn=-1, waits=range(5, 15)))
    assert [r.status for r in run.replans][5:16] == ["wait"] * 10 + ["kept"]
    expected = (run.times > 0.5 - 1e-6) & (run.times < 1.5 - 1e-6)
    np.testing.assert_array_equal(run.waiting, expected)
    assert expected.sum() == 100 and not run.stopped.any()
    plain = run_checked(scenario, "kinematic", "synchronized", None, None, None, 1.0, False, None, None)
    assert len(plain.waiting) == len(plain.times) and not plain.waiting.any()


# ---- with the real replanner ---------------------------------------------------

CORRIDOR = """
description: "corridor: two routes around a central block, a walker stepping into one"
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
planner: {iterations: 1500, planning_range: 2.0, near_radius: 3.0, replan_iterations: 400, replan_budget: 60.0}
execution: {time_limit: 90.0}
"""

#: The walker: standing in the north-east corner (where the first plan sees them, the same for
#: both routes), then at 1.2 m/s into the east end of one corridor, where they stay (blocking it:
#: 0.75 m are left on either side, the robot is 0.95 m wide).
WALKERS = {
    "north": [[2.5, 11.5, 6.5], [4.6, 9.0, 6.0], [5.85, 7.5, 6.0]],
    "south": [[0.5, 11.5, 6.5], [3.6, 9.3, 3.5], [5.7, 9.0, 1.0], [6.95, 7.5, 1.0]],
}
WALKER = """
people:
  - {{name: walker, x: 11.5, y: 6.5, theta: 3.1416, radius: 0.25, trajectory: {trajectory}}}
"""


def _corridor(route: str):
    return load_scenario_text(CORRIDOR + WALKER.format(trajectory=WALKERS[route]), f"corridor, walker {route}")


def _route(waypoints) -> str:
    wp = np.asarray(waypoints, float)
    fine = np.concatenate([a + np.linspace(0, 1, 50)[:, None] * (b - a) for a, b in zip(wp[:-1], wp[1:])])
    inside = fine[(fine[:, 0] > 4.0) & (fine[:, 0] < 8.0)]
    return "north" if inside[0, 1] > 3.5 else "south"


@pytest.fixture(scope="module")
def walked():
    """The corridor with the walker stepping into the first plan's route (the first plan only sees
    the walker standing at the corridor's end, the same for both routes), run twice."""
    pytest.importorskip("drake_social.planning.replan")
    built = build_diagram(_corridor("north"), replan=True)
    context = built.diagram.CreateDefaultContext()
    built.diagram.ExecuteInitializationEvents(context)
    planner = built.autonomy.planner
    route = _route(planner.GetOutputPort("waypoints").Eval(planner.GetMyContextFromRoot(context)))
    scenario = _corridor(route)
    runs = [simulate(scenario, mode="kinematic", replan=True, analyze=k == 0) for k in range(2)]
    return scenario, route, runs


@pytest.mark.slow
def test_the_robot_never_comes_within_the_safety_distance_of_the_walker(walked):
    scenario, route, (run, _) = walked
    geometry = arm_geometry(scenario)
    d = np.array([part_distances(geometry, q[None], run.people.positions[k], run.people.radii)["robot"].min()
                  for k, q in enumerate(run.q)])
    assert d.min() > scenario.execution.safety_distance
    statuses = [r.status for r in run.replans]
    assert run.reached or statuses[-1] == "wait"
    # The walker mattered: the robot changed route or waited.
    assert any(s in ("new", "wait") for s in statuses[1:]) or run.stops
    assert run.replanning["count"] == len(run.replans) - 1 > 0
    # The hand-overs (a turn from the current motion towards the new path) stay clear of the block and walls.
    assert run.report.collision_free and run.report.within_limits


@pytest.mark.slow
def test_same_seed_same_episode_bit_for_bit(walked):
    _, _, (a, b) = walked
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.times, b.times)
    assert [(r.t, r.status, r.cost) for r in a.replans] == [(r.t, r.status, r.cost) for r in b.replans]
    assert not any(r.deadline_hit for r in a.replans)  # the iteration cap bound, not the clock


def test_replan_none_follows_the_scenario_when_it_plans(tiny):
    from drake_social.sim.checks import resolve_replan

    on = dc.replace(tiny, planner=dc.replace(tiny.planner, replan=True))
    assert resolve_replan(on, None, False, True, "f") is True
    assert resolve_replan(on, None, True, True, "f") is False  # a given path is executed as given
    assert resolve_replan(on, None, False, False, "f") is False  # a planner outside the diagram
    assert resolve_replan(tiny, None, False, True, "f") is False
    assert resolve_replan(on, False, False, True, "f") is False
    with pytest.raises(ValueError, match="f: replan=True needs the built-in planner"):
        resolve_replan(tiny, True, False, False, "f")


def test_a_robot_that_waits_the_whole_run_is_measured_where_it_held(tiny_scenario_path):
    """Someone within the safety distance of the robot for the whole run: every replan waits, and
    simulate returns the run (not reached) analysed against the one configuration held."""
    from drake_social.scenario import ScenarioError
    from drake_social.sim.execution_analysis import analyze_execution

    text = tiny_scenario_path.read_text().replace(
        'name: "standing"}  # faces south\n',
        'name: "standing"}\n  - {x: 0.37, y: 2.5, theta: 0.0, radius: 0.25, name: "beside the start"}\n')
    dut = load_scenario_text(text + "execution: {time_limit: 1.0}\n", "tiny, a person beside the start")
    assert len(dut.people) == 2
    run = simulate(dut, mode="kinematic", replan=True)
    assert not run.reached and run.message == "goal not reached within the time limit of 1 s (the last replan: wait)"
    assert [r.status for r in run.replans] == ["wait"] * 10  # the first plan and t = 0.1 .. 0.9 s
    np.testing.assert_array_equal(run.waypoints, [dut.start])
    np.testing.assert_array_equal(run.q, np.tile(dut.start, (len(run.times), 1)))
    report = run.report
    assert report is not None and report.collision_free and report.within_limits
    assert report.planned_social_cost == report.executed_social_cost == 0.0
    assert report.max_point_deviation["max"] == report.max_config_deviation == 0.0
    # The base's surface 0.63 - 0.35 - 0.25 m from the person's.
    assert report.min_clearance == pytest.approx(0.03, abs=1e-9)
    # One configuration is a path to analyse; a step off it is measured; none is refused, naming the rule.
    moved = run.q.copy()
    moved[-1, 0] += 0.02
    assert analyze_execution(dut, run.waypoints, run.times, moved).max_config_deviation == pytest.approx(0.02)
    with pytest.raises(ScenarioError, match=r"1 <= N <= 10,000 .*got 0 waypoints"):
        analyze_execution(dut, np.zeros((0, 4)), run.times, run.q)
