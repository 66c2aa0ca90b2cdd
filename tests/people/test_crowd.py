"""The simulated crowd: walkers against hand computations, the robot as an
obstacle, seeded determinism, the open-loop composition and the input rules."""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest

from drake_social.errors import ScenarioError
from drake_social.people.compose import CrowdModel, ScenarioPeople
from drake_social.people.crowd import (CROWD_SEED_TAG, SocialForceCrowd, crowd_model, crowd_problems,
                                       draw_speeds)
from drake_social.people.model import PeopleState, StaticPeople
from drake_social.people.proximity import part_distances
from drake_social.scenario.geometry import arm_geometry
from drake_social.scenario.schema import Box, Crowd, CrowdPerson, Person, Scenario, World
from drake_social.scenario.validate import validate_scenario

NOBODY = PeopleState(t=0.0, positions=np.zeros((0, 2)), headings=np.zeros(0), velocities=np.zeros((0, 2)),
                     radii=np.zeros(0), names=())


def scenario(people, bounds=(0.0, 0.0, 10.0, 10.0), start=(1.0, 1.0, 0.0, 0.0), **crowd) -> Scenario:
    sc = Scenario()
    sc.world = World(bounds=list(bounds))
    sc.start, sc.goal = list(start), [start[0] + 0.5, start[1], 0.0, 0.0]
    sc.crowd = Crowd(people=list(people), **crowd)
    return sc


def run(model: SocialForceCrowd, steps: int, robot_q=None) -> np.ndarray:
    """(steps + 1, 6, P) states: x, y, vx, vy, heading, goal."""
    state = model.initial_state()
    out = [state]
    for k in range(steps):
        q = robot_q(k) if callable(robot_q) else robot_q
        state = model.step(state, k * model.time_step, NOBODY, q)
        out.append(state)
    return np.array(out).reshape(steps + 1, 6, model.count)


def test_a_crowd_model_is_a_crowd_model():
    m = crowd_model(scenario([CrowdPerson(x=2, y=2, goals=[[8, 8]], desired_speed=1.0)]))
    assert isinstance(m, CrowdModel)
    assert m.count == 1 and m.time_step == 0.05
    np.testing.assert_allclose(m.initial_state(), [2, 2, 0, 0, math.pi / 4, 0])
    assert crowd_model(Scenario()) is None


def test_a_lone_walker_follows_the_discrete_relaxation_and_stops_at_its_goal():
    # Walls 5 m away or more push with < 1e-9 m/s^2, the north and south ones cancel.
    v0, tau, dt = 1.3, 0.5, 0.05
    m = crowd_model(scenario([CrowdPerson(x=5, y=1.5, goals=[[15, 1.5]], desired_speed=v0)],
                             bounds=(0, 0, 20, 3), start=(1.0, 0.6, 0.0, 0.0)))
    tr = run(m, 300)
    # By hand: v_k = v0 (1 - (1 - dt / tau)^k), x_k = x_0 + dt (v_1 + ... + v_k).
    k = np.arange(301)
    v = v0 * (1 - (1 - dt / tau) ** k)
    x = 5 + dt * np.cumsum(np.concatenate([[0.0], v[1:]]))
    reach = int(np.argmax(x >= 15 - 0.3))  # the first state within the goal radius
    np.testing.assert_allclose(tr[:reach + 1, 0, 0], x[:reach + 1], atol=1e-6)
    np.testing.assert_allclose(tr[:reach + 1, 2, 0], v[:reach + 1], atol=1e-6)
    assert tr[reach, 5, 0] == 0 and tr[reach + 1, 5, 0] == 1  # the goal is passed one step later
    # Within distance / speed + relaxation time (the continuous law's lag).
    assert (10 - 0.3) / v0 <= reach * dt <= (10 - 0.3) / v0 + tau + dt
    # Then they stand on it: speed 0, not moving.
    after = tr[reach + 1:]
    np.testing.assert_array_equal(after[:, 2:4], 0.0)
    np.testing.assert_array_equal(after[:, 0, 0], after[0, 0, 0])
    assert abs(after[0, 0, 0] - 15) <= 0.3 + v0 * 1.3 * dt
    np.testing.assert_array_equal(tr[:, 1, 0], 1.5)


