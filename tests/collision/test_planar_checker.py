"""The planar checker built from the SceneGraph: soundness properties, agreement, poses, wiring.

The reference distances here are independent of both the kernel and the numpy
checker: the robot's capsules come from ``ArmGeometry.segments`` (the
scenario, not the SceneGraph), the room from the scenario and ``wall_boxes``,
and each (capsule, shape) distance is the minimum of the shape's exact
signed-distance function along the capsule's axis found by golden-section
search (that function is convex), minus the radius.
"""

from __future__ import annotations

import functools
import math
import tempfile
import zlib
from pathlib import Path

import numpy as np
import pytest

from drake_social.experiments.bench.maps import map_bench_scenario
from drake_social.maps import map_boxes, read_map
from drake_social.people import people_model
from drake_social.collision.drake_checker import CHECKERS, SceneGraphChecker, make_checker, verify_path
from drake_social.collision.planar_checker import PlanarChecker
from drake_social.model.plant import wall_boxes
from drake_social.collision.geometric import GeometricChecker
from drake_social.collision.validity import ValidityChecker
from drake_social.scenario import Box, LShape, Person, Scenario, World, load_scenario

SCENARIO_DIR = Path(__file__).resolve().parents[2] / "scenarios"
SCENARIOS = sorted(SCENARIO_DIR.glob("*.yaml"))


def rotated_room(seed: int) -> Scenario:
    """A 12 x 8 m room with 10 randomly rotated boxes, 3 people and the L object."""
    rng = np.random.default_rng(seed)
    boxes = [Box(center=rng.uniform([1, 1], [11, 7]).tolist(), size=rng.uniform(0.1, 1.5, 2).tolist(),
                 yaw=float(rng.uniform(-math.pi, math.pi))) for _ in range(10)]
    people = [Person(x=float(x), y=float(y), radius=0.25) for x, y in rng.uniform([1, 1], [11, 7], (3, 2))]
    return Scenario(world=World(bounds=[0.0, 0.0, 12.0, 8.0], obstacles=boxes), people=people,
                    object=LShape(lengths=[1.6, 0.8], thickness=0.05), start=[1, 1, 0, 0], goal=[2, 2, 0, 0])


_MAP_FOLDER = tempfile.TemporaryDirectory(prefix="test_planar_checker_map_")


def ragged_floor() -> Scenario:
    """A generated 16 x 14 m floor map with ragged walls (hundreds of boxes,
    so the grid's paths and the room read in several parts), 4 people."""
    return load_scenario(map_bench_scenario(_MAP_FOLDER.name, width=16.0, height=14.0, resolution=0.05))


CASES = [(p.name, lambda p=p: load_scenario(p)) for p in SCENARIOS] + [
    (f"rotated_room_{s}", lambda s=s: rotated_room(s)) for s in (1, 2, 3)
] + [("ragged_floor", ragged_floor)]


@functools.lru_cache(maxsize=None)
def _case(name: str):
    scenario = dict(CASES)[name]()
    return scenario, PlanarChecker(scenario), GeometricChecker(scenario)


NAMES = [n for n, _ in CASES]


# ---- the independent reference ------------------------------------------------


def _golden_min(f, n_iter: int = 110):
    g = (math.sqrt(5) - 1) / 2
    lo = np.zeros_like(f(0.0))
    hi = np.ones_like(lo)
    for _ in range(n_iter):
        a, b = hi - g * (hi - lo), lo + g * (hi - lo)
        left = f(a) < f(b)
        hi, lo = np.where(left, b, hi), np.where(left, lo, a)
    return np.minimum(np.minimum(f(0.0), f(1.0)), f(0.5 * (lo + hi)))


