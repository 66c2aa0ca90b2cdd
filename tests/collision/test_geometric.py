"""The pure-numpy checker: exact distances against brute force, hand values, motions, limits.

The last section holds the details a mutation run of collision/geometric.py
found untested: touching is not valid, a motion shorter than the resolution is
sampled at its two ends, and conservative advancement queries what a plainly
written scalar loop queries.
"""

from __future__ import annotations

import dataclasses as dc
import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from drake_social.collision import geometric
from drake_social.collision.geometric import GeometricChecker, _segment_box_sdf
from drake_social.collision.planar_kernel import STEP_MARGIN, TOLERANCE
from drake_social.collision.validity import ValidityChecker
from drake_social.scenario.geometry import arm_geometry
from drake_social.scenario import Bar, Box, LShape, Person, Polyline, Scenario, World

# ---- an independent reference: polygon geometry by half-planes and edge distances


def _box_corners(box: Box) -> np.ndarray:
    c, s = math.cos(box.yaw), math.sin(box.yaw)
    hx, hy = box.size[0] / 2, box.size[1] / 2
    local = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])  # counter-clockwise
    return np.asarray(box.center) + local @ np.array([[c, s], [-s, c]])


def _point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    d = b - a
    t = np.clip(((p - a) @ d) / (d @ d), 0.0, 1.0)
    return np.hypot(*(p - a - t[:, None] * d).T)