def test_two_walkers_head_on_in_a_corridor_pass_without_touching_and_arrive():
    people = [CrowdPerson(x=1, y=1.45, goals=[[11, 1.45]], desired_speed=1.3),
              CrowdPerson(x=11, y=1.55, goals=[[1, 1.55]], desired_speed=1.2)]
    sc = scenario(people, bounds=(0, 0, 12, 3), start=(0.5, 0.5, 0.0, 0.0))
    assert crowd_problems(sc) == []
    tr = run(crowd_model(sc), 400)
    gap = np.hypot(tr[:, 0, 0] - tr[:, 0, 1], tr[:, 1, 0] - tr[:, 1, 1])
    assert gap.min() > 0.5  # the two radii: never overlapping
    # They swapped sides along the corridor, each veering to its own right.
    assert tr[-1, 0, 0] > tr[-1, 0, 1]
    assert tr[:, 1, 0].min() < 1.45 - 0.1 and tr[:, 1, 1].max() > 1.55 + 0.1
    np.testing.assert_array_equal(tr[-1, 5], [1, 1])  # both reached their goal
    for i, (goal, v0) in enumerate(((11, 1.3), (1, 1.2))):
        assert abs(tr[-1, 0, i] - goal) < 0.3 + 0.1
        reach = np.argmax(tr[:, 5, i] >= 1) * 0.05
        assert reach < 9.7 / v0 + 0.5 + 1.0  # the meeting costs them under a second
    # Nobody left the corridor.
    assert (tr[:, 1] - 0.25 > 0).all() and (tr[:, 1] + 0.25 < 3).all()


def test_a_wall_repels_a_walker_heading_into_it_at_an_angle():
    m = crowd_model(scenario([CrowdPerson(x=5, y=8, goals=[[9, 12]], desired_speed=1.3)]))
    tr = run(m, 200)
    # The goal is beyond the north wall (y = 10), at 45 degrees: the walker
    # never touches the wall and slides along it.
    assert (tr[:, 1, 0] + 0.25 < 10).all()
    assert 10 - 0.25 - tr[:, 1, 0].max() > 0.1
    assert tr[-1, 0, 0] > 8.5


def test_a_box_repels_like_a_wall():
    sc = scenario([CrowdPerson(x=2, y=5, goals=[[8, 5.2]], desired_speed=1.2)])
    sc.world.obstacles = [Box(center=[5, 5], size=[1, 1], yaw=0.3)]
    tr = run(crowd_model(sc), 300)
    from drake_social.people.social_force import box_nearest
    d, _ = box_nearest(tr[:, :2, 0], np.array([[5.0, 5.0]]), np.array([[0.5, 0.5]]), np.array([math.cos(0.3)]),
                       np.array([math.sin(0.3)]))
    assert d.min() > 0.25  # around the box, not through it
    assert tr[-1, 5, 0] == 1


def test_a_person_steps_aside_from_a_bar_swinging_towards_them():
    sc = scenario([CrowdPerson(x=2, y=6.6, goals=[[9, 6.6]], desired_speed=1.0)], start=(5, 5, -math.pi / 2, 0))
    assert crowd_problems(sc) == []
    m = crowd_model(sc)

    def swing(k):  # from t = 1 s, link 1 turns up at 1.5 rad/s until it points at +y
        return np.array([5.0, 5.0, -math.pi / 2 + min(max(k * 0.05 - 1.0, 0.0) * 1.5, math.pi / 2 + 0.3), 0.0])

    swung = run(m, 200, swing)
    still = run(m, 200, np.array([5.0, 5.0, -math.pi / 2, 0.0]))
    lateral = swung[:, 1, 0] - still[:, 1, 0]
    assert lateral.max() > 0.3  # away from the bar (+y), by far more than the still arm causes
    assert still[:, 1, 0].max() - 6.6 < 0.1
    assert lateral.min() > -0.01  # never pulled towards it
    geometry = arm_geometry(sc)
    qs = np.array([swing(k) for k in range(201)])
    gap = part_distances(geometry, qs, swung[:, :2, 0][:, None, :], np.array([0.25]))["robot"]
    assert gap.min() > 0  # never touched
    assert swung[-1, 5, 0] == 1  # and went on to the goal


