"""The pure-numpy checker: exact distances against brute force, hand values, motions, limits."""

from __future__ import annotations

import dataclasses as dc
import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from drake_social.kinematics import ArmGeometry
from drake_social.collision.geometric import GeometricChecker, _segment_box_sdf
from drake_social.collision.validity import ValidityChecker
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
    g = ArmGeometry.from_scenario(scenario)
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
