"""planning/geometric.py details the broader checker tests leave open (found
by the mutation run): touching is not valid, and a motion shorter than the
resolution is sampled at its two ends only."""

from __future__ import annotations

import math

import numpy as np

from drake_social.planning.geometric import GeometricChecker


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
