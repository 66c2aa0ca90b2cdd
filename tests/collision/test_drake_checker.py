"""The SceneGraph validity checker: hand-made cases, tunnelling, agreement with numpy, start/goal."""

from __future__ import annotations

import dataclasses as dc
import functools
import math
from pathlib import Path

import numpy as np
import pytest

from drake_social.kinematics import ArmGeometry
from drake_social.collision.drake_checker import Contact, SceneGraphChecker, check_start_goal
from drake_social.collision.planar_checker import PlanarChecker
from drake_social.collision.geometric import GeometricChecker
from drake_social.collision.validity import ValidityChecker
from drake_social.scenario import Box, Polyline, Scenario, ScenarioError, World, load_scenario

SCENARIO_DIR = Path(__file__).resolve().parents[2] / "scenarios"
SCENARIOS = sorted(SCENARIO_DIR.glob("*.yaml"))


@functools.lru_cache(maxsize=None)
def _checkers(path: Path) -> tuple[Scenario, SceneGraphChecker, GeometricChecker]:
    scenario = load_scenario(path)
    return scenario, SceneGraphChecker(scenario), GeometricChecker(scenario)


@pytest.fixture(scope="module")
def tiny(tiny_scenario_path):
    return _checkers(tiny_scenario_path)


def test_both_checkers_keep_the_protocols_contract(tiny, rng):
    """What the planners rely on, not just the method names: batched answers
    are (N,) bool arrays equal to the single calls, a configuration off the
    joint limits or the room is invalid, inside them validity is clearance >
    0, a motion is invalid when an end is, and a zero-length motion is valid
    iff its configuration is."""
    _, drake, numpy_ = tiny
    qs = rng.uniform(drake.lower - 0.2, drake.upper + 0.2, size=(60, 4))
    q_b = qs + rng.normal(scale=0.5, size=qs.shape)
    for dut in (drake, numpy_):
        assert isinstance(dut, ValidityChecker)
        valid = dut.are_valid(qs)
        assert valid.shape == (60,) and valid.dtype == bool
        np.testing.assert_array_equal(valid, [dut.is_valid(q) for q in qs])
        inside = np.all((qs >= dut.lower) & (qs <= dut.upper), axis=1)
        assert 5 < inside.sum() < 55
        assert not valid[~inside].any()
        clear = np.array([dut.clearance(q) for q in qs[inside]])
        np.testing.assert_array_equal(valid[inside], clear > 0)
        assert 0 < valid.sum() < inside.sum()  # both outcomes inside the limits
        motions = dut.are_motions_valid(qs, q_b)
        assert motions.shape == (60,) and motions.dtype == bool
        np.testing.assert_array_equal(motions, [dut.is_motion_valid(a, b) for a, b in zip(qs, q_b)])
        assert not motions[~(valid & dut.are_valid(q_b))].any()
        np.testing.assert_array_equal(dut.are_motions_valid(qs, qs), valid)
    np.testing.assert_array_equal(drake.are_valid(qs), numpy_.are_valid(qs))


# ---- hand-made configurations in tiny.yaml (8 x 5 m room, desk x 3.2..4.8 y 0.2..1.0,
# ---- person r = 0.25 at (4, 3.8), base r = 0.35, links 0.6 + 0.5, bar 1.5 x 0.05 across link 2)


def test_object_through_the_person_is_invalid(tiny):
    _, dut, numpy_ = tiny
    q = np.array([2.9, 3.3, 0.0, 0.0])  # gripper at (4, 3.3); the bar runs x = 4, y 2.55..4.05
    assert not dut.is_valid(q) and not numpy_.is_valid(q)
    (contact,) = dut.contacts(q)
    assert (contact.robot_body, contact.other) == ("object", "person[0] 'standing'")
    # The bar's axis passes through the person's centre: depth = 0.25 + 0.025.
    assert contact.distance == pytest.approx(-0.275, abs=1e-6)
    assert numpy_.clearance(q) == pytest.approx(-0.275, abs=1e-9)


def test_base_against_a_wall_is_invalid(tiny):
    _, dut, numpy_ = tiny
    q = np.array([0.3, 2.5, 0.0, math.pi / 2])
    assert not dut.is_valid(q) and not numpy_.is_valid(q)
    assert [(c.robot_body, c.other) for c in dut.contacts(q)] == [("base", "wall_west")]
    assert dut.contacts(q)[0].distance == pytest.approx(-0.05, abs=1e-6)
    # Touching the wall from outside 1 mm is valid.
    q_ok = np.array([0.351, 2.5, 0.0, math.pi / 2])
    assert dut.is_valid(q_ok) and numpy_.is_valid(q_ok)
    assert dut.clearance(q_ok) == pytest.approx(0.001, abs=1e-6)