def exact_clearances(scenario: Scenario, geometry, qs: np.ndarray) -> np.ndarray:
    """(N,) exact planar signed clearance (sign only when negative) of configurations (N, 4)."""
    seg = geometry.segments(qs)  # (N, S, 2, 2)
    base = np.repeat(qs[:, None, None, :2], 2, axis=2)  # the base disc: a zero-length capsule
    seg = np.concatenate([base, seg], 1)
    radii = np.concatenate([[geometry.base_radius], geometry.segment_radii])
    a, d = seg[:, :, None, 0], seg[:, :, None, 1] - seg[:, :, None, 0]  # (N, S, 1, 2)
    boxes = list(scenario.world.obstacles) + list(wall_boxes(scenario).values())
    if scenario.world.map is not None:  # the map's boxes (their union: exactly its cells, tests/maps)
        grid = map_boxes(read_map(scenario.world.map), scenario.world.unknown)
        boxes += [Box(center=list(c), size=list(z), yaw=float(y)) for c, z, y in zip(grid.centers, grid.sizes,
                                                                                      grid.yaws)]
    best = np.full(len(qs), np.inf)
    if boxes:
        c = np.array([b.center for b in boxes], float)
        h = np.array([b.size for b in boxes], float) / 2
        yaw = np.array([b.yaw for b in boxes], float)
        co, si = np.cos(yaw), np.sin(yaw)

        def sdf(t):
            px, py = a[..., 0] + t * d[..., 0] - c[:, 0], a[..., 1] + t * d[..., 1] - c[:, 1]
            u, v = co * px + si * py, -si * px + co * py
            ux, uy = np.abs(u) - h[:, 0], np.abs(v) - h[:, 1]
            return np.hypot(np.maximum(ux, 0), np.maximum(uy, 0)) + np.minimum(np.maximum(ux, uy), 0)

        best = np.minimum(best, (_golden_min(sdf) - radii[:, None]).min((1, 2)))
    people = people_model(scenario).state_at(0.0).visible()  # standing, scripted and crowd people at t = 0
    if people.count:
        p, r = people.positions, people.radii

        def dist(t):
            return np.hypot(a[..., 0] + t * d[..., 0] - p[:, 0], a[..., 1] + t * d[..., 1] - p[:, 1]) - r

        best = np.minimum(best, (_golden_min(dist) - radii[:, None]).min((1, 2)))
    return best


