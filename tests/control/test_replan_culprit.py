"""Who made a path unsafe (drake_social.control.replan_culprit): the person
whose prediction comes nearest the robot over the reason's window (not the
one nearest now), nobody for a cheaper route or the room."""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest

from drake_social.collision.drake_checker import make_checker
from drake_social.control.replan_culprit import culprit, robot_along
from drake_social.kinematics import nominal_path_times
from drake_social.people import PeopleState, constant_velocity, without_people
from drake_social.scenario import load_scenario


@dc.dataclass(frozen=True)
class Result:
    """The fields of a ReplanResult culprit() reads."""

    t: float
    status: str
    reason: str
    candidate_cost: float = math.inf


@pytest.fixture(scope="module")
def room(tiny_scenario_path):
    scenario = load_scenario(tiny_scenario_path)
    scene = make_checker(without_people(scenario), "planar").compiled_scene()
    ex = scenario.execution
    return scenario, scene, (ex.max_base_speed, ex.arm_max_velocity)


T0 = 1.0


def _setup(scenario, limits):
    """The path: 3 m east from the start. A (index 1) walks north across it, on the base's
    centre when the robot is there at the motion's middle time; B (index 0) stands 1.2 m north
    of the start, nearer the robot than A now."""
    q = np.array(scenario.start, float)
    path = np.array([q, q + [3.0, 0.0, 0.0, 0.0]])
    times = nominal_path_times(path, *limits, T0)
    mid = 0.5 * (times[0] + times[1])
    at_mid = robot_along(path, T0, np.array([mid]), *limits)[0, :2]
    speed = 1.0
    a_now = at_mid - [0.0, speed * (mid - T0)]
    state = PeopleState(t=T0, positions=np.array([q[:2] + [0.0, 1.2], a_now]), headings=np.array([0.0, math.pi / 2]),
                        velocities=np.array([[0.0, 0.0], [0.0, speed]]), radii=np.array([0.25, 0.25]),
                        names=("B", "A"))
    assert np.linalg.norm(state.positions[0] - q[:2]) < np.linalg.norm(state.positions[1] - q[:2])
    return q, path, times, constant_velocity(state, horizon=max(5.0, times[1] - T0 + 1.0))


def test_robot_along_passes_its_waypoints_at_their_times(room):
    scenario, _, limits = room
    q, path, times, _ = _setup(scenario, limits)
    np.testing.assert_allclose(robot_along(path, T0, times, *limits), path, atol=1e-12)
    half = robot_along(path, T0, np.array([0.5 * (times[0] + times[1])]), *limits)[0]
    np.testing.assert_allclose(half, 0.5 * (path[0] + path[1]), atol=1e-12)
    np.testing.assert_allclose(robot_along(path, T0, np.array([T0 - 1.0, times[1] + 1.0]), *limits), path,
                               atol=1e-12)  # held before and after


def test_the_person_on_the_path_in_the_window_not_the_nearest_now(room):
    scenario, scene, limits = room
    q, path, times, prediction = _setup(scenario, limits)
    reason = (f"the current path is not safe any more (motion 0, t = {times[0]:.2f} .. {times[1]:.2f} s comes "
              "within 0.05 m of a predicted person); the search's path costs 12.3")
    assert culprit(Result(T0, "new", reason), prediction, path, q, scene, *limits) == 1
    wait = Result(T0, "wait", f"waiting: the current path is not safe ({reason[35:]}")
    assert culprit(wait, prediction, path, q, scene, *limits) == 1


def test_the_judges_own_words_name_the_culprit(room):
    """The reasons as the replanner's judge words them (PathJudge.unsafe_words and wait_words,
    not hand-written): the window of the unsafe motion, and a person near now."""
    from types import SimpleNamespace

    from drake_social.planning.replan_eval import PathEvaluation, PathJudge

    scenario, scene, limits = room
    q, path, times, prediction = _setup(scenario, limits)
    ev = PathEvaluation(times, math.inf, 0.0, 3.0, -1, 0)  # motion 0 comes within the safety distance
    judge = SimpleNamespace(safety=0.05, unsafe_words=lambda e: PathJudge.unsafe_words(judge, e),
                            people_safety=SimpleNamespace(clearance=lambda q_, t_: 1.0))
    unsafe = PathJudge.unsafe_words(judge, ev)
    assert culprit(Result(T0, "new", f"the current path is not safe any more ({unsafe})"), prediction, path, q,
                   scene, *limits) == 1
    wait = PathJudge.wait_words(judge, q, T0, ev, "500 samples")
    assert culprit(Result(T0, "wait", wait), prediction, path, q, scene, *limits) == 1
    judge.people_safety = SimpleNamespace(clearance=lambda q_, t_: 0.02)  # someone within the distance now
    near = PathJudge.wait_words(judge, q, T0, ev, "500 samples")
    assert "from the robot now" in near
    assert culprit(Result(T0, "wait", near), prediction, path, q, scene, *limits) == 0