def _polygon_sdf(p: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Signed distance of points (P, 2) to a convex counter-clockwise polygon."""
    edges = [(corners[i], corners[(i + 1) % len(corners)]) for i in range(len(corners))]
    dist = np.min([_point_segment(p, a, b) for a, b in edges], axis=0)
    inside = np.all([(b - a)[0] * (p - a)[:, 1] - (b - a)[1] * (p - a)[:, 0] >= 0 for a, b in edges], axis=0)
    return np.where(inside, -dist, dist)


def _reference_clearance(scenario: Scenario, q: np.ndarray, samples: int = 2001) -> tuple[float, float]:
    """Dense-sampling clearance of one configuration and its worst-case sampling error."""
    g = arm_geometry(scenario)
    seg = g.segments(q)
    x0, y0, x1, y1 = scenario.world.bounds
    t = np.linspace(0.0, 1.0, samples)[:, None]
    values, error = [], 0.0
    base = np.asarray(q[:2])[None]
    shapes = [(base, g.base_radius)] + [(a + t * (b - a), r) for (a, b), r in zip(seg, g.segment_radii)]
    for pts, r in shapes:
        if len(pts) > 1:
            error = max(error, np.hypot(*(pts[1] - pts[0])) / 2)
        values.append(np.min(np.minimum.reduce([pts[:, 0] - x0, x1 - pts[:, 0], pts[:, 1] - y0, y1 - pts[:, 1]])) - r)
        for box in scenario.world.obstacles:
            values.append(_polygon_sdf(pts, _box_corners(box)).min() - r)
        for p in scenario.people:
            values.append(np.hypot(pts[:, 0] - p.x, pts[:, 1] - p.y).min() - p.radius - r)
    return min(values), error


def cluttered_scenario(obj=None) -> Scenario:
    """Rotated, thin, touching and overlapping boxes, and people, in a 10 x 8 m room."""
    return Scenario(
        world=World(
            bounds=[0.0, 0.0, 10.0, 8.0],
            obstacles=[
                Box(center=[3.0, 2.0], size=[1.2, 0.6], yaw=math.pi / 4),
                Box(center=[6.5, 5.5], size=[2.0, 0.05], yaw=-0.3),
                Box(center=[5.0, 1.0], size=[0.4, 2.0], yaw=0.0),
                Box(center=[5.3, 1.0], size=[0.4, 0.4], yaw=1.0),  # overlaps the previous one
                Box(center=[8.5, 2.0], size=[1.0, 1.0], yaw=math.pi / 2),
                Box(center=[1.0, 6.5], size=[3.0, 0.3], yaw=2.5),
            ],
        ),
        people=[Person(x=2.0, y=5.0, theta=math.pi / 4, radius=0.3), Person(x=7.5, y=3.5, radius=0.25)],
        object=obj or LShape(lengths=[1.6, 1.0], thickness=0.06),
    )


OBJECTS = [
    Bar(length=1.5, thickness=0.05),
    LShape(lengths=[1.6, 1.0], thickness=0.06),
    Polyline(points=[[0.0, -0.3], [0.0, -0.3], [0.6, 0.4], [-0.5, 0.7]], thickness=0.04),  # repeated vertex
]


@pytest.mark.slow
@pytest.mark.parametrize("obj", OBJECTS, ids=["bar", "L", "polyline"])
def test_clearances_equal_dense_sampling(obj, rng):
    scenario = cluttered_scenario(obj)
    dut = GeometricChecker(scenario, chunk=64)  # several chunks
    qs = rng.uniform(dut.lower, dut.upper, size=(150, 4))
    got = dut.clearances(qs)
    for q, value in zip(qs, got):
        ref, err = _reference_clearance(scenario, q)
        # Sampling only overestimates the minimum, by at most half a step.
        assert ref - err - 1e-12 <= value <= ref + 1e-12
    assert 0.1 < (got > 0).mean() < 0.9


def test_culling_does_not_change_any_clearance(rng):
    """The broad and narrow phases only skip pairs: compare with all pairs, exact."""
    scenario = cluttered_scenario()
    dut = GeometricChecker(scenario)
    qs = rng.uniform(dut.lower, dut.upper, size=(3000, 4))
    g = dut.geometry
    seg = g.segments(qs)  # (N, S, 2, 2)
    all_pairs = []
    for box in scenario.world.obstacles:
        c, s = math.cos(box.yaw), math.sin(box.yaw)
        R_BW = np.array([[c, s], [-s, c]])
        a = (seg[:, :, 0] - box.center) @ R_BW.T
        b = (seg[:, :, 1] - box.center) @ R_BW.T
        half = np.broadcast_to(np.asarray(box.size) / 2, a.shape)
        all_pairs.append((_segment_box_sdf(a, b, half) - g.segment_radii).min(-1))
        p = (qs[:, :2] - box.center) @ R_BW.T
        all_pairs.append(_segment_box_sdf(p, p, np.broadcast_to(np.asarray(box.size) / 2, p.shape)) - g.base_radius)
    x0, y0, x1, y1 = scenario.world.bounds
    ends = np.concatenate([qs[:, None, :2], seg.reshape(len(qs), -1, 2)], 1)
    radii = np.concatenate([[g.base_radius], np.repeat(g.segment_radii, 2)])
    margin = np.minimum.reduce([ends[..., 0] - x0, x1 - ends[..., 0], ends[..., 1] - y0, y1 - ends[..., 1]])
    all_pairs.append((margin - radii).min(-1))
    for p in scenario.people:
        c = np.array([p.x, p.y])
        d = [np.hypot(*(qs[:, :2] - c).T) - g.base_radius]
        d += [_point_segment_rows(c, seg[:, k, 0], seg[:, k, 1]) - g.segment_radii[k] for k in range(seg.shape[1])]
        all_pairs.append(np.min(d, axis=0) - p.radius)
    expected = np.min(all_pairs, axis=0)
    np.testing.assert_allclose(dut.clearances(qs), expected, rtol=0, atol=1e-12)


def _point_segment_rows(c, a, b):
    d = b - a
    t = np.clip(np.einsum("ni,ni->n", c - a, d) / np.einsum("ni,ni->n", d, d), 0, 1)
    return np.hypot(*(c - a - t[:, None] * d).T)


finite = st.floats(-3.0, 3.0, allow_nan=False)


@pytest.mark.slow
@given(
    a=st.tuples(finite, finite),
    b=st.tuples(finite, finite),
    half=st.tuples(st.floats(0.01, 2.0), st.floats(0.01, 2.0)),
)
def test_segment_box_minimum_is_exact(a, b, half):
    a, b, half = np.array(a), np.array(b), np.array(half)
    dut = _segment_box_sdf(a, b, half)
    corners = np.array([[half[0], half[1]], [-half[0], half[1]], [-half[0], -half[1]], [half[0], -half[1]]])
    t = np.linspace(0.0, 1.0, 20001)[:, None]
    ref = _polygon_sdf(a + t * (b - a), corners).min()
    step = np.hypot(*(b - a)) / 20000
    assert ref - step / 2 - 1e-12 <= dut <= ref + 1e-12


@pytest.mark.parametrize(
    "a, b, half, expected",
    [
        ([-2.0, 0.0], [2.0, 0.0], [1.0, 0.5], -0.5),  # through the middle, along x
        ([-2.0, 0.5], [2.0, 0.5], [1.0, 0.5], 0.0),  # grazing the top face
        ([-2.0, 0.7], [2.0, 0.7], [1.0, 0.5], 0.2),  # parallel above the top face
        ([2.0, 2.0], [3.0, 3.0], [1.0, 0.5], math.hypot(1.0, 1.5)),  # nearest: the end vs the corner
        ([3.0, 0.0], [0.0, 3.0], [1.0, 1.0], math.sqrt(0.5)),  # passes the corner (1, 1) diagonally
        ([3.0, -1.0], [-1.0, 3.0], [1.0, 1.0], 0.0),  # through the corner (1, 1)
        ([0.2, 0.1], [0.2, 0.1], [1.0, 0.5], -0.4),  # a point inside
        ([0.0, -3.0], [0.0, 3.0], [0.2, 1.0], -0.2),  # across a tall box: depth half its width
    ],
)
def test_segment_box_hand_values(a, b, half, expected):
    assert _segment_box_sdf(np.array(a), np.array(b), np.array(half)) == pytest.approx(expected, abs=1e-12)


# ---- hand values in a configured room


def test_clearance_hand_values_rotated_box_person_and_walls():
    scenario = Scenario(
        world=World(
            bounds=[0.0, 0.0, 10.0, 10.0], obstacles=[Box(center=[5.0, 5.0], size=[1.0, 1.0], yaw=math.pi / 4)]
        ),
        people=[Person(x=2.0, y=8.0, theta=math.pi / 4, radius=0.25)],
        object=Bar(length=0.4, thickness=0.04),
    )
    dut = GeometricChecker(scenario)
    # Base 2 m west of the diamond's west corner (5 - sqrt(0.5), 5); the arm points away (west).
    q = np.array([5.0 - math.sqrt(0.5) - 2.0, 5.0, math.pi, 0.0])
    # The arm reaches 1.1 m west; the link-2 tip disc (radius 0.04) is nearest the west wall.
    wall = q[0] - 1.1 - 0.04
    base_box = 2.0 - 0.35
    assert dut.clearance(q) == pytest.approx(min(wall, base_box), abs=1e-12)
    # Slide towards the diamond until the base touches it: invalid at 1 mm overlap.
    q_touch = q + [2.0 - 0.35 + 0.001, 0.0, 0.0, 0.0]
    assert dut.clearance(q_touch) == pytest.approx(-0.001, abs=1e-12)
    assert not dut.is_valid(q_touch) and dut.is_valid(q_touch - [0.002, 0, 0, 0])
    # The bar tip at the person: arm up-left towards (2, 8), stopping 0.1 m short of her.
    p_WB = np.array([2.0, 8.0]) - (1.1 + 0.25 + 0.1) * np.array([-math.sqrt(0.5), math.sqrt(0.5)])
    q_person = np.array([*(p_WB), 3 * math.pi / 4, 0.0])
    # The link-2 tip is 0.1 + 0.25 from her centre; its disc (0.04) reaches further than the bar's (0.02).
    assert dut.clearance(q_person) == pytest.approx(0.1 - 0.04, abs=1e-12)


def test_empty_room_only_walls_count(tiny_scenario):
    scenario = dc.replace(tiny_scenario, world=dc.replace(tiny_scenario.world, obstacles=[]), people=[])
    dut = GeometricChecker(scenario)
    q = np.array([4.0, 2.5, math.pi / 2, 0.0])  # arm straight north, bar across at y = 3.6
    # Nearest: the link-2 tip disc (radius 0.04) and the north wall; then the base and the south wall.
    assert dut.clearance(q) == pytest.approx(5.0 - 3.6 - 0.04, abs=1e-12)
    q_low = q - [0.0, 1.0, 0.0, 0.0]
    assert dut.clearance(q_low) == pytest.approx(1.5 - 0.35, abs=1e-12)
    qs = np.random.default_rng(3).uniform(dut.lower, dut.upper, size=(500, 4))
    assert dut.are_valid(qs).any() and not dut.are_valid(qs).all()


@pytest.mark.parametrize(
    "q",
    [[-0.01, 2.5, 0.0, math.pi], [4.0, 5.2, 0.0, math.pi], [2.0, 2.5, 3.2, math.pi], [2.0, 2.5, 0.0, -3.15]],
)
def test_outside_the_bounds_or_joint_limits_is_invalid(tiny_scenario, q):
    dut = GeometricChecker(tiny_scenario)
    assert not dut.is_valid(q)
    assert not dut.is_motion_valid([2.0, 2.5, 0.0, math.pi], q)
    assert dut.is_valid([2.0, 2.5, 0.0, math.pi])


def test_protocol_and_batched_equals_single(tiny_scenario, rng):
    dut = GeometricChecker(tiny_scenario, chunk=50)
    assert isinstance(dut, ValidityChecker)
    qs = rng.uniform(dut.lower - 0.3, dut.upper + 0.3, size=(400, 4))
    np.testing.assert_array_equal(dut.are_valid(qs), [dut.is_valid(q) for q in qs])
    np.testing.assert_array_equal(dut.are_valid(qs), dut.in_limits(qs) & (dut.clearances(qs) > 0))
    q_b = qs + rng.normal(scale=0.4, size=qs.shape)
    np.testing.assert_array_equal(
        dut.are_motions_valid(qs, q_b), [dut.is_motion_valid(a, b) for a, b in zip(qs, q_b)]
    )
    assert dut.are_valid(np.empty((0, 4))).shape == (0,)
    assert dut.are_motions_valid(np.empty((0, 4)), np.empty((0, 4))).shape == (0,)


# ---- motions


def test_motion_samples_bound_every_body_point_step(tiny_scenario, rng):
    dut = GeometricChecker(tiny_scenario, resolution=0.05)
    g = dut.geometry
    q_a = rng.uniform(dut.lower, dut.upper, size=(30, 4))
    q_b = q_a + rng.normal(scale=1.0, size=q_a.shape)
    qs, starts = dut.motion_samples(q_a, q_b)
    ends = np.append(starts[1:], len(qs))
    worst = 0.0
    ang = np.linspace(0.0, 2 * math.pi, 16, endpoint=False)
    circle = np.stack([np.cos(ang), np.sin(ang)], -1)
    for e, (i, j) in enumerate(zip(starts, ends)):
        np.testing.assert_array_equal(qs[i], q_a[e])
        np.testing.assert_allclose(qs[j - 1], q_b[e], atol=1e-12)
        seg = g.segments(qs[i:j])  # dense points on every capsule's rim and the base disc
        t = np.linspace(0.0, 1.0, 21)[:, None]
        axis = seg[:, :, None, 0] + t * (seg[:, :, None, 1] - seg[:, :, None, 0])
        rim = axis[:, :, :, None] + g.segment_radii[:, None, None, None] * circle
        pts = np.concatenate([rim.reshape(j - i, -1, 2), qs[i:j, None, :2] + g.base_radius * circle], 1)
        step = np.linalg.norm(np.diff(pts, axis=0), axis=-1).max()
        assert step <= 0.05 + 1e-12
        worst = max(worst, step)
        # No more samples than the bound needs.
        assert j - i - 1 == max(1, math.ceil(g.max_displacement(q_a[e], q_b[e], include_body=True) / 0.05))
    assert worst > 0.025


def thin_wall_scenario() -> Scenario:
    """A 3 m object's tip swings across a 5 cm wall when psi1 goes -0.3 -> 0.4 rad."""
    return Scenario(
        world=World(bounds=[0.0, 0.0, 10.0, 10.0], obstacles=[Box(center=[8.9, 5.0], size=[0.3, 0.05])]),
        object=Polyline(points=[[0.0, 0.0], [3.0, 0.0]], thickness=0.05),
    )


def test_thin_wall_tunnelling_is_caught():
    q_a, q_b = np.array([5.0, 5.0, -0.3, 0.0]), np.array([5.0, 5.0, 0.4, 0.0])
    dut = GeometricChecker(thin_wall_scenario())
    assert dut.is_valid(q_a) and dut.is_valid(q_b) and dut.is_valid((q_a + q_b) / 2)
    assert not dut.is_motion_valid(q_a, q_b) and not dut.is_motion_valid(q_b, q_a)
    # Exact clearances, not sampling: even a 3 m resolution cannot tunnel through.
    assert not GeometricChecker(thin_wall_scenario(), resolution=3.0).is_motion_valid(q_a, q_b)


def test_zero_length_motion_is_its_configuration(tiny_scenario):
    dut = GeometricChecker(tiny_scenario)
    q = np.array([2.0, 2.5, 0.0, math.pi])
    assert dut.is_motion_valid(q, q)
    assert not dut.is_motion_valid([2.9, 3.3, 0.0, 0.0], [2.9, 3.3, 0.0, 0.0])


def test_bad_resolution_is_rejected(tiny_scenario):
    with pytest.raises(ValueError, match="resolution must be > 0"):
        GeometricChecker(tiny_scenario, resolution=0.0)


def test_module_does_not_import_pydrake():
    code = "import sys, drake_social.collision.geometric; sys.exit('pydrake' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0


# ---- touching is not valid, short motions, conservative advancement against a scalar loop


def test_a_configuration_touching_a_wall_is_invalid(tiny_scenario):
    """The base disc (radius 0.35 m) centred 0.35 m from the west wall touches
    it: clearance exactly 0 (the arm points into the room), so not valid."""
    dut = GeometricChecker(tiny_scenario)
    touching = np.array([0.35, 2.5, 0.0, 1.5708])
    assert dut.geometry.base_radius == 0.35 and dut.in_limits(touching)
    assert dut.clearance(touching) == 0.0
    assert not dut.is_valid(touching) and dut.are_valid(touching[None]).tolist() == [False]
    apart = touching + [0.01, 0.0, 0.0, 0.0]
    assert math.isclose(dut.clearance(apart), 0.01, rel_tol=1e-12) and dut.is_valid(apart)


def test_motions_shorter_than_the_resolution_have_two_samples(tiny_scenario):
    """n_e = max(1, ceil(displacement / resolution)): one step, its two ends,
    for a motion that moves no point by more than the resolution (here the
    base by 1 cm, resolution 5 cm), and for a zero-length motion."""
    dut = GeometricChecker(tiny_scenario, resolution=0.05)
    q_a = np.array([[2.0, 2.5, 0.0, 1.5], [3.0, 2.0, 0.5, -1.0], [2.0, 2.5, 0.0, 1.5]])
    q_b = q_a + [[0.01, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.18, 0.0, 0.0, 0.0]]  # 1 cm, 0, 18 cm
    qs, starts = dut.motion_samples(q_a, q_b)
    assert starts.tolist() == [0, 2, 4]  # 2 + 2 + (4 steps + 1) samples
    assert len(qs) == 9
    np.testing.assert_array_equal(qs[:4], [q_a[0], q_b[0], q_a[1], q_b[1]])
    np.testing.assert_allclose(qs[4:, 0], [2.0, 2.045, 2.09, 2.135, 2.18], rtol=0, atol=1e-15)


# ---- conservative advancement, against a plainly written scalar loop


def reference_motion(dut: GeometricChecker, q_a: np.ndarray, q_b: np.ndarray, tolerance=TOLERANCE):
    """The documented scheme one motion at a time: the verdict and the (lo, hi)
    of every round of queries. A query at clearance c clears (c - margin) / D
    of t on its side, D the displacement bound of the body per unit t."""
    dq = q_b - q_a
    if not (dut.in_limits(q_a) and dut.in_limits(q_b)):
        return False, []
    c_a, c_b = dut.clearance(q_a), dut.clearance(q_b)
    if c_a <= tolerance or c_b <= tolerance:
        return False, []
    span = float(dut.geometry.max_displacement(q_a, q_b, include_body=True))
    if span == 0.0:
        return True, []
    lo, hi = (c_a - STEP_MARGIN) / span, 1.0 - (c_b - STEP_MARGIN) / span
    rounds = []
    while lo <= hi:
        rounds.append((lo, hi))
        c_lo, c_hi = dut.clearance(q_a + lo * dq), dut.clearance(q_a + hi * dq)
        if c_lo <= tolerance or c_hi <= tolerance:
            return False, rounds
        lo += (c_lo - STEP_MARGIN) / span
        hi -= (c_hi - STEP_MARGIN) / span
    return True, rounds


def queries_of(dut: GeometricChecker, monkeypatch) -> list:
    """Records every batch of configurations the checker's clearances see."""
    seen = []
    original = dut.clearances

    def spy(qs):
        seen.append(np.array(qs, float).reshape(-1, 4))
        return original(qs)

    monkeypatch.setattr(dut, "clearances", spy)
    return seen


def rotated_wall_scenario() -> Scenario:
    return Scenario(
        world=World(bounds=[0.0, 0.0, 10.0, 8.0], obstacles=[Box(center=[5.0, 4.0], size=[0.05, 0.3]),
                                                             Box(center=[2.5, 6.0], size=[1.0, 0.6], yaw=0.4)]),
        people=[Person(x=7.5, y=2.0, radius=0.25)],
        object=Bar(length=1.2, thickness=0.05),
    )


# (q_a, q_b): valid and invalid motions, turning and translating, short and long.
MOTIONS = [
    ([3.0, 3.0, 0.0, 1.5], [3.2, 3.4, 1.2, -0.5]),  # turning, clear of everything
    ([2.0, 4.5, -1.0, 0.5], [3.3, 4.4, 0.9, 0.2]),  # passing below the rotated box
    ([4.55, 4.0, 1.5708, 0.0], [5.45, 4.0, 1.5708, 0.0]),  # 0.9 m straight through the thin wall
    ([6.5, 2.0, 0.0, 1.0], [8.5, 2.6, 0.0, 1.0]),  # through the person
    ([4.0, 4.0, 0.5, 0.0], [4.0, 4.0, -0.5, 0.0]),  # the arm swings across the thin wall
    ([1.0, 1.0, 0.0, 0.0], [1.0, 1.0, 0.0, 0.0]),  # zero length, clear
]


@pytest.mark.parametrize("k", range(len(MOTIONS)))
def test_advancement_queries_and_verdict_equal_the_scalar_loop(k, monkeypatch):
    scenario = rotated_wall_scenario()
    dut = GeometricChecker(scenario)
    q_a, q_b = (np.array(q) for q in MOTIONS[k])
    expected, rounds = reference_motion(dut, q_a, q_b)
    seen = queries_of(dut, monkeypatch)
    assert dut.is_motion_valid(q_a, q_b) is expected
    np.testing.assert_array_equal(seen[0], q_a[None])  # the ends first
    np.testing.assert_array_equal(seen[1], q_b[None])
    assert len(seen) == 2 + len(rounds)
    dq = q_b - q_a
    for (lo, hi), qs in zip(rounds, seen[2:]):
        np.testing.assert_allclose(qs, [q_a + lo * dq, q_a + hi * dq], rtol=0, atol=1e-12)


def test_the_motions_cover_both_verdicts_and_many_rounds():
    dut = GeometricChecker(rotated_wall_scenario())
    results = [reference_motion(dut, np.array(a), np.array(b)) for a, b in MOTIONS]
    assert [ok for ok, _ in results] == [True, True, False, False, False, True]
    rounds = [len(r) for _, r in results]
    assert min(rounds[:5]) >= 1 and max(rounds) >= 10 and rounds[5] == 0  # advancing, some for many rounds
    assert dut.geometry.max_displacement(np.array(MOTIONS[2][0]), np.array(MOTIONS[2][1]), include_body=True) < 1.0


def test_batched_motions_equal_the_scalar_loop_one_by_one(monkeypatch):
    dut = GeometricChecker(rotated_wall_scenario())
    q_a, q_b = (np.array([m[i] for m in MOTIONS]) for i in (0, 1))
    expected = [reference_motion(dut, a, b) for a, b in zip(q_a, q_b)]
    seen = queries_of(dut, monkeypatch)
    assert dut.are_motions_valid(q_a, q_b).tolist() == [ok for ok, _ in expected]
    # Each round queries two configurations of every motion still open.
    assert sum(len(qs) for qs in seen[2:]) == 2 * sum(len(rounds) for _, rounds in expected)


def test_one_end_in_collision_rejects_the_motion():
    dut = GeometricChecker(rotated_wall_scenario())
    clear, inside = np.array([3.0, 3.0, 0.0, 1.5]), np.array([5.0, 4.0, 0.0, 1.5])  # the base on the thin wall
    assert dut.is_valid(clear) and not dut.is_valid(inside)
    assert not dut.is_motion_valid(clear, inside) and not dut.is_motion_valid(inside, clear)
    assert dut.are_motions_valid([clear, inside], [inside, clear]).tolist() == [False, False]


def test_a_motion_needing_more_rounds_than_max_steps_is_rejected(monkeypatch):
    dut = GeometricChecker(rotated_wall_scenario())
    q_a, q_b = (np.array(q) for q in MOTIONS[1])
    ok, rounds = reference_motion(dut, q_a, q_b)
    assert ok and len(rounds) >= 2
    monkeypatch.setattr(geometric, "MAX_STEPS", len(rounds))
    assert dut.is_motion_valid(q_a, q_b)  # exactly enough rounds
    monkeypatch.setattr(geometric, "MAX_STEPS", len(rounds) - 1)
    assert not dut.is_motion_valid(q_a, q_b)  # one round short: rejected, conservatively


def test_an_end_at_exactly_the_tolerance_is_rejected(tiny_scenario, monkeypatch):
    """The tolerance set to the clearance of one end (the base 5 cm from the
    west wall, the arm pointing into the room): the motion is rejected from
    either side, and accepted with the tolerance 1 um lower."""
    dut = GeometricChecker(tiny_scenario)
    near_wall, inside = np.array([0.4, 2.5, 0.0, 1.5708]), np.array([2.0, 2.5, 0.0, 1.5708])
    c = dut.clearance(near_wall)
    assert math.isclose(c, 0.05, rel_tol=1e-12) and dut.clearance(inside) > 0.5
    monkeypatch.setattr(geometric, "TOLERANCE", c)
    assert not dut.is_motion_valid(near_wall, inside) and not dut.is_motion_valid(inside, near_wall)
    monkeypatch.setattr(geometric, "TOLERANCE", c - 1e-6)
    assert dut.is_motion_valid(near_wall, inside) and dut.is_motion_valid(inside, near_wall)


def test_the_point_where_both_sides_meet_is_queried(monkeypatch):
    """[0, lo) and (hi, 1] are cleared, so at lo == hi the point itself is
    still queried. The base passes 1.2 m from a person's centre (clearance
    0.6 m at the closest point, the midpoint, 0.7 m at the ends); the step margin is set so that
    both ends clear exactly half the motion, the tolerance to the midpoint's
    clearance: the query there rejects the motion."""
    scenario = Scenario(world=World(bounds=[0.0, 0.0, 10.0, 8.0], obstacles=[]),
                        people=[Person(x=5.0, y=5.0, radius=0.25)], object=Bar(length=1.0, thickness=0.05))
    dut = GeometricChecker(scenario)
    q_a, q_b = np.array([4.5, 3.8, -1.5708, 0.0]), np.array([5.5, 3.8, -1.5708, 0.0])  # the arm points away
    c, mid = dut.clearance(q_a), dut.clearance((q_a + q_b) / 2)
    assert c == dut.clearance(q_b) and math.isclose(c, 0.7, rel_tol=1e-12)
    assert math.isclose(mid, 0.6, rel_tol=1e-12)
    assert dut.geometry.max_displacement(q_a, q_b, include_body=True) == 1.0
    monkeypatch.setattr(geometric, "STEP_MARGIN", c - 0.5)  # 0.2 m; lo = hi = 0.5 exactly
    monkeypatch.setattr(geometric, "TOLERANCE", mid)
    seen = queries_of(dut, monkeypatch)
    assert not dut.is_motion_valid(q_a, q_b)
    np.testing.assert_array_equal(seen[2], [(q_a + q_b) / 2] * 2)
    monkeypatch.setattr(geometric, "TOLERANCE", mid - 1e-6)
    assert dut.is_motion_valid(q_a, q_b)


def test_the_limits_are_closed(tiny_scenario):
    """in_limits includes both bounds (room bounds for x, y, the joint limits
    for the joints) and nothing beyond them, for one and for many q."""
    dut = GeometricChecker(tiny_scenario)
    lower, upper = dut.lower, dut.upper
    np.testing.assert_array_equal(lower, [0.0, 0.0, *tiny_scenario.robot.joint_lower])
    np.testing.assert_array_equal(upper, [8.0, 5.0, *tiny_scenario.robot.joint_upper])
    assert dut.in_limits(lower) and dut.in_limits(upper)
    qs = [lower, upper]
    for i in range(4):
        below, above = lower.copy(), upper.copy()
        below[i], above[i] = np.nextafter(lower[i], -np.inf), np.nextafter(upper[i], np.inf)
        qs += [below, above]
    assert dut.in_limits(np.array(qs)).tolist() == [True, True] + [False] * 8
    assert dut.in_limits(np.array(qs).reshape(2, 5, 4)).shape == (2, 5)


def test_walls_of_a_room_not_at_the_origin():
    """Room bounds [-3, -2] .. [5, 4]: the base 0.5 m from the west (then
    the south) wall, the arm and a 1 m bar pointing into the room: clearance
    0.5 - 0.35 m, by hand."""
    scenario = Scenario(world=World(bounds=[-3.0, -2.0, 5.0, 4.0], obstacles=[]), people=[],
                        object=Bar(length=1.0, thickness=0.05))
    dut = GeometricChecker(scenario)
    assert dut.geometry.base_radius == 0.35
    west = np.array([-2.5, 1.0, 0.0, 0.0])  # the arm along +x
    south = np.array([1.0, -1.5, math.pi / 2, 0.0])  # the arm along +y
    np.testing.assert_allclose(dut.clearances(np.array([west, south])), [0.15, 0.15], rtol=1e-12)
    assert dut.is_valid(west) and not dut.is_valid(west - [0.2, 0.0, 0.0, 0.0])  # 0.05 m into the wall


def test_the_checker_keeps_its_scenario(tiny_scenario):
    assert GeometricChecker(tiny_scenario).scenario is tiny_scenario
