"""The time-indexed motion social cost (the replanner's objective).

Each trapezoid sample of a motion is evaluated against the people predicted
at the time the robot is there. The compiled kernel
(:func:`drake_social.cost.timed_kernel.msc_sums_timed`) must equal the numpy
reference on random motions, times and predictions (walkers, people who come
and go, times before the first sample and beyond the horizon); a static
prediction must give today's :meth:`SocialCost.motion_cost`; one person
walking past a point robot must give a direct quadrature of the AGF along the
motion, with and without Kirby's speed scaling.
"""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest

from drake_social.cost import PersonalSpace, SocialCost, timed_kernel
from drake_social.cost.agf import speed_scaled_sigmas
from drake_social.kinematics import config_distance
from drake_social.scenario.geometry import arm_geometry
from drake_social.people import PeopleState, Prediction, constant_velocity
from drake_social.scenario import Bar, LShape, Robot, Scenario, SocialCostOptions

OBJECTS = {"bar": Bar(length=1.5), "L": LShape(lengths=[3.0, 2.0])}


def both(dut: SocialCost, *args) -> tuple[np.ndarray, np.ndarray]:
    dut.backend = "numba"
    fast = dut.timed_motion_cost(*args)
    dut.backend = "numpy"
    reference = dut.timed_motion_cost(*args)
    return fast, reference