def test_without_a_robot_configuration_the_robot_is_not_seen():
    sc = scenario([CrowdPerson(x=2, y=6.6, goals=[[9, 6.6]], desired_speed=1.0)], start=(5, 6.0, math.pi / 2, 0))
    m = crowd_model(sc)
    # Only the north wall, 3.15 m away, pushes (10 exp(-3.15 / 0.2) ~ 1e-6 m/s^2).
    assert np.abs(run(m, 120)[:, 1, 0] - 6.6).max() < 1e-5
    assert np.abs(run(m, 120, np.asarray(sc.start, float))[:, 1, 0] - 6.6).max() > 0.1  # the arm stands across


def test_goals_in_order_and_cycling():
    people = [CrowdPerson(x=2, y=2, goals=[[4, 2], [4, 4]], cycle=True, desired_speed=1.2),
              CrowdPerson(x=6, y=6, goals=[[8, 6], [8, 8]], desired_speed=1.2)]
    tr = run(crowd_model(scenario(people)), 600)
    g0, g1 = tr[:, 5, 0], tr[:, 5, 1]
    assert set(np.unique(g0)) == {0, 1} and (np.diff(g0) != 0).sum() >= 4  # 0 1 0 1 0 ...: cycling
    assert list(np.unique(g1)) == [0, 1, 2] and (np.diff(g1) >= 0).all()  # in order, then done
    assert np.hypot(tr[-1, 0, 1] - 8, tr[-1, 1, 1] - 8) < 0.3 + 0.1
    # Headings follow the motion: towards +x on the first leg.
    k = 20
    assert tr[k, 4, 1] == pytest.approx(math.atan2(tr[k, 3, 1], tr[k, 2, 1]))
    assert abs(tr[k, 4, 1]) < 0.05


def test_speeds_are_capped():
    people = [CrowdPerson(x=2, y=5, goals=[[8, 5]], desired_speed=1.0),
              CrowdPerson(x=2.6, y=5, goals=[[9, 5]], desired_speed=1.0)]
    m = crowd_model(scenario(people, max_speed_factor=1.2))
    tr = run(m, 100)
    speed = np.hypot(tr[:, 2], tr[:, 3])
    assert speed.max() <= 1.2 + 1e-12
    np.testing.assert_allclose(m.max_speeds, [1.2, 1.2])


def test_seeded_speeds_and_trajectories_are_deterministic():
    people = [CrowdPerson(x=2 + i, y=2 + 0.7 * i, goals=[[8 - i, 8]]) for i in range(4)]
    sc = scenario(people)
    sc.random_seed = 3
    a, b = crowd_model(sc), crowd_model(sc)
    np.testing.assert_array_equal(a.speeds, b.speeds)
    np.testing.assert_array_equal(run(a, 120), run(b, 120))
    # The speeds are the seeded draws, redrawn (never clamped) until > 0.1 m/s.
    rng = np.random.default_rng(np.random.SeedSequence([3, CROWD_SEED_TAG]))
    np.testing.assert_array_equal(a.speeds, draw_speeds(4, 1.34, 0.26, rng))
    sc.random_seed = 4
    assert not np.any(crowd_model(sc).speeds == a.speeds)
    # Given speeds are kept; the drawn ones go to the others, in order.
    sc.random_seed = 3
    sc.crowd.people[1] = dc.replace(people[1], desired_speed=0.9)
    c = crowd_model(sc)
    rng = np.random.default_rng(np.random.SeedSequence([3, CROWD_SEED_TAG]))
    drawn = draw_speeds(3, 1.34, 0.26, rng)
    np.testing.assert_array_equal(c.speeds, [drawn[0], 0.9, drawn[1], drawn[2]])


