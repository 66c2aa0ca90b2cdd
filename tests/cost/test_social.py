"""The multi-point social cost S(q), its motion integral Msc and the field G.

The last section holds the details a mutation run of cost/social.py found
untested (the numpy window, its floating-point guards, which backend runs,
the grid's reach, the scenario's options, the shapes of the early returns),
each against numbers computed by hand or by a second method.
"""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drake_social.cost import PersonalSpace, SocialCost, agf, agf_algorithm1, kernel
from drake_social.cost.social import interpolation_segments
from drake_social.kinematics import ArmGeometry, config_distance
from drake_social.scenario.geometry import arm_geometry
from drake_social.scenario import Bar, LShape, Robot, Scenario, load_scenario

PI = math.pi
PAPER = PersonalSpace()

# Three people at awkward poses: rotated by pi/4, facing ~pi, more than a turn.
PEOPLE_3 = np.array([[0.0, 0.0, PI / 4], [3.0, 1.0, PI - 1e-9], [1.0, -3.0, 2 * PI + 2.0]])


def l_shape_cost(**kwargs) -> SocialCost:
    """The 3 m x 2 m L-shape (6 interest points) among three people."""
    geometry = arm_geometry(Scenario(robot=Robot(), object=LShape(lengths=[3.0, 2.0])))
    weights = kwargs.pop("weights", np.array([1.0, 0.5, 1.0, 2.0, 1.0, 1.5]))
    return SocialCost(geometry, PEOPLE_3, weights=weights, **kwargs)


@pytest.fixture
def bar_cost(tiny_scenario) -> SocialCost:
    """The tiny scenario's cost: the 1.5 m bar and one person at (4, 3.8) facing -y."""
    return SocialCost.from_scenario(tiny_scenario)


@pytest.fixture(params=["bar", "L"])
def cost(request, tiny_scenario) -> SocialCost:
    if request.param == "bar":
        return SocialCost.from_scenario(tiny_scenario)
    return l_shape_cost()


def near_people(dut: SocialCost, rng, n: int, spread: float = 3.0) -> np.ndarray:
    """n configurations with the base within ``spread`` metres of some person."""
    who = rng.integers(0, len(dut.people), n)
    xy = dut.people[who, :2] + rng.uniform(-spread, spread, (n, 2))
    return np.column_stack([xy, rng.uniform(-PI, PI, (n, 2))])