def test_folded_arm_in_open_space_is_valid_with_the_object_over_the_base(tiny):
    _, dut, numpy_ = tiny
    q = np.array([2.0, 2.5, 0.0, math.pi])  # gripper back at (2.1, 2.5): the bar crosses the base disc
    assert dut.is_valid(q) and numpy_.is_valid(q)
    assert dut.contacts(q) == []
    # Nearest pair: the bar's lower end (2.1, 1.75) and the desk's corner (3.2, 1.0).
    expected = math.hypot(1.1, 0.75) - 0.025
    assert numpy_.clearance(q) == pytest.approx(expected, abs=1e-12)
    assert dut.clearance(q) == pytest.approx(expected, abs=1e-6)


@pytest.mark.parametrize(
    "q",
    [
        [-0.5, 2.5, 0.0, 0.0],  # base centre west of the room
        [8.2, 2.5, math.pi, 0.0],
        [4.0, 5.01, 0.0, 0.0],
        [2.0, 2.5, 0.0, math.pi + 0.1],  # the folded arm above, one joint past its limit
        [2.0, 2.5, -math.pi - 1e-9, math.pi],
    ],
)
def test_outside_the_bounds_or_joint_limits_is_invalid(tiny, q):
    _, dut, numpy_ = tiny
    assert not dut.is_valid(q) and not numpy_.is_valid(q)
    assert not dut.are_valid(np.array([q]))[0] and not numpy_.are_valid(np.array([q]))[0]
    q_in = np.array([2.0, 2.5, 0.0, math.pi])
    assert not dut.is_motion_valid(q_in, q) and not numpy_.is_motion_valid(q_in, q)


@pytest.mark.slow
def test_batched_calls_equal_single_calls(tiny, rng):
    _, dut, numpy_ = tiny
    qs = rng.uniform(dut.lower - 0.2, dut.upper + 0.2, size=(300, 4))
    for checker in (dut, numpy_):
        np.testing.assert_array_equal(checker.are_valid(qs), [checker.is_valid(q) for q in qs])
    q_b = np.clip(qs + rng.normal(scale=0.3, size=qs.shape), dut.lower, dut.upper)
    for checker in (dut, numpy_):
        np.testing.assert_array_equal(
            checker.are_motions_valid(qs, q_b), [checker.is_motion_valid(a, b) for a, b in zip(qs, q_b)]
        )


@pytest.mark.slow
def test_sequential_and_parallel_agree(tiny_scenario, rng):
    single = SceneGraphChecker(tiny_scenario, parallelism=False)
    dut = SceneGraphChecker(tiny_scenario, parallelism=2)
    qs = rng.uniform(dut.lower, dut.upper, size=(2000, 4))
    np.testing.assert_array_equal(dut.are_valid(qs), single.are_valid(qs))
    q_b = np.clip(qs + rng.normal(scale=0.5, size=qs.shape), dut.lower, dut.upper)
    np.testing.assert_array_equal(dut.are_motions_valid(qs, q_b), single.are_motions_valid(qs, q_b))


# ---- motions


def thin_wall_scenario() -> Scenario:
    """A 3 m object whose tip swings across a 5 cm wall when psi1 goes -0.3 -> 0.4 rad.

    Base at (5, 5); the object runs along the gripper x axis from 1.1 m to
    4.1 m from the base centre; the wall (0.3 x 0.05 m) lies across its path
    at 3.75..4.05 m. At psi1 = 0.05 (the midpoint) the object passes 0.19 m
    beside the wall, so checking the ends and the midpoint misses it.
    """
    return Scenario(
        world=World(bounds=[0.0, 0.0, 10.0, 10.0], obstacles=[Box(center=[8.9, 5.0], size=[0.3, 0.05])]),
        object=Polyline(points=[[0.0, 0.0], [3.0, 0.0]], thickness=0.05),
        start=[5.0, 5.0, -0.3, 0.0],
        goal=[5.0, 5.0, 0.4, 0.0],
    )


def test_thin_wall_tunnelling_is_caught():
    scenario = thin_wall_scenario()
    q_a, q_b = np.array(scenario.start), np.array(scenario.goal)
    dut = SceneGraphChecker(scenario)
    numpy_ = GeometricChecker(scenario)
    for checker in (dut, numpy_):
        assert checker.is_valid(q_a) and checker.is_valid(q_b)
        assert checker.is_valid((q_a + q_b) / 2)
        assert not checker.is_valid([5.0, 5.0, 0.0, 0.0])
        assert not checker.is_motion_valid(q_a, q_b)
        assert not checker.is_motion_valid(q_b, q_a)
    check_start_goal(scenario, dut)
    # The test has teeth: at a 3 m resolution Drake's checker only looks at the
    # ends and the midpoint, and misses the wall; the numpy checker advances by
    # its exact clearance, so its resolution does not matter.
    assert SceneGraphChecker(scenario, resolution=3.0).is_motion_valid(q_a, q_b)
    assert not GeometricChecker(scenario, resolution=3.0).is_motion_valid(q_a, q_b)