class _Normals:
    """A generator stand-in whose normals are the given values, in order."""

    def __init__(self, values):
        self.values = list(values)

    def normal(self, mean, std):
        return self.values.pop(0)


def test_drawn_speeds_keep_to_the_range_of_a_given_speed_at_its_ends():
    above, below = math.nextafter(3.0, 4.0), math.nextafter(3.0, 0.0)
    floor = math.nextafter(0.1, 1.0)
    values = [0.1, floor, above, 3.0, 1e3, -1e3, below]
    dut = draw_speeds(3, 1.34, 0.26, _Normals(values))
    np.testing.assert_array_equal(dut, [floor, 3.0, below])  # 0.1, 3.0000000000000004, +-1000 drawn again


@pytest.mark.parametrize("std", [0.26, 1.0, 1000.0])
def test_draws_outside_the_range_are_drawn_again_and_the_rest_is_the_stream(std):
    dut = draw_speeds(300, 1.34, std, np.random.default_rng(5))
    raw = np.random.default_rng(5).normal(1.34, std, 2_000_000 if std > 1 else 3000)
    np.testing.assert_array_equal(dut, raw[(raw > 0.1) & (raw <= 3.0)][:300])
    assert dut.min() > 0.1 and dut.max() <= 3.0


def test_a_crowd_with_a_wide_speed_spread_is_refused_naming_speed_std_and_its_drawn_speeds_are_walks():
    people = [CrowdPerson(x=4 + i, y=3 + 0.7 * i, goals=[[8 - i, 8]]) for i in range(4)]
    for std, ok in ((1.0, True), (math.nextafter(1.0, 0.0), True), (math.nextafter(1.0, 2.0), False),
                    (0.0, True), (-5e-324, False)):
        fields = [f for f, _ in problems_of(people, speed_std=std)]
        assert fields == ([] if ok else ["crowd.speed_std"]), std
    for factor, ok in ((2.0, True), (math.nextafter(2.0, 0.0), True), (math.nextafter(2.0, 3.0), False),
                       (1.0, True), (math.nextafter(1.0, 0.0), False)):
        fields = [f for f, _ in problems_of(people, max_speed_factor=factor)]
        assert fields == ([] if ok else ["crowd.max_speed_factor"]), factor
    dut = crowd_model(scenario(people, speed_mean=3.0, speed_std=1.0))
    assert dut.speeds.min() > 0.1 and dut.speeds.max() <= 3.0
    np.testing.assert_array_equal(dut.max_speeds, 1.3 * dut.speeds)


def test_the_shipped_crowds_draw_the_speeds_of_the_floor_alone():
    # lobby_crowd's draws (its seed and the crowd study's episode seeds) never pass 3 m/s: the
    # generator's normals above 0.1 m/s, as drawn before the range had an upper end.
    from pathlib import Path

    from drake_social.experiments.study.crowd import episode_seeds
    from drake_social.scenario import load_scenario

    lobby = load_scenario(Path(__file__).resolve().parents[2] / "scenarios" / "lobby_crowd.yaml")
    drawn = [i for i, p in enumerate(lobby.crowd.people) if p.desired_speed is None]
    assert len(drawn) == 10

    def floor_only(seed):
        raw = np.random.default_rng(np.random.SeedSequence([seed, CROWD_SEED_TAG])).normal(1.34, 0.26, 100)
        return raw[raw > 0.1][:len(drawn)]

    np.testing.assert_array_equal(crowd_model(lobby).speeds[drawn], floor_only(lobby.random_seed))
    for seed in episode_seeds(0, 50) + episode_seeds(1, 50):
        rng = np.random.default_rng(np.random.SeedSequence([seed, CROWD_SEED_TAG]))
        np.testing.assert_array_equal(draw_speeds(len(drawn), 1.34, 0.26, rng), floor_only(seed))


