"""Planar kinematics: hand-computed points, batching, and the displacement bound."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drake_social.kinematics import ArmGeometry, config_distance, cumulative_distance
from drake_social.scenario.geometry import arm_geometry, object_interest_points, object_polyline
from drake_social.scenario import Bar, LShape, Polyline, Robot, Scenario

PI = math.pi


def geometry(obj) -> ArmGeometry:
    """The default robot (l1 = 0.6, l2 = 0.5, link width 0.08) holding ``obj``."""
    return arm_geometry(Scenario(robot=Robot(), object=obj))


BAR = geometry(Bar(length=1.5, thickness=0.05))
L_SHAPE = geometry(LShape(lengths=[3.0, 2.0], thickness=0.06))
# An object folded back towards the elbow: every object point is nearer the
# elbow than the link-2 tip, so the tip itself sets the gripper's lever.
FOLDED = geometry(Polyline(points=[[-0.3, 0.0], [-0.4, 0.05]], thickness=0.04))


# ---- an independent scalar forward kinematics ---------------------------------------


def rot(angle: float, p) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([c * p[0] - s * p[1], s * p[0] + c * p[1]])


def fk_scalar(dut: ArmGeometry, q) -> dict[str, np.ndarray]:
    """Base, elbow, gripper origin and object points for one q, by plain math."""
    x, y, psi1, psi2 = (float(v) for v in q)
    l1, l2 = dut.link_lengths
    base = np.array([x, y])
    elbow = base + l1 * np.array([math.cos(psi1), math.sin(psi1)])
    grip = elbow + l2 * np.array([math.cos(psi1 + psi2), math.sin(psi1 + psi2)])
    to_world = lambda p_G: grip + rot(psi1 + psi2, p_G)  # noqa: E731
    return {
        "base": base,
        "elbow": elbow,
        "grip": grip,
        "interest": np.array([base, elbow, grip] + [to_world(p) for p in dut.object_interest]),
        "verts": np.array([to_world(p) for p in dut.object_points]),
    }


# ---- object definitions ----------------------------------------------------------------


def test_object_polylines_and_default_interest_points():
    np.testing.assert_array_equal(object_polyline(Bar(length=2.0)), [[0, -1], [0, 1]])
    np.testing.assert_array_equal(object_polyline(LShape(lengths=[3.0, 2.0])), [[0, -1.5], [0, 1.5], [2, 1.5]])
    poly = Polyline(points=[[0, -1], [0, 1], [1, 1], [1, 0.5]])
    np.testing.assert_array_equal(object_polyline(poly), poly.points)
    # Defaults: bar ends, L vertices, first and last polyline vertex.
    np.testing.assert_array_equal(object_interest_points(Bar(length=2.0)), [[0, -1], [0, 1]])
    np.testing.assert_array_equal(object_interest_points(LShape(lengths=[3.0, 2.0])), [[0, -1.5], [0, 1.5], [2, 1.5]])
    np.testing.assert_array_equal(object_interest_points(poly), [[0, -1], [1, 0.5]])
    explicit = Bar(length=2.0, interest_points=[[0.0, 0.0], [0.1, 0.9]])
    np.testing.assert_array_equal(object_interest_points(explicit), [[0, 0], [0.1, 0.9]])


def test_geometry_from_scenario_and_counts():
    assert BAR.base_radius == 0.35
    assert BAR.link_lengths == (0.6, 0.5)
    assert BAR.link_radius == pytest.approx(0.04)
    assert BAR.object_radius == pytest.approx(0.025)
    assert BAR.num_interest_points == 5
    assert BAR.interest_names == ["base", "link1_tip", "link2_tip", "object_1", "object_2"]
    assert BAR.num_segments == 3
    np.testing.assert_allclose(BAR.segment_radii, [0.04, 0.04, 0.025])
    assert L_SHAPE.num_interest_points == 6
    assert L_SHAPE.interest_names[-1] == "object_3"
    assert L_SHAPE.num_segments == 4
    np.testing.assert_allclose(L_SHAPE.segment_radii, [0.04, 0.04, 0.03, 0.03])


# ---- hand-computed configurations ----------------------------------------------------------

# (q, [base, link-1 tip, link-2 tip, object points...]) worked out on paper.
BAR_CASES = [
    ([0, 0, 0, 0], [[0, 0], [0.6, 0], [1.1, 0], [1.1, -0.75], [1.1, 0.75]]),
    # link 2 points +y: the gripper y axis is world -x, so the bar lies along x
    ([1, 2, 0, PI / 2], [[1, 2], [1.6, 2], [1.6, 2.5], [2.35, 2.5], [0.85, 2.5]]),
    ([0, 0, PI / 2, -PI / 2], [[0, 0], [0, 0.6], [0.5, 0.6], [0.5, -0.15], [0.5, 1.35]]),
    # folded back: link 2 at 2 pi, i.e. along +x again
    ([-1, 3, PI, PI], [[-1, 3], [-1.6, 3], [-1.1, 3], [-1.1, 2.25], [-1.1, 3.75]]),
]
L_CASES = [
    ([0, 0, 0, 0], [[0, 0], [0.6, 0], [1.1, 0], [1.1, -1.5], [1.1, 1.5], [3.1, 1.5]]),
    ([0, 0, 0, PI / 2], [[0, 0], [0.6, 0], [0.6, 0.5], [2.1, 0.5], [-0.9, 0.5], [-0.9, 2.5]]),
    ([2, 1, PI, 0], [[2, 1], [1.4, 1], [0.9, 1], [0.9, 2.5], [0.9, -0.5], [-1.1, -0.5]]),
]


@pytest.mark.parametrize(
    "dut, q, expected",
    [(BAR, q, e) for q, e in BAR_CASES] + [(L_SHAPE, q, e) for q, e in L_CASES],
    ids=[f"bar{i}" for i in range(len(BAR_CASES))] + [f"L{i}" for i in range(len(L_CASES))],
)
def test_interest_points_by_hand(dut, q, expected):
    got = dut.interest_points(np.array(q, dtype=float))
    np.testing.assert_allclose(got, expected, atol=1e-12)
    # Capsules: link 1 (base -> elbow), link 2 (elbow -> gripper), then the
    # object polyline, whose vertices are the default interest points here.
    e = np.array(expected, dtype=float)
    seg = dut.segments(np.array(q, dtype=float))
    np.testing.assert_allclose(seg[0], [e[0], e[1]], atol=1e-12)
    np.testing.assert_allclose(seg[1], [e[1], e[2]], atol=1e-12)
    for k in range(len(e) - 4):
        np.testing.assert_allclose(seg[2 + k], [e[3 + k], e[4 + k]], atol=1e-12)
    base, elbow, grip = dut.joints(np.array(q, dtype=float))
    np.testing.assert_allclose([base, elbow, grip], e[:3], atol=1e-12)


def test_base_does_not_rotate_and_angles_wrap():
    q = np.array([0.3, -0.2, 0.7, -1.9])
    ref = BAR.interest_points(q)
    for turns in ([2 * PI, 0], [0, -2 * PI], [4 * PI, 2 * PI]):
        np.testing.assert_allclose(BAR.interest_points(q + [0, 0, *turns]), ref, atol=1e-12)
    # The base point is (x, y) whatever the joints.
    np.testing.assert_array_equal(BAR.interest_points(q + [0, 0, 1.0, 2.0])[0], q[:2])
    # Link 1 tip does not depend on psi2.
    np.testing.assert_allclose(BAR.interest_points(q + [0, 0, 0, 1.3])[1], ref[1], atol=1e-15)


def test_gripper_to_world_maps_the_gripper_axes():
    q = np.array([1.0, 1.0, 0.4, 0.8])  # gripper at world angle 1.2
    pts = BAR.gripper_to_world(q, np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]))
    grip = fk_scalar(BAR, q)["grip"]
    np.testing.assert_allclose(pts[0], grip, atol=1e-12)
    np.testing.assert_allclose(pts[1] - grip, [math.cos(1.2), math.sin(1.2)], atol=1e-12)
    np.testing.assert_allclose(pts[2] - grip, [-math.sin(1.2), math.cos(1.2)], atol=1e-12)


# ---- batching equals a plain loop ---------------------------------------------------------------


@pytest.mark.parametrize("dut", [BAR, L_SHAPE], ids=["bar", "L"])
def test_batched_kinematics_equal_a_loop(dut, rng):
    q = np.column_stack([rng.uniform(-5, 5, (60, 2)), rng.uniform(-10, 10, (60, 2))]).reshape(3, 4, 5, 4)
    pts = dut.interest_points(q)
    seg = dut.segments(q)
    assert pts.shape == (3, 4, 5, dut.num_interest_points, 2)
    assert seg.shape == (3, 4, 5, dut.num_segments, 2, 2)
    for idx in np.ndindex(q.shape[:-1]):
        ref = fk_scalar(dut, q[idx])
        np.testing.assert_allclose(pts[idx], ref["interest"], atol=1e-12)
        np.testing.assert_allclose(dut.interest_points(q[idx]), ref["interest"], atol=1e-12)
        np.testing.assert_allclose(seg[idx][0], [ref["base"], ref["elbow"]], atol=1e-12)
        np.testing.assert_allclose(seg[idx][1], [ref["elbow"], ref["grip"]], atol=1e-12)
        v = ref["verts"]
        np.testing.assert_allclose(seg[idx][2:], np.stack([v[:-1], v[1:]], 1), atol=1e-12)
        np.testing.assert_allclose(dut.segments(q[idx]), seg[idx], atol=1e-15)


def test_config_distance_by_hand():
    assert config_distance([0, 0, 0, 0], [3, 4, 0, 0]) == pytest.approx(5.0)
    assert config_distance([1, 1, 1, 1], [1, 1, 2, 2]) == pytest.approx(math.sqrt(2))
    assert config_distance([0, 0, 0, 0], [0, 0, 1, 1], [1, 1, 2, 2]) == pytest.approx(math.sqrt(8))
    d = config_distance(np.zeros((3, 4)), np.array([[1, 0, 0, 0], [0, 0, 0, 2], [1, 1, 1, 1]]))
    np.testing.assert_allclose(d, [1, 2, 2])


# ---- the displacement bound -------------------------------------------------------------------


def test_reach_lever_arms_by_hand():
    far = math.hypot(0.5, 0.75)  # elbow -> bar end: 0.5 along link 2, 0.75 across
    np.testing.assert_allclose(BAR.reach(), [1, 1, 0.6 + far, far])
    np.testing.assert_allclose(BAR.reach(include_body=True), [1, 1, 0.6 + far + 0.04, far + 0.04])
    np.testing.assert_allclose(BAR.reach(active=[0]), [1, 1, 0, 0])  # the base only translates
    np.testing.assert_allclose(BAR.reach(active=[1]), [1, 1, 0.6, 0])
    np.testing.assert_allclose(BAR.reach(active=[0, 2]), [1, 1, 1.1, 0.5])
    far_l = math.hypot(0.5 + 2.0, 1.5)  # elbow -> the L's far corner
    np.testing.assert_allclose(L_SHAPE.reach(), [1, 1, 0.6 + far_l, far_l])
    np.testing.assert_allclose(L_SHAPE.reach(include_body=True), [1, 1, 0.6 + far_l + 0.04, far_l + 0.04])


def body_points(dut: ArmGeometry, qs: np.ndarray, body: dict[str, np.ndarray]) -> np.ndarray:
    """World positions (T, K, 2) of body-fixed points of the base, links and object.

    Written from the conventions, independently of the library's kinematics.
    """
    l1, l2 = dut.link_lengths
    x, y, psi1, psi2 = qs.T
    base = np.stack([x, y], -1)[:, None, :]

    def rotate(angle, p):  # angle (T,), p (K, 2) -> (T, K, 2)
        c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
        return np.stack([c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1]], -1)

    elbow = base + rotate(psi1, np.array([[l1, 0.0]]))
    grip = elbow + rotate(psi1 + psi2, np.array([[l2, 0.0]]))
    return np.concatenate(
        [
            base + body["base"],  # the base translates only
            base + rotate(psi1, body["link1"]),  # link-1 frame, origin at the shoulder
            grip + rotate(psi1 + psi2, body["grip"]),  # link 2 and object, in G
        ],
        1,
    )


def random_body_points(dut: ArmGeometry, rng, n: int = 40) -> dict[str, np.ndarray]:
    """Points on the surfaces and axes of the base disc and every capsule."""

    def offsets(r):
        ang = rng.uniform(-PI, PI, n)
        rad = r * np.sqrt(rng.uniform(0, 1, n))
        rad[: n // 2] = r  # half of them on the surface, the farthest points
        return np.column_stack([rad * np.cos(ang), rad * np.sin(ang)])

    l1, l2 = dut.link_lengths
    s = rng.uniform(-0.0, 1.0, n)
    link1 = np.column_stack([s * l1, np.zeros(n)]) + offsets(dut.link_radius)
    link2 = np.column_stack([-s * l2, np.zeros(n)]) + offsets(dut.link_radius)
    verts = dut.object_points
    seg = rng.integers(0, len(verts) - 1, n)
    obj = verts[seg] + s[:, None] * (verts[seg + 1] - verts[seg]) + offsets(dut.object_radius)
    # The object's vertices pushed out by the full radius: the extreme points.
    d = verts - [-l2, 0.0]
    tips = verts + dut.object_radius * d / np.linalg.norm(d, axis=1, keepdims=True)
    return {"base": offsets(dut.base_radius), "link1": link1, "grip": np.concatenate([link2, obj, tips])}


def random_motions(rng, n: int) -> tuple[np.ndarray, np.ndarray]:
    q_a = np.column_stack([rng.uniform(-3, 3, (n, 2)), rng.uniform(-PI, PI, (n, 2))])
    scale = rng.choice([0.05, 0.5, 3.0], size=(n, 1))
    step = rng.normal(size=(n, 4)) * scale
    # Some pure motions: translation only, one joint only, joints opposite.
    step[0, 2:] = 0
    step[1, [0, 1, 3]] = 0
    step[2, [0, 1, 2]] = 0
    step[3, 3] = -step[3, 2]
    return q_a, q_a + step


def arc_lengths(points: np.ndarray) -> np.ndarray:
    """Polyline length of each point's track; points (T, K, 2) -> (K,)."""
    return np.linalg.norm(np.diff(points, axis=0), axis=-1).sum(0)