def _body_points(geometry: ArmGeometry, q: np.ndarray) -> np.ndarray:
    """Dense points (N, K, 2) on the boundary and axes of every body at q (N, 4)."""
    seg = geometry.segments(q)  # (N, S, 2, 2)
    t = np.linspace(0.0, 1.0, 41)
    axis = seg[:, :, None, 0] + t[:, None] * (seg[:, :, None, 1] - seg[:, :, None, 0])  # (N, S, T, 2)
    ang = np.linspace(0.0, 2 * math.pi, 24, endpoint=False)
    circle = np.stack([np.cos(ang), np.sin(ang)], -1)  # (C, 2)
    rim = axis[:, :, :, None, :] + geometry.segment_radii[:, None, None, None] * circle  # (N, S, T, C, 2)
    base = q[:, None, :2] + geometry.base_radius * circle
    return np.concatenate([rim.reshape(len(q), -1, 2), axis.reshape(len(q), -1, 2), base], 1)


def test_no_body_point_moves_more_than_the_resolution_between_drake_edge_samples(tiny_scenario, rng):
    dut = SceneGraphChecker(tiny_scenario, resolution=0.05)
    assert dut.edge_step_size == pytest.approx(0.05 / math.sqrt(3))
    geometry = dut.geometry
    worst = 0.0
    for _ in range(40):
        q_a = rng.uniform(dut.lower, dut.upper)
        q_b = np.clip(q_a + rng.normal(scale=1.0, size=4), dut.lower, dut.upper)
        d = dut.drake.ComputeConfigurationDistance(q_a, q_b)
        w = geometry.reach(include_body=True)
        assert d == pytest.approx(np.linalg.norm(w * (q_b - q_a)), rel=1e-12)
        n = max(1, math.ceil(d / dut.edge_step_size))  # Drake's step count
        qs = q_a + np.linspace(0.0, 1.0, n + 1)[:, None] * (q_b - q_a)
        pts = _body_points(geometry, qs)
        step = np.linalg.norm(np.diff(pts, axis=0), axis=-1).max()
        assert step <= 0.05 + 1e-12
        worst = max(worst, step)
    assert worst > 0.05 / 4  # the sampling is not absurdly fine either


# ---- numpy vs SceneGraph, start and goal of every scenario


@pytest.mark.slow
@pytest.mark.parametrize("path", SCENARIOS, ids=[p.name for p in SCENARIOS])
def test_numpy_and_scenegraph_agree_on_10000_random_configurations(path, rng):
    scenario, dut, numpy_ = _checkers(path)
    qs = rng.uniform(dut.lower, dut.upper, size=(10_000, 4))
    drake_valid = dut.are_valid(qs)
    numpy_valid = numpy_.are_valid(qs)
    disagree = np.flatnonzero(drake_valid != numpy_valid)
    # Any disagreement must be a contact closer than 1 mm (floating point / GJK tolerance).
    margins = numpy_.clearances(qs[disagree])
    assert np.all(np.abs(margins) < 1e-3), f"{path.name}: disagreements at clearance {margins}"
    assert len(disagree) <= 5
    assert 0.05 < drake_valid.mean() < 0.999  # both outcomes are exercised
    # Clearances agree too, where they are exact (positive). Tolerance: FCL's
    # GJK on cylinder-box pairs errs by up to ~2e-5 m (measured: base disc vs
    # wall 0.813523 where the exact value is 0.813505).
    some = qs[:200]
    c_drake = np.array([dut.clearance(q) for q in some])
    c_numpy = numpy_.clearances(some)
    np.testing.assert_array_equal(c_drake > 0, c_numpy > 0)
    pos = c_numpy > 0
    np.testing.assert_allclose(c_drake[pos], c_numpy[pos], atol=1e-4)


def _dense_min_clearance(checker, q_a: np.ndarray, q_b: np.ndarray, step: float = 0.001) -> float:
    """Least exact clearance along q_a -> q_b at configurations no body point
    is more than ``step`` metres apart (an upper bound on the true minimum,
    at most ``step / 2`` above it)."""
    geometry = checker.geometry
    n = max(1, math.ceil(float(geometry.max_displacement(q_a, q_b, include_body=True)) / step))
    return float(checker.clearances(q_a + np.linspace(0.0, 1.0, n + 1)[:, None] * (q_b - q_a)).min())