def test_draws_below_the_floor_are_drawn_again():
    rng = np.random.default_rng(0)
    speeds = draw_speeds(200, 0.2, 0.5, rng)
    assert (speeds > 0.1).all()
    # The same generator's raw normals, filtered: what "drawn again" means.
    raw = np.random.default_rng(0).normal(0.2, 0.5, 2000)
    np.testing.assert_array_equal(speeds, raw[raw > 0.1][:200])


def test_scenario_people_runs_the_crowd_open_loop_like_stepping_by_hand():
    sc = scenario([CrowdPerson(x=2, y=5, goals=[[8, 5]], desired_speed=1.1, name="ann"),
                   CrowdPerson(x=8, y=5.2, goals=[[2, 5.2]], desired_speed=1.0)])
    m = crowd_model(sc)
    standing = StaticPeople([[5.0, 6.0, 0.0]], [0.3], ["bob"])
    both = ScenarioPeople([standing], crowd=m)
    t = 2.37
    state = both.state_at(t)
    # By hand: floor(2.37 / 0.05) = 47 steps from t = 0 with bob as the others and no robot.
    s = m.initial_state()
    for k in range(47):
        s = m.step(s, k * 0.05, standing.state_at(k * 0.05), None)
    by_hand = m.people_state(s, t)
    assert state.names == ("bob", "ann", "")
    np.testing.assert_array_equal(state.positions[1:], by_hand.positions)
    np.testing.assert_array_equal(state.velocities[1:], by_hand.velocities)
    np.testing.assert_array_equal(state.headings[1:], by_hand.headings)
    np.testing.assert_array_equal(state.positions[0], [5.0, 6.0])
    # Bob counts: without him the crowd walks differently.
    alone = ScenarioPeople([], crowd=crowd_model(sc)).state_at(t)
    assert not np.array_equal(alone.positions, by_hand.positions)
    assert alone.t == t and state.t == t


# ---- crowd_problems --------------------------------------------------------


def ok_person(**kw) -> CrowdPerson:
    base = dict(x=5.0, y=5.0, goals=[[8.0, 8.0]], desired_speed=1.0)
    base.update(kw)
    return CrowdPerson(**base)


def problems_of(people=None, people_list=(), obstacles=(), **crowd):
    sc = scenario([ok_person()] if people is None else people, **crowd)
    sc.people = list(people_list)
    sc.world.obstacles = list(obstacles)
    return crowd_problems(sc)


def test_a_valid_crowd_and_no_crowd_have_no_problems():
    assert problems_of() == []
    assert crowd_problems(Scenario()) == []


PERSON_CASES = [
    (dict(goals=[]), "crowd.people[0].goals", "needs at least one goal"),
    (dict(x=math.nan), "crowd.people[0]", "x and y must be finite numbers"),
    (dict(goals=[[math.nan, 1.0]]), "crowd.people[0].goals[0]", "must be a point [x, y] of finite numbers"),
    (dict(goals=[[1.0]]), "crowd.people[0].goals[0]", "must be a point [x, y] of finite numbers"),
    (dict(x=0.1), "crowd.people[0]", "start (0.1, 5) must lie at least the radius 0.25 m inside world.bounds"),
    (dict(goals=[[9.9, 5.0]]), "crowd.people[0].goals[0]", "goal (9.9, 5) must lie at least the radius"),
    (dict(radius=0.0), "crowd.people[0].radius", "must be > 0 metres, got 0.0"),
    (dict(desired_speed=0.05), "crowd.people[0].desired_speed", "must be in (0.1, 3] m/s or left out (drawn)"),
    (dict(desired_speed=math.inf), "crowd.people[0].desired_speed", "must be in (0.1, 3] m/s"),
    (dict(x=1.3, y=1.0), "crowd.people[0]", "overlaps the robot at its start configuration"),
]