def _near_configs(dut: PlanarChecker, rng: np.random.Generator, n: int) -> np.ndarray:
    """n configurations: half uniform, half pulled to within ~0.3 m of contact."""
    qs = rng.uniform(dut.lower, dut.upper, size=(8 * n, 4))
    c = dut.clearances(qs)
    near = qs[np.abs(c) < 0.3][: n // 2]
    return np.concatenate([qs[: n - len(near)], near])


# ---- (1) the clearance is never larger than the exact planar distance -------------


@pytest.mark.slow
@pytest.mark.parametrize("name", NAMES)
def test_clearance_never_exceeds_the_exact_planar_distance(name, rng):
    """1,500 configurations per map (6 maps: 9,000), half of them within 0.3 m
    of contact: the planar and numpy clearances equal the exact distance to
    1e-9 where it is positive, and are <= 1e-9 where it is not."""
    scenario, dut, numpy_ = _case(name)
    qs = _near_configs(dut, rng, 1500)
    ref = exact_clearances(scenario, dut.geometry, qs)
    apart = ref > 0
    assert 0.2 < apart.mean() < 0.95
    for got in (dut.clearances(qs), numpy_.clearances(qs)):
        np.testing.assert_allclose(got[apart], ref[apart], atol=1e-9, rtol=0)
        assert np.all(got[~apart] <= 1e-9)


# ---- (2) accepted motions near obstacles are free at 1 mm steps ---------------------


def _dense_min_clearance(checkers, q_a, q_b, step=0.001):
    """Least clearance along q_a -> q_b sampled so no body point moves more than ``step``, by each checker."""
    geometry = checkers[0].geometry
    n = max(1, math.ceil(float(geometry.max_displacement(q_a, q_b, include_body=True)) / step))
    qs = q_a + np.linspace(0.0, 1.0, n + 1)[:, None] * (q_b - q_a)
    return min(float(c.clearances(qs).min()) for c in checkers)


@functools.lru_cache(maxsize=None)
def _near_motions(name: str, n: int = 300):
    scenario, dut, _ = _case(name)
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    q_a = rng.uniform(dut.lower, dut.upper, size=(60 * n, 4))
    q_a = q_a[dut.are_valid(q_a) & (dut.clearances(q_a) < 0.3)][:n]
    q_b = np.clip(q_a + rng.normal(scale=0.8, size=q_a.shape), dut.lower, dut.upper)
    keep = dut.are_valid(q_b)
    return q_a[keep], q_b[keep]


@pytest.mark.slow
@pytest.mark.parametrize("kind", CHECKERS)
@pytest.mark.parametrize("name", NAMES)
def test_accepted_motions_near_obstacles_are_free_at_1_mm(name, kind):
    """Up to 300 motions per map (6 maps) between valid ends within 0.3 m of
    contact, for every --checker: every accepted one is free at 1 mm steps by
    the exact planar and numpy clearances (each independent of the other).
    ``drake`` is approximate (module docstring of drake_social.collision.drake_checker):
    its unsound acceptances are counted and must stay rare and shallow."""
    scenario, planar, numpy_ = _case(name)
    q_a, q_b = _near_motions(name)
    dut = {"planar": planar, "numpy": numpy_}.get(kind) or SceneGraphChecker(scenario)
    accepted = np.flatnonzero([dut.is_motion_valid(a, b) for a, b in zip(q_a, q_b)])
    assert len(q_a) > 100 and 0.1 < len(accepted) / len(q_a) < 0.98
    worst = [_dense_min_clearance([planar, numpy_], q_a[i], q_b[i]) for i in accepted]
    bad = [w for w in worst if w <= 0.0]
    if kind == "drake":
        assert len(bad) <= 0.02 * len(accepted) and min(worst) > -0.01, (len(bad), min(worst))
    else:
        assert not bad, f"{kind} accepted {len(bad)} colliding motions, deepest {min(worst)}"
        # And the batched call agrees with the single one.
        np.testing.assert_array_equal(np.flatnonzero(dut.are_motions_valid(q_a, q_b)), accepted)


# ---- (3) agreement with the numpy checker and Drake's collision queries --------------


@pytest.mark.parametrize("name", NAMES)
def test_agrees_with_numpy_and_drake_away_from_grazing(name, rng):
    """3,000 configurations per map (6 maps: 18,000): validity equals the numpy
    checker's and Drake's (CheckConfigsCollisionFree) wherever the exact
    clearance is more than 1e-6 m from 0; clearances equal numpy's to 1e-9."""
    scenario, dut, numpy_ = _case(name)
    drake = SceneGraphChecker(scenario)
    qs = _near_configs(dut, rng, 3000)
    c = dut.clearances(qs)
    clear = np.abs(c) > 1e-6
    valid = dut.are_valid(qs)
    np.testing.assert_array_equal(valid[clear], numpy_.are_valid(qs)[clear])
    np.testing.assert_array_equal(valid[clear], drake.are_valid(qs)[clear])
    pos = c > 0
    np.testing.assert_allclose(c[pos], numpy_.clearances(qs)[pos], atol=1e-9, rtol=0)
    np.testing.assert_array_equal(valid, [dut.is_valid(q) for q in qs])


# ---- (4) the configuration where Drake overestimates ----------------------------------


def test_the_cylinder_box_overestimate_of_issue_8():
    scenario = load_scenario(SCENARIO_DIR / "generic_L.yaml")
    dut = PlanarChecker(scenario)
    q = np.array([10.78156014, 5.65723962, 0.02822218, -0.18334348])
    ref = float(exact_clearances(scenario, dut.geometry, q[None])[0])
    assert ref == pytest.approx(0.4043, abs=1e-4)
    assert dut.clearance(q) == pytest.approx(ref, abs=1e-9)
    # A motion of the base past obstacle[3]'s corner (10.65, 6.4): both ends free, the middle not.
    q_b = q + np.array([0.24, 1.54, 0.0, 0.0])
    assert dut.is_valid(q) and dut.is_valid(q_b)
    assert _dense_min_clearance([dut], q, q_b) < -0.05
    assert not dut.is_motion_valid(q, q_b) and not dut.is_motion_valid(q_b, q)
    assert not GeometricChecker(scenario).is_motion_valid(q, q_b)
    assert verify_path(dut, np.array([q, q_b])) == 0
    # Drake itself still reports far more than the exact distance here (FCL's GJK;
    # when this fails, Drake was fixed and the drake checker's docstring can say so).
    assert SceneGraphChecker(scenario).clearance(q) > ref + 0.2  # 0.714 m with Drake 1.51


# ---- (5) body poses are the plant's -------------------------------------------------


@pytest.mark.parametrize("name", NAMES)
def test_body_poses_and_capsules_equal_drakes_and_the_scenarios(name, rng):
    """200 random configurations per map: each body's planar pose equals
    MultibodyPlant.EvalBodyPoseInWorld to 1e-12, and the capsules read from
    the SceneGraph equal ArmGeometry's (the scenario's) to 1e-12."""
    scenario, dut, _ = _case(name)
    plant = dut.model.diagram.plant()
    context = plant.CreateDefaultContext()
    g = dut.geometry
    for q in rng.uniform(dut.lower, dut.upper, size=(200, 4)):
        plant.SetPositions(context, q)
        poses = dut.body_poses(q)
        for name_, pose in zip(dut.body_names, poses):
            X = plant.EvalBodyPoseInWorld(context, plant.GetBodyByName(name_))
            np.testing.assert_allclose(X.translation()[:2], pose[:2], atol=1e-12)
            np.testing.assert_allclose(X.rotation().matrix()[:2, :2],
                                       [[math.cos(pose[2]), -math.sin(pose[2])],
                                        [math.sin(pose[2]), math.cos(pose[2])]], atol=1e-12)
        caps = dut.capsules(q)
        seg = g.segments(q)
        expected = np.concatenate([[[*q[:2], *q[:2], g.base_radius]],
                                   np.column_stack([seg.reshape(-1, 4), g.segment_radii])])
        np.testing.assert_allclose(caps, expected, atol=1e-12)
    np.testing.assert_allclose(dut.lever, g.lever(include_body=True), atol=0.02)
    assert np.all(dut.lever <= g.lever(include_body=True) + 1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("name", NAMES)
def test_each_capsule_moves_no_more_than_its_lever_bound(name, rng):
    """The motion check advances capsule j by displacement(dq, levers[j]):
    every point of the capsule (its axis ends pushed out by r in 16
    directions fixed to its body) moves at most that far per unit of t,
    measured along random motions at 1/64 steps; the base's capsules move
    with the base only."""
    from drake_social.collision import planar_kernel as kernel

    _, dut, _ = _case(name)
    angles = np.linspace(0, 2 * np.pi, 16, endpoint=False)

    def points(q):
        poses = kernel.body_poses(q, dut.bodies)
        out = []
        for body, ax, ay, bx, by, r in dut.robot:
            x, y, c, s = poses[int(body)]
            for px, py in ((ax, ay), (bx, by)):
                local = np.column_stack([px + r * np.cos(angles), py + r * np.sin(angles)])
                out.append(np.column_stack([x + c * local[:, 0] - s * local[:, 1], y + s * local[:, 0] + c * local[:, 1]]))
        return np.stack(out).reshape(len(dut.robot), 2, 16, 2)

    worst = 0.0
    for _ in range(40):
        q_a = rng.uniform(dut.lower, dut.upper)
        dq = rng.normal(scale=[1.0, 1.0, 1.5, 1.5])
        bound = kernel.capsule_spans(dq, dut.levers)
        ts = np.linspace(0.0, 1.0, 65)
        p = np.stack([points(q_a + t * dq) for t in ts])  # (T, S, 2, 16, 2)
        moved = np.linalg.norm(np.diff(p, axis=0), axis=-1).max(axis=(2, 3)).sum(axis=0)  # path length per capsule
        assert np.all(moved <= bound + 1e-9)
        worst = max(worst, float((moved / bound).max()))
        assert np.all(bound <= kernel.displacement(dq, dut.lever) + 1e-12)  # never looser than the whole robot's
    assert worst > 0.8  # the bound is not vacuous: some capsule comes close to it
    base = dut.robot[:, 0] == 0
    np.testing.assert_array_equal(dut.levers[base], 0.0)


# ---- protocol, reports, wiring --------------------------------------------------------


def test_protocol_contacts_and_make_checker(tiny_scenario, tiny_scenario_path):
    dut = make_checker(tiny_scenario)
    assert isinstance(dut, PlanarChecker) and isinstance(dut, ValidityChecker)
    assert CHECKERS[0] == "planar"
    q = np.array([2.9, 3.3, 0.0, 0.0])  # the bar through the person (see test_checker.py)
    (contact,) = dut.contacts(q)
    assert (contact.robot_body, contact.other) == ("object", "person[0] 'standing'")
    assert contact.distance == pytest.approx(-0.275, abs=1e-12)
    assert dut.contacts(np.array([2.0, 2.5, 0.0, math.pi])) == []
    assert not dut.is_valid([-0.5, 2.5, 0.0, 0.0])  # outside the bounds


def test_verify_path(tiny_scenario):
    dut = PlanarChecker(tiny_scenario)
    free = np.array([[2.0, 2.5, 0.0, math.pi], [2.0, 3.0, 0.5, math.pi], [1.5, 3.0, 0.5, math.pi]])
    assert all(dut.is_motion_valid(a, b) for a, b in zip(free[:-1], free[1:]))
    for x in (dut, tiny_scenario, GeometricChecker(tiny_scenario), SceneGraphChecker(tiny_scenario)):
        assert verify_path(x, free) is None
        assert verify_path(x, free[:1]) is None
    through = np.vstack([free, [[2.9, 3.3, 0.0, 0.0]]])  # its last waypoint is in collision
    assert verify_path(dut, through) == 2
    assert verify_path(dut, through[-1:]) == 0
    with pytest.raises(TypeError):
        verify_path("tiny.yaml", free)


def test_the_ragged_floor_goes_through_the_grid_and_parts():
    scenario, dut, numpy_ = _case("ragged_floor")
    from drake_social.collision.planar_checker import READ_PART
    from drake_social.collision.planar_kernel import GRID_MIN_SHAPES

    assert len(dut.env) > max(GRID_MIN_SHAPES, 2 * READ_PART)