@pytest.mark.slow
@pytest.mark.parametrize("path", SCENARIOS, ids=[p.name for p in SCENARIOS])
def test_numpy_and_scenegraph_motions_agree(path, rng):
    """Random motions between valid ends (the planner's case), checked by
    what each checker guarantees (drake_social.collision.drake_checker's docstring):

    * numpy and planar are exact and sound: a motion is accepted iff its
      exact clearance stays > 0 all along. Against a 1 mm reference: every
      accepted motion is free at every 1 mm sample, every rejected one comes
      within 1 mm of contact, and the two agree wherever the reference is
      more than 1 mm from contact.
    * Drake's motion check is approximate: it may differ from numpy only by
      missing a shallow contact (< 1 cm, FCL's overestimates) or by finding
      one that is real to 1 mm, on at most 1 % of the motions.

    A numpy checker stepping twice as far as its clearance allows accepts
    colliding motions here (5 over the three maps) and fails."""
    scenario, dut, numpy_ = _checkers(path)
    planar = PlanarChecker(scenario)
    q_a = rng.uniform(dut.lower, dut.upper, size=(600, 4))
    q_b = np.clip(q_a + rng.normal(scale=1.5, size=q_a.shape), dut.lower, dut.upper)
    ok = numpy_.are_valid(q_a) & numpy_.are_valid(q_b)
    q_a, q_b = q_a[ok], q_b[ok]
    drake_valid = dut.are_motions_valid(q_a, q_b)
    numpy_valid = numpy_.are_motions_valid(q_a, q_b)
    planar_valid = planar.are_motions_valid(q_a, q_b)
    assert len(q_a) > 50 and 0.05 < numpy_valid.mean() < 0.95
    reference = np.array([_dense_min_clearance(planar, a, b) for a, b in zip(q_a, q_b)])
    for name, valid in (("numpy", numpy_valid), ("planar", planar_valid)):
        assert np.all(reference[valid] > 0), f"{name} accepted colliding motions: {reference[valid].min()} m"
        assert np.all(reference[~valid] < 1e-3), f"{name} rejected free motions: {reference[~valid].max()} m"
    away = np.abs(reference) > 1e-3
    np.testing.assert_array_equal(numpy_valid[away], planar_valid[away])
    missed = drake_valid & ~numpy_valid
    assert np.all(reference[missed] > -0.01), reference[missed]
    found = ~drake_valid & numpy_valid
    assert np.all(reference[found] < 1e-3), reference[found]
    assert (drake_valid != numpy_valid).sum() <= 0.01 * len(q_a)


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.name)
def test_start_and_goal_of_every_scenario_are_valid(path):
    scenario, dut, numpy_ = _checkers(path)
    check_start_goal(scenario, dut, source=str(path))
    for q in (scenario.start, scenario.goal):
        assert dut.is_valid(q) and numpy_.is_valid(q)


def test_a_colliding_start_is_rejected_naming_the_bodies(tiny_scenario_path):
    # Base 0.5 m from the person: 0.1 m into her; the arm hangs south, clear of the desk.
    # (Loading refuses such a start; the checker's own message is tested here.)
    scenario = dc.replace(load_scenario(tiny_scenario_path), start=[4.0, 3.3, -1.5708, 0.0])
    with pytest.raises(ScenarioError) as e:
        check_start_goal(scenario, source=str(tiny_scenario_path))
    message = str(e.value)
    assert message.startswith(f"{tiny_scenario_path}: start: ")
    assert "base with person[0] 'standing' (-0.100 m)" in message
    assert "object" not in message and "link" not in message


def test_a_start_outside_the_limits_is_rejected(tiny_scenario):
    scenario = dc.replace(tiny_scenario, start=[1.0, 2.5, 0.0, 4.0])
    with pytest.raises(ScenarioError, match=r"<scenario>: start: configuration .* outside the limits"):
        check_start_goal(scenario)


def test_a_colliding_goal_names_every_colliding_body(tiny_scenario):
    # Base into the west wall and the bar through the person at once.
    scenario = dc.replace(tiny_scenario, start=[2.0, 2.5, 0.0, math.pi], goal=[0.3, 3.3, 0.0, 0.0])
    scenario = dc.replace(
        scenario,
        robot=dc.replace(scenario.robot, link_lengths=[2.0, 1.7]),  # gripper at (4.0, 3.3)
    )
    with pytest.raises(ScenarioError) as e:
        check_start_goal(scenario)
    message = str(e.value)
    assert "goal" in message
    assert "object with person[0] 'standing' (-0.275 m)" in message
    assert "base with wall_west (-0.050 m)" in message


def test_contact_reads_naturally():
    assert str(Contact("object", "person[0] 'ana'", -0.12345)) == "object with person[0] 'ana' (-0.123 m)"
