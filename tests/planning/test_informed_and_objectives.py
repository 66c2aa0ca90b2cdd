"""Informed sampling against an ellipse computed here, the admissible bound
with anisotropic distance weights, and distance weights kept by base-only costs."""

from __future__ import annotations

import copy
import dataclasses as dc
import math

import numpy as np
import pytest

from drake_social.cost import SocialCost
from drake_social.collision.geometric import GeometricChecker
from drake_social.planning.objective import SocialObjective
from drake_social.planning.sampling import EllipseSampler, transverse_diameter
from drake_social.planning.space import ConfigurationSpace
from drake_social.planning.algorithms import base_only_weights, make_objective, plan
from drake_social.scenario import Person, Scenario, World, validate_scenario

PI = math.pi


@pytest.mark.slow
def test_informed_samples_lie_in_the_ellipse_of_start_goal_and_c(tiny_scenario, monkeypatch):
    """The ellipse is computed here from the scenario's start and goal (the
    foci) and the diameter c the planner passed, not with the sampler's own
    ``contains`` (a wrong second focus passed that check)."""
    from drake_social.planning import sampling

    scenario = copy.deepcopy(tiny_scenario)
    scenario.planner = dc.replace(scenario.planner, iterations=400)
    drawn = []
    original = sampling.EllipseSampler.sample

    def recording(self, rng, c):
        q = original(self, rng, c)
        drawn.append((q, c))
        return q

    monkeypatch.setattr(sampling.EllipseSampler, "sample", recording)
    dut = plan(scenario, GeometricChecker(scenario), algorithm="informed_social_rrt_star", seed=5)
    assert dut.success
    f1, f2 = np.array(scenario.start[:2]), np.array(scenario.goal[:2])
    inside = [(q, c) for q, c in drawn if np.isfinite(c)]
    assert len(inside) > 50
    for q, c in inside:
        assert math.dist(q[:2], f1) + math.dist(q[:2], f2) <= max(c, math.dist(f1, f2)) + 1e-9
    # The samples fill the ellipse: some lie near its far end from the start.
    c_last = inside[-1][1]
    assert max(math.dist(q[:2], f1) for q, _ in inside) > 0.8 * (c_last + math.dist(f1, f2)) / 2


def test_ellipse_sampler_fills_exactly_the_independent_ellipse(rng):
    """Rotated foci: every sample inside, and samples reach both vertices of
    the major axis and the minor axis (a wrong axis or focus fails one)."""
    space = ConfigurationSpace(np.array([-20.0, -20.0, -PI, -PI]), np.array([20.0, 20.0, PI, PI]))
    f1, f2 = np.array([1.0, -2.0]), np.array([4.0, 2.0])  # focal distance 5, rotated
    c = 7.0
    dut = EllipseSampler(space, f1, f2)
    xy = np.array([dut.sample(rng, c)[:2] for _ in range(4000)])
    s = np.hypot(*(xy - f1).T) + np.hypot(*(xy - f2).T)
    assert np.all(s <= c + 1e-9)
    centre, axis = (f1 + f2) / 2, (f2 - f1) / 5.0
    along = (xy - centre) @ axis
    across = (xy - centre) @ np.array([-axis[1], axis[0]])
    a, b = c / 2, math.sqrt(c**2 - 25) / 2
    assert along.max() > 0.95 * a and along.min() < -0.95 * a
    assert across.max() > 0.95 * b and across.min() < -0.95 * b
    # Uniform over the area: a quarter of the samples within half the scale.
    assert np.mean((along / a) ** 2 + (across / b) ** 2 <= 0.25) == pytest.approx(0.25, abs=0.03)


def room_with_weights(weights) -> Scenario:
    scenario = Scenario(
        world=World(bounds=[0.0, 0.0, 10.0, 8.0]),
        people=[Person(x=5.0, y=4.0, theta=PI / 4)],
        start=[1.0, 1.0, 0.0, 0.5],
        goal=[8.0, 7.0, 0.3, -0.5],
    )
    scenario.social.length_weight = 0.5
    scenario.planner = dc.replace(scenario.planner, distance_weights=list(weights), near_radius_mode="fixed",
                                  optimize=False)
    validate_scenario(scenario)
    return scenario