def random_edges(dut: SocialCost, rng, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Edges of configuration length 0.2 .. 1.5 (the planning range) near people."""
    q_a = near_people(dut, rng, n)
    d = rng.normal(size=(n, 4))
    d *= rng.uniform(0.2, 1.5, (n, 1)) / np.linalg.norm(d, axis=1, keepdims=True)
    return q_a, q_a + d


# ---- independent references ------------------------------------------------------------


def s_loop(dut: SocialCost, q) -> float:
    """S(q) for one configuration by plain loops over the literal Algorithm 1."""
    pts = dut.geometry.interest_points(np.asarray(q, float))
    total = 0.0
    for j, (x, y) in enumerate(pts):
        for person in dut.people:
            total += dut.weights[j] * agf_algorithm1(float(x), float(y), person, dut.space)
    return total


def reference_integral(dut: SocialCost, q_a, q_b, steps: int = 2000) -> float:
    """Trapezoid rule over ``steps + 1`` linearly interpolated configurations,
    each step weighted by its configuration-space norm (the paper's ds)."""
    t = np.linspace(0.0, 1.0, steps + 1)[:, None]
    qs = q_a + t * (q_b - q_a)
    s = dut(qs)
    ds = config_distance(qs[:-1], qs[1:], dut.distance_weights)
    return float(np.sum(0.5 * ds * (s[1:] + s[:-1])))


def crossing_budget(dut: SocialCost, q_a, q_b, steps: int = 2000) -> float:
    """Largest quadrature error the threshold jumps can explain, for Msc and the reference.

    Each point/person term ``f = g 1[g > tau]`` jumps between 0 and tau where
    it crosses the threshold. On a step of length h where it switches on or
    off, with F the largest f on the step, the exact integral lies in
    ``[0, h F]`` and the trapezoid ``h/2 f_end`` (one end is 0, the other in
    (tau, F]) so the error is at most ``h (F - tau / 2)``; a step with c
    switches gets c times that. Steps without a switch are smooth (the 1% of
    the caller). Msc's steps are sampled densely with its own grid included;
    the reference's steps are its 2,000 intervals.
    """
    tau = dut.space.threshold
    raw = dc.replace(dut.space, threshold=0.0)
    length = float(config_distance(q_a, q_b, dut.distance_weights))
    n = int(dut.segments(q_a, q_b))
    w = dut.weights[:, None]

    def terms(t):  # raw Gaussians (T, J, H) and thresholded terms
        g = agf(dut.geometry.interest_points(q_a + t[:, None] * (q_b - q_a)), dut.people, raw)
        return g > tau, np.where(g > tau, g, 0.0)

    # The reference: every switch is inside one of its own intervals.
    t = np.linspace(0.0, 1.0, steps + 1)
    on, f = terms(t)
    switch = on[1:] != on[:-1]
    peak = np.maximum(f[1:], f[:-1])
    budget = (length / steps) * float(np.sum(w * switch * (peak - tau / 2)))
    # Msc: switches and peaks per step of its grid k / n.
    t = np.union1d(t, np.arange(n + 1) / n)
    on, f = terms(t)
    step = np.minimum((t[:-1] * n + 1e-9).astype(int), n - 1)  # Msc step of each dense interval
    for k in np.unique(step[np.any(on[1:] != on[:-1], axis=(1, 2))]):
        inside = np.flatnonzero(step == k)
        count = (on[inside + 1] != on[inside]).sum(0)
        peak = f[np.r_[inside, inside[-1] + 1]].max(0)
        budget += (length / n) * float(np.sum(w * count * (peak - tau / 2)))
    return budget


def paper_trapezoid(dut: SocialCost, q_a, q_b) -> tuple[float, float, int]:
    """The paper's ``h/2 sum [S(q_k) + S(q_k+1)]`` on Msc's own grid, by loops.

    Returns:
        (value, slack, mixed): ``slack`` bounds how far any quadrature that
        agrees with the rule away from threshold crossings may differ from it:
        on a step where a term switches on or off, both the rule's
        ``h/2 max(g)`` and any integral of the part above tau lie in
        ``[0, h max(g)]``. ``mixed`` counts such (step, term) pairs.
    """
    n = int(dut.segments(q_a, q_b))
    raw = dc.replace(dut.space, threshold=0.0)
    g = np.array(
        [
            [[agf_algorithm1(x, y, p, raw) for p in dut.people] for x, y in dut.geometry.interest_points(q)]
            for q in (q_a + k / n * (q_b - q_a) for k in range(n + 1))
        ]
    )  # (n + 1, J, H) raw Gaussians
    tau = dut.space.threshold
    f = np.where(g > tau, g, 0.0)
    h = float(config_distance(q_a, q_b, dut.distance_weights)) / n
    w = dut.weights[None, :, None]
    mixed = (g[1:] > tau) != (g[:-1] > tau)
    value = float(np.sum(w * 0.5 * h * (f[1:] + f[:-1])))
    slack = float(np.sum(w * h * np.maximum(g[1:], g[:-1]) * mixed))
    return value, slack, int(np.count_nonzero(mixed & (w > 0)))


# ---- S(q) ---------------------------------------------------------------------------------


def test_s_equals_a_plain_loop_over_configurations(cost, rng):
    dut = cost
    q = near_people(dut, rng, 120).reshape(3, 40, 4)
    got = dut(q)
    point = dut.point_costs(q)
    assert got.shape == (3, 40)
    assert point.shape == (3, 40, dut.geometry.num_interest_points)
    for idx in np.ndindex(q.shape[:-1]):
        assert got[idx] == pytest.approx(s_loop(dut, q[idx]), rel=1e-9, abs=1e-12)
        assert dut(q[idx]) == pytest.approx(got[idx], rel=1e-12, abs=1e-15)
        pts = dut.geometry.interest_points(q[idx])
        per_point = [sum(agf_algorithm1(x, y, p, dut.space) for p in dut.people) for x, y in pts]
        np.testing.assert_allclose(point[idx], per_point, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(point @ dut.weights, got, rtol=1e-12, atol=1e-15)
    assert np.count_nonzero(got) > 60  # the configurations really are near people


def test_s_by_hand_base_in_front_of_the_tiny_person(bar_cost):
    # The person at (4, 3.8) faces -y. Base 1 m ahead at (4, 2.8), arm folded so
    # that every other point is far: only the base counts, exp(-1/8).
    dut = bar_cost.with_weights(np.array([1.0, 0, 0, 0, 0]))
    assert dut(np.array([4.0, 2.8, 0.3, 2.0])) == pytest.approx(math.exp(-1 / 8), rel=1e-4)


def test_base_only_weights_equal_an_independent_base_only_cost(cost, rng):
    n = cost.geometry.num_interest_points
    dut = cost.with_weights(np.r_[1.0, np.zeros(n - 1)])
    q = near_people(cost, rng, 300)
    # The base point is (x, y) and does not depend on the arm.
    ref = [sum(agf_algorithm1(x, y, p, cost.space) for p in cost.people) for x, y, _, _ in q]
    np.testing.assert_allclose(dut(q), ref, rtol=1e-9, atol=1e-12)
    assert np.count_nonzero(ref) > 100
    scaled = cost.with_weights(np.r_[2.5, np.zeros(n - 1)])
    np.testing.assert_allclose(scaled(q), 2.5 * np.array(ref), rtol=1e-12)

    # Msc: only the base is tracked, so the step count comes from the base path,
    # and the cost is the trapezoid rule over the base's AGF alone (exactly,
    # unless the base crosses the threshold inside a step; see paper_trapezoid).
    q_a, q_b = random_edges(cost, rng, 40)
    exact = 0
    for a, b in zip(q_a, q_b):
        steps = max(1, math.ceil(math.hypot(*(b[:2] - a[:2])) / dut.resolution - 1e-9))
        assert dut.segments(a, b) == steps
        xy = [a[:2] + k / steps * (b[:2] - a[:2]) for k in range(steps + 1)]
        raw = [[agf_algorithm1(x, y, p, dc.replace(cost.space, threshold=0.0)) for p in cost.people] for x, y in xy]
        g = np.array(raw)  # (steps + 1, H)
        f = np.where(g > cost.space.threshold, g, 0.0).sum(1)
        h = math.dist(a, b) / steps
        ref_msc = h * (f.sum() - 0.5 * (f[0] + f[-1]))
        mixed = (g[1:] > cost.space.threshold) != (g[:-1] > cost.space.threshold)
        slack = h * float(np.sum(np.maximum(g[1:], g[:-1]) * mixed))
        assert dut.motion_cost(a, b) == pytest.approx(ref_msc, rel=1e-9, abs=1e-12 + slack)
        exact += slack == 0 and ref_msc > 0
    assert exact >= 10

    # Turning the arm in place: one step, S constant, Msc = length * S.
    a = np.array([*cost.people[0, :2] + [0.5, 0.5], 0.0, 0.0])
    b = a + [0, 0, 1.0, -2.0]
    assert dut.segments(a, b) == 1
    assert dut(a) > 0.2
    assert dut.motion_cost(a, b) == pytest.approx(math.sqrt(5.0) * dut(a), rel=1e-12)


def test_all_zero_weights_cost_nothing(cost, rng):
    dut = cost.with_weights(np.zeros(cost.geometry.num_interest_points))
    q_a, q_b = random_edges(cost, rng, 20)
    np.testing.assert_array_equal(dut(q_a), 0.0)
    np.testing.assert_array_equal(dut.motion_cost(q_a, q_b), 0.0)
    assert cost(q_a).max() > 0  # the same configurations do cost something with weights


def test_s_is_linear_in_the_weights(cost, rng):
    n = cost.geometry.num_interest_points
    q = near_people(cost, rng, 200)
    w1 = rng.uniform(0, 2, n) * (rng.uniform(size=n) < 0.6)  # with zeros
    w2 = rng.uniform(0, 2, n) * (rng.uniform(size=n) < 0.6)
    s1, s2 = cost.with_weights(w1)(q), cost.with_weights(w2)(q)
    np.testing.assert_allclose(cost.with_weights(w1 + 3.0 * w2)(q), s1 + 3.0 * s2, rtol=1e-12, atol=1e-14)
    # One weight at a time reproduces the per-point costs.
    for j in range(n):
        np.testing.assert_allclose(cost.with_weights(np.eye(n)[j])(q), cost.point_costs(q)[:, j], rtol=1e-12)


def test_msc_is_linear_in_weights_of_the_same_support(cost, rng):
    """With every weight > 0 the step counts are the same, so Msc is exactly linear.

    (Different supports track different points and may step differently; the
    results then agree only to discretisation error.)
    """
    n = cost.geometry.num_interest_points
    q_a, q_b = random_edges(cost, rng, 30)
    w1, w2 = rng.uniform(0.1, 2, n), rng.uniform(0.1, 2, n)
    m1 = cost.with_weights(w1).motion_cost(q_a, q_b)
    m2 = cost.with_weights(w2).motion_cost(q_a, q_b)
    m12 = cost.with_weights(w1 + 2.0 * w2).motion_cost(q_a, q_b)
    np.testing.assert_allclose(m12, m1 + 2.0 * m2, rtol=1e-12, atol=1e-14)
    assert np.count_nonzero(m1) > 10


def test_a_far_person_changes_nothing(cost, rng):
    q_a, q_b = random_edges(cost, rng, 40)
    # Farther than the AGF's longest reach plus the arm and object from every
    # configuration used here: every one of its AGF values is exactly 0.
    far = np.array([[60.0, -40.0, 2.2], [-50.0, 45.0, -7.0]])
    dut = SocialCost(cost.geometry, np.vstack([cost.people, far]), cost.space, cost.weights, cost.resolution)
    np.testing.assert_array_equal(dut(q_a), cost(q_a))
    np.testing.assert_array_equal(dut.point_costs(q_a), cost.point_costs(q_a))
    np.testing.assert_array_equal(dut.motion_cost(q_a, q_b), cost.motion_cost(q_a, q_b))
    x, y = np.meshgrid(np.linspace(-5, 8, 40), np.linspace(-6, 6, 30))
    np.testing.assert_array_equal(dut.field(x, y), cost.field(x, y))
    # ... but the same person near the robot does count.
    near = np.array([[q_a[0, 0] + 1.0, q_a[0, 1], PI]])
    moved = SocialCost(cost.geometry, np.vstack([cost.people, near]), cost.space, cost.weights, cost.resolution)
    assert moved(q_a[0]) > cost(q_a[0]) + 0.2


def test_no_people_cost_nothing(cost, rng):
    dut = SocialCost(cost.geometry, np.zeros((0, 3)), cost.space, cost.weights)
    q_a, q_b = random_edges(cost, rng, 10)
    np.testing.assert_array_equal(dut(q_a), 0.0)
    assert dut(q_a).shape == (10,)
    np.testing.assert_array_equal(dut.motion_cost(q_a, q_b), 0.0)
    assert dut.motion_cost(q_a[0], q_b[0]) == 0.0
    np.testing.assert_array_equal(dut.point_costs(q_a), 0.0)
    np.testing.assert_array_equal(dut.field(np.zeros(3), np.ones(3)), 0.0)


# ---- Msc against a 2,000-step reference -------------------------------------------------------


def test_msc_matches_2000_step_reference_without_threshold(cost, rng):
    """tau = 0 (a smooth integrand): the default resolution is well within 1%."""
    dut = SocialCost(cost.geometry, cost.people, dc.replace(cost.space, threshold=0.0), cost.weights)
    q_a, q_b = random_edges(cost, rng, 60)
    got = dut.motion_cost(q_a, q_b)
    ref = np.array([reference_integral(dut, a, b) for a, b in zip(q_a, q_b)])
    assert np.all(ref > 0)
    np.testing.assert_allclose(got, ref, rtol=0.01)


@pytest.mark.slow
def test_msc_error_at_the_paper_threshold_is_explained_by_the_jumps(cost, rng):
    """tau = 0.2: |Msc - reference| <= 1% + what the threshold jumps can cause.

    Edges that never cross the threshold have a zero budget and must be within
    1%; edges that cross it may be off by about ``w tau h / 2`` per crossing
    and step length h, for Msc and for the reference alike (see crossing_budget).
    """
    dut = cost
    q_a, q_b = random_edges(dut, rng, 80)
    got = dut.motion_cost(q_a, q_b)
    crossed = 0
    for e, (a, b) in enumerate(zip(q_a, q_b)):
        ref = reference_integral(dut, a, b)
        budget = crossing_budget(dut, a, b)
        crossed += budget > 0
        assert abs(got[e] - ref) <= 0.01 * ref + budget + 1e-12, (e, got[e], ref, budget)
    assert crossed > 20  # the test really exercises the jumps
    assert np.count_nonzero(got) > 60


def test_msc_within_1pct_of_reference_at_the_paper_threshold(bar_cost, rng):
    """The issue's check, on this fixed sample of 150 edges.

    Not universal: on 1000-edge samples (bar and L, two seeds, resolution
    0.1 m) 0 to 0.5% of the non-zero edges miss 1% (worst 7.7% relative, on
    edges that graze a threshold contour and cost ~3e-3; absolute error
    < 1.5e-3 against typical edge costs of 1 to 2), partly the 2000-step
    reference's own jump error. Every edge is covered by
    test_msc_error_at_the_paper_threshold_is_explained_by_the_jumps.
    """
    q_a, q_b = random_edges(bar_cost, rng, 150)
    got = bar_cost.motion_cost(q_a, q_b)
    ref = np.array([reference_integral(bar_cost, a, b) for a, b in zip(q_a, q_b)])
    np.testing.assert_allclose(got, ref, rtol=0.01, atol=1e-12)


def test_msc_is_the_trapezoid_rule_with_the_adaptive_step_count(cost, rng):
    """Exactly the paper's rule on Msc's grid wherever no term crosses the threshold
    inside a step; within the crossing slack of it where one does."""
    q_a, q_b = random_edges(cost, rng, 30)
    # Short edges too: their terms often stay inside a zone the whole way.
    q_b[15:] = q_a[15:] + 0.1 * (q_b[15:] - q_a[15:])
    exact = crossed = 0
    for a, b in zip(q_a, q_b):
        n = int(cost.segments(a, b))
        bound = cost.geometry.max_displacement(a, b, active=np.flatnonzero(cost.weights))
        assert n == max(1, math.ceil(bound / cost.resolution - 1e-9))
        by_hand, slack, mixed = paper_trapezoid(cost, a, b)
        assert cost.motion_cost(a, b) == pytest.approx(by_hand, rel=1e-9, abs=1e-12 + slack)
        exact += mixed == 0 and by_hand > 0
        crossed += mixed > 0
    assert exact >= 5 and crossed >= 5


def test_step_count_follows_the_farthest_point(bar_cost):
    q = np.array([2.0, 2.0, 0.3, -0.4])
    assert bar_cost.resolution == 0.1  # the scenario default
    # 1 m of base translation at 0.1 m: 10 steps.
    assert bar_cost.segments(q, q + [0.6, 0.8, 0, 0]) == 10
    # The bar end is hypot(0.5, 0.75) = 0.901 m from the elbow: 0.4 rad -> 0.36 m -> 4 steps.
    assert bar_cost.segments(q, q + [0, 0, 0, 0.4]) == 4
    # The example: the L's far corner (hypot(2.5, 1.5) = 2.92 m from the
    # elbow) swinging 0.1 rad moves 0.29 m: 6 steps, not a fixed N.
    dut = l_shape_cost(resolution=0.05)
    assert dut.segments(q, q + [0, 0, 0, 0.1]) == math.ceil(math.hypot(2.5, 1.5) * 0.1 / 0.05)


def test_msc_sees_a_person_between_two_free_ends(bar_cost):
    # 10 m straight past the tiny person, 1 m in front of them: both ends and a
    # one-step trapezoid cost 0, the adaptive rule does not.
    a = np.array([-1.0, 2.8, -PI / 2, 0.0])
    b = np.array([9.0, 2.8, -PI / 2, 0.0])
    assert bar_cost(a) == 0.0 and bar_cost(b) == 0.0
    got = bar_cost.motion_cost(a, b)
    ref = reference_integral(bar_cost, a, b)
    assert got > 1.0
    assert abs(got - ref) <= 0.01 * ref + crossing_budget(bar_cost, a, b)


def test_zero_length_edge_costs_zero(cost, rng):
    q = near_people(cost, rng, 30)
    assert cost(q).max() > 0.2
    np.testing.assert_array_equal(cost.motion_cost(q, q), 0.0)
    assert cost.motion_cost(q[0], q[0]) == 0.0
    np.testing.assert_array_equal(cost.segments(q, q), 1)


def test_msc_is_symmetric(cost, rng):
    q_a, q_b = random_edges(cost, rng, 60)
    ab = cost.motion_cost(q_a, q_b)
    np.testing.assert_allclose(cost.motion_cost(q_b, q_a), ab, rtol=1e-9, atol=1e-12)
    assert np.count_nonzero(ab) > 40


def test_batched_msc_equals_one_at_a_time(cost, rng):
    q_a, q_b = random_edges(cost, rng, 50)
    q_b[3] = q_a[3]  # a zero-length edge inside the batch
    batch = cost.motion_cost(q_a, q_b)
    assert batch.shape == (50,)
    singles = [cost.motion_cost(a, b) for a, b in zip(q_a, q_b)]
    assert all(np.ndim(s) == 0 for s in singles)
    np.testing.assert_allclose(batch, singles, rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(cost.segments(q_a, q_b), [cost.segments(a, b) for a, b in zip(q_a, q_b)])
    # One start broadcast against many ends, and a batch of one.
    fan = cost.motion_cost(q_a[0], q_b)
    np.testing.assert_allclose(fan, [cost.motion_cost(q_a[0], b) for b in q_b], rtol=1e-12, atol=1e-15)
    assert cost.motion_cost(q_a[:1], q_b[:1]).shape == (1,)
    assert cost.motion_cost(np.zeros((0, 4)), np.zeros((0, 4))).shape == (0,)


def test_distance_weights_scale_ds(cost, rng):
    dut = SocialCost(cost.geometry, cost.people, cost.space, cost.weights, distance_weights=[1, 1, 2, 2])
    q_a = near_people(cost, rng, 20)
    q_b = q_a + rng.normal(size=(20, 4)) * [0, 0, 0.5, 0.5]  # joints only: every ds doubles
    np.testing.assert_allclose(dut.motion_cost(q_a, q_b), 2 * cost.motion_cost(q_a, q_b), rtol=1e-12)
    assert dut.motion_cost(q_a, q_b).max() > 0
    a, b = q_a[0], q_a[0] + [0.3, 0.4, 0.5, 0]
    assert dut.motion_cost(a, b) == pytest.approx(reference_integral(dut, a, b), rel=0.01, abs=1e-12)


# ---- the field, construction ---------------------------------------------------------------------


def test_field_is_the_sum_of_agf_over_people(cost):
    x = np.linspace(-4, 6, 25)
    y = np.linspace(-6, 4, 20)
    dut = cost.field(x[:, None], y[None, :])
    assert dut.shape == (25, 20)
    for i, xi in enumerate(x):
        for k, yk in enumerate(y):
            ref = sum(agf_algorithm1(xi, yk, p, cost.space) for p in cost.people)
            assert dut[i, k] == pytest.approx(ref, rel=1e-9, abs=1e-12)
    assert np.count_nonzero(dut) > 50
    # Independent of the robot and its weights.
    np.testing.assert_array_equal(cost.with_weights(np.zeros(cost.geometry.num_interest_points)).field(x, 0.0),
                                  cost.field(x, 0.0))


def test_from_scenario(tiny_scenario):
    dut = SocialCost.from_scenario(tiny_scenario)
    np.testing.assert_array_equal(dut.weights, np.ones(5))
    np.testing.assert_allclose(dut.people, [[4.0, 3.8, -1.5708]])
    assert dut.space == PersonalSpace(2.0, 4.0 / 3.0, 1.0, 0.2)
    assert dut.resolution == tiny_scenario.social.resolution
    np.testing.assert_array_equal(dut.distance_weights, tiny_scenario.planner.distance_weights)
    base_only = SocialCost.from_scenario(tiny_scenario, weights=[1, 0, 0, 0, 0])
    np.testing.assert_array_equal(base_only.weights, [1, 0, 0, 0, 0])
    scenario = dc.replace(tiny_scenario, social=dc.replace(tiny_scenario.social, weights=[0, 0, 0, 2, 2]))
    np.testing.assert_array_equal(SocialCost.from_scenario(scenario).weights, [0, 0, 0, 2, 2])


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"weights": np.ones(4)}, "weights must have 5 values"),
        ({"weights": [1, 1, -1, 1, 1]}, ">= 0"),
        ({"weights": [1, 1, np.nan, 1, 1]}, "finite"),
        ({"resolution": 0.0}, "resolution"),
        ({"resolution": -1.0}, "resolution"),
    ],
)
def test_bad_construction_is_refused(bar_cost, kwargs, match):
    args = {"weights": None, "resolution": 0.05, **kwargs}
    with pytest.raises(ValueError, match=match):
        SocialCost(bar_cost.geometry, bar_cost.people, bar_cost.space, **args)