def test_now_the_nearest_person_standing(room):
    scenario, scene, limits = room
    q, path, _, prediction = _setup(scenario, limits)
    reason = "waiting: a person is 0.020 m from the robot now (safety distance 0.05 m)"
    assert culprit(Result(T0, "wait", reason), prediction, path, q, scene, *limits) == 0


@pytest.mark.parametrize("result", [
    Result(T0, "new", "the search's path costs 3, below (1 - 0.05) x 4 of the current path", candidate_cost=4.0),
    Result(T0, "new", "the current path is not safe any more (motion 0, t = 1.00 .. 2.00 s collides with the room)"),
    Result(T0, "initial", "the first plan: cost 3 after 300 samples"),
    Result(T0, "kept", "the current path (cost 3) stays"),
])
def test_no_culprit_for_a_cheaper_route_the_room_or_no_change(room, result):
    scenario, scene, limits = room
    q, path, _, prediction = _setup(scenario, limits)
    assert culprit(result, prediction, path, q, scene, *limits) == -1


def test_no_culprit_without_a_scene(room):
    scenario, _, limits = room
    q, path, times, prediction = _setup(scenario, limits)
    reason = f"motion 0, t = {times[0]:.2f} .. {times[1]:.2f} s comes within 0.05 m of a predicted person"
    assert culprit(Result(T0, "wait", reason), prediction, path, q, None, *limits) == -1


@pytest.mark.parametrize("status, named, who", [
    ("new", "A would have to brake at 2.10 m/s^2, more than planner.courtesy_deceleration 1.5 m/s^2", 1),
    ("wait", "B would be moved 1.20 m off their way, more than planner.courtesy_deviation 1 m", 0),
    ("new", "C would be moved 1.20 m off their way, more than planner.courtesy_deviation 1 m", -1),  # nobody's name
])
def test_a_courtesy_bound_names_its_person(room, status, named, who):
    """Under the interactive prediction a path asking too much of someone is
    not safe, the person named in the reason: that person is the culprit
    (not the one nearest the robot standing, B, nor nobody)."""
    scenario, scene, limits = room
    q, path, _, prediction = _setup(scenario, limits)
    reason = f"the current path is not safe any more (courtesy: {named}); the search's path costs 12.3"
    if status == "wait":
        reason = f"waiting: the current path is not safe (courtesy: {named}), and the search found no safe path"
    assert culprit(Result(T0, status, reason), prediction, path, q, scene, *limits) == who


def test_a_courtesy_bound_names_an_unnamed_person_by_index(room):
    scenario, scene, limits = room
    q, path, _, prediction = _setup(scenario, limits)
    unnamed = dc.replace(prediction, names=("", ""))
    reason = ("the current path is not safe any more (courtesy: person 1 would be moved 1.20 m off their way, "
              "more than planner.courtesy_deviation 1 m); the search's path costs 12.3")
    assert culprit(Result(T0, "new", reason), unnamed, path, q, scene, *limits) == 1
    # "person 1" of a named crowd is nobody's name: no culprit.
    assert culprit(Result(T0, "new", reason), prediction, path, q, scene, *limits) == -1


def test_the_standing_cases_read_the_people_predicted_with_the_robot_standing(room):
    """Under the interactive prediction the people react to the robot: who
    is near the robot standing is read from ``standing`` (here A and B
    swapped places), the replaced path's window from ``prediction``."""
    scenario, scene, limits = room
    q, path, times, prediction = _setup(scenario, limits)
    swapped = dc.replace(prediction, positions=prediction.positions[:, ::-1])
    near = Result(T0, "wait", "waiting: a person is 0.020 m from the robot now (safety distance 0.05 m)")
    assert culprit(near, prediction, path, q, scene, *limits, standing=swapped) == 1
    assert culprit(near, prediction, path, q, scene, *limits) == 0
    window = Result(T0, "new", f"the current path is not safe any more (motion 0, t = {times[0]:.2f} .. "
                               f"{times[1]:.2f} s comes within 0.05 m of a predicted person)")
    assert culprit(window, prediction, path, q, scene, *limits, standing=swapped) == 1


def test_beyond_the_safety_horizon_only_who_stands_is_the_culprit(room):
    """The replaced path's window lies after the safety horizon: there the
    replanner's check sees only people who stand (B), not the walker A who
    crosses the path then; within the horizon A is the culprit."""
    scenario, scene, limits = room
    q, path, times, prediction = _setup(scenario, limits)
    reason = (f"the current path is not safe any more (motion 0, t = {times[0]:.2f} .. {times[1]:.2f} s comes "
              "within 0.05 m of a predicted person)")
    result = Result(T0, "new", reason)
    short = 0.05  # the horizon ends before the window's middle, where A crosses
    mid = 0.5 * (times[0] + times[1])
    assert T0 + short < mid
    assert culprit(result, prediction, path, q, scene, *limits, safety_horizon=short) == 0
    assert culprit(result, prediction, path, q, scene, *limits, safety_horizon=mid - T0 + 1.0) == 1
    assert culprit(result, prediction, path, q, scene, *limits) == 1
