"""The interactive prediction (drake_social.people.interactive): a social-force
rollout of the people reacting to the robot's planned motion.

The first step of a walker meeting the robot is computed here by hand from
the documented terms (Helbing and Molnar's repulsion ``A exp(-d / B)`` of the
base disc, the links and the bar's segment); the rest checks behaviour: a
walker with nobody about goes straight on as constant velocity predicts,
a standing person stays, a walker brakes for a robot in their way and steps
aside from one beside it, and :func:`demands` against numbers worked out by hand.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_social.people import PeopleState, constant_velocity, predict
from drake_social.people.crowd import STANDING_SPEED
from drake_social.people.interactive import (GOAL_DISTANCE, InteractiveModel, InteractivePeople, demands,
                                             predict_interactive, robot_samples)
from drake_social.scenario.geometry import arm_geometry
from drake_social.scenario.load import load_scenario_text
from drake_social.scenario.schema import Crowd

OPEN = """
description: "an open floor"
world: {bounds: [-20.0, -20.0, 20.0, 20.0]}
robot: {base_radius: 0.35, link_lengths: [0.6, 0.5], link_width: 0.08}
object: !Bar {length: 1.5, thickness: 0.05}
start: [0.0, 0.0, 0.0, 0.0]
goal: [1.0, 0.0, 0.0, 0.0]
"""


@pytest.fixture(scope="module")
def scenario():
    return load_scenario_text(OPEN, "open")


@pytest.fixture(scope="module")
def model(scenario):
    dut = InteractiveModel.from_scenario(scenario)
    assert dut.boxes.shape == (4, 6) and dut.crowd == Crowd()  # the walls, 20 m out
    return dut


def people(positions, velocities, t=0.0, present=None) -> PeopleState:
    pos = np.asarray(positions, float).reshape(-1, 2)
    vel = np.asarray(velocities, float).reshape(-1, 2)
    p = len(pos)
    return PeopleState(t=t, positions=pos, headings=np.arctan2(vel[:, 1], vel[:, 0]), velocities=vel,
                       radii=np.full(p, 0.25), names=tuple(f"p{i}" for i in range(p)),
                       present=np.ones(p, bool) if present is None else np.asarray(present, bool))


def standing_robot(q, t0=0.0):
    return np.asarray(q, float)[None], np.array([t0])


def test_a_lone_walker_without_the_robot_goes_straight_on(model):
    state = people([[1.0, 2.0]], [[1.2, -0.5]], t=3.0)
    dut = predict_interactive(state, None, 5.0, model)
    cv = constant_velocity(state, 5.0)
    assert dut.samples == cv.samples == 51 and dut.t0 == 3.0
    np.testing.assert_allclose(dut.positions, cv.positions, rtol=0, atol=1e-12)
    np.testing.assert_allclose(dut.headings, math.atan2(-0.5, 1.2), rtol=0, atol=1e-12)
    assert dut.max_speeds == pytest.approx([1.3], abs=1e-9)
    # predict("interactive") is this rollout.
    same = predict("interactive", None, state, 5.0, interactive=model)
    np.testing.assert_array_equal(same.positions, dut.positions)
    with pytest.raises(ValueError, match="interactive="):
        predict("interactive", None, state, 5.0)


def test_a_standing_person_stays(model):
    state = people([[0.0, 0.0]], [[0.0, 0.0]])
    dut = predict_interactive(state, None, 5.0, model)
    np.testing.assert_array_equal(dut.positions, np.zeros((51, 1, 2)))
    # A robot passing 3 m away leaves them where they are (the push is below the standing speed's brake).
    far = predict_interactive(state, (np.array([[-5.0, 3.0, 0.0, 0.0], [5.0, 3.0, 0.0, 0.0]]),
                                      np.array([0.0, 20.0])), 5.0, model)
    np.testing.assert_array_equal(far.positions, np.zeros((51, 1, 2)))
    # Slower than the standing speed is standing too: they come to rest where they are.
    slow = predict_interactive(people([[0.0, 0.0]], [[0.9 * STANDING_SPEED, 0.0]]), None, 5.0, model)
    assert np.all(slow.positions[1:, 0, 0] == slow.positions[1, 0, 0])
    assert slow.positions[1, 0, 0] < 0.1 * STANDING_SPEED


def test_first_step_towards_the_robot_by_hand(model, scenario):
    """Walker at the origin, 1.3 m/s along +x; the robot stands at (3, 0)
    with its arm and bar pointing +x (away). One step of 0.1 s: the goal
    force is zero (v = v0 e), the base disc, link 1 (nearest point: the base
    centre), link 2 (its start, the elbow at 3.6) and the bar (its nearest
    point: the middle, at the gripper 4.1) push along -x."""
    g = arm_geometry(scenario)
    c = Crowd()
    q = np.array([3.0, 0.0, 0.0, 0.0])
    state = people([[0.0, 0.0]], [[1.3, 0.0]])
    pos, vel = InteractivePeople(model, state, 0.1, 0.1).rollout(np.stack([q, q]))[0].positions, None
    body = 0.25
    gaps = [3.0 - g.base_radius - body, 3.0 - g.link_radius - body, 3.6 - g.link_radius - body,
            4.1 - g.object_radius - body]
    push = sum(c.obstacle_strength * math.exp(-d / c.obstacle_range) for d in gaps)
    v1 = 1.3 - 0.1 * push
    assert pos[1, 0] == pytest.approx([0.1 * v1, 0.0], abs=1e-12)
    assert 0.1 * v1 < 0.13  # the robot slows them (barely, 2.4 m away)


def test_a_walker_brakes_for_the_robot_in_their_way(model):
    state = people([[0.0, 0.0]], [[1.3, 0.0]])
    robot = standing_robot([3.0, 0.0, math.pi / 2, 0.0])  # the arm out of the way: the base blocks
    dut = predict_interactive(state, robot, 5.0, model)
    free = predict_interactive(state, None, 5.0, model)
    speeds = np.hypot(*np.diff(dut.positions[:, 0], axis=0).T) / 0.1
    assert speeds.min() < 0.5 * 1.3  # they slow down ...
    gap = np.hypot(*(dut.positions[:, 0] - [3.0, 0.0]).T) - 0.35 - 0.25
    assert gap.min() > 0.0  # ... and never walk into the base
    assert free.positions[-1, 0, 0] == pytest.approx(6.5, abs=1e-9)


def test_a_walker_steps_aside_from_the_robot_beside_their_line(model):
    state = people([[0.0, 0.0]], [[1.3, 0.0]])
    robot = standing_robot([3.0, 0.4, math.pi / 2, 0.0])  # base 0.4 m to the left of their line
    dut = predict_interactive(state, robot, 5.0, model)
    y = dut.positions[:, 0, 1]
    assert y.min() < -0.2 and np.all(y <= 1e-12)  # they turn away, to the right
    assert dut.positions[-1, 0, 0] > 4.0  # and walk on past it


def test_goals_and_speeds_inferred_from_the_motion(model):
    state = people([[1.0, 1.0], [2.0, 2.0]], [[0.0, 0.8], [0.0, 0.0]])
    dut = InteractivePeople(model, state, 2.0)
    np.testing.assert_array_equal(dut.walking, [True, False])
    np.testing.assert_allclose(dut.goals[0], [1.0, 1.0 + GOAL_DISTANCE], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(dut.preferred, [0.8, 0.0])
    c = Crowd()
    np.testing.assert_allclose(dut.max_speeds, c.max_speed_factor * c.speed_mean, rtol=1e-15)


def test_absent_people_go_on_at_their_velocity_unseen(model):
    state = people([[0.0, 0.0], [0.5, 0.0]], [[1.0, 0.0], [-1.0, 0.0]], present=[True, False])
    dut = predict_interactive(state, None, 3.0, model)
    cv = constant_velocity(state, 3.0)
    np.testing.assert_allclose(dut.positions, cv.positions, rtol=0, atol=1e-12)
    assert not dut.present[:, 1].any()


def test_deterministic(model):
    rng = np.random.default_rng(5)
    state = people(rng.uniform(-4, 4, (30, 2)), rng.normal(0, 1, (30, 2)))
    robot = (np.array([[-3.0, -3.0, 0.3, 0.4], [3.0, 3.0, 1.0, -0.5]]), np.array([0.0, 12.0]))
    a = predict_interactive(state, robot, 5.0, model)
    b = predict_interactive(state, robot, 5.0, model)
    for field in ("positions", "headings", "max_speeds"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))


def test_robot_samples_interpolate_in_time():
    wp = np.array([[0.0, 0.0, 0.0, 0.0], [2.0, 0.0, 1.0, 0.0], [2.0, 2.0, 1.0, 1.0]])
    dut = robot_samples(wp, np.array([1.0, 3.0, 5.0]), np.array([0.0, 2.0, 4.0, 9.0]))
    np.testing.assert_allclose(dut, [[0, 0, 0, 0], [1, 0, 0.5, 0], [2, 1, 1, 0.5], [2, 2, 1, 1]], atol=1e-15)


def test_demands_by_hand(model):
    """Reference: walking at 1 m/s along x. Induced: the same until t = 0.2 s,
    then 0.5 m/s and 0.3 m off to the side from t = 0.3 s: the speed deficit
    0, 0, 0.5, 0.5 grows by 0.5 in one step of 0.1 s: 5 m/s^2."""
    state = people([[0.0, 0.0]], [[1.0, 0.0]])
    ref, ref_vel = InteractivePeople(model, state, 0.3).rollout(None)
    pos = ref.positions.copy()
    pos[3, 0, 1] = 0.3
    vel = ref_vel.copy()
    vel[2:, 0, 0] = 0.5
    from drake_social.people.prediction import Prediction
    induced = Prediction(t0=0.0, dt=0.1, positions=pos, headings=ref.headings, present=ref.present,
                         radii=ref.radii, speeds=ref.speeds, max_speeds=ref.max_speeds, names=ref.names)
    dut = demands(induced, vel, ref, ref_vel)
    assert dut.deceleration == pytest.approx([5.0], abs=1e-9)
    assert dut.deviation == pytest.approx([0.3], abs=1e-15)
    assert dut.effort == pytest.approx(0.3 ** 2 * 0.1, abs=1e-15)
    none = demands(ref, ref_vel, ref, ref_vel)
    assert none.deceleration[0] == 0.0 and none.deviation[0] == 0.0 and none.effort == 0.0


def test_people_react_to_each_other_within_the_range(model):
    """Two walkers meeting head on step aside from each other; two walking
    side by side repel each other within INTERACTION_RANGE, not beyond it."""
    from drake_social.people.interactive import INTERACTION_RANGE
    state = people([[0.0, 0.05], [3.0, 0.0]], [[1.0, 0.0], [-1.0, 0.0]])
    dut = predict_interactive(state, None, 3.0, model)
    assert abs(dut.positions[-1, 0, 1] - dut.positions[-1, 1, 1]) > 0.4
    for gap, apart in ((INTERACTION_RANGE + 0.01, False), (INTERACTION_RANGE, True), (INTERACTION_RANGE - 0.01, True)):
        pair = people([[0.0, 0.0], [0.0, gap]], [[1.0, 0.0], [1.0, 0.0]])
        got = predict_interactive(pair, None, 1.0, model).positions[-1, :, 1]
        assert bool(got[1] - got[0] > gap + 1e-6) is apart and got[1] - got[0] >= gap - 1e-12


def test_walking_is_faster_than_the_standing_speed(model):
    """The goal inference's threshold at its value and either side: exactly
    STANDING_SPEED stands, a hair faster walks (towards GOAL_DISTANCE ahead)."""
    speeds = [math.nextafter(STANDING_SPEED, 0.0), STANDING_SPEED, math.nextafter(STANDING_SPEED, 1.0)]
    state = people([[0.0, 0.0], [0.0, 2.0], [0.0, 4.0]], [[v, 0.0] for v in speeds])
    dut = InteractivePeople(model, state, 1.0)
    np.testing.assert_array_equal(dut.walking, [False, False, True])
    np.testing.assert_array_equal(dut.preferred, [0.0, 0.0, speeds[2]])
    np.testing.assert_allclose(dut.goals[2], [GOAL_DISTANCE, 4.0], rtol=0, atol=1e-9)