@pytest.mark.parametrize("weights", [[2.0, 0.5, 1.0, 1.0], [0.3, 3.0, 0.2, 2.0]])
def test_admissible_bound_holds_with_anisotropic_distance_weights(weights, rng):
    """Every path's base XY length is at most xy_length_bound(its cost), in
    particular paths that move along the lightly weighted axis (where
    max(w_x, w_y) in place of min would give a bound 4 to 10 times too small)."""
    scenario = room_with_weights(weights)
    dut = make_objective(scenario, "social_rrt_star")
    np.testing.assert_array_equal(dut.distance_weights, weights)
    light = int(np.argmin(weights[:2]))
    space = ConfigurationSpace.from_scenario(scenario)
    for trial in range(30):
        n = int(rng.integers(2, 6))
        wp = space.sample_uniform(rng, n)
        if trial < 10:  # straight along the light axis, arm still
            wp = np.repeat(wp[:1], n, axis=0)
            wp[:, light] = np.linspace(space.lower[light], space.upper[light], n)
        cost = float(dut.motion_cost(wp[:-1], wp[1:]).sum())
        xy_length = float(np.hypot(*np.diff(wp[:, :2], axis=0).T).sum())
        assert xy_length <= dut.xy_length_bound(cost) * (1 + 1e-12)
        assert transverse_diameter("admissible", cost, 0.0, dut) == dut.xy_length_bound(cost)
    # Along the light axis the bound is tight when the path costs no social cost.
    far = copy.deepcopy(scenario)
    far.people = []
    flat = make_objective(far, "social_rrt_star")
    a, b = np.zeros(4), np.zeros(4)
    b[light] = 3.0
    assert flat.xy_length_bound(float(flat.motion_cost(a, b)[0])) == pytest.approx(3.0, rel=1e-12)


def test_base_only_cost_keeps_the_distance_weights():
    """``with_weights`` keeps ``distance_weights``; the base-only objective
    integrates over ``ds = ||W dq||`` like the multi-point one."""
    weights = [2.0, 0.5, 1.0, 3.0]
    scenario = room_with_weights(weights)
    full = SocialCost.from_scenario(scenario)
    dut = full.with_weights(base_only_weights(full.geometry.num_interest_points))
    np.testing.assert_array_equal(dut.distance_weights, weights)
    np.testing.assert_array_equal(dut.weights, [1, 0, 0, 0, 0])
    objective = make_objective(scenario, "base_rrt_star")
    assert isinstance(objective, SocialObjective)
    np.testing.assert_array_equal(objective.social.distance_weights, weights)
    np.testing.assert_array_equal(objective.distance_weights, weights)
    # A motion through the person's space: the cost scales with ||W dq||.
    q_a, q_b = np.array([3.0, 3.0, 0.0, 0.0]), np.array([6.0, 5.0, 0.0, 0.0])
    plain = full.with_weights(np.array([1.0, 0, 0, 0, 0]))
    plain.distance_weights = None
    ratio = float(dut.motion_cost(q_a, q_b)) / float(plain.motion_cost(q_a, q_b))
    assert ratio == pytest.approx(math.hypot(2.0 * 3.0, 0.5 * 2.0) / math.hypot(3.0, 2.0), rel=1e-12)


# ---- the objectives' own arithmetic (found untested by the mutation run of objective.py) ----


