"""cells_to_rectangles: the rectangles are disjoint and their union is exactly
the selected cells, for many masks; map_boxes puts them in the world, turned
by the map's yaw."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drake_social.maps import OCCUPIED, UNKNOWN, cells_to_rectangles, map_boxes, read_map, row_rectangles, write_map


def _coverage(rectangles: np.ndarray, shape) -> np.ndarray:
    """How many rectangles cover each cell."""
    count = np.zeros(shape, np.int64)
    for r0, c0, r1, c1 in rectangles:
        count[r0:r1, c0:c1] += 1
    return count


def _assert_exact(mask: np.ndarray, rectangles: np.ndarray) -> None:
    assert rectangles.dtype == np.int64 and rectangles.shape[1:] == (4,)
    assert (rectangles[:, 0] < rectangles[:, 2]).all() and (rectangles[:, 1] < rectangles[:, 3]).all()
    np.testing.assert_array_equal(_coverage(rectangles, mask.shape), mask.astype(np.int64))


def _blobs(rng: np.random.Generator, shape, count: int) -> np.ndarray:
    mask = np.zeros(shape, bool)
    h, w = shape
    for _ in range(count):
        r, c = rng.integers(0, h), rng.integers(0, w)
        mask[r:r + rng.integers(1, h + 1), c:c + rng.integers(1, w + 1)] ^= True  # xor: holes and notches too
    return mask


@settings(max_examples=150)
@given(seed=st.integers(0, 2**32 - 1), h=st.integers(1, 40), w=st.integers(1, 40),
       density=st.floats(0.0, 1.0), kind=st.sampled_from(["noise", "blobs"]))
def test_the_rectangles_are_disjoint_and_cover_exactly_the_mask(seed, h, w, density, kind):
    rng = np.random.default_rng(seed)
    mask = rng.random((h, w)) < density if kind == "noise" else _blobs(rng, (h, w), 1 + int(density * 8))
    for dut in (cells_to_rectangles(mask), row_rectangles(mask), row_rectangles(mask.T)[:, [1, 0, 3, 2]]):
        _assert_exact(mask, dut)
    assert len(cells_to_rectangles(mask)) == min(len(row_rectangles(mask)), len(row_rectangles(mask.T)))


@pytest.mark.parametrize("mask, count", [
    (np.zeros((5, 7), bool), 0), (np.ones((5, 7), bool), 1), (np.zeros((0, 3), bool), 0),
    (np.ones((1, 9), bool), 1), (np.ones((9, 1), bool), 1), (np.array([[1, 0, 1, 1, 0, 1]], bool), 3),
    (np.array([[1], [1], [0], [1]], bool), 2),
], ids=["empty", "full", "no-rows", "one-row", "one-column", "row-runs", "column-runs"])
def test_edge_masks(mask, count):
    dut = cells_to_rectangles(mask)
    _assert_exact(mask, dut)
    assert len(dut) == count


def test_few_rectangles_for_walls_and_rooms():
    ring = np.ones((20, 30), bool)
    ring[2:-2, 2:-2] = False
    assert len(cells_to_rectangles(ring)) == 4  # two full-width walls, two short side walls
    ell = np.zeros((10, 10), bool)
    ell[:, :2] = True
    ell[:2, :] = True
    assert len(cells_to_rectangles(ell)) == 2
    tall = np.zeros((50, 8), bool)
    tall[:, 3] = True
    tall[10, :] = True  # by rows: the wall below, the crossing row, the wall above; by columns: the wall, two stubs
    assert len(cells_to_rectangles(tall)) == 3
    assert len(row_rectangles(tall)) == 3 and len(row_rectangles(tall.T)) == 3


def test_a_mask_must_be_two_dimensional():
    with pytest.raises(ValueError, match="2-D"):
        cells_to_rectangles(np.ones(4, bool))


def _inside_counts(points: np.ndarray, boxes) -> np.ndarray:
    """How many (turned) boxes hold each point strictly inside."""
    d = points[:, None, :] - boxes.centers[None, :, :]
    c, s = np.cos(boxes.yaws), np.sin(boxes.yaws)
    local = np.stack([c * d[..., 0] + s * d[..., 1], -s * d[..., 0] + c * d[..., 1]], axis=-1)
    return (np.abs(local) < boxes.sizes / 2).all(axis=-1).sum(axis=1)


@pytest.mark.parametrize("unknown", ["obstacle", "free"])
def test_each_obstacle_cell_centre_lies_in_exactly_one_turned_box(tmp_path, rng, unknown):
    image = rng.choice(np.array([0, 255, 205], np.uint8), size=(23, 31), p=[0.3, 0.5, 0.2])
    image[5:15, 4:20] = 0  # a block: one box or a few
    dut_map = read_map(write_map(tmp_path, "m", image, 0.1, origin=(3.0, -2.0, 0.7)))
    dut = map_boxes(dut_map, unknown)
    obstacle = dut_map.classes == OCCUPIED
    if unknown == "obstacle":
        obstacle |= dut_map.classes == UNKNOWN
    _assert_exact(obstacle, dut.cells)
    rows, cols = np.meshgrid(np.arange(23), np.arange(31), indexing="ij")
    centres = dut_map.cell_centers(rows, cols).reshape(-1, 2)
    np.testing.assert_array_equal(_inside_counts(centres, dut), obstacle.ravel().astype(int))
    assert len(dut) == len(dut.centers) == len(dut.sizes) == len(dut.yaws)
    np.testing.assert_array_equal(dut.yaws, 0.7)
    # The boxes' areas add up to the obstacle cells' area.
    assert dut.sizes.prod(axis=1).sum() == pytest.approx(obstacle.sum() * 0.01)


def test_a_box_by_hand(tmp_path):
    image = np.full((4, 6), 255, np.uint8)
    image[0:2, 1:4] = 0  # image rows 0-1 = grid rows 2-3, columns 1-3
    dut = map_boxes(read_map(write_map(tmp_path, "m", image, 0.5, origin=(1.0, 2.0, np.pi / 2))))
    np.testing.assert_array_equal(dut.cells, [[2, 1, 4, 4]])
    # Map-frame centre (1.25, 1.5), turned by 90 degrees: (-1.5, 1.25), plus (1, 2).
    np.testing.assert_allclose(dut.centers, [[-0.5, 3.25]], atol=1e-12)
    np.testing.assert_allclose(dut.sizes, [[1.5, 1.0]])


def test_unknown_must_be_obstacle_or_free(tmp_path):
    grid = read_map(write_map(tmp_path, "m", np.zeros((2, 2), np.uint8), 0.5))
    with pytest.raises(ValueError, match="unknown: must be one of obstacle, free, got 'wall'"):
        map_boxes(grid, "wall")