@pytest.mark.parametrize("change, field, message", PERSON_CASES)
def test_each_person_problem_names_its_field(change, field, message):
    problems = problems_of([ok_person(**change)])
    assert any(f == field and message in m for f, m in problems), problems


def test_obstacles_people_and_crowd_overlaps():
    box = Box(center=[5.0, 5.0], size=[1.0, 1.0])
    (f, m), = problems_of([ok_person(x=5.6)], obstacles=[box])
    assert f == "crowd.people[0]" and "start (5.6, 5) puts the body (radius 0.25 m) inside world.obstacles[0]" in m
    assert "0.1 m from it; must be >= 0.25" in m
    (f, m), = problems_of([ok_person(x=3.0, goals=[[5.2, 4.4]])], obstacles=[box])
    assert f == "crowd.people[0].goals[0]" and "goal (5.2, 4.4)" in m and "inside world.obstacles[0]" in m
    # Touching is allowed: 0.25 m from the face.
    assert problems_of([ok_person(x=5.75)], obstacles=[box]) == []
    (f, m), = problems_of([ok_person(), ok_person(x=5.4)])
    assert f == "crowd.people[1]" and "overlaps crowd.people[0] at (5, 5) by 0.1 m" in m
    (f, m), = problems_of([ok_person()], people_list=[Person(x=5.0, y=5.5, radius=0.3)])
    assert f == "crowd.people[0]" and "overlaps people[0] at (5, 5.5) by 0.05 m" in m
    scripted = Person(trajectory=[[0.0, 5.2, 5.0], [3.0, 9.0, 9.0]])
    (f, m), = problems_of([ok_person()], people_list=[scripted])
    assert "overlaps people[0] at (5.2, 5)" in m


PARAMETER_CASES = [
    (dict(time_step=0.0), "crowd.time_step", "must be in (0, 0.1] seconds"),
    (dict(time_step=0.2), "crowd.time_step", "must be in (0, 0.1] seconds"),
    (dict(time_step=math.nan), "crowd.time_step", "must be a finite number"),
    (dict(time_step=0.1, relaxation_time=0.1), "crowd.time_step", "must be < crowd.relaxation_time (0.1 s)"),
    (dict(speed_mean=0.1), "crowd.speed_mean", "must be in (0.1, 3] m/s, got 0.1"),
    (dict(speed_mean=4.0), "crowd.speed_mean", "must be in (0.1, 3] m/s, got 4.0"),
    (dict(speed_std=-0.1), "crowd.speed_std", "must be in [0, 1] m/s (the drawn speeds keep to (0.1, 3] m/s)"),
    (dict(speed_std=1000.0), "crowd.speed_std", "must be in [0, 1] m/s (the drawn speeds keep to (0.1, 3] m/s), "
                                                "got 1000.0"),
    (dict(speed_std=math.inf), "crowd.speed_std", "must be a finite number"),
    (dict(max_speed_factor=0.9), "crowd.max_speed_factor", "must be in [1, 2]"),
    (dict(max_speed_factor=1000.0), "crowd.max_speed_factor", "must be in [1, 2] (a multiple of each person's "
                                                              "preferred speed), got 1000.0"),
    (dict(relaxation_time=0.0), "crowd.relaxation_time", "must be > 0 seconds"),
    (dict(goal_radius=-1.0), "crowd.goal_radius", "must be > 0 metres"),
    (dict(interaction_lambda=0.0), "crowd.interaction_lambda", "must be > 0"),
    (dict(interaction_gamma=0.0), "crowd.interaction_gamma", "must be > 0"),
    (dict(interaction_n=0.0), "crowd.interaction_n", "must be > 0"),
    (dict(interaction_n_prime=-2.0), "crowd.interaction_n_prime", "must be > 0"),
    (dict(interaction_strength=-1.0), "crowd.interaction_strength", "must be >= 0 m/s^2"),
    (dict(obstacle_strength=-1.0), "crowd.obstacle_strength", "must be >= 0 m/s^2"),
    (dict(obstacle_range=0.0), "crowd.obstacle_range", "must be > 0 metres"),
]