@pytest.mark.parametrize("dut", [BAR, L_SHAPE, FOLDED], ids=["bar", "L", "folded"])
def test_max_displacement_bounds_every_interest_and_body_point(dut, rng):
    body = random_body_points(dut, rng)
    t = np.linspace(0.0, 1.0, 1001)[:, None]
    q_a, q_b = random_motions(rng, 40)
    bound_pts = dut.max_displacement(q_a, q_b)
    bound_body = dut.max_displacement(q_a, q_b, include_body=True)
    assert bound_pts.shape == (40,)
    for e in range(len(q_a)):
        qs = q_a[e] + t * (q_b[e] - q_a[e])
        track = dut.interest_points(qs)  # (T, 3 + P, 2)
        arcs = arc_lengths(track)
        assert np.all(arcs <= bound_pts[e] * (1 + 1e-9) + 1e-12)
        assert np.all(np.linalg.norm(track[-1] - track[0], axis=-1) <= bound_pts[e] + 1e-12)
        body_track = body_points(dut, qs, body)
        assert np.all(arc_lengths(body_track) <= bound_body[e] * (1 + 1e-9) + 1e-12)
        # Subsets of interest points: each bound covers its own points.
        for active in ([0], [1], [2], [0, 3], [len(arcs) - 1]):
            sub = dut.max_displacement(q_a[e], q_b[e], active=np.array(active))
            assert np.all(arcs[active] <= sub * (1 + 1e-9) + 1e-12)
        # The base alone moves exactly its straight displacement: the subset's bound is that, not the whole arm's.
        base_only = dut.max_displacement(q_a[e], q_b[e], active=np.array([0]))
        assert base_only == pytest.approx(math.hypot(*(q_b[e, :2] - q_a[e, :2])), rel=1e-12)


