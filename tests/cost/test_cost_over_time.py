"""The social cost at time t (walking people) and Kirby's speed scaling.

A test double walks people on straight lines at constant velocity; the cost
at time t must be the static AGF cost at the interpolated pose, absent people
must add nothing, and the speed-scaled variances must give hand-computed AGF
values, in the numpy path, the compiled kernel and the compiled planner.
"""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest

from drake_social.cost import PersonalSpace, SocialCost, agf_algorithm1, kernel
from drake_social.cost.agf import speed_scaled_sigmas
from drake_social.people import PeopleModel, PeopleState, StaticPeople

PI = math.pi


class LineWalkers:
    """Test double of a PeopleModel: person i at ``starts[i] + t velocities[i]``,
    facing their direction of motion, present for ``windows[i][0] <= t <= windows[i][1]``."""

    def __init__(self, starts, velocities, windows=None):
        self.starts = np.asarray(starts, float).reshape(-1, 2)
        self.velocities = np.asarray(velocities, float).reshape(-1, 2)
        self.windows = windows or [(-math.inf, math.inf)] * len(self.starts)

    @property
    def count(self) -> int:
        return len(self.starts)

    @property
    def static(self) -> bool:
        return False

    def state_at(self, t: float) -> PeopleState:
        n = self.count
        return PeopleState(t=t, positions=self.starts + t * self.velocities,
                           headings=np.arctan2(self.velocities[:, 1], self.velocities[:, 0]),
                           velocities=self.velocities, radii=np.full(n, 0.25), names=tuple(f"w{i}" for i in range(n)),
                           present=np.array([a <= t <= b for a, b in self.windows]))


def near(points: np.ndarray, rng, n: int, spread: float = 2.5) -> np.ndarray:
    """n configurations with the base within ``spread`` of one of ``points`` (k, 2)."""
    xy = points[rng.integers(0, len(points), n)] + rng.uniform(-spread, spread, (n, 2))
    return np.column_stack([xy, rng.uniform(-PI, PI, (n, 2))])


def static_cost(scenario, poses) -> SocialCost:
    poses = np.asarray(poses, float).reshape(-1, 3)
    return SocialCost.from_scenario(scenario, people=StaticPeople(poses, np.full(len(poses), 0.25)).state_at(0.0))


def test_a_walker_at_time_t_costs_the_static_agf_at_the_interpolated_pose(tiny_scenario, rng):
    """At every t of a grid: S(q), Msc and the field of SocialCost.at_time equal
    those of a SocialCost of a standing person at (x0 + vx t, y0 + vy t, atan2(v)),
    and S(q) equals Algorithm 1 summed by hand over the interest points."""
    walker = LineWalkers([[1.0, 2.0]], [[0.6, 0.25]])  # 0.65 m/s, heading atan2(0.25, 0.6)
    heading = math.atan2(0.25, 0.6)
    for t in np.linspace(0.0, 8.0, 17):
        dut = SocialCost.at_time(tiny_scenario, float(t), model=walker)
        pose = [1.0 + 0.6 * t, 2.0 + 0.25 * t, heading]
        ref = static_cost(tiny_scenario, pose)
        np.testing.assert_allclose(dut.people, [pose], rtol=0, atol=1e-12)
        q = near(np.array([pose[:2]]), rng, 40)
        values = dut(q)
        np.testing.assert_allclose(values, ref(q), rtol=1e-12, atol=1e-12)
        assert np.count_nonzero(values) > 10
        by_hand = [sum(w * agf_algorithm1(x, y, pose, dut.space)
                       for w, (x, y) in zip(dut.weights, dut.geometry.interest_points(qi))) for qi in q]
        np.testing.assert_allclose(values, by_hand, rtol=1e-12, atol=1e-12)
        q_b = q + rng.normal(scale=0.5, size=q.shape)
        np.testing.assert_allclose(dut.motion_cost(q, q_b), ref.motion_cost(q, q_b), rtol=1e-12, atol=1e-12)
        xs, ys = np.meshgrid(np.linspace(pose[0] - 3, pose[0] + 3, 25), np.linspace(pose[1] - 3, pose[1] + 3, 25))
        np.testing.assert_allclose(dut.field(xs, ys), ref.field(xs, ys), rtol=1e-12, atol=1e-12)


