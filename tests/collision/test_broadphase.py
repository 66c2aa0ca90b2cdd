"""The broadphase grid: its cells list every shape that meets them, and the
kernels answer with it exactly as the plain loops over every shape do."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_social.collision import planar_kernel as pk
from drake_social.collision.broadphase import bounding_boxes, build_grid

# A base disc, a link capsule and a long bar (the chain of test_planar_kernel).
BODIES = np.array([[-1, 0, 0, 1, 0, -1], [0, 0, 0, 1, 0, 2], [1, 1.0, 0, 1, 0, 3]], float)
ROBOT = np.array([[0, 0, 0, 0, 0, 0.3], [1, 0, 0, 1.0, 0, 0.05], [2, -0.2, -0.75, -0.2, 0.75, 0.04]], float)
LEVERS = np.array([[0.0, 0.0], [1.05, 0.0], [1.0, 0.8]])
LOWER, UPPER = np.array([-40.0, -40.0, -4.0, -4.0]), np.array([40.0, 40.0, 4.0, 4.0])


def random_env(rng: np.random.Generator, n: int, span: float = 30.0) -> np.ndarray:
    """n shapes in [-span, span]^2: rotated boxes of sizes from 1 mm to 1 m,
    a few long walls (up to 40 m) and huge blocks, and discs."""
    kind = (rng.random(n) < 0.2).astype(float)  # 1 = disc
    centre = rng.uniform(-span, span, (n, 2))
    yaw = rng.uniform(-math.pi, math.pi, n)
    h = np.exp(rng.uniform(math.log(5e-4), math.log(0.3), (n, 2)))
    walls = rng.random(n) < 0.01
    h[walls, 0] = rng.uniform(5.0, 20.0, walls.sum())
    h[walls, 1] = 0.05
    huge = rng.random(n) < 0.002
    h[huge] = rng.uniform(2.0, 4.0, (huge.sum(), 2))
    h[kind == 1, 1] = 0.0
    rho = np.where(kind == 1, h[:, 0], np.hypot(h[:, 0], h[:, 1]))
    return np.column_stack([kind, centre, np.cos(yaw), np.sin(yaw), h, rho])


def random_qs(rng: np.random.Generator, n: int, span: float = 34.0) -> np.ndarray:
    """Configurations over the map and a little beyond it (outside the grid's core)."""
    return np.column_stack([rng.uniform(-span, span, (n, 2)), rng.uniform(-4, 4, (n, 2))])


@pytest.fixture(scope="module")
def scene():
    rng = np.random.default_rng(22)
    env = random_env(rng, 3000)
    return env, build_grid(env)


def test_every_cell_lists_every_shape_that_meets_it(scene):
    """A direct check: cell by cell, the listed shapes are exactly those
    whose padded bounding box meets the closed cell, each once, ascending."""
    env, grid = scene
    lo, hi = bounding_boxes(env)
    x0, y0, cell = grid.header[:3]
    nx, ny = grid.dims
    assert np.all(lo >= [x0, y0]) and np.all(hi <= [x0 + nx * cell, y0 + ny * cell])
    for c in range(nx * ny):
        i, j = c % nx, c // nx
        a = np.array([x0 + i * cell, y0 + j * cell])
        meets = np.flatnonzero(np.all(lo <= a + cell, axis=1) & np.all(hi >= a, axis=1))
        listed = grid.items[grid.start[c]:grid.start[c + 1]]
        assert np.all(np.diff(listed) > 0)
        # Shapes exactly on a cell boundary may be listed in both neighbours.
        assert set(meets) <= set(listed), c
        strict = np.flatnonzero(np.all(lo < a + cell, axis=1) & np.all(hi > a, axis=1))
        assert set(listed) <= set(meets) | set(np.flatnonzero(np.any(np.isclose(lo, a + cell) | np.isclose(hi, a),
                                                                             axis=1)))
        assert set(strict) <= set(listed)


@pytest.mark.parametrize("cell", [None, 0.25, 3.0])
def test_clearances_and_validity_equal_the_plain_loops(scene, cell):
    """Thousands of configurations, on and off the map: clearances (==, the
    same floats), per-capsule clearances and validity as the plain loops."""
    env, grid = scene
    if cell is not None:
        grid = build_grid(env, cell)
    rng = np.random.default_rng(1)
    qs = random_qs(rng, 3000)
    got, ref = pk.clearances(qs, BODIES, ROBOT, env, grid), pk.clearances_plain(qs, BODIES, ROBOT, env)
    assert np.array_equal(got, ref)
    assert 0.2 < np.mean(ref > 0) < 0.95  # both free and colliding configurations
    for q in qs[:500]:
        assert np.array_equal(pk.capsule_clearances(q, BODIES, ROBOT, env, grid),
                              pk.capsule_clearances_plain(q, BODIES, ROBOT, env))
    assert np.array_equal(pk.valid(qs, LOWER, UPPER, BODIES, ROBOT, env, grid),
                          pk.valid_plain(qs, LOWER, UPPER, BODIES, ROBOT, env))


def test_motions_equal_the_plain_kernel(scene):
    """Thousands of short and long motions between random configurations."""
    env, grid = scene
    rng = np.random.default_rng(2)
    q_a = random_qs(rng, 2000, 30.0)
    step = np.exp(rng.uniform(math.log(0.01), math.log(6.0), (2000, 1)))
    q_b = np.clip(q_a + step * rng.uniform(-1, 1, (2000, 4)), LOWER, UPPER)
    got = pk.motions_valid(q_a, q_b, LOWER, UPPER, BODIES, ROBOT, env, grid, LEVERS)
    ref = pk.motions_valid_plain(q_a, q_b, LOWER, UPPER, BODIES, ROBOT, env, grid, LEVERS)
    assert np.array_equal(got, ref)
    assert 0.05 < got.mean() < 0.95


def test_odd_scenes():
    """An empty room, one shape, a configuration far off and a NaN one."""
    rng = np.random.default_rng(3)
    q = np.array([[0.0, 0.0, 0.5, 0.5], [1e6, -1e6, 0.0, 0.0], [1e18, 0.0, 0.0, 0.0], [np.nan, 0.0, 0.0, 0.0]])
    # Under GRID_MIN_SHAPES the plain loop runs; 200 and 2,000 shapes take the grid's paths.
    for env in (np.zeros((0, 8)), random_env(rng, 1), random_env(rng, 5, span=0.5), random_env(rng, 200, span=3.0),
                random_env(rng, 2000)):
        grid = build_grid(env)
        assert np.array_equal(pk.clearances(q, BODIES, ROBOT, env, grid), pk.clearances_plain(q, BODIES, ROBOT, env),
                              equal_nan=True)
        assert np.array_equal(pk.valid(q, LOWER, UPPER, BODIES, ROBOT, env, grid),
                              pk.valid_plain(q, LOWER, UPPER, BODIES, ROBOT, env))
    assert pk.clearance(q[0], BODIES, ROBOT, np.zeros((0, 8)), build_grid(np.zeros((0, 8)))) == math.inf
    # Motions that start or end far off, or in NaN.
    env = random_env(rng, 2000)
    grid = build_grid(env)
    a = np.array([[0.0, 0.0, 0.5, 0.5], [1e6, 0.0, 0.0, 0.0], [np.nan, 0.0, 0.0, 0.0], [35.0, 35.0, 0.0, 0.0]])
    b = np.array([[0.5, 0.2, 0.5, 0.6], [1e6, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [39.0, 39.0, 1.0, 0.0]])
    lo, hi = np.full(4, -1e7), np.full(4, 1e7)
    assert np.array_equal(pk.motions_valid(a, b, lo, hi, BODIES, ROBOT, env, grid, LEVERS),
                          pk.motions_valid_plain(a, b, lo, hi, BODIES, ROBOT, env, grid, LEVERS))


def test_the_cell_side_doubles_for_huge_shapes():
    env = np.array([[0, 0.0, 0.0, 1.0, 0.0, 5000.0, 5000.0, 5000.0 * math.sqrt(2)]])
    grid = build_grid(env)
    assert grid.dims.prod() <= (1 << 20) + 1 and grid.header[2] > 1.0


def test_the_numpy_checker_answers_as_without_its_grid(tmp_path):
    """GeometricChecker on a 60 x 60 m room of 800 boxes: with its grid and
    with the (N, K) arrays over every box, the same clearances (==),
    validity and motion answers."""
    from crowd_scenarios import crowd_scenario_text
    from drake_social.collision.geometric import GRID_MIN_BOXES, GeometricChecker
    from drake_social.scenario import load_scenario

    path = tmp_path / "boxes.yaml"
    path.write_text(crowd_scenario_text(60.0, people=20, obstacles=800, seed=4, clearance=1.0))
    scenario = load_scenario(path)
    fast, plain = GeometricChecker(scenario), GeometricChecker(scenario)
    assert len(scenario.world.obstacles) >= GRID_MIN_BOXES and fast.grid is not None
    plain.grid = None
    rng = np.random.default_rng(5)
    qs = rng.uniform(fast.lower, fast.upper, (3000, 4))
    got, ref = fast.clearances(qs), plain.clearances(qs)
    assert np.array_equal(got, ref)
    assert 0.05 < np.mean(ref > 0) < 0.95
    assert np.array_equal(fast.are_valid(qs), plain.are_valid(qs))
    q_b = np.clip(qs[:300] + rng.uniform(-0.5, 0.5, (300, 4)), fast.lower, fast.upper)
    assert np.array_equal(fast.are_motions_valid(qs[:300], q_b), plain.are_motions_valid(qs[:300], q_b))