@pytest.mark.parametrize("change, field, message", PARAMETER_CASES)
def test_each_parameter_problem_names_its_field(change, field, message):
    problems = problems_of(**change)
    assert any(f == field and message in m for f, m in problems), problems


def test_an_empty_crowd_is_a_problem():
    assert problems_of([]) == [("crowd.people",
                                "needs at least one person (leave out the crowd section for none)")]


def test_the_validator_raises_each_problem_before_anything_runs():
    sc = scenario([ok_person(goals=[])])
    with pytest.raises(ScenarioError, match=r"^crowd\.yaml: crowd\.people\[0\]\.goals: needs at least one goal"):
        validate_scenario(sc, source="crowd.yaml")
    validate_scenario(scenario([ok_person()]), source="crowd.yaml")


def test_the_compiled_step_is_the_numpy_reference():
    # Many people with cycling goals, a turned box, a standing open-loop
    # person, a moving robot: every branch of the kernel, compared step by
    # step from the same states.
    rng = np.random.default_rng(11)
    people = [CrowdPerson(x=float(x), y=float(y), goals=[[float(a), float(b)] for a, b in rng.uniform(1, 9, (2, 2))],
                          cycle=bool(i % 2), radius=0.2 + 0.02 * i) for i, (x, y) in
              enumerate([(2, 6), (3, 7), (4, 8), (6, 7), (7, 6), (8, 8), (2, 8), (5, 9)])]
    sc = scenario(people, start=(5.0, 4.0, 0.0, 0.0))
    sc.world.obstacles = [Box(center=[3.0, 3.0], size=[1.0, 0.6], yaw=0.5)]
    sc.random_seed = 5
    fast, slow = crowd_model(sc), crowd_model(sc, compiled=False)
    others = StaticPeople([[6.0, 2.0, 0.0]], [0.3]).state_at(0.0)
    state = fast.initial_state()
    worst = 0.0
    for k in range(400):
        q = np.array([5.0 + 0.5 * math.sin(0.02 * k), 4.0, 0.05 * k, 0.3 * math.cos(0.05 * k)])
        a = fast.step(state, 0.05 * k, others, q if k % 3 else None)
        b = slow.step(state, 0.05 * k, others, q if k % 3 else None)
        worst = max(worst, float(np.abs(a - b).max()))
        state = a
    assert worst < 1e-12
    goals = state.reshape(6, -1)[5]
    assert len(set(goals.tolist())) > 1  # people at different stages


def test_a_scenario_file_with_a_bad_goal_fails_to_load_naming_file_and_field(tmp_path):
    from drake_social.scenario import load_scenario

    path = tmp_path / "lobby.yaml"
    path.write_text("crowd:\n  people:\n    - {x: 5, y: 5, goals: [[8, 8], [9.9, 2]]}\n")
    with pytest.raises(ScenarioError) as error:
        load_scenario(str(path))
    assert str(error.value) == (f"{path}: crowd.people[0].goals[1]: goal (9.9, 2) must lie at least the radius "
                                "0.25 m inside world.bounds [0.0, 0.0, 10.0, 10.0]")
    path.write_text("crowd:\n  people:\n    - {x: 5, y: 5, goals: [[8, 8], [9.5, 2]]}\n")
    m = crowd_model(load_scenario(str(path)))
    assert m.count == 1 and 0.1 < m.speeds[0]