# ---- properties ------------------------------------------------------------------------------------

finite = st.floats(allow_nan=False, allow_infinity=False)
angle = st.floats(min_value=-50, max_value=50, allow_nan=False)
person = st.tuples(
    st.floats(min_value=-1e6, max_value=1e6, allow_nan=False),
    st.floats(min_value=-1e6, max_value=1e6, allow_nan=False),
    finite,  # any facing
)
L_GEOMETRY = l_shape_cost().geometry


@pytest.mark.slow
@settings(max_examples=200)
@given(q=st.tuples(finite, finite, finite, finite), people=st.lists(person, min_size=1, max_size=4))
def test_property_s_is_finite_and_non_negative(q, people):
    """Any finite q (up to +-1.8e308, any joint angle) and any person pose."""
    dut = SocialCost(L_GEOMETRY, np.array(people), weights=np.array([1.0, 0.5, 1.0, 2.0, 1.0, 1.5]))
    s = dut(np.array(q))
    assert np.isfinite(s) and s >= 0.0
    assert s <= dut.weights.sum() * len(people) + 1e-12
    assert np.all(np.isfinite(dut.point_costs(np.array(q))))


box = st.floats(min_value=-15, max_value=15, allow_nan=False)


@settings(max_examples=60)
@given(
    q_a=st.tuples(box, box, angle, angle),
    q_b=st.tuples(box, box, angle, angle),
    people=st.lists(st.tuples(box, box, finite), min_size=1, max_size=3),
)
def test_property_msc_is_finite_and_non_negative(q_a, q_b, people):
    """Edges anywhere in a 30 m room with any joint angles in +-50 rad."""
    dut = SocialCost(L_GEOMETRY, np.array(people), resolution=0.1)
    a, b = np.array(q_a), np.array(q_b)
    m = dut.motion_cost(a, b)
    assert np.isfinite(m) and m >= 0.0
    # Bounded by the largest possible S times the edge length.
    assert m <= dut.weights.sum() * len(people) * math.dist(q_a, q_b) * (1 + 1e-12) + 1e-12