def random_prediction(rng, people: int, samples: int, dt: float = 0.1, t0: float = 3.0,
                      absent: float = 0.2) -> Prediction:
    """People walking random piecewise-straight routes around the origin,
    turning at random, each absent at a random fraction of the samples."""
    start = rng.uniform(-3.0, 3.0, (people, 2))
    velocity = rng.normal(0.0, 0.8, (samples, people, 2))
    velocity[:, : people // 3] = 0.0  # some stand still
    positions = start + np.cumsum(velocity * dt, axis=0) - velocity[:1] * dt
    headings = rng.uniform(-math.pi, math.pi, (samples, people))
    present = rng.random((samples, people)) >= absent
    step = np.diff(positions, axis=0)
    max_speeds = np.hypot(step[..., 0], step[..., 1]).max(axis=0) / dt if samples > 1 else np.zeros(people)
    return Prediction(t0=t0, dt=dt, positions=positions, headings=headings, present=present,
                      radii=np.full(people, 0.25), speeds=rng.uniform(0.0, 1.5, people), max_speeds=max_speeds,
                      names=tuple(f"p{i}" for i in range(people)))


def motions(rng, n: int, spread: float = 3.5, length: float = 2.5):
    q_a = np.column_stack([rng.uniform(-spread, spread, (n, 2)), rng.uniform(-math.pi, math.pi, (n, 2))])
    d = rng.normal(size=(n, 4))
    d *= rng.uniform(0.0, length, (n, 1)) / np.linalg.norm(d, axis=1, keepdims=True)
    return q_a, q_a + d


def scenario(kind: str = "bar", weights=None, speed_scaling: bool = False, **social) -> Scenario:
    return Scenario(robot=Robot(), object=OBJECTS[kind],
                    social=SocialCostOptions(weights=weights, speed_scaling=speed_scaling, **social))


pytestmark = pytest.mark.skipif(not timed_kernel.AVAILABLE, reason="numba is not importable")


@pytest.mark.parametrize("kind", list(OBJECTS))
@pytest.mark.parametrize("weights", ["ones", "base", "object", "random"])
@pytest.mark.parametrize("speed_scaling", [False, True], ids=["agf", "kirby"])
def test_kernel_equals_numpy_reference(kind, weights, speed_scaling, rng):
    k = arm_geometry(scenario(kind)).num_interest_points
    w = {"ones": None, "base": [1.0] + [0.0] * (k - 1), "object": [0.0] * 3 + [1.0] * (k - 3),
         "random": list(rng.uniform(0, 2, k) * (rng.random(k) < 0.7))}[weights]
    for _ in range(3):
        prediction = random_prediction(rng, people=int(rng.integers(1, 12)), samples=int(rng.integers(1, 40)))
        dut = SocialCost.for_prediction(scenario(kind, w, speed_scaling), prediction)
        q_a, q_b = motions(rng, 150)
        # Times from before the first sample to beyond the horizon (5.0 + ...).
        t_a = rng.uniform(2.0, 7.0, len(q_a))
        t_b = t_a + rng.uniform(0.0, 3.0, len(q_a))
        fast, reference = both(dut, q_a, q_b, t_a, t_b, prediction)
        if w is None or any(w):
            assert (reference > 0).sum() > 20
        np.testing.assert_allclose(fast, reference, rtol=1e-12, atol=1e-13)


def test_kernel_without_threshold_and_with_sample_aligned_times(rng):
    """No threshold (no culling: every person matters everywhere), and times
    that fall exactly on the prediction's samples (the slot is the same in both paths)."""
    prediction = random_prediction(rng, people=5, samples=20, dt=0.25, t0=1.0)
    dut = SocialCost.for_prediction(scenario("bar", threshold=0.0, resolution=0.37), prediction)
    q_a, q_b = motions(rng, 100)
    t_a = 1.0 + 0.25 * rng.integers(-2, 25, len(q_a))
    t_b = t_a + 0.25 * rng.integers(0, 8, len(q_a))
    fast, reference = both(dut, q_a, q_b, t_a, t_b, prediction)
    assert np.all(reference[config_distance(q_a, q_b) > 0] > 0)
    np.testing.assert_allclose(fast, reference, rtol=1e-12)


def test_kernel_equals_numpy_reference_far_from_the_people_and_for_zero_motions(rng):
    prediction = random_prediction(rng, people=6, samples=30)
    dut = SocialCost.for_prediction(scenario(), prediction)
    q_a, q_b = motions(rng, 50)
    t = np.full(len(q_a), 4.0)
    fast, reference = both(dut, q_a, q_a, t, t + 1.0, prediction)  # zero-length motions
    assert np.all(fast == 0) and np.all(reference == 0)
    far_a, far_b = q_a + [100.0, 0.0, 0.0, 0.0], q_b + [100.0, 0.0, 0.0, 0.0]
    fast, reference = both(dut, far_a, far_b, t, t + 1.0, prediction)
    assert np.all(fast == 0) and np.all(reference == 0)
    single = both(dut, q_a[0], q_b[0], 4.0, 5.0, prediction)
    assert np.ndim(single[0]) == 0 and single[0] == pytest.approx(single[1], rel=1e-12, abs=1e-14)


def static_people() -> PeopleState:
    return PeopleState(t=0.0, positions=[[0.0, 0.0], [3.0, 1.0], [1.0, -3.0], [-2.0, 2.0]],
                       headings=[math.pi / 4, math.pi - 1e-9, 2 * math.pi + 2.0, -1.0], velocities=np.zeros((4, 2)),
                       radii=np.full(4, 0.25), names=("a", "b", "c", "d"))


@pytest.mark.parametrize("kind", list(OBJECTS))
@pytest.mark.parametrize("speed_scaling", [False, True], ids=["agf", "kirby"])
def test_a_static_prediction_gives_todays_motion_cost(kind, speed_scaling, rng):
    people = static_people()
    prediction = constant_velocity(people, horizon=4.0)
    assert prediction.static
    s = scenario(kind, speed_scaling=speed_scaling)
    today = SocialCost.from_scenario(s, people=people)
    dut = SocialCost.for_prediction(s, prediction)
    q_a, q_b = motions(rng, 300)
    t_a = rng.uniform(-1.0, 6.0, len(q_a))  # before, within and beyond the horizon
    t_b = t_a + rng.uniform(0.0, 3.0, len(q_a))
    expected = today.motion_cost(q_a, q_b)
    assert (expected > 0).sum() > 50
    for backend in ("numba", "numpy"):
        dut.backend = backend
        np.testing.assert_allclose(dut.timed_motion_cost(q_a, q_b, t_a, t_b, prediction), expected, rtol=1e-12,
                                   atol=1e-14)


def walker_prediction(speed: float, t0: float = 0.0, horizon: float = 6.0) -> Prediction:
    """One person walking +x at ``speed`` along y = 1, at x = -2 at t0, facing +x."""
    state = PeopleState(t=t0, positions=[[-2.0, 1.0]], headings=[0.0], velocities=[[speed, 0.0]], radii=[0.25],
                        names=("walker",))
    return constant_velocity(state, horizon=horizon)


def direct_quadrature(q_a, q_b, t_a, t_b, person_at, space: PersonalSpace, sigma_h: float | None = None,
                      count: int = 400_001) -> float:
    """Msc of a base-only cost by a fine trapezoid rule of the thresholded AGF
    at the base, the person at ``person_at(t) -> (x, y, theta)``."""
    u = np.linspace(0.0, 1.0, count)
    q = q_a + u[:, None] * (q_b - q_a)
    x, y, theta = person_at(t_a + u * (t_b - t_a))
    if sigma_h is not None:
        space = dc.replace(space, sigma_h=sigma_h, sigma_s=space.sigma_s / space.sigma_h * sigma_h,
                           sigma_r=space.sigma_r / space.sigma_h * sigma_h)
    along = np.cos(theta) * (q[:, 0] - x) + np.sin(theta) * (q[:, 1] - y)
    side = np.cos(theta) * (q[:, 1] - y) - np.sin(theta) * (q[:, 0] - x)
    sigma = np.where(along > 0, space.sigma_h, space.sigma_r)
    g = np.exp(-(along**2 / (2 * sigma**2) + side**2 / (2 * space.sigma_s**2)))
    g = np.where(g > space.threshold, g, 0.0)
    return float(np.sum(0.5 * (g[1:] + g[:-1])) / (count - 1) * np.linalg.norm(q_b - q_a))


@pytest.mark.parametrize("speed_scaling", [False, True], ids=["agf", "kirby"])
def test_one_walker_past_a_point_robot_equals_a_direct_quadrature(speed_scaling):
    """The base drives +x along y = 0 from x = -1 to 3 in 4 s while a walker
    overtakes it along y = 1 at 1.5 m/s: the cost follows the walker's
    position at each time (their AGF first ahead of the base, then behind),
    unlike the static cost of the walker where they stand at t = 0."""
    speed = 1.5
    prediction = walker_prediction(speed)
    s = scenario(weights=[1.0, 0.0, 0.0, 0.0, 0.0], speed_scaling=speed_scaling, resolution=0.002)
    dut = SocialCost.for_prediction(s, prediction)
    q_a, q_b = np.array([-1.0, 0.0, 0.3, 1.0]), np.array([3.0, 0.0, 0.3, 1.0])
    t_a, t_b = 0.0, 4.0

    def walker_at(t):
        return -2.0 + speed * t, np.ones_like(t), np.zeros_like(t)

    sigma_h = max(2.0 * speed, 0.5) if speed_scaling else None
    expected = direct_quadrature(q_a, q_b, t_a, t_b, walker_at, PersonalSpace.from_options(s.social), sigma_h)
    assert expected > 0.1
    for backend in ("numba", "numpy"):
        dut.backend = backend
        assert dut.timed_motion_cost(q_a, q_b, t_a, t_b, prediction) == pytest.approx(expected, rel=1e-5)
    standing = direct_quadrature(q_a, q_b, t_a, t_b, lambda t: (np.full_like(t, -2.0), np.ones_like(t),
                                                                np.zeros_like(t)),
                                 PersonalSpace.from_options(s.social), sigma_h)
    assert dut.timed_motion_cost(q_a, q_b, t_a, t_b, prediction) != pytest.approx(standing, rel=0.05)
    # Beyond the horizon (6 s) the walker holds at x = 7: the static cost there.
    held = direct_quadrature(q_a + [6.0, 0, 0, 0], q_b + [6.0, 0, 0, 0], 10.0, 14.0,
                             lambda t: (np.full_like(t, 7.0), np.ones_like(t), np.zeros_like(t)),
                             PersonalSpace.from_options(s.social), sigma_h)
    assert held > 0.1
    assert dut.timed_motion_cost(q_a + [6.0, 0, 0, 0], q_b + [6.0, 0, 0, 0], 10.0, 14.0,
                                 prediction) == pytest.approx(held, rel=1e-5)


def test_speed_scaling_follows_the_predicted_speeds():
    """With ``social.speed_scaling`` each person's sigmas are Kirby's of the
    prediction's speeds: a walker at 1.5 m/s gets sigma_h = 3 m (a larger
    cost ahead of them than the paper's 2 m), a standing person 0.5 m (a
    smaller one)."""
    walking = walker_prediction(1.5)
    standing = walker_prediction(0.0)
    on, off = scenario(speed_scaling=True), scenario(speed_scaling=False)
    np.testing.assert_array_equal(SocialCost.for_prediction(on, walking).sigmas,
                                  speed_scaled_sigmas([1.5], 2.0 / 3.0, 0.5))
    assert SocialCost.for_prediction(off, walking).sigmas is None
    # A motion 3 m ahead of where the walker is at its time.
    q_a, q_b = np.array([2.5, 1.5, 0.3, 1.0]), np.array([2.5, 0.5, 0.3, 1.0])
    t_a, t_b = 1.0, 2.0  # the walker at x = -0.5 .. 1
    walker_on = SocialCost.for_prediction(on, walking).timed_motion_cost(q_a, q_b, t_a, t_b, walking)
    walker_off = SocialCost.for_prediction(off, walking).timed_motion_cost(q_a, q_b, t_a, t_b, walking)
    assert walker_on > 1.2 * walker_off > 0
    q_a, q_b = q_a - [4.0, 0, 0, 0], q_b - [4.0, 0, 0, 0]  # 1.5 m ahead of the standing person
    still_on = SocialCost.for_prediction(on, standing).timed_motion_cost(q_a, q_b, t_a, t_b, standing)
    still_off = SocialCost.for_prediction(off, standing).timed_motion_cost(q_a, q_b, t_a, t_b, standing)
    assert still_off > 0 and still_on < 0.5 * still_off


def test_absent_people_add_nothing(rng):
    """A person absent at every sample costs nothing; one who leaves halfway
    costs what the reference gives and less than if they stayed."""
    base = random_prediction(rng, people=4, samples=30, absent=0.0)
    q_a, q_b = motions(rng, 200)
    t_a = rng.uniform(3.0, 5.0, len(q_a))
    t_b = t_a + rng.uniform(0.5, 2.0, len(q_a))
    s = scenario()
    present = base.present.copy()
    present[:, 1] = False  # never there
    present[15:, 2] = False  # leaves at t = 4.5
    gone = dc.replace(base, present=present)
    without = dc.replace(base, positions=base.positions[:, [0, 2, 3]], headings=base.headings[:, [0, 2, 3]],
                         present=present[:, [0, 2, 3]], radii=base.radii[[0, 2, 3]], speeds=base.speeds[[0, 2, 3]],
                         max_speeds=base.max_speeds[[0, 2, 3]], names=("p0", "p2", "p3"))
    dut, fewer, full = (SocialCost.for_prediction(s, p) for p in (gone, without, base))
    fast, reference = both(dut, q_a, q_b, t_a, t_b, gone)
    np.testing.assert_allclose(fast, reference, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(fast, fewer.timed_motion_cost(q_a, q_b, t_a, t_b, without), rtol=1e-12, atol=1e-13)
    assert np.all(fast <= full.timed_motion_cost(q_a, q_b, t_a, t_b, base) + 1e-12)


def test_timed_kernel_args_call_the_kernel_as_the_tree_does(rng):
    prediction = random_prediction(rng, people=5, samples=25)
    dut = SocialCost.for_prediction(scenario(), prediction)
    q_a, q_b = motions(rng, 40)
    t_a = rng.uniform(3.0, 5.0, len(q_a))
    t_b = t_a + 1.0
    args = dut.timed_kernel_args(prediction)
    assert len(args) == 19 and args[2].dtype == np.bool_ and args[9].dtype == np.int64
    sums, n = timed_kernel.msc_sums_timed(q_a, q_b, t_a, t_b, *args)
    dut.backend = "numba"
    np.testing.assert_array_equal(sums * (config_distance(q_a, q_b) / n), dut.timed_motion_cost(q_a, q_b, t_a, t_b,
                                                                                                  prediction))
    np.testing.assert_array_equal(n, dut.segments(q_a, q_b))


def test_bad_arguments_are_named():
    prediction = walker_prediction(1.0)
    dut = SocialCost.for_prediction(scenario(speed_scaling=True), prediction)
    q = np.zeros(4)
    with pytest.raises(TypeError, match="prediction must be a drake_social.people.Prediction"):
        dut.timed_motion_cost(q, q + 1, 0.0, 1.0, np.zeros((3, 1, 2)))
    with pytest.raises(TypeError, match="scenario"):
        SocialCost.for_prediction("office.yaml", prediction)
    with pytest.raises(ValueError, match=r"t_b must be >= t_a; motion 1"):
        dut.timed_motion_cost(np.zeros((2, 4)), np.ones((2, 4)), [0.0, 2.0], [1.0, 1.0], prediction)
    with pytest.raises(ValueError, match="t_a must be finite"):
        dut.timed_motion_cost(q, q + 1, math.nan, 1.0, prediction)
    with pytest.raises(ValueError, match=r"t_b must be a scalar or \(2,\) times"):
        dut.timed_motion_cost(np.zeros((2, 4)), np.ones((2, 4)), 0.0, [1.0, 2.0, 3.0], prediction)
    with pytest.raises(ValueError, match=r"\(E, 4\)"):
        dut.timed_motion_cost(np.zeros(3), np.ones(3), 0.0, 1.0, prediction)
    with pytest.raises(ValueError, match="finite configurations"):
        dut.timed_motion_cost(q, q + math.inf, 0.0, 1.0, prediction)
    two = constant_velocity(static_people(), horizon=1.0)
    with pytest.raises(ValueError, match="the prediction has 4 people but this cost's per-person variances"):
        dut.timed_motion_cost(q, q + 1, 0.0, 1.0, two)
    slow = dc.replace(prediction, max_speeds=np.array([0.5]))
    with pytest.raises(ValueError, match=r"prediction.max_speeds\[0\] = 0.5 m/s is below"):
        dut.timed_motion_cost(q, q + 1, 0.0, 1.0, slow)
    for backend in ("numba", "numpy"):
        dut.backend = backend
        with pytest.raises(ValueError, match="motion 0 .* is too long to sample"):
            dut.timed_motion_cost(q, q + [1e6, 0, 0, 0], 0.0, 1.0, prediction)