def test_at_time_defaults_to_the_scenario_people_model(tiny_scenario):
    """Without a model, at_time takes the scenario's people (standing: the same at every t)."""
    p = tiny_scenario.people[0]
    for t in (0.0, 3.5):
        dut = SocialCost.at_time(tiny_scenario, t)
        np.testing.assert_array_equal(dut.people, [[p.x, p.y, p.theta]])
        np.testing.assert_array_equal(dut.people, SocialCost.from_scenario(tiny_scenario).people)


def test_absent_people_add_nothing(tiny_scenario, rng):
    """Person 1 is present for 2 <= t <= 4 only: outside that window the cost
    is that of person 0 alone; with nobody present it is 0 everywhere."""
    walkers = LineWalkers([[2.0, 2.0], [3.0, 3.0]], [[0.5, 0.0], [0.0, -0.4]], windows=[(0.0, 6.0), (2.0, 4.0)])
    for t, present in ((1.0, [True, False]), (3.0, [True, True]), (5.0, [True, False]), (7.0, [False, False])):
        state = walkers.state_at(t)
        dut = SocialCost.at_time(tiny_scenario, t, model=walkers)
        assert len(dut.people) == sum(present)
        q = near(state.positions, rng, 60)
        q_b = q + rng.normal(scale=0.5, size=q.shape)
        if not any(present):
            assert np.all(dut(q) == 0) and np.all(dut.motion_cost(q, q_b) == 0)
            assert np.all(dut.field(q[:, 0], q[:, 1]) == 0)
            continue
        alone = static_cost(tiny_scenario, state.poses()[np.array(present)])
        np.testing.assert_allclose(dut(q), alone(q), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(dut.motion_cost(q, q_b), alone.motion_cost(q, q_b), rtol=1e-12, atol=1e-12)
        with_everyone = static_cost(tiny_scenario, state.poses())
        if not all(present):  # the absent person would have counted
            assert np.any(np.abs(with_everyone(q) - dut(q)) > 1e-3)


def scaled(scenario):
    return dc.replace(scenario, social=dc.replace(scenario.social, speed_scaling=True))


def base_only(scenario) -> np.ndarray:
    n = len(SocialCost.from_scenario(scenario).weights)
    return np.eye(n)[0]


@pytest.mark.parametrize("speed, sigma_h", [(1.0, 2.0), (0.1, 0.5), (0.0, 0.5), (0.4, 0.8)])
def test_speed_scaling_gives_kirbys_sigma_h(tiny_scenario, speed, sigma_h):
    """A person at the origin walking along +x at ``speed`` m/s: sigma_h =
    max(2 v, 0.5), sigma_s = 2/3 sigma_h, sigma_r = 1/2 sigma_h. The base at
    (d, 0), (0, d), (-d, 0) gets exp(-d^2 / (2 sigma^2)) with the front, side
    and rear sigma (written out by hand), 0 where that is <= 0.2."""
    scenario = scaled(tiny_scenario)
    state = PeopleState(t=0.0, positions=[[0.0, 0.0]], headings=[0.0], velocities=[[speed, 0.0]], radii=[0.25],
                        names=("a",))
    dut = SocialCost.from_scenario(scenario, base_only(scenario), people=state)
    np.testing.assert_allclose(dut.sigmas, [[sigma_h, sigma_h * 2 / 3, sigma_h / 2]], rtol=1e-15)
    d = 0.3
    q = np.array([[d, 0.0, 0.0, 0.0], [0.0, d, 0.0, 0.0], [-d, 0.0, 0.0, 0.0], [0.0, -d, 1.0, 2.0]])
    by_hand = np.array([math.exp(-d * d / (2 * sigma_h**2)), math.exp(-d * d / (2 * (2 * sigma_h / 3) ** 2)),
                        math.exp(-d * d / (2 * (sigma_h / 2) ** 2)), math.exp(-d * d / (2 * (2 * sigma_h / 3) ** 2))])
    by_hand = np.where(by_hand > 0.2, by_hand, 0.0)
    np.testing.assert_allclose(dut(q), by_hand, rtol=1e-14, atol=0)


def test_speed_scaling_hand_values_at_a_distance(tiny_scenario):
    """v = 1 m/s (sigma_h = 2): 1 m ahead exp(-1/8), 1 m aside exp(-9/32), 1 m
    behind exp(-1/2); v = 0.1 m/s (sigma_h = 0.5): 1 m ahead exp(-2) < 0.2 -> 0."""
    scenario = scaled(tiny_scenario)
    state = PeopleState(t=0.0, positions=[[0.0, 0.0], [10.0, 0.0]], headings=[PI / 2, 0.0],
                        velocities=[[0.0, 1.0], [0.1, 0.0]], radii=[0.25, 0.25], names=("fast", "slow"))
    dut = SocialCost.from_scenario(scenario, base_only(scenario), people=state)
    q = np.array([[0.0, 1.0, 0, 0], [-1.0, 0.0, 0, 0], [0.0, -1.0, 0, 0], [11.0, 0.0, 0, 0], [10.0, 0.45, 0, 0]])
    expected = [math.exp(-1 / 8), math.exp(-9 / 32), math.exp(-1 / 2), 0.0,
                math.exp(-0.45**2 / (2 * (1 / 3) ** 2))]
    np.testing.assert_allclose(dut(q), expected, rtol=1e-14, atol=0)


def test_speed_scaling_of_standing_people_gives_everyone_sigma_h_half(tiny_scenario, rng):
    """Standing people (v = 0) with speed_scaling: sigma_h = 0.5 for all, and
    the cost is that of a PersonalSpace(0.5, 1/3, 1/4) shared by everyone."""
    scenario = scaled(tiny_scenario)
    poses = np.array([[1.0, 1.0, 0.3], [4.0, 2.0, -2.0], [2.0, 4.0, 3.0]])
    dut = static_cost(scenario, poses)
    np.testing.assert_array_equal(dut.sigmas, np.tile([0.5, 0.5 * 2 / 3, 0.25], (3, 1)))
    shared = SocialCost(dut.geometry, poses, PersonalSpace(0.5, 0.5 * 2 / 3, 0.25, 0.2), dut.weights, dut.resolution,
                        dut.distance_weights)
    q = near(poses[:, :2], rng, 200, spread=1.0)
    np.testing.assert_allclose(dut(q), shared(q), rtol=1e-14, atol=0)
    assert np.count_nonzero(dut(q)) > 20
    q_b = q + rng.normal(scale=0.4, size=q.shape)
    np.testing.assert_allclose(dut.motion_cost(q, q_b), shared.motion_cost(q, q_b), rtol=1e-12, atol=1e-14)


def test_speed_scaling_off_keeps_the_scenario_sigma(tiny_scenario):
    """speed_scaling false: no per-person variances, whatever the speeds."""
    walker = LineWalkers([[1.0, 2.0]], [[1.5, 0.0]])
    assert SocialCost.at_time(tiny_scenario, 1.0, model=walker).sigmas is None
    assert speed_scaled_sigmas(np.array([1.5]), 2 / 3, 0.5)[0, 0] == 3.0


def test_speed_scaled_sigmas_reject_bad_speeds():
    with pytest.raises(ValueError, match="finite speeds >= 0"):
        speed_scaled_sigmas(np.array([0.5, np.nan]), 2 / 3, 0.5)
    with pytest.raises(ValueError, match="finite speeds >= 0"):
        speed_scaled_sigmas(np.array([-0.1]), 2 / 3, 0.5)


def walking_crowd_cost(scenario, rng) -> SocialCost:
    """Eight people at different speeds (sigma_h from 0.5 to 3 m)."""
    speeds = np.array([0.0, 0.1, 0.3, 0.5, 0.8, 1.0, 1.2, 1.5])
    headings = rng.uniform(-PI, PI, 8)
    state = PeopleState(t=0.0, positions=rng.uniform(0.0, 8.0, (8, 2)), headings=headings,
                        velocities=speeds[:, None] * np.column_stack([np.cos(headings), np.sin(headings)]),
                        radii=np.full(8, 0.25), names=tuple("abcdefgh"))
    return SocialCost.from_scenario(scaled(scenario), people=state)


@pytest.mark.skipif(not kernel.AVAILABLE, reason="numba is not importable")
def test_the_compiled_kernel_matches_numpy_with_per_person_sigmas(tiny_scenario, rng):
    """Msc of the kernel (per-person variances, reaches and culling) against
    the numpy path, 1e-12; and against per-person costs summed: each person
    alone with a shared PersonalSpace of their own variances."""
    dut = walking_crowd_cost(tiny_scenario, rng)
    assert len(np.unique(dut.sigmas[:, 0])) == 7
    q_a = near(dut.people[:, :2], rng, 300)
    q_b = q_a + rng.normal(scale=0.7, size=q_a.shape)
    assert dut.backend == "numba"
    fast = dut.motion_cost(q_a, q_b)
    dut.backend = "numpy"
    slow = dut.motion_cost(q_a, q_b)
    assert np.count_nonzero(slow) > 100
    np.testing.assert_allclose(fast, slow, rtol=1e-12, atol=1e-13)
    total = np.zeros(len(q_a))
    for person, sigma in zip(dut.people, dut.sigmas):
        one = SocialCost(dut.geometry, person[None], PersonalSpace(*sigma, dut.space.threshold), dut.weights,
                         dut.resolution, dut.distance_weights)
        one.backend = "numpy"
        total += one.motion_cost(q_a, q_b)
    np.testing.assert_allclose(slow, total, rtol=1e-12, atol=1e-13)


@pytest.mark.skipif(not kernel.AVAILABLE, reason="numba is not importable")
def test_the_compiled_planner_takes_per_person_sigmas(tiny_scenario, rng):
    """The compiled tree loop (SocialParams with per-person variances) grows
    exactly the Python loop's tree; the sigmas matter (another tree without them)."""
    from drake_social.collision.planar_checker import PlanarChecker
    from drake_social.planning.objective import SocialObjective
    from drake_social.planning.rrt_star import RrtStar, RrtStarOptions, compiled_support
    from drake_social.planning.space import ConfigurationSpace

    scenario = tiny_scenario
    social = walking_crowd_cost(scenario, np.random.default_rng(5))
    plain = SocialCost(social.geometry, social.people, social.space, social.weights, social.resolution,
                       social.distance_weights)
    runs = []
    for cost, compiled in ((social, False), (social, True), (plain, True)):
        options = dc.replace(RrtStarOptions.from_scenario(scenario.planner), compiled=compiled, iterations=300,
                             optimize=False)
        planner = RrtStar(ConfigurationSpace.from_scenario(scenario), PlanarChecker(scenario),
                          SocialObjective(cost, 0.1), options)
        assert compiled_support(planner.checker, planner.objective, options)[0] == compiled
        runs.append(planner.solve(np.array(scenario.start), np.array(scenario.goal), np.random.default_rng(3)))
    python, compiled, without = runs
    np.testing.assert_array_equal(compiled.tree_nodes, python.tree_nodes)
    assert compiled.raw_cost == python.raw_cost and compiled.num_cost_evaluations == python.num_cost_evaluations
    assert not (without.raw_cost == compiled.raw_cost and np.array_equal(without.tree_nodes, compiled.tree_nodes))


def test_people_model_protocol_fits_the_double():
    assert isinstance(LineWalkers([[0.0, 0.0]], [[1.0, 0.0]]), PeopleModel)


def test_at_time_reads_a_people_log_between_its_samples(tiny_scenario, rng):
    """A PeopleLog of the walker sampled every 0.4 s, read between samples
    (linear interpolation), gives the walker's own cost at that time: its motion is linear."""
    from drake_social.people import PeopleLog

    walker = LineWalkers([[1.0, 2.0]], [[0.6, 0.25]])
    log = PeopleLog.sample(walker, np.arange(0.0, 8.01, 0.4))
    for t in (0.1, 1.3, 5.55, 7.9):
        from_log = SocialCost.at_time(tiny_scenario, t, model=log)
        direct = SocialCost.at_time(tiny_scenario, t, model=walker)
        np.testing.assert_allclose(from_log.people, direct.people, rtol=0, atol=1e-12)
        q = near(direct.people[:, :2], rng, 30)
        np.testing.assert_allclose(from_log(q), direct(q), rtol=1e-10, atol=1e-12)