def test_non_finite_configurations_are_not_hidden(bar_cost):
    q = np.array([4.0, 3.0, 0.0, np.nan])
    assert np.isnan(bar_cost(q))
    good = np.array([4.0, 3.0, 0.0, 0.0])
    for bad in (q, np.array([np.inf, 3.0, 0.0, 0.0])):
        with pytest.raises(ValueError, match="finite configurations"):
            bar_cost.motion_cost(good, bad)


def test_long_edge_with_subnormal_far_samples(bar_cost):
    """120 m past a person: the far samples' Gaussians are subnormal (~1e-310),
    which must neither warn (pytest turns RuntimeWarning into errors) nor matter."""
    dut = SocialCost(bar_cost.geometry, np.array([[0.0, 0.0, 0.0]]), bar_cost.space, bar_cost.weights)
    a, b = np.array([-60.0, 0.3, 0.0, 0.0]), np.array([60.0, 0.3, 0.0, 0.0])
    got = dut.motion_cost(a, b)
    ref = reference_integral(dut, a, b, steps=24000)  # 5 mm steps
    assert got > 1.0
    assert got == pytest.approx(ref, rel=0.01)
    assert dut.motion_cost(b, a) == pytest.approx(got, rel=1e-9)


def test_culling_keeps_a_person_swept_by_the_object_between_far_ends():
    """Every interest point starts and ends > 5 m from the person (beyond the
    3.59 m reach), but the L's far corner sweeps through the zone on the way."""
    base = l_shape_cost()
    dut = SocialCost(base.geometry, np.array([[0.0, 0.0, 0.0]]), base.space, base.weights)
    a = np.array([6.75, 0.0, 3 * PI / 4, -PI / 2])
    b = np.array([6.75, 0.0, 3 * PI / 4, PI / 2])
    for q in (a, b):
        assert np.hypot(*dut.geometry.interest_points(q).T).min() > 5.0
    assert dut(a) == 0.0 and dut(b) == 0.0
    assert dut.relevant_people(a, b).tolist() == [[True]]
    got = dut.motion_cost(a, b)
    ref = reference_integral(dut, a, b)
    assert ref > 0.1
    assert abs(got - ref) <= 0.01 * ref + crossing_budget(dut, a, b)
    # Far ends and a short motion: culled, and exactly 0.
    assert dut.relevant_people(a, a + [0, 0, 0, 0.05]).tolist() == [[False]]
    assert dut.motion_cost(a, a + [0, 0, 0, 0.05]) == 0.0


