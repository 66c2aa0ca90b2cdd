"""The world model: the room's bounds, walls and obstacle boxes as arrays."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from drake_social.scenario import Box, load_scenario
from drake_social.world import WALL_NAMES, Boxes, WorldGeometry, world_model


@pytest.fixture(scope="module")
def office(repo_root):
    return load_scenario(repo_root / "scenarios" / "office_bar.yaml")


def test_the_boxes_are_the_scenarios_obstacles_in_order(office):
    dut = world_model(office)
    obstacles = office.world.obstacles
    assert len(dut.boxes) == len(obstacles) >= 10
    np.testing.assert_array_equal(dut.boxes.centers, [b.center for b in obstacles])
    np.testing.assert_array_equal(dut.boxes.sizes, [b.size for b in obstacles])
    np.testing.assert_array_equal(dut.boxes.yaws, [b.yaw for b in obstacles])
    np.testing.assert_array_equal(dut.boxes.halves, np.array([b.size for b in obstacles]) / 2)
    np.testing.assert_array_equal(dut.bounds, office.world.bounds)
    assert dut.wall_thickness == office.world.wall_thickness


def test_the_walls_close_the_room_outside_the_bounds():
    world = WorldGeometry(bounds=[1.0, 2.0, 11.0, 8.0], wall_thickness=0.5,
                          boxes=Boxes(centers=np.zeros((0, 2)), sizes=np.zeros((0, 2)), yaws=[]))
    assert world.wall_names == WALL_NAMES == ("wall_south", "wall_north", "wall_west", "wall_east")
    # By hand: a 10 x 6 room from (1, 2), walls 0.5 thick; south and north run past the corners.
    np.testing.assert_allclose(world.walls.centers, [[6.0, 1.75], [6.0, 8.25], [0.75, 5.0], [11.25, 5.0]], atol=1e-15)
    np.testing.assert_allclose(world.walls.sizes, [[11.0, 0.5], [11.0, 0.5], [0.5, 6.0], [0.5, 6.0]], atol=1e-15)
    np.testing.assert_array_equal(world.walls.yaws, np.zeros(4))
    lo, hi = world.walls.corners.min(axis=(0, 1)), world.walls.corners.max(axis=(0, 1))
    np.testing.assert_allclose([*lo, *hi], [0.5, 1.5, 11.5, 8.5], atol=1e-15)  # the bounds grown by t
    # The west wall stands between the south and north walls, touching both.
    np.testing.assert_allclose(world.walls.corners[2], [[0.5, 2.0], [1.0, 2.0], [1.0, 8.0], [0.5, 8.0]], atol=1e-15)
    assert len(world.boxes) == 0 and world.boxes.corners.shape == (0, 4, 2)


def test_corners_and_radii_of_rotated_boxes_match_hand_values():
    dut = Boxes(centers=[[1.0, 2.0], [0.0, 0.0]], sizes=[[2.0, 1.0], [2.0, 2.0]], yaws=[math.pi / 2, math.pi / 4])
    # A 2 x 1 box turned a quarter: its long side runs along y.
    np.testing.assert_allclose(dut.corners[0], [[1.5, 1.0], [1.5, 3.0], [0.5, 3.0], [0.5, 1.0]], atol=1e-12)
    r = math.sqrt(2.0)
    np.testing.assert_allclose(dut.corners[1], [[0.0, -r], [r, 0.0], [0.0, r], [-r, 0.0]], atol=1e-12)
    np.testing.assert_allclose(dut.radii, [math.sqrt(1.25), r], rtol=1e-15)
    np.testing.assert_allclose(dut.cos, [0.0, math.sqrt(0.5)], atol=1e-15)
    np.testing.assert_allclose(dut.sin, [1.0, math.sqrt(0.5)], atol=1e-15)
    # Every corner lies at the half diagonal from its centre.
    np.testing.assert_allclose(np.linalg.norm(dut.corners - dut.centers[:, None], axis=-1),
                               np.repeat(dut.radii[:, None], 4, 1), rtol=1e-14)


def test_arrays_are_read_only_and_copied(office):
    centers = np.array([[1.0, 1.0]])
    dut = Boxes(centers=centers, sizes=[[1.0, 1.0]], yaws=[0.0])
    centers[0, 0] = 5.0
    assert dut.centers[0, 0] == 1.0
    world = world_model(office)
    for array in (world.bounds, world.boxes.centers, world.boxes.corners, world.boxes.radii, world.walls.sizes,
                  world.boxes.cos):
        with pytest.raises(ValueError, match="read-only"):
            array.flat[0] = 0.0
    with pytest.raises(AttributeError):
        world.wall_thickness = 1.0


def test_an_empty_room_has_empty_boxes(office):
    empty = copy.deepcopy(office)
    empty.world.obstacles = []
    dut = world_model(empty)
    assert dut.boxes.centers.shape == (0, 2) and dut.boxes.yaws.shape == (0,) and len(dut.walls) == 4


@pytest.mark.parametrize("args, message", [
    (dict(centers=[[0.0, 0.0]], sizes=[[1.0, 1.0]], yaws=[0.0, 1.0]),
     r"Boxes.centers has shape \(1, 2\); expected \(2, 2\)"),
    (dict(centers=[[0.0, 0.0]], sizes=[1.0, 1.0, 1.0], yaws=[0.0]), r"Boxes.sizes has shape \(3,\); expected \(1, 2\)"),
    (dict(centers=[[0.0, 0.0]], sizes=[[1.0, 1.0]], yaws=[[0.0]]), r"Boxes.yaws must be one angle per box"),
])
def test_bad_boxes_are_refused(args, message):
    with pytest.raises(ValueError, match=message):
        Boxes(**args)


def test_bad_worlds_are_refused():
    none = Boxes(centers=np.zeros((0, 2)), sizes=np.zeros((0, 2)), yaws=[])
    with pytest.raises(ValueError, match=r"WorldGeometry.bounds has shape \(3,\); expected \(4,\)"):
        WorldGeometry(bounds=[0.0, 0.0, 1.0], wall_thickness=0.1, boxes=none)
    with pytest.raises(TypeError, match="WorldGeometry.boxes must be Boxes, got list"):
        WorldGeometry(bounds=[0.0, 0.0, 1.0, 1.0], wall_thickness=0.1, boxes=[Box()])
