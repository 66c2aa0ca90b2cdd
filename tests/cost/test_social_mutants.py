"""SocialCost details that the mutation run of cost/social.py found untested.

Each test asserts numbers computed by hand or by a second method (never by
the code under test), and names the mutants it kills: the culling window of
the numpy path, its floating-point guards, which backend runs, the grid's
reach, the scenario's options and the shapes of the early returns.
"""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest

from drake_social.cost import PersonalSpace, SocialCost, agf, kernel
from drake_social.cost.social import interpolation_segments
from drake_social.kinematics import ArmGeometry
from drake_social.scenario import Bar, Scenario, load_scenario

PI = math.pi
#: The paper's AGF reaches at most 3.588 m (in front), bit for bit the
#: distance the window and the kernel cull with.
R = PersonalSpace().max_reach
BASE_ONLY = np.array([1.0, 0.0, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def bar(tiny_scenario_path) -> ArmGeometry:
    """The tiny scenario's robot (links 0.6 m, 0.5 m) and its 1.5 m bar."""
    return ArmGeometry.from_scenario(load_scenario(tiny_scenario_path))


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
    geometry = ArmGeometry.from_scenario(Scenario(object=Bar(length=8.0)))
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