# ---- details of the numpy window, the guards, the backend, the grid's reach and the early returns

#: The paper's AGF reaches at most 3.588 m (in front), bit for bit the
#: distance the window and the kernel cull with.
R = PersonalSpace().max_reach
BASE_ONLY = np.array([1.0, 0.0, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def bar(tiny_scenario_path) -> ArmGeometry:
    """The tiny scenario's robot (links 0.6 m, 0.5 m) and its 1.5 m bar."""
    return arm_geometry(load_scenario(tiny_scenario_path))


def test_the_reach_used_here_is_the_paper_front_reach():
    # sigma_h sqrt(-2 ln tau): where exp(-d^2 / (2 sigma_h^2)) falls to tau = 0.2.
    assert R == pytest.approx(2.0 * math.sqrt(-2.0 * math.log(0.2)), rel=1e-15)
    assert math.exp(-R * R / 8.0) == pytest.approx(0.2, rel=1e-14)


# ---- the culling window of the numpy path (SocialCost._window) --------------------------


def test_window_by_hand_for_the_base(bar):
    """Base-only weights, a person at the origin facing +x: the base is the only
    tracked point and moves at most its XY distance, so for a motion of XY
    length L whose ends are A and B from the person the window is
    [(A - R) / L, 1 - (B - R) / L], clipped to [0, 1]. The arm points at the
    person in the first motion: were the unweighted points tracked too, it
    would start earlier (mutants _window 13, 15), and every clipping and
    branch of the window shows in one of the motions (45, 52, 56, 58, 65,
    67, 74, 79, 81, 82, 86, 87)."""
    dut = SocialCost(bar, np.array([[0.0, 0.0, 0.0], [50.0, 50.0, 1.0]]), weights=BASE_ONLY)
    q_a = np.array([
        [-10.0, 0.5, 0.0, 0.0],  # 20 m past the person, arm stretched towards them
        [R + 0.5, 0.0, 0.3, 0.2],  # 0.8 m towards the person, ending 0.3 m inside the reach
        [R - 0.3, 0.0, 0.3, 0.2],  # the same motion backwards
        [1.0, 0.0, 0.0, 0.0],  # the arm turns in place, the base 1 m from the person
        [R, 0.0, 0.0, 0.0],  # the arm turns in place, the base exactly at the reach
    ])
    q_b = np.array([
        [10.0, 0.5, 0.0, 0.0],
        [R - 0.3, 0.0, 0.3, 0.2],
        [R + 0.5, 0.0, 0.3, 0.2],
        [1.0, 0.0, 1.0, -2.0],
        [R, 0.0, 1.0, -2.0],
    ])
    span = np.hypot(*(q_b[:, :2] - q_a[:, :2]).T)
    np.testing.assert_allclose(span, [20.0, 0.8, 0.8, 0.0, 0.0], atol=1e-15)
    relevant, t0, t1 = dut._window(q_a, q_b, span)
    a = math.hypot(10.0, 0.5) - R
    np.testing.assert_array_equal(relevant, [[True, False]] * 5)
    np.testing.assert_allclose(t0[:, 0], [a / 20, 0.5 / 0.8, 0.0, 0.0, 0.0], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(t1[:, 0], [1 - a / 20, 1.0, 1 - 0.5 / 0.8, 1.0, 1.0], rtol=1e-12, atol=1e-12)
    # The far person (70 m away) is culled, and its window is clipped into [0, 1]
    # (unclipped: t0 = (A - R) / L > 1 and t1 < 0 on the moving motions).
    np.testing.assert_array_equal(t0[:3, 1], 1.0)
    np.testing.assert_array_equal(t1[:3, 1], 0.0)
    assert np.all((0 <= t0) & (t0 <= 1) & (0 <= t1) & (t1 <= 1))
    assert np.all(t0[relevant] <= t1[relevant])
    # The window is sound: along each moving motion the base's term is 0 outside it.
    t = np.linspace(0.0, 1.0, 4001)
    for e in range(3):
        base = q_a[e, :2] + t[:, None] * (q_b[e, :2] - q_a[e, :2])
        on = agf(base, dut.people[:1], dut.space)[:, 0] > 0
        assert on.any()
        assert np.all((t[on] >= t0[e, 0] - 1e-12) & (t[on] <= t1[e, 0] + 1e-12))


def test_relevant_people_track_only_the_weighted_points(bar):
    """The bar reaches into the person's zone, the base stays 0.3 m beyond the
    reach: with base-only weights the person is culled (and costs nothing),
    with all weights it matters (mutants _window 13, 15 track every point)."""
    person = np.array([[0.0, 0.0, 0.0]])
    a = np.array([R + 0.3, 0.0, PI, 0.0])  # arm and bar pointing at the person
    b = a + [0.0, 0.1, 0.0, 0.0]
    base_only = SocialCost(bar, person, weights=BASE_ONLY)
    every_point = SocialCost(bar, person)
    assert np.hypot(*bar.interest_points(a)[1:].T).max() < R - 0.25  # every other point is inside the zone
    assert base_only.relevant_people(a, b).tolist() == [[False]]
    assert every_point.relevant_people(a, b).tolist() == [[True]]
    for backend in ("numpy", "numba"):
        base_only.backend = every_point.backend = backend
        assert base_only.motion_cost(a, b) == 0.0
        assert every_point.motion_cost(a, b) > 0.1


# ---- floating-point guards of the numpy path ------------------------------------------------


def test_numpy_path_turning_in_place_at_and_inside_the_reach(bar):
    """Base-only weights, only the arm moves: the base's Gaussian is the same at
    both ends of the one step (hi - lo = 0 in the crossing formula, a division
    by zero that must stay silent: mutants _integrate 110, 113), Msc is the
    motion's length times S. With the base exactly at the reach the window
    divides 0 by the zero span (_window 37, 39; 51 and 64 divide there too)."""
    dut = SocialCost(bar, np.array([[0.0, 0.0, 0.0]]), weights=BASE_ONLY)
    dut.backend = "numpy"
    a = np.array([1.0, 0.0, 0.0, 0.0])
    b = a + [0.0, 0.0, 1.0, -2.0]
    assert dut.segments(a, b) == 1
    s = math.exp(-1.0 / 8.0)  # 1 m in front of a person with sigma_h = 2
    assert dut(a) == pytest.approx(s, rel=1e-14)
    assert dut.motion_cost(a, b) == pytest.approx(math.sqrt(5.0) * s, rel=1e-12)
    at_reach = np.array([R, 0.0, 0.0, 0.0])  # S is 0 or 0.2 there, by rounding
    assert dut(at_reach) in (0.0, pytest.approx(0.2, rel=1e-12))
    got = dut.motion_cost(at_reach, at_reach + [0.0, 0.0, 1.0, -2.0])
    assert got == pytest.approx(math.sqrt(5.0) * dut(at_reach), rel=1e-12, abs=0.0)


def test_numpy_path_without_threshold_far_from_the_person(bar):
    """tau = 0 (no culling: every sample of a 240 m motion is walked), the base
    passing 0.3 m beside a person facing +x: far samples are exactly 0, so the
    crossing formula computes 0 * 0 / 0 there, which must stay silent
    (mutants _integrate 111, 114). The value is the closed form
    ``exp(-y^2 / (2 sigma_s^2)) (sigma_h + sigma_r) sqrt(pi / 2)``."""
    space = dc.replace(PersonalSpace(), threshold=0.0)
    dut = SocialCost(bar, np.array([[0.0, 0.0, 0.0]]), space, weights=BASE_ONLY)
    a, b = np.array([-120.0, 0.3, 0.0, 0.0]), np.array([120.0, 0.3, 0.0, 0.0])
    assert dut(a) == 0.0 and dut(b) == 0.0  # exp underflows: exactly 0 far away
    expected = math.exp(-0.09 / (2 * space.sigma_s**2)) * (space.sigma_h + space.sigma_r) * math.sqrt(PI / 2)
    for backend in ("numpy", "numba"):
        dut.backend = backend
        assert dut.motion_cost(a, b) == pytest.approx(expected, rel=1e-4)


def test_numpy_path_with_a_narrow_personal_space(bar):
    """A personal space of sigma = 0.035 m in every direction (a 60th of the
    paper's), the person standing at the bar's end, the robot moving 4 cm
    sideways. The base, 1.33 m = 38 sigma away, has subnormal Gaussians
    (~1e-314) at both ends: the crossing formula, computed for every term and
    discarded for this one, divides tau^2 by their difference and overflows,
    which must stay silent (mutants _integrate 112, 115). Only the bar end
    counts: one step, both ends above tau, Msc = h (1 + exp(-h^2 / (2 sigma^2))) / 2."""
    sigma = 0.035
    dut = SocialCost(bar, np.array([[1.1, 0.75, 0.0]]), PersonalSpace(sigma, sigma, sigma, 0.2))
    a = np.zeros(4)
    np.testing.assert_allclose(bar.interest_points(a)[4], [1.1, 0.75], atol=1e-15)
    h = 0.04
    b = a + h * np.array([-0.75, 1.1, 0.0, 0.0]) / math.hypot(0.75, 1.1)
    assert dut.segments(a, b) == 1
    expected = 0.5 * h * (1.0 + math.exp(-h * h / (2 * sigma**2)))
    for backend in ("numpy", "numba"):
        dut.backend = backend
        assert dut.motion_cost(a, b) == pytest.approx(expected, rel=1e-12)


# ---- which backend runs -----------------------------------------------------------------------


@pytest.mark.skipif(not kernel.AVAILABLE, reason="numba is not importable")
def test_the_compiled_kernel_runs_exactly_when_the_backend_is_numba(bar, monkeypatch, rng):
    """The default backend is the kernel where numba imports (mutants __init__
    66, 67, 69), and motion_cost calls it for "numba" only (motion_cost 53 to
    55); both give the same costs."""
    dut = SocialCost(bar, np.array([[4.0, 3.8, -PI / 2], [1.0, 1.0, 0.5]]))
    assert dut.backend == "numba"
    calls = []
    compiled = kernel.msc_sums

    def spy(*args):
        calls.append(len(args[0]))
        return compiled(*args)

    monkeypatch.setattr(kernel, "msc_sums", spy)
    q_a = np.column_stack([rng.uniform(0, 6, (30, 2)), rng.uniform(-PI, PI, (30, 2))])
    q_b = q_a + rng.normal(size=(30, 4))
    fast = dut.motion_cost(q_a, q_b)
    assert calls == [30]
    dut.backend = "numpy"
    reference = dut.motion_cost(q_a, q_b)
    assert calls == [30]
    assert np.count_nonzero(reference) > 5
    np.testing.assert_allclose(fast, reference, rtol=1e-12, atol=1e-13)


# ---- the compiled kernel's people grid ---------------------------------------------------------


def test_grid_point_reach_is_the_farthest_weighted_point_from_the_base(bar, rng):
    """The culling radius adds the largest distance of a weighted point from
    the base: 0 for base-only weights (mutant _people_grid 14 takes every
    point), and for all points the stretched arm's bar end, reached but not
    exceeded over random configurations."""
    people = np.array([[0.0, 0.0, 0.0]])
    q = np.column_stack([rng.uniform(-5, 5, (20000, 2)), rng.uniform(-PI, PI, (20000, 2))])
    assert SocialCost(bar, people, weights=BASE_ONLY)._people_grid()[0] == 0.0
    point_reach = SocialCost(bar, people)._people_grid()[0]
    farthest = np.hypot(*(bar.interest_points(q) - q[:, None, :2]).transpose(2, 0, 1)).max()
    assert farthest <= point_reach + 1e-12
    assert farthest == pytest.approx(point_reach, abs=2e-3)
    # The stretched arm: 0.6 + hypot(0.5, 0.75), the bar end 0.75 m to the side of the gripper.
    assert point_reach == pytest.approx(0.6 + math.hypot(0.5, 0.75), rel=1e-12)


def test_grid_is_built_once_per_crowd(bar):
    """The grid is cached while the people stay the same (mutants _people_grid
    2, 7, 8, 35 rebuild it on every call) and rebuilt when they change."""
    dut = SocialCost(bar, np.array([[0.0, 0.0, 0.0], [5.0, 1.0, 2.0]]))
    grid = dut._people_grid()
    assert dut._people_grid() is grid
    dut.people = np.array([[20.0, -3.0, 0.0]])
    moved = dut._people_grid()
    assert moved is not grid
    assert (moved[2], moved[3]) == (20.0, -3.0)  # the grid's corner is the one person


@pytest.mark.skipif(not kernel.AVAILABLE, reason="numba is not importable")
def test_kernel_culls_correctly_for_an_object_longer_than_the_reach(rng):
    """An 8 m bar: its end is farther from the base (4.6 m) than the AGF
    reaches (3.6 m). The kernel's grid cells (reach plus that distance) and
    culling must still keep every person that matters (mutant _people_grid 21
    makes the cell side negative); the numpy path has no grid."""
    geometry = arm_geometry(Scenario(object=Bar(length=8.0)))
    people = np.column_stack([rng.uniform(-10, 10, (12, 2)), rng.uniform(-PI, PI, 12)])
    dut = SocialCost(geometry, people)
    assert dut._people_grid()[0] > dut.space.max_reach
    q_a = np.column_stack([rng.uniform(-10, 10, (60, 2)), rng.uniform(-PI, PI, (60, 2))])
    q_b = q_a + rng.normal(size=(60, 4))
    fast = dut.motion_cost(q_a, q_b)
    dut.backend = "numpy"
    reference = dut.motion_cost(q_a, q_b)
    assert np.count_nonzero(reference) > 30
    np.testing.assert_allclose(fast, reference, rtol=1e-12, atol=1e-13)


# ---- construction, early returns, messages ------------------------------------------------------


def test_from_scenario_takes_the_scenario_variances_and_resolution(tiny_scenario):
    """Mutants from_scenario 10 and 12 drop these and keep the defaults."""
    social = dc.replace(tiny_scenario.social, sigma_h=1.5, side_ratio=0.6, rear_ratio=0.4, threshold=0.3,
                        resolution=0.07)
    dut = SocialCost.from_scenario(dc.replace(tiny_scenario, social=social))
    space = dut.space
    assert (space.sigma_h, space.sigma_s, space.sigma_r, space.threshold) == pytest.approx((1.5, 0.9, 0.6, 0.3), rel=1e-15)
    assert dut.resolution == 0.07
    # 1 m of base translation at 0.07 m per step.
    assert dut.segments(np.zeros(4), np.array([0.6, 0.8, 0.0, 0.0])) == 15


def test_early_returns_keep_the_shapes(bar):
    """No people: S has the batch shape of q (mutant __call__ 12 keeps only the
    first axis), and a single motion's cost is 0-d (motion_cost 43)."""
    dut = SocialCost(bar, np.zeros((0, 3)))
    assert dut(np.zeros(4)).shape == ()
    assert dut(np.zeros((2, 3, 4))).shape == (2, 3)
    single = dut.motion_cost(np.zeros(4), np.ones(4))
    assert np.ndim(single) == 0 and single == 0.0
    assert SocialCost(bar, np.array([[0.0, 0.0, 0.0]]), weights=np.zeros(5))(np.zeros((2, 3, 4))).shape == (2, 3)


def test_non_finite_messages_name_the_culprits(bar):
    """interpolation_segments lists the non-finite bounds (mutants 9, 10, 11);
    motion_cost says what it needs (31)."""
    with pytest.raises(ValueError, match=r"^motions need finite configurations \(and ends whose difference does "
                                         r"not overflow\); displacement bounds: \[nan inf\]$"):
        interpolation_segments(np.array([0.3, np.nan, 2.0, np.inf]), 0.1)
    np.testing.assert_array_equal(interpolation_segments(np.array([0.0, 0.3, 0.31]), 0.1), [1, 3, 4])
    dut = SocialCost(bar, np.array([[0.0, 0.0, 0.0]]))
    with pytest.raises(ValueError, match=r"^motion_cost needs finite configurations$"):
        dut.motion_cost(np.zeros(4), np.array([0.0, np.nan, 0.0, 0.0]))


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_a_window_starting_at_the_motions_end_stays_within_the_motion(bar, backend):
    """A point that reaches the personal space's edge only at q_b (t0 = 1):
    the window is the last step, never a sample beyond q_b, so the motion
    costs (about) nothing, as a dense reference integral of its own says.
    The two cases of the mutation run (a sample past q_b cost 0.02: numpy
    in the first, the kernel, out of its buffers, in the second)."""
    for x_a, x_b in ((R + 0.3, R), (R + 1e-9 + 1.0563545150501672, R + 1e-9)):
        cost = SocialCost(bar, np.array([[0.0, 0.0, 0.0]]), weights=BASE_ONLY)
        cost.backend = backend
        q_a, q_b = np.array([x_a, 0.0, 0.0, 0.0]), np.array([x_b, 0.0, 0.0, 0.0])
        got = float(cost.motion_cost(q_a, q_b))
        # Independent: 20,001 samples of S along the motion, trapezoid rule.
        t = np.linspace(0.0, 1.0, 20001)
        s = cost(q_a + t[:, None] * (q_b - q_a))
        ref = float(np.sum(0.5 * (s[1:] + s[:-1])) * (x_a - x_b) / 20000)
        assert ref < 1e-6 and got == pytest.approx(ref, abs=1e-4)