def test_path_length_objective_is_the_weighted_norm(rng):
    """Cost and bound of the RRT* baseline against ||W dq|| written out; the
    state cost is 0 with the batch shape of q; the XY bound divides by the
    lighter of w_x, w_y and is inf when one is 0."""
    from drake_social.planning.objective import PathLengthObjective

    default = PathLengthObjective()
    assert default.length_weight == 1.0 and default.length_is_cost is True
    np.testing.assert_array_equal(default.distance_weights, np.ones(4))
    assert default.xy_length_bound(3.0) == 3.0
    dut = PathLengthObjective([2.0, 0.5, 1.0, 3.0])
    q_a, q_b = rng.normal(size=(20, 4)), rng.normal(size=(20, 4))
    by_hand = [math.sqrt(sum((w * (b - a)) ** 2 for w, a, b in zip([2.0, 0.5, 1.0, 3.0], qa, qb)))
               for qa, qb in zip(q_a, q_b)]
    np.testing.assert_allclose(dut.motion_cost(q_a, q_b), by_hand, rtol=1e-14)
    np.testing.assert_allclose(default.motion_cost(q_a, q_b), np.linalg.norm(q_b - q_a, axis=1), rtol=1e-14)
    np.testing.assert_array_equal(dut.length_bound(q_a, q_b), dut.motion_cost(q_a, q_b))
    single = dut.motion_cost(np.zeros(4), np.array([1.0, 1.0, 1.0, 1.0]))
    assert single.shape == (1,) and single[0] == pytest.approx(math.sqrt(4 + 0.25 + 1 + 9), rel=1e-15)
    assert dut.xy_length_bound(3.0) == pytest.approx(6.0, rel=1e-15)  # 3 / min(2, 0.5)
    assert PathLengthObjective([0.0, 1.0, 1.0, 1.0]).xy_length_bound(3.0) == math.inf
    for shape in [(4,), (3, 4), (2, 3, 4)]:
        state = dut.state_cost(np.ones(shape))
        assert state.shape == shape[:-1] and np.all(state == 0.0)


def test_social_objective_arithmetic(tiny_scenario):
    """lambda defaults to 0 (the pure social integral, bit for bit the cost's
    Msc), the length term is lambda ||W dq|| and is its lower bound, the
    state cost is S (by hand: the base 1 m in front of the person), the
    length is not the cost, and the XY bound is inf without a length term."""
    cost = SocialCost.from_scenario(tiny_scenario)
    cost.distance_weights = None
    pure = SocialObjective(cost)
    assert pure.length_weight == 0.0 and pure.length_is_cost is False
    np.testing.assert_array_equal(pure.distance_weights, np.ones(4))
    q_a = np.array([[3.0, 2.8, 0.0, 1.0], [1.0, 1.0, 0.0, 0.0], [4.0, 2.0, 0.5, 0.5]])
    q_b = np.array([[5.0, 2.8, 0.5, 1.0], [1.5, 1.0, 0.0, 0.0], [4.0, 2.0, 1.5, -0.5]])
    social = cost.motion_cost(q_a, q_b)
    assert social[0] > 0.5
    np.testing.assert_array_equal(pure.motion_cost(q_a, q_b), social)
    np.testing.assert_array_equal(pure.length_bound(q_a, q_b), 0.0)
    assert pure.xy_length_bound(2.0) == math.inf
    lengths = np.linalg.norm(q_b - q_a, axis=1)
    dut = SocialObjective(cost, length_weight=0.5)
    np.testing.assert_allclose(dut.motion_cost(q_a, q_b), social + 0.5 * lengths, rtol=1e-14)
    np.testing.assert_allclose(dut.length_bound(q_a, q_b), 0.5 * lengths, rtol=1e-14)
    assert np.all(dut.motion_cost(q_a, q_b) >= dut.length_bound(q_a, q_b))
    assert dut.xy_length_bound(2.0) == pytest.approx(4.0, rel=1e-15)  # 2 / (0.5 min(1, 1))
    base = cost.with_weights(np.array([1.0, 0.0, 0.0, 0.0, 0.0]))
    q = np.array([[4.0, 2.8, 0.3, 2.0]])  # 1 m in front of the person at (4, 3.8) facing -y (-1.5708)
    assert SocialObjective(base).state_cost(q)[0] == pytest.approx(math.exp(-1 / 8), rel=1e-9)
    for bad in (-0.5, math.nan):
        with pytest.raises(ValueError, match=rf"^length_weight must be >= 0, got {bad}$"):
            SocialObjective(cost, length_weight=bad)