def test_max_displacement_is_tight_for_simple_motions():
    far = math.hypot(0.5, 0.75)
    q = np.array([1.0, -1.0, 0.3, 0.9])
    # Pure translation: every point moves by exactly the base displacement.
    assert BAR.max_displacement(q, q + [3, 4, 0, 0]) == pytest.approx(5.0)
    # Pure elbow turn by 0.2 rad: the bar end travels an arc of radius `far`.
    dq = np.array([0, 0, 0, 0.2])
    assert BAR.max_displacement(q, q + dq) == pytest.approx(far * 0.2)
    arcs = arc_lengths(BAR.interest_points(q + np.linspace(0, 1, 2001)[:, None] * dq))
    assert arcs.max() == pytest.approx(far * 0.2, rel=1e-6)
    # Zero motion: zero bound.
    assert BAR.max_displacement(q, q) == 0.0
    # Batched over (..., 4) like everything else.
    assert BAR.max_displacement(np.zeros((2, 3, 4)), np.ones((2, 3, 4))).shape == (2, 3)


# ---- properties ---------------------------------------------------------------------------------

finite = st.floats(allow_nan=False, allow_infinity=False)


@settings(max_examples=200)
@given(q=st.tuples(finite, finite, finite, finite))
def test_property_finite_for_any_finite_q(q):
    """Even absurd joint angles (psi1 + psi2 would overflow past 1.8e308) stay finite."""
    q = np.array(q)
    for dut in (BAR, L_SHAPE):
        pts = dut.interest_points(q)
        assert np.all(np.isfinite(pts))
        assert np.all(np.isfinite(dut.segments(q)))
        np.testing.assert_array_equal(pts[0], q[:2])
        # Every point stays within the arm's reach of the base (relative to the
        # base's magnitude: at 1e308 the sums round).
        reach = dut.reach()[2]
        scale = max(1.0, float(np.abs(q[:2]).max()))
        assert np.all(np.abs(pts - q[:2]) <= reach * (1 + 1e-9) + 1e-15 * scale)


def test_cumulative_distance_by_hand():
    """The path parameter of the cost profiles: 0 at the first waypoint, then
    the running sum of weighted configuration distances (a mutation run found
    it untested by the core's tests)."""
    wp = [[0, 0, 0, 0], [3, 4, 0, 0], [3, 4, 1, 0], [3, 4, 1, -2]]
    np.testing.assert_allclose(cumulative_distance(wp), [0.0, 5.0, 6.0, 8.0], rtol=0, atol=1e-12)
    dut = cumulative_distance(wp, [1.0, 1.0, 0.5, 3.0])
    np.testing.assert_allclose(dut, [0.0, 5.0, 5.5, 11.5], rtol=0, atol=1e-12)
    assert dut.shape == (4,) and dut.dtype == float
    one = cumulative_distance([[1.0, 2.0, 3.0, 4.0]])
    assert one.shape == (1,) and one[0] == 0.0
    empty = cumulative_distance(np.zeros((0, 4)))
    assert empty.shape == (0,)
    # A flat list of 8 numbers is two waypoints.
    np.testing.assert_allclose(cumulative_distance([0, 0, 0, 0, 0, 0, 0, 2]), [0.0, 2.0], atol=1e-12)
