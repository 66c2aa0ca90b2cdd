"""planning/geometric.py details the broader checker tests leave open (found
by the mutation run): touching is not valid, and a motion shorter than the
resolution is sampled at its two ends only."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_social.collision import geometric
from drake_social.collision.geometric import GeometricChecker
from drake_social.collision.planar_kernel import STEP_MARGIN, TOLERANCE
from drake_social.scenario import Bar, Box, Person, Scenario, World


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