# ---- the sampler's and the space's own arithmetic (found by the mutation run of sampling.py, space.py) ----


def test_ellipse_contains_against_focal_distances(rng):
    """contains is the sum of the distances to the two foci <= c (plus 1e-9),
    broadcast over any leading shape."""
    space = ConfigurationSpace(np.array([-20.0, -20.0, -PI, -PI]), np.array([20.0, 20.0, PI, PI]))
    f1, f2 = np.array([1.0, -2.0]), np.array([4.0, 2.0])
    dut = EllipseSampler(space, [1, -2], [4, 2])
    xy = rng.uniform(-6, 10, (3, 400, 2))
    s = np.hypot(*np.moveaxis(xy - f1, -1, 0)) + np.hypot(*np.moveaxis(xy - f2, -1, 0))
    got = dut.contains(xy, 7.0)
    assert got.shape == (3, 400)
    np.testing.assert_array_equal(got, s <= 7.0 + 1e-9)
    assert 0.05 < got.mean() < 0.5
    # The ends of the major axis: 1 m beyond each focus along the axis (c = 7, focal distance 5).
    axis = (f2 - f1) / 5.0
    assert dut.contains(f2 + axis, 7.0) and dut.contains(f1 - axis, 7.0)
    assert not dut.contains(f2 + 1.001 * axis, 7.0) and not dut.contains(f1 - 1.001 * axis, 7.0)


def test_ellipse_sampler_thin_ellipse_quadrants_and_room(rng):
    """A thin ellipse (c^2 - f^2 = 0.5: minor semi-axis 0.354 m) stays thin;
    the angle is uniform (a quarter of the samples in each quadrant of the
    ellipse's frame); a room that cuts the ellipse clips every sample."""
    space = ConfigurationSpace(np.array([-20.0, -20.0, -PI, -PI]), np.array([20.0, 20.0, PI, PI]))
    dut = EllipseSampler(space, [0.0, 0.0], [5.0, 0.0])
    c = math.sqrt(25.5)
    xy = np.array([dut.sample(rng, c)[:2] for _ in range(4000)])
    assert np.all(np.hypot(*xy.T) + np.hypot(*(xy - [5.0, 0.0]).T) <= c + 1e-9)
    assert np.abs(xy[:, 1]).max() == pytest.approx(0.5 * math.sqrt(0.5), rel=0.03)
    u, v = xy[:, 0] - 2.5, xy[:, 1]
    for quadrant in [(u > 0) & (v > 0), (u < 0) & (v > 0), (u < 0) & (v < 0), (u > 0) & (v < 0)]:
        assert quadrant.mean() == pytest.approx(0.25, abs=0.03)
    room = ConfigurationSpace(np.array([1.0, -0.1, -PI, -PI]), np.array([20.0, 20.0, PI, PI]))
    clipped = EllipseSampler(room, [0.0, 0.0], [5.0, 0.0])
    xy = np.array([clipped.sample(rng, 6.0)[:2] for _ in range(1000)])
    assert np.all(room.contains(np.column_stack([xy, np.zeros((1000, 2))])))
    assert xy[:, 0].min() < 1.05 and xy[:, 1].min() < -0.09 and xy[:, 0].max() > 5.4


def test_ellipse_sampler_gives_up_after_its_attempts_and_modes_are_named(rng):
    """A room that misses the ellipse: 1000 attempts by default, then an error
    that says so; an unknown informed mode is refused by name."""
    room = ConfigurationSpace(np.array([10.0, 10.0, -PI, -PI]), np.array([11.0, 11.0, PI, PI]))
    dut = EllipseSampler(room, [0.0, 0.0], [1.0, 0.0])
    assert dut.max_attempts == 1000
    with pytest.raises(RuntimeError, match=r"^no ellipse sample inside the room bounds after 1000 attempts$"):
        dut.sample(rng, 1.5)
    with pytest.raises(ValueError, match=r"^unknown informed mode 'papers'; allowed: paper, admissible$"):
        transverse_diameter("papers", 1.0, 1.0, None)


