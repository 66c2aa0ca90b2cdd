"""The seeded office floor: deterministic, every room reachable through its door
from the corridors, doors and corridors wide enough; the shipped map is the
generator's output bit for bit; written maps read back."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage

from drake_social.maps import (FREE, OCCUPIED, UNKNOWN, cells_to_rectangles, map_boxes, office_floor_image,
                               office_floor_layout, read_map, write_map)

MAPS = Path(__file__).resolve().parents[2] / "scenarios" / "maps"


def _script():
    spec = importlib.util.spec_from_file_location("make_office_floor", MAPS / "make_office_floor.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_shipped_map_is_the_generators_output_bit_for_bit(tmp_path):
    script = _script()
    dut = script.make(tmp_path)
    assert dut == tmp_path / "office_floor.yaml"
    for name in ("office_floor.pgm", "office_floor.yaml"):
        assert (tmp_path / name).read_bytes() == (MAPS / name).read_bytes(), name
    assert (MAPS / "office_floor.pgm").read_bytes().startswith(b"P5\n400 280\n255\n")


def test_the_same_seed_gives_the_same_floor_and_another_seed_another():
    a = office_floor_image(20, 14, 0.05, np.random.default_rng(3))
    b = office_floor_image(20, 14, 0.05, np.random.default_rng(3))
    c = office_floor_image(20, 14, 0.05, np.random.default_rng(4))
    np.testing.assert_array_equal(a, b)
    assert (a != c).any()
    assert a.dtype == np.uint8 and a.shape == (280, 400)
    assert set(np.unique(a)) == {0, 205, 255}


@pytest.mark.parametrize("width, height, resolution, seed", [
    (20, 14, 0.05, 22), (20, 14, 0.05, 5), (14, 12, 0.1, 1), (50, 30, 0.03, 22), (33, 25, 0.05, 9),
])
def test_every_room_is_reached_from_the_corridor_through_its_door(width, height, resolution, seed):
    layout = office_floor_layout(width, height, resolution, np.random.default_rng(seed))
    image = layout.image()
    free = image[::-1] == 255  # grid order: row 0 at the bottom, as the layout's y
    labels, _ = ndimage.label(free)  # 4-connected
    h, w = free.shape

    def cells(rect):
        x0, y0, x1, y1 = (np.array(rect) / resolution).round().astype(int)
        return labels[max(y0, 0):min(y1, h), max(x0, 0):min(x1, w)]

    corridor = np.bincount(cells(layout.corridors[0]).ravel()).argmax()
    assert corridor != 0
    assert len(layout.rooms) >= 4 and len(layout.rooms) == len(layout.doors)
    for room in layout.rooms:
        inside = cells(room)
        assert (inside[inside != 0] == corridor).all() and (inside == corridor).sum() > 0.5 * inside.size
    assert set(np.unique(labels)) == {0, corridor}  # the free space is one region
    for x0, y0, x1, y1 in layout.doors:
        assert x1 - x0 >= 1.8 - 1e-9
    for x0, y0, x1, y1 in layout.corridors:
        assert min(x1 - x0, y1 - y0) >= 3.0
    # Unknown only outside the outer wall, a band of it all around.
    grey = image == 205
    assert grey[0].all() and grey[-1].all() and grey[:, 0].all() and grey[:, -1].all()
    ox0, oy0, ox1, oy1 = (np.array(layout.outer) / resolution).round().astype(int)
    assert not grey[::-1][oy0 + 1:oy1 - 1, ox0 + 1:ox1 - 1].any()


def test_a_floor_too_small_or_too_coarse_is_refused(rng):
    with pytest.raises(ValueError, match="at least 14 x 12 m"):
        office_floor_image(10, 14, 0.05, rng)
    with pytest.raises(ValueError, match=r"resolution: must be in \(0, 0.2\]"):
        office_floor_image(20, 14, 0.5, rng)


def test_the_written_floor_reads_back_with_its_classes_and_boxes(tmp_path):
    image = office_floor_image(50, 30, 0.03, np.random.default_rng(22))
    grid = read_map(write_map(tmp_path, "floor", image, 0.03, origin=(-2.0, 1.0, 0.3)))
    assert grid.shape == (1000, 1667)
    expected = np.select([image == 0, image == 255], [OCCUPIED, FREE], UNKNOWN)[::-1]
    np.testing.assert_array_equal(grid.classes, expected)
    dut = map_boxes(grid)
    count = np.zeros(grid.shape, np.int64)
    for r0, c0, r1, c1 in dut.cells:
        count[r0:r1, c0:c1] += 1
    np.testing.assert_array_equal(count, (grid.classes != FREE).astype(np.int64))
    # Walls, furniture and the unknown band: a few hundred boxes for 1.67 million cells.
    assert len(dut) < 400
    np.testing.assert_array_equal(map_boxes(grid, "free").cells, cells_to_rectangles(grid.classes == OCCUPIED))
