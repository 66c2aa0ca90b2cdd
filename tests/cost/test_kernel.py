"""The compiled Msc kernel equals the batched numpy reference."""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest

from drake_social.cost import PersonalSpace, SocialCost, kernel
from drake_social.cost.social import interpolation_segments
from drake_social.kinematics import config_distance
from drake_social.scenario.geometry import arm_geometry
from drake_social.scenario import Bar, LShape, Polyline, Robot, Scenario

pytestmark = pytest.mark.skipif(not kernel.AVAILABLE, reason="numba is not importable")

OBJECTS = {
    "bar": Bar(length=1.5),
    "L": LShape(lengths=[3.0, 2.0]),
    "polyline": Polyline(points=[[0.0, -0.5], [0.0, 0.5], [0.4, 0.9]], interest_points=[[0.4, 0.9], [0.0, 0.0]]),
}
PEOPLE = np.array([[0.0, 0.0, math.pi / 4], [3.0, 1.0, math.pi - 1e-9], [1.0, -3.0, 2 * math.pi + 2.0]])


def both(dut: SocialCost, q_a, q_b) -> tuple[np.ndarray, np.ndarray]:
    dut.backend = "numba"
    fast = dut.motion_cost(q_a, q_b)
    dut.backend = "numpy"
    reference = dut.motion_cost(q_a, q_b)
    return fast, reference


def edges(rng, n: int, spread: float = 4.0, length: float = 2.5):
    q_a = np.column_stack([rng.uniform(-spread, spread, (n, 2)), rng.uniform(-math.pi, math.pi, (n, 2))])
    d = rng.normal(size=(n, 4))
    d *= rng.uniform(0.0, length, (n, 1)) / np.linalg.norm(d, axis=1, keepdims=True)
    return q_a, q_a + d


@pytest.mark.parametrize("kind", list(OBJECTS))
@pytest.mark.parametrize(
    "weights", ["ones", "base_only", "object_only", "random"], ids=["ones", "base", "object", "random"]
)
def test_kernel_equals_numpy_reference(kind, weights, rng):
    geometry = arm_geometry(Scenario(robot=Robot(), object=OBJECTS[kind]))
    k = geometry.num_interest_points
    w = {
        "ones": np.ones(k),
        "base_only": np.r_[1.0, np.zeros(k - 1)],
        "object_only": np.r_[np.zeros(3), np.ones(k - 3)],
        "random": rng.uniform(0, 2, k) * (rng.random(k) < 0.7),
    }[weights]
    dut = SocialCost(geometry, PEOPLE, weights=w)
    q_a, q_b = edges(rng, 400)
    fast, reference = both(dut, q_a, q_b)
    assert (reference > 0).sum() > (50 if w.any() else -1)
    np.testing.assert_allclose(fast, reference, rtol=1e-12, atol=1e-13)


def test_kernel_without_threshold_and_with_another_resolution(rng):
    geometry = arm_geometry(Scenario())
    space = dc.replace(PersonalSpace(), threshold=0.0)
    dut = SocialCost(geometry, PEOPLE, space=space, resolution=0.37, distance_weights=[1, 2, 0.5, 1])
    q_a, q_b = edges(rng, 200)
    fast, reference = both(dut, q_a, q_b)
    assert np.all(reference > 0)  # no threshold: every motion costs something
    np.testing.assert_allclose(fast, reference, rtol=1e-12)


def test_kernel_edge_cases(rng):
    geometry = arm_geometry(Scenario())
    dut = SocialCost(geometry, PEOPLE)
    q = edges(rng, 5)[0]
    fast, reference = both(dut, q, q)  # zero-length motions
    assert np.all(fast == 0) and np.all(reference == 0)
    far = q + [100.0, 100.0, 0.0, 0.0]
    fast, reference = both(dut, far, far + [1.0, 0.0, 0.3, 0.0])  # nobody near
    assert np.all(fast == 0) and np.all(reference == 0)
    single = both(dut, q[0], q[1])
    assert np.ndim(single[0]) == 0 and single[0] == pytest.approx(single[1], rel=1e-12)


def test_exp_neg_is_within_3_ulp_of_libm_and_flushes_to_zero_at_the_cap(rng):
    """The vectorisable exp against math.exp: a dense grid below EXP_CAP,
    random arguments, the binary digits' edges; 0 from EXP_CAP on; only the
    first ``count`` entries change."""
    cap = kernel.EXP_CAP
    x = np.concatenate([np.linspace(0.0, cap, 400_001)[:-1], rng.uniform(0.0, 2.0, 100_000),
                        [0.0, 0.5, 1.0, 2.0 - 1e-15, 2.0, 32.0, 63.0, np.nextafter(cap, 0.0)]])
    got = np.append(x, 3.0)
    kernel.exp_neg(got, len(x))
    assert got[-1] == 3.0
    want = np.array([math.exp(-v) for v in x])
    ulp = np.abs(got[:-1] - want) / np.spacing(want)
    assert ulp.max() <= 3.0 and ulp[x < 2.0].max() <= 2.0, (ulp.max(), x[np.argmax(ulp)])
    above = np.array([cap, cap + 1e-9, 100.0, 1e300, np.inf])
    kernel.exp_neg(above, len(above))
    assert np.all(above == 0.0)


def _all_samples(dut: SocialCost, q_a, q_b) -> np.ndarray:
    """The numpy path's trapezoid sums (times h) on every sample of every
    motion, for every person: no culling, no windows."""
    q_a, q_b = np.atleast_2d(q_a), np.atleast_2d(q_b)
    e, h = len(q_a), len(dut.people)
    n = dut.segments(q_a, q_b)
    length = config_distance(q_a, q_b, dut.distance_weights)
    every = np.ones((e, h), dtype=bool)
    return dut._integrate(q_a, q_b - q_a, n, every, np.zeros((e, h)), np.ones((e, h))) * (length / n)