def test_configuration_space_bounds_and_contains(tiny_scenario):
    """from_scenario keeps the base disc inside the room (by hand for the
    tiny room, 8 x 5 m, base radius 0.35 m) and takes the distance weights;
    contains is the closed box, per configuration of a batch; lists become arrays."""
    scenario = dc.replace(tiny_scenario, planner=dc.replace(tiny_scenario.planner, distance_weights=[1, 2, 0.5, 3]))
    dut = ConfigurationSpace.from_scenario(scenario)
    np.testing.assert_allclose(dut.lower, [0.35, 0.35, -PI, -PI], rtol=1e-15)
    np.testing.assert_allclose(dut.upper, [7.65, 4.65, PI, PI], rtol=1e-15)
    np.testing.assert_array_equal(dut.weights, [1.0, 2.0, 0.5, 3.0])
    q = np.array([dut.lower, dut.upper, [4.0, 2.0, 0.0, 0.0], [4.0, 4.7, 0.0, 0.0], [0.3, 2.0, 0.0, 0.0],
                  [4.0, 2.0, 0.0, 3.2]])
    np.testing.assert_array_equal(dut.contains(q), [True, True, True, False, False, False])
    assert dut.contains(q[2]) and not dut.contains(q[3])
    listed = ConfigurationSpace([0.0, 0.0, -1.0, -1.0], [2.0, 1.0, 1.0, 1.0], [1.0, 1.0, 2.0, 2.0])
    assert all(isinstance(a, np.ndarray) for a in (listed.lower, listed.upper, listed.weights))
    samples = listed.sample_uniform(np.random.default_rng(0), 500)
    assert np.all(listed.contains(samples)) and samples[:, 0].max() > 1.9
    assert listed.distance(np.zeros(4), np.array([0.0, 0.0, 1.0, 0.0])) == pytest.approx(2.0, rel=1e-15)


@pytest.mark.parametrize(
    "lower, upper",
    [
        ([0.0, 0.0, -1.0, -1.0], [1.0, 1.0, -2.0, 1.0]),  # upper < lower in one coordinate
        ([0.0, 0.0, -1.0, -1.0], [1.0, 1.0, 1.0, -1.0]),  # an empty interval
        ([0.0], [1.0, 1.0, 1.0, 1.0]),  # a lower bound that would broadcast
        ([0.0, 0.0, 0.0, 0.0], [1.0, 1.0, 1.0, 1.0, 1.0]),
    ],
)
def test_configuration_space_refuses_bad_bounds(lower, upper):
    with pytest.raises(ValueError, match=r"^bounds must be \(4,\) with upper > lower, got "):
        ConfigurationSpace(np.array(lower), np.array(upper))


def test_steer_returns_the_target_itself_within_one_step():
    """Within ``step`` (here: exactly at it) Steer returns q_to bit for bit
    (-2.2 + (2.1 + 2.2) is not 2.1 in floating point), beyond it the point at
    distance ``step`` on the way."""
    space = ConfigurationSpace(np.array([-5.0, -5.0, -PI, -PI]), np.array([5.0, 5.0, PI, PI]))
    q_from, q_to = np.array([-2.2, 0.0, 0.0, 0.0]), np.array([2.1, 0.0, 0.0, 0.0])
    d = float(space.distance(q_from, q_to))
    got = space.steer(q_from, q_to, step=d)
    assert got.tolist() == [2.1, 0.0, 0.0, 0.0] and got is not q_to
    assert (q_from + (q_to - q_from) * (d / d)).tolist() != [2.1, 0.0, 0.0, 0.0]  # what interpolation would give
    np.testing.assert_allclose(space.steer(np.zeros(4), np.array([3.0, 4.0, 0.0, 0.0]), step=1.0),
                               [0.6, 0.8, 0.0, 0.0], rtol=1e-15)
