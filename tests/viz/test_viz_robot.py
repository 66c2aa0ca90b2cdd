"""drake_social.viz.robot: the robot is drawn where the kinematics put it."""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest
from matplotlib.figure import Figure

from drake_social.scenario.geometry import arm_geometry
from drake_social.scenario import LShape
from drake_social.viz import capsule_outline, draw_robot


def _point_segment_distance(p, a, b):
    t = np.clip(np.dot(p - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
    return np.linalg.norm(p - (a + t * (b - a)))


@pytest.mark.parametrize("b", [(1.0, 0.0), (-0.3, 0.7), (0.0, -2.0)])
def test_capsule_outline_is_at_the_radius_from_the_axis(b):
    a, b = np.array([0.2, -0.1]), np.array(b)
    dut = capsule_outline(a, b, 0.05, arc_points=13)
    assert dut.shape == (26, 2)
    for p in dut:
        assert _point_segment_distance(p, a, b) == pytest.approx(0.05, abs=1e-12)
    # It reaches past both ends by the radius.
    axis = (b - a) / np.linalg.norm(b - a)
    along = (dut - a) @ axis
    assert along.min() == pytest.approx(-0.05) and along.max() == pytest.approx(np.linalg.norm(b - a) + 0.05)


def test_capsule_outline_of_a_point_is_a_circle():
    dut = capsule_outline([1.0, 1.0], [1.0, 1.0], 0.2)
    np.testing.assert_allclose(np.hypot(dut[:, 0] - 1.0, dut[:, 1] - 1.0), 0.2)


def _draw(scenario, q, **kwargs):
    fig = Figure()
    ax = fig.add_subplot()
    geometry = arm_geometry(scenario)
    return geometry, draw_robot(ax, geometry, np.asarray(q, float), **kwargs), ax


def test_robot_parts_follow_the_kinematics(tiny_scenario):
    """Hand values: q = [1, 2, pi/2, -pi/2]: link 1 up to (1, 2.6), link 2
    right to (1.5, 2.6), the bar across link 2 from (1.5, 1.85) to (1.5, 3.35)."""
    geometry, dut, _ = _draw(tiny_scenario, [1.0, 2.0, math.pi / 2, -math.pi / 2])
    (base,) = dut["base"]
    assert base.center == pytest.approx((1.0, 2.0)) and base.radius == pytest.approx(0.35)
    expected_axes = {
        "link1": ([1.0, 2.0], [1.0, 2.6], 0.04),
        "link2": ([1.0, 2.6], [1.5, 2.6], 0.04),
        "object": ([1.5, 1.85], [1.5, 3.35], 0.025),
    }
    for part, (a, b, r) in expected_axes.items():
        (patch,) = dut[part]
        for p in patch.get_xy():
            assert _point_segment_distance(p, np.array(a), np.array(b)) == pytest.approx(r, abs=1e-9)
    (markers,) = dut["interest"]
    pts = np.column_stack([markers.get_xdata(), markers.get_ydata()])
    np.testing.assert_allclose(pts, [[1, 2], [1, 2.6], [1.5, 2.6], [1.5, 1.85], [1.5, 3.35]], atol=1e-12)


def test_l_shape_gets_one_patch_per_bar_and_three_object_points(tiny_scenario):
    scenario = dc.replace(tiny_scenario, object=LShape(lengths=[3.0, 2.0]))
    geometry, dut, _ = _draw(scenario, [4.0, 2.5, 0.3, 2.5], labels=True)
    assert len(dut["object"]) == 2
    assert len(dut["interest"][0].get_xdata()) == 6
    # Legend labels once per part, not per object bar.
    labels = [a.get_label() for part in dut.values() for a in part]
    assert labels.count("object") == 1
    assert {"robot base", "link 1", "link 2", "object", "interest points"} <= set(labels)


def test_options_alpha_no_interest_no_labels(tiny_scenario):
    _, dut, ax = _draw(tiny_scenario, [1.0, 2.0, 0.0, 0.0], alpha=0.3, interest_points=False)
    assert dut["interest"] == []
    assert all(a.get_alpha() == 0.3 for part in dut.values() for a in part)
    assert ax.get_legend_handles_labels() == ([], [])


def test_robot_needs_one_configuration(tiny_scenario):
    with pytest.raises(ValueError, match="one configuration"):
        _draw(tiny_scenario, np.zeros((2, 4)))