@pytest.mark.parametrize("kind", list(OBJECTS))
def test_windows_leave_out_only_terms_that_are_zero(kind, rng):
    """Motions that pass beside and behind people, inside the AGF's front
    reach but outside its narrower side and rear level sets (where the
    window in the exponent's own metric is the tighter one): the kernel
    equals every sample evaluated, with a narrow and a wide personal space."""
    geometry = arm_geometry(Scenario(robot=Robot(), object=OBJECTS[kind]))
    people = np.array([[0.0, 0.0, 0.0], [0.0, 2.5, math.pi / 2]])
    for space in (PersonalSpace(), dc.replace(PersonalSpace(), sigma_s=0.5, sigma_r=0.4)):
        dut = SocialCost(geometry, people, space=space)
        # Base segments behind (x < 0) and beside the first person, arm turning.
        q_a = np.column_stack([rng.uniform(-3.5, -0.8, 300), rng.uniform(-3.0, 3.0, 300),
                               rng.uniform(-math.pi, math.pi, (300, 2))])
        q_b = q_a + np.column_stack([rng.uniform(-0.5, 0.5, 300), rng.uniform(-3.0, 3.0, 300),
                                     rng.uniform(-1.0, 1.0, (300, 2))])
        dut.backend = "numba"
        fast = dut.motion_cost(q_a, q_b)
        every = _all_samples(dut, q_a, q_b)
        assert (every > 0).sum() > 30 and (every == 0).sum() > 30, ((every > 0).sum(), (every == 0).sum())
        np.testing.assert_allclose(fast, every, rtol=1e-12, atol=1e-15)


def test_thresholds_below_the_vector_exps_range_keep_libms_exp():
    """exp_neg flushes exp(-a) to 0 from a = 64: with a threshold of 0 or
    below VECTOR_EXP_MIN_THRESHOLD the kernel takes libm's exp, so a motion
    25 m from the only person still costs what the numpy path says (1e-34),
    not 0; at the threshold itself the vector exp is used, to the same result."""
    geometry = arm_geometry(Scenario())
    for threshold, x in ((0.0, 25.0), (1e-40, 25.0), (kernel.VECTOR_EXP_MIN_THRESHOLD / 2, 14.0),
                         (kernel.VECTOR_EXP_MIN_THRESHOLD, 14.0)):
        q_a = np.array([[x, 0.0, 0.0, 0.0]])  # in front of the person, x m away
        q_b = q_a + [0.0, 1.0, 0.5, 0.0]
        dut = SocialCost(geometry, np.zeros((1, 3)), space=dc.replace(PersonalSpace(), threshold=threshold))
        fast, reference = both(dut, q_a, q_b)
        assert 0.0 < reference[0] < (1e-20 if x == 25.0 else 1e-9)
        np.testing.assert_allclose(fast, reference, rtol=1e-12)


@pytest.mark.filterwarnings("ignore:overflow encountered in divide:RuntimeWarning")  # the numpy path's window
def test_a_motion_too_short_for_its_span_to_survive_the_lipschitz_product():
    """lip * span underflows to 0 for a denormal arm motion: the metric window
    is skipped (no division by 0) and the cost equals the numpy path's."""
    geometry = arm_geometry(Scenario())
    dut = SocialCost(geometry, np.array([[0.3, 0.0, 0.0]]), space=PersonalSpace(3.0, 3.0, 3.0))
    for k in (2, 3):
        q_b = np.zeros((1, 4))
        q_b[0, k] = 5e-324
        fast, reference = both(dut, np.zeros((1, 4)), q_b)
        np.testing.assert_array_equal(fast, reference)


@pytest.mark.filterwarnings("ignore:overflow encountered in subtract:RuntimeWarning")  # numpy's, for 1e308 - -1e308
@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_a_motion_too_long_to_sample_is_refused_by_name(backend):
    """A motion whose samples would not fit (more than MAX_MOTION_STEPS steps),
    or whose ends are so far apart that their difference overflows, is a
    ValueError naming the motion, from either backend; the step limit
    itself is allowed."""
    geometry = arm_geometry(Scenario())
    dut = SocialCost(geometry, PEOPLE)
    dut.backend = backend
    limit = kernel.MAX_MOTION_STEPS * dut.resolution
    q_a = np.zeros((3, 4))
    q_b = np.array([[1.0, 0, 0, 0], [limit * 1.001, 0, 0, 0], [2.0, 0, 0, 0]])
    with pytest.raises(ValueError, match=r"motion 1 \(1 in all\) is too long to sample: its displacement bound "
                                         r"100100 m needs more than 1,000,000 steps of 0\.1 m; split it"):
        dut.motion_cost(q_a, q_b)
    with pytest.raises(ValueError, match=r"motions need finite configurations \(and ends whose difference does not "
                                         r"overflow\); displacement bounds: .inf"):
        dut.motion_cost(np.array([-1e308, 0, 0, 0]), np.array([1e308, 0, 0, 0]))
    if backend == "numba":  # the kernel's own guard, before it allocates the samples
        with pytest.raises(ValueError, match="not finite or needs more than MAX_MOTION_STEPS steps"):
            dut._msc_sums(q_a, q_b)
    # The limit itself is allowed: MAX_MOTION_STEPS steps exactly.
    np.testing.assert_array_equal(interpolation_segments(np.array([limit]), dut.resolution), [kernel.MAX_MOTION_STEPS])
    # Just below the limit (a base motion far from everyone): allowed, and free.
    assert dut.motion_cost(np.array([100.0, 0, 0, 0]), np.array([100.0 + limit * (1 - 1e-12), 0, 0, 0])) == 0.0
