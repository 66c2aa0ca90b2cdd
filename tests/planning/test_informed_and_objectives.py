"""Informed sampling against an ellipse computed here, the admissible bound
with anisotropic distance weights, and distance weights kept by base-only costs."""

from __future__ import annotations

import copy
import dataclasses as dc
import math

import numpy as np
import pytest

from drake_social.cost import SocialCost
from drake_social.planning.geometric import GeometricChecker
from drake_social.planning.objective import SocialObjective
from drake_social.planning.sampling import EllipseSampler, transverse_diameter
from drake_social.planning.space import ConfigurationSpace
from drake_social.planning.variants import base_only_weights, make_objective, plan
from drake_social.scenario import Person, Scenario, World, validate_scenario

PI = math.pi


def test_informed_samples_lie_in_the_ellipse_of_start_goal_and_c(tiny_scenario, monkeypatch):
    """The ellipse is computed here from the scenario's start and goal (the
    foci) and the diameter c the planner passed, not with the sampler's own
    ``contains`` (a wrong second focus passed that check)."""
    from drake_social.planning import sampling

    scenario = copy.deepcopy(tiny_scenario)
    scenario.planner = dc.replace(scenario.planner, iterations=400)
    drawn = []
    original = sampling.EllipseSampler.sample

    def recording(self, rng, c):
        q = original(self, rng, c)
        drawn.append((q, c))
        return q

    monkeypatch.setattr(sampling.EllipseSampler, "sample", recording)
    dut = plan(scenario, GeometricChecker(scenario), algorithm="informed_social_rrt_star", seed=5)
    assert dut.success
    f1, f2 = np.array(scenario.start[:2]), np.array(scenario.goal[:2])
    inside = [(q, c) for q, c in drawn if np.isfinite(c)]
    assert len(inside) > 50
    for q, c in inside:
        assert math.dist(q[:2], f1) + math.dist(q[:2], f2) <= max(c, math.dist(f1, f2)) + 1e-9
    # The samples fill the ellipse: some lie near its far end from the start.
    c_last = inside[-1][1]
    assert max(math.dist(q[:2], f1) for q, _ in inside) > 0.8 * (c_last + math.dist(f1, f2)) / 2


def test_ellipse_sampler_fills_exactly_the_independent_ellipse(rng):
    """Rotated foci: every sample inside, and samples reach both vertices of
    the major axis and the minor axis (a wrong axis or focus fails one)."""
    space = ConfigurationSpace(np.array([-20.0, -20.0, -PI, -PI]), np.array([20.0, 20.0, PI, PI]))
    f1, f2 = np.array([1.0, -2.0]), np.array([4.0, 2.0])  # focal distance 5, rotated
    c = 7.0
    dut = EllipseSampler(space, f1, f2)
    xy = np.array([dut.sample(rng, c)[:2] for _ in range(4000)])
    s = np.hypot(*(xy - f1).T) + np.hypot(*(xy - f2).T)
    assert np.all(s <= c + 1e-9)
    centre, axis = (f1 + f2) / 2, (f2 - f1) / 5.0
    along = (xy - centre) @ axis
    across = (xy - centre) @ np.array([-axis[1], axis[0]])
    a, b = c / 2, math.sqrt(c**2 - 25) / 2
    assert along.max() > 0.95 * a and along.min() < -0.95 * a
    assert across.max() > 0.95 * b and across.min() < -0.95 * b
    # Uniform over the area: a quarter of the samples within half the scale.
    assert np.mean((along / a) ** 2 + (across / b) ** 2 <= 0.25) == pytest.approx(0.25, abs=0.03)


def room_with_weights(weights) -> Scenario:
    scenario = Scenario(
        world=World(bounds=[0.0, 0.0, 10.0, 8.0]),
        people=[Person(x=5.0, y=4.0, theta=PI / 4)],
        start=[1.0, 1.0, 0.0, 0.5],
        goal=[8.0, 7.0, 0.3, -0.5],
    )
    scenario.social.length_weight = 0.5
    scenario.planner = dc.replace(scenario.planner, distance_weights=list(weights))
    validate_scenario(scenario)
    return scenario


@pytest.mark.parametrize("weights", [[2.0, 0.5, 1.0, 1.0], [0.3, 3.0, 0.2, 2.0]])
def test_admissible_bound_holds_with_anisotropic_distance_weights(weights, rng):
    """Every path's base XY length is at most xy_length_bound(its cost), in
    particular paths that move along the lightly weighted axis (where
    max(w_x, w_y) in place of min would give a bound 4 to 10 times too small)."""
    scenario = room_with_weights(weights)
    dut = make_objective(scenario, "social_rrt_star")
    np.testing.assert_array_equal(dut.distance_weights, weights)
    light = int(np.argmin(weights[:2]))
    space = ConfigurationSpace.from_scenario(scenario)
    for trial in range(30):
        n = int(rng.integers(2, 6))
        wp = space.sample_uniform(rng, n)
        if trial < 10:  # straight along the light axis, arm still
            wp = np.repeat(wp[:1], n, axis=0)
            wp[:, light] = np.linspace(space.lower[light], space.upper[light], n)
        cost = float(dut.motion_cost(wp[:-1], wp[1:]).sum())
        xy_length = float(np.hypot(*np.diff(wp[:, :2], axis=0).T).sum())
        assert xy_length <= dut.xy_length_bound(cost) * (1 + 1e-12)
        assert transverse_diameter("admissible", cost, 0.0, dut) == dut.xy_length_bound(cost)
    # Along the light axis the bound is tight when the path costs no social cost.
    far = copy.deepcopy(scenario)
    far.people = []
    flat = make_objective(far, "social_rrt_star")
    a, b = np.zeros(4), np.zeros(4)
    b[light] = 3.0
    assert flat.xy_length_bound(float(flat.motion_cost(a, b)[0])) == pytest.approx(3.0, rel=1e-12)


def test_base_only_cost_keeps_the_distance_weights():
    """``with_weights`` keeps ``distance_weights``; the base-only objective
    integrates over ``ds = ||W dq||`` like the multi-point one."""
    weights = [2.0, 0.5, 1.0, 3.0]
    scenario = room_with_weights(weights)
    full = SocialCost.from_scenario(scenario)
    dut = full.with_weights(base_only_weights(full.geometry.num_interest_points))
    np.testing.assert_array_equal(dut.distance_weights, weights)
    np.testing.assert_array_equal(dut.weights, [1, 0, 0, 0, 0])
    objective = make_objective(scenario, "base_rrt_star")
    assert isinstance(objective, SocialObjective)
    np.testing.assert_array_equal(objective.social.distance_weights, weights)
    np.testing.assert_array_equal(objective.distance_weights, weights)
    # A motion through the person's space: the cost scales with ||W dq||.
    q_a, q_b = np.array([3.0, 3.0, 0.0, 0.0]), np.array([6.0, 5.0, 0.0, 0.0])
    plain = full.with_weights(np.array([1.0, 0, 0, 0, 0]))
    plain.distance_weights = None
    ratio = float(dut.motion_cost(q_a, q_b)) / float(plain.motion_cost(q_a, q_b))
    assert ratio == pytest.approx(math.hypot(2.0 * 3.0, 0.5 * 2.0) / math.hypot(3.0, 2.0), rel=1e-12)
