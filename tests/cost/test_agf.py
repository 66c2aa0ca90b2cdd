"""Kirby's AGF (the paper's Algorithm 1): hand values, reach, symmetry, wrap-around."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drake_social.cost import PersonalSpace, agf, agf_algorithm1
from drake_social.scenario import SocialCostOptions

PAPER = PersonalSpace()  # sigma_h = 2, sigma_s = 4/3, sigma_r = 1, tau = 0.2
LN5 = math.log(5.0)  # exp(-Q) = 0.2  <=>  Q = ln 5


def vectorised(x: float, y: float, person, space: PersonalSpace = PAPER) -> float:
    """``agf`` for one point and one person, as a float."""
    return float(agf(np.array([x, y]), np.array(person, dtype=float), space)[0])


BOTH = pytest.mark.parametrize("dut", [vectorised, agf_algorithm1], ids=["agf", "agf_algorithm1"])


def algorithm1_b_sign(x, y, person, space: PersonalSpace, b_sign: float) -> float:
    """Algorithm 1 without threshold, with the sign of b as a parameter.

    Written out again here (not calling the library) so the tests can show that
    a wrong sign of b gives a different value at a rotated person.
    """
    x_i, y_i, theta = person
    alpha = math.remainder(math.atan2(y - y_i, x - x_i) - theta + math.pi / 2, 2 * math.pi)
    sigma = space.sigma_r if alpha <= 0 else space.sigma_h
    a = math.cos(theta) ** 2 / (2 * sigma**2) + math.sin(theta) ** 2 / (2 * space.sigma_s**2)
    b = b_sign * (math.sin(2 * theta) / (4 * sigma**2) - math.sin(2 * theta) / (4 * space.sigma_s**2))
    c = math.sin(theta) ** 2 / (2 * sigma**2) + math.cos(theta) ** 2 / (2 * space.sigma_s**2)
    dx, dy = x - x_i, y - y_i
    return math.exp(-(a * dx * dx + 2 * b * dx * dy + c * dy * dy))


# ---- hand values at a rotated person ---------------------------------------------
#
# Person at (1, 2) facing theta = pi/4. With sigma_h = 2, sigma_s = 4/3, sigma_r = 1:
#   front (sigma = 2): a = c = (1/8 + 9/32)/2 = 13/64, b = 1/16 - 9/64 = -5/64
#   rear  (sigma = 1): a = c = (1/2 + 9/32)/2 = 25/64, b = 1/4  - 9/64 =  7/64
# and Q = a dx^2 + 2 b dx dy + c dy^2:
#   (+1, +1) ahead:       Q = 26/64 - 10/64 = 1/4     (wrong sign of b: 36/64)
#   (+1, -1) right side:  Q = 50/64 - 14/64 = 36/64   (alpha = 0 -> rear branch; wrong b: 1)
#   (-1, -1) behind:      Q = 50/64 + 14/64 = 1       (wrong b: 36/64)
#   (+2, +0.5) ahead-right: u^2 = 25/8, v^2 = 9/8, Q = (25/8)/8 + (9/8)(9/32) = 181/256
HAND = [
    ((1.0, 1.0), 1 / 4, 36 / 64),
    ((1.0, -1.0), 36 / 64, 1.0),
    ((-1.0, -1.0), 1.0, 36 / 64),
    ((2.0, 0.5), 181 / 256, None),
]


@BOTH
@pytest.mark.parametrize("offset, q_hand, q_wrong_b", HAND)
def test_hand_values_at_a_person_facing_pi_over_4(dut, offset, q_hand, q_wrong_b):
    person = (1.0, 2.0, math.pi / 4)
    x, y = person[0] + offset[0], person[1] + offset[1]
    expected = math.exp(-q_hand)
    assert expected > 0.2
    assert dut(x, y, person, PAPER) == pytest.approx(expected, rel=1e-12)
    # The same person described with theta + 2 pi and theta - 4 pi.
    for turns in (1, -2):
        wrapped = (person[0], person[1], person[2] + 2 * math.pi * turns)
        assert dut(x, y, wrapped, PAPER) == pytest.approx(expected, rel=1e-9)
    # The independent re-derivation agrees, and flipping b would not.
    assert algorithm1_b_sign(x, y, person, PAPER, +1) == pytest.approx(expected, rel=1e-12)
    if q_wrong_b is not None:
        wrong = algorithm1_b_sign(x, y, person, PAPER, -1)
        assert wrong == pytest.approx(math.exp(-q_wrong_b), rel=1e-12)
        assert abs(wrong - expected) > 0.1


@BOTH
def test_hand_value_at_a_person_facing_3pi_over_4(dut):
    # Facing (-1, 1)/sqrt2; the point 0.8 sqrt2 m straight ahead: Q = 1.28 / 8.
    person = (-3.0, 0.5, 3 * math.pi / 4)
    assert dut(-3.8, 1.3, person, PAPER) == pytest.approx(math.exp(-0.16), rel=1e-12)
    # 0.8 sqrt2 m straight behind: Q = 1.28 / 2.
    assert dut(-2.2, -0.3, person, PAPER) == pytest.approx(math.exp(-0.64), rel=1e-12)


@BOTH
def test_value_at_the_person_is_one(dut):
    assert dut(2.0, -1.0, (2.0, -1.0, 0.7), PAPER) == 1.0


# ---- reach of the threshold -------------------------------------------------------


def test_reach_of_the_paper_parameters():
    dut = PAPER
    # exp(-d^2 / (2 sigma^2)) = 0.2  <=>  d = sigma sqrt(2 ln 5)
    assert dut.reach("front") == pytest.approx(2.0 * math.sqrt(2 * LN5), rel=1e-12)
    assert dut.reach("front") == pytest.approx(3.59, abs=0.005)  # the paper's "about 3.60 m"
    assert dut.reach("rear") == pytest.approx(1.79, abs=0.005)
    assert dut.reach("side") == pytest.approx(4 / 3 * math.sqrt(2 * LN5), rel=1e-12)
    assert PersonalSpace(threshold=0.0).reach() == math.inf


def test_personal_space_from_options_uses_the_ratios():
    dut = PersonalSpace.from_options(SocialCostOptions())
    assert (dut.sigma_h, dut.sigma_s, dut.sigma_r, dut.threshold) == pytest.approx((2.0, 4 / 3, 1.0, 0.2))
    dut = PersonalSpace.from_options(SocialCostOptions(sigma_h=3.0, side_ratio=0.5, rear_ratio=0.25, threshold=0.1))
    assert (dut.sigma_h, dut.sigma_s, dut.sigma_r, dut.threshold) == pytest.approx((3.0, 1.5, 0.75, 0.1))


@BOTH
@pytest.mark.parametrize("theta", [0.0, math.pi / 4, -2.0, math.pi, 2.5 + 2 * math.pi])
@pytest.mark.parametrize("direction, hand_reach", [("front", 3.5882), ("rear", 1.7941), ("side", 2.3922)])
def test_threshold_reach_and_exact_zero_beyond(dut, theta, direction, hand_reach):
    person = (0.5, -1.5, theta)
    angle = {"front": theta, "rear": theta + math.pi, "side": theta + math.pi / 2}[direction]
    reach = PAPER.reach(direction)
    assert reach == pytest.approx(hand_reach, abs=1e-4)

    def at(d):
        return dut(person[0] + d * math.cos(angle), person[1] + d * math.sin(angle), person, PAPER)

    inside = at(reach - 1e-6)
    assert 0.2 < inside < 0.2 + 1e-5  # the value just inside is the threshold
    for d in (reach + 1e-6, reach + 0.01, 2 * reach, 50.0, 1e6):
        assert at(d) == 0.0


def test_exactly_zero_outside_the_zone_and_above_threshold_inside(rng):
    """The zone is the union of two half-ellipses; check it on random points."""
    people = np.array([[1.0, 1.0, 0.3], [-2.0, 0.5, -2.8], [0.0, -2.0, 7.5]])
    pts = rng.uniform(-7, 7, size=(20000, 2))
    dut = agf(pts, people, PAPER)
    for h, (px, py, th) in enumerate(people):
        dx, dy = pts[:, 0] - px, pts[:, 1] - py
        u = math.cos(th) * dx + math.sin(th) * dy
        v = -math.sin(th) * dx + math.cos(th) * dy
        q = u**2 / (2 * np.where(u > 0, 2.0, 1.0) ** 2) + v**2 / (2 * (4 / 3) ** 2)
        outside, inside = q > LN5 + 1e-9, q < LN5 - 1e-9
        assert outside.sum() > 1000 and inside.sum() > 1000
        assert np.all(dut[outside, h] == 0.0)
        assert np.all(dut[inside, h] > 0.2)
        np.testing.assert_allclose(dut[inside, h], np.exp(-q[inside]), rtol=1e-12)


# ---- symmetry and agreement ---------------------------------------------------------


@BOTH
def test_left_right_symmetry_about_the_facing_direction(dut, rng):
    for _ in range(300):
        px, py = rng.uniform(-3, 3, 2)
        theta = rng.uniform(-10, 10)
        forward, left = rng.uniform(-4, 4), rng.uniform(0, 3)
        f = np.array([math.cos(theta), math.sin(theta)])
        n = np.array([-f[1], f[0]])
        p_left = np.array([px, py]) + forward * f + left * n
        p_right = np.array([px, py]) + forward * f - left * n
        a = dut(*p_left, (px, py, theta), PAPER)
        b = dut(*p_right, (px, py, theta), PAPER)
        if abs(a - 0.2) > 1e-9:  # away from the threshold jump
            assert a == pytest.approx(b, rel=1e-9, abs=1e-12)


@pytest.mark.slow
def test_vectorised_equals_algorithm1_on_random_points_and_people(rng):
    near_pi = [math.pi, -math.pi, math.pi - 1e-12, -math.pi + 1e-12, math.pi + 1e-9, 3 * math.pi]
    thetas = np.concatenate(
        [
            rng.uniform(-math.pi, math.pi, 40),
            rng.uniform(2 * math.pi, 40.0, 20),  # more than one turn
            rng.uniform(-40.0, -2 * math.pi, 10),
            near_pi,
            [0.0, math.pi / 2, -math.pi / 2, 1000.0],
        ]
    )
    people = np.column_stack([rng.uniform(-3, 3, len(thetas)), rng.uniform(-3, 3, len(thetas)), thetas])
    pts = rng.uniform(-6, 6, size=(25, 40, 2))
    # Awkward points too: at a person, straight ahead/behind/beside (alpha = pi/2, -pi/2, pi, 0).
    extra = []
    for px, py, th in people[:12]:
        for ang in (0.0, math.pi, math.pi / 2, -math.pi / 2):
            extra.append([px + 1.5 * math.cos(th + ang), py + 1.5 * math.sin(th + ang)])
        extra.append([px, py])
    dut = agf(pts, people, PAPER)
    assert dut.shape == (25, 40, len(people))
    dut_extra = agf(np.array(extra), people, PAPER)
    checked = 0
    for got, points in ((dut.reshape(-1, len(people)), pts.reshape(-1, 2)), (dut_extra, np.array(extra))):
        for k, (x, y) in enumerate(points):
            for h, person in enumerate(people):
                ref = agf_algorithm1(x, y, person, PAPER)
                raw = algorithm1_b_sign(x, y, person, PAPER, +1)
                if abs(raw - 0.2) < 1e-9:
                    continue  # rounding may put either side of the jump
                assert got[k, h] == pytest.approx(ref, rel=1e-9, abs=1e-12)
                checked += 1
    assert checked > 0.99 * (dut.size + dut_extra.size)
    assert np.count_nonzero(dut) > 1000  # many points are inside some zone


def test_periodic_in_theta(rng):
    people = np.column_stack([rng.uniform(-2, 2, (30, 2)), rng.uniform(-math.pi, math.pi, 30)])
    pts = rng.uniform(-4, 4, (500, 2))
    dut = agf(pts, people, PAPER)
    for turns in (1, -1, 7):
        shifted = people + [0, 0, 2 * math.pi * turns]
        np.testing.assert_allclose(agf(pts, shifted, PAPER), dut, rtol=1e-9, atol=1e-12)


# ---- shapes and inputs --------------------------------------------------------------


def test_shapes_and_empty_people():
    people = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 1.0, 2.0]])
    assert agf(np.zeros((2, 5, 2)), people, PAPER).shape == (2, 5, 3)
    assert agf(np.zeros(2), people, PAPER).shape == (3,)
    assert agf(np.zeros((4, 2)), np.zeros((0, 3)), PAPER).shape == (4, 0)
    assert agf(np.zeros((4, 2)), [0.0, 0.0, 0.0], PAPER).shape == (4, 1)
    np.testing.assert_array_equal(agf(np.zeros((4, 2)), people, PAPER)[:, 0], 1.0)


def test_other_threshold_and_sigmas():
    space = PersonalSpace(sigma_h=1.0, sigma_s=0.5, sigma_r=0.25, threshold=0.0)
    person = (0.0, 0.0, 0.0)
    assert vectorised(1.0, 0.0, person, space) == pytest.approx(math.exp(-0.5), rel=1e-12)
    assert vectorised(-1.0, 0.0, person, space) == pytest.approx(math.exp(-8.0), rel=1e-12)
    assert vectorised(0.0, 1.0, person, space) == pytest.approx(math.exp(-2.0), rel=1e-12)
    assert agf_algorithm1(-1.0, 0.0, person, space) == pytest.approx(math.exp(-8.0), rel=1e-12)


# ---- properties ------------------------------------------------------------------------

finite = st.floats(allow_nan=False, allow_infinity=False)
person_xy = st.floats(min_value=-1e9, max_value=1e9, allow_nan=False)


@pytest.mark.slow
@settings(max_examples=300)
@given(x=finite, y=finite, px=person_xy, py=person_xy, theta=finite)
def test_property_values_are_zero_or_above_threshold(x, y, px, py, theta):
    """Any finite point, any person within 1e9 m of the origin, any finite facing."""
    dut = agf(np.array([x, y]), np.array([px, py, theta]), PAPER)
    assert dut.shape == (1,)
    assert np.isfinite(dut[0])
    assert dut[0] == 0.0 or 0.2 < dut[0] <= 1.0


def test_nan_input_stays_nan():
    """A NaN point or person is an error upstream; it must not read as "no discomfort"."""
    people = np.array([[0.0, 0.0, 0.5], [1.0, 1.0, 0.0]])
    dut = agf(np.array([[np.nan, 0.0], [0.5, 0.5]]), people, PAPER)
    assert np.all(np.isnan(dut[0]))
    assert np.all(dut[1] > 0.2)
    assert np.isnan(agf(np.array([0.5, 0.5]), [np.nan, 0.0, 0.0], PAPER)[0])


@BOTH
def test_a_value_exactly_at_the_threshold_counts_as_zero(dut):
    """tau itself is "no discomfort" (values <= tau are 0), one ulp above is
    kept: the threshold is set to the point's own AGF value, so the
    comparison is hit exactly (a mutation run found ``>=`` surviving)."""
    person, x, y = [1.0, 2.0, math.pi / 4], 2.1, 2.6
    value = dut(x, y, person, PersonalSpace(threshold=0.0))
    assert 0.2 < value < 1.0
    assert dut(x, y, person, PersonalSpace(threshold=value)) == 0.0
    below = math.nextafter(value, 0.0)
    assert dut(x, y, person, PersonalSpace(threshold=below)) == value


def test_unthresholded_agf_xy_is_the_raw_gaussian():
    """``thresholded=False`` keeps the values <= tau that the motion integral
    needs to locate threshold crossings: 3 m straight ahead of a person
    facing +x, exp(-9 / (2 sigma_h^2)) = exp(-9/8) = 0.325 with the paper's
    sigma_h = 2, and 5 m ahead exp(-25/8) = 0.044 < tau, zeroed only when
    thresholded (a mutation run found the flag ignored without a test)."""
    from drake_social.cost.agf import agf_xy

    people = np.array([[0.0, 0.0, 0.0]])
    x, y = np.array([3.0, 5.0]), np.array([0.0, 0.0])
    raw = agf_xy(x, y, people, PAPER, thresholded=False)
    np.testing.assert_allclose(raw[:, 0], [math.exp(-9 / 8), math.exp(-25 / 8)], rtol=1e-12)
    np.testing.assert_allclose(agf_xy(x, y, people, PAPER)[:, 0], [math.exp(-9 / 8), 0.0], rtol=1e-12)
