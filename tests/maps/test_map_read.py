"""read_map against map_server's values worked out by hand (Nav2 humble's
loadMapFromFile): each mode, negate, the thresholds' strict inequalities,
colour averaged, alpha; and the grid's geometry (row flip, origin, yaw)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from PIL import Image

from drake_social.maps import FREE, OCCUPIED, UNKNOWN, classify, read_map, write_map

# Image order: row 0 is the top row.
PIXELS = np.array([[0, 89, 90, 205],
                   [206, 255, 128, 0],
                   [255, 255, 0, 100]], np.uint8)


def _write_png(path, array, mode):
    Image.fromarray(np.asarray(array, np.uint8), mode).save(path, format="PNG")


def _yaml(path, image, **fields):
    values = {"resolution": 0.5, "origin": "[0.0, 0.0, 0.0]", "negate": 0, "occupied_thresh": 0.65,
              "free_thresh": 0.196, **fields}
    path.write_text(f"image: {image}\n" + "".join(f"{k}: {v}\n" for k, v in values.items()))
    return path


@pytest.mark.parametrize("mode, negate, expected", [
    # occ = 1 - p/255; trinary: 100 if occ > 0.65 (p <= 89), 0 if occ < 0.196 (p >= 206), else -1.
    ("trinary", 0, [[100, 100, -1, -1], [0, 0, -1, 100], [0, 0, 100, -1]]),
    # occ = p/255: 100 if p >= 166, 0 if p <= 49.
    ("trinary", 1, [[0, -1, -1, 100], [100, 100, -1, 0], [100, 100, 0, -1]]),
    # scale: rint((occ - 0.196) / 0.454 * 100): p=90: 99.35 -> 99, 205: 0.017 -> 0, 128: 66.53 -> 67, 100: 90.71 -> 91.
    ("scale", 0, [[100, 100, 99, 0], [0, 0, 67, 100], [0, 0, 100, 91]]),
    # raw: the value itself where it is in 0..100, else -1 (negate does not matter).
    ("raw", 0, [[0, 89, 90, -1], [-1, -1, -1, 0], [-1, -1, 0, 100]]),
    ("raw", 1, [[0, 89, 90, -1], [-1, -1, -1, 0], [-1, -1, 0, 100]]),
])
def test_each_mode_gives_map_servers_values_with_the_image_top_row_last(tmp_path, mode, negate, expected):
    path = write_map(tmp_path, "m", PIXELS, 0.5, negate=negate, mode=mode)
    dut = read_map(path)
    assert dut.mode == mode and dut.negate == bool(negate)
    np.testing.assert_array_equal(dut.values, np.array(expected, np.int8)[::-1])
    assert dut.values.dtype == np.int8 and dut.classes.dtype == np.int8
    assert not dut.values.flags.writeable and not dut.classes.flags.writeable
    np.testing.assert_array_equal(dut.classes, classify(dut.values))


def test_classes_are_occupied_at_100_free_at_0_and_unknown_elsewhere():
    dut = classify(np.array([-1, 0, 1, 50, 99, 100], np.int8))
    np.testing.assert_array_equal(dut, [UNKNOWN, FREE, UNKNOWN, UNKNOWN, UNKNOWN, OCCUPIED])


def test_a_shade_exactly_at_a_threshold_is_unknown(tmp_path):
    # p = 0 gives occ = 1.0 exactly, p = 255 gives occ = 0.0 exactly.
    image = np.array([[0, 255]], np.uint8)
    at = read_map(write_map(tmp_path, "at", image, 1.0, occupied_thresh=1.0, free_thresh=0.0))
    np.testing.assert_array_equal(at.values, [[-1, -1]])
    inside = read_map(write_map(tmp_path, "inside", image, 1.0, occupied_thresh=0.999, free_thresh=0.001))
    np.testing.assert_array_equal(inside.values, [[100, 0]])
    # scale: at occupied_thresh the scaled value is rint(100) = 100, at free_thresh rint(0) = 0.
    scale = read_map(write_map(tmp_path, "scale", image, 1.0, occupied_thresh=1.0, free_thresh=0.0, mode="scale"))
    np.testing.assert_array_equal(scale.values, [[100, 0]])


def test_colour_is_the_average_of_red_green_blue(tmp_path):
    # Average (not luminance): green (0, 255, 0) has mean 85, occ = 2/3 > 0.65: occupied
    # (its luminance, 150, would be unknown); (255, 255, 0): mean 170, occ 1/3: unknown;
    # (255, 255, 204): mean 238, occ 0.067: free.
    rgb = np.array([[[0, 255, 0], [255, 255, 0], [255, 255, 204]]], np.uint8)
    _write_png(tmp_path / "c.png", rgb, "RGB")
    dut = read_map(_yaml(tmp_path / "c.yaml", "c.png"))
    np.testing.assert_array_equal(dut.values, [[100, -1, 0]])
    # raw: round(mean): (10, 20, 31) -> 20.33 -> 20, (10, 20, 32) -> 20.67 -> 21, (100, 101, 101) -> 101: -1.
    _write_png(tmp_path / "r.png", [[[10, 20, 31], [10, 20, 32], [100, 101, 101]]], "RGB")
    raw = read_map(_yaml(tmp_path / "r.yaml", "r.png", mode="raw"))
    np.testing.assert_array_equal(raw.values, [[20, 21, -1]])


def test_alpha_is_averaged_in_trinary_and_makes_scale_unknown(tmp_path):
    # White with alpha 0: trinary averages (255, 255, 255, 0): 191.25, shade 0.75, occ 0.25.
    rgba = np.array([[[255, 255, 255, 0], [255, 255, 255, 255], [255, 255, 255, 254], [0, 0, 0, 0]]], np.uint8)
    _write_png(tmp_path / "a.png", rgba, "RGBA")
    strict = read_map(_yaml(tmp_path / "t1.yaml", "a.png", free_thresh=0.25))
    # occ 0.25 is not < 0.25: unknown; opaque white free; alpha 254: occ 0.25 / 255 / 4 ~ 0.001: free;
    # black transparent: (0, 0, 0, 0): occ 1: occupied.
    np.testing.assert_array_equal(strict.values, [[-1, 0, 0, 100]])
    above = read_map(_yaml(tmp_path / "t2.yaml", "a.png", free_thresh=0.2500001))
    np.testing.assert_array_equal(above.values, [[0, 0, 0, 100]])
    scale = read_map(_yaml(tmp_path / "s.yaml", "a.png", mode="scale"))
    np.testing.assert_array_equal(scale.values, [[-1, 0, -1, -1]])
    raw = read_map(_yaml(tmp_path / "r.yaml", "a.png", mode="raw"))  # alpha ignored
    np.testing.assert_array_equal(raw.values, [[-1, -1, -1, 0]])


def test_grey_with_alpha_averages_three_grey_channels_and_alpha(tmp_path):
    # (g, g, g, a) = (255, 255, 255, 0): occ 0.25 as above; (0, 0, 0, 255): occupied.
    _write_png(tmp_path / "la.png", [[[255, 0], [0, 255]]], "LA")
    dut = read_map(_yaml(tmp_path / "la.yaml", "la.png", free_thresh=0.25))
    np.testing.assert_array_equal(dut.values, [[-1, 100]])


def test_png_bmp_and_ascii_pgm_read_as_the_binary_pgm(tmp_path):
    expected = read_map(write_map(tmp_path, "pgm", PIXELS, 0.5)).values
    for fmt in ("png", "bmp"):
        np.testing.assert_array_equal(read_map(write_map(tmp_path, fmt, PIXELS, 0.5, fmt=fmt)).values, expected)
    body = "\n".join(" ".join(str(v) for v in row) for row in PIXELS)
    (tmp_path / "ascii.pgm").write_text(f"P2\n# a comment\n4 3\n255\n{body}\n")
    np.testing.assert_array_equal(read_map(_yaml(tmp_path / "ascii.yaml", "ascii.pgm")).values, expected)
    # A palette PNG reads as its colours.
    Image.fromarray(PIXELS, "L").convert("P").save(tmp_path / "p.png")
    np.testing.assert_array_equal(read_map(_yaml(tmp_path / "p.yaml", "p.png")).values, expected)


def test_the_yaml_fields_are_kept(tmp_path):
    path = _yaml(tmp_path / "m.yaml", "m.pgm", resolution=0.05, origin="[-1.5, 2, 0.25]", negate="true",
                 occupied_thresh=0.7, free_thresh=0.2, mode="Scale")
    Image.fromarray(PIXELS, "L").save(tmp_path / "m.pgm")
    dut = read_map(path)
    assert dut.path == path.resolve() and dut.image_path == (tmp_path / "m.pgm").resolve()
    assert (dut.resolution, dut.origin, dut.negate, dut.occupied_thresh, dut.free_thresh, dut.mode) == \
        (0.05, (-1.5, 2.0, 0.25), True, 0.7, 0.2, "scale")
    assert dut.shape == (3, 4)
    assert dut.width_m == pytest.approx(0.2) and dut.height_m == pytest.approx(0.15)


def test_mode_defaults_to_trinary_and_an_absolute_image_path_is_kept(tmp_path):
    Image.fromarray(PIXELS, "L").save(tmp_path / "abs.pgm")
    sub = tmp_path / "elsewhere"
    sub.mkdir()
    dut = read_map(_yaml(sub / "m.yaml", str(tmp_path / "abs.pgm")))
    assert dut.mode == "trinary" and dut.image_path == tmp_path / "abs.pgm"


def test_cell_centres_follow_origin_yaw_and_the_row_flip(tmp_path):
    dut = read_map(write_map(tmp_path, "m", PIXELS, 0.5, origin=(1.0, 2.0, math.pi / 2)))
    # Image pixel (0, 1) is grid cell (2, 1): map-frame centre (0.75, 1.25), turned by 90 degrees:
    # (-1.25, 0.75), plus the origin: (-0.25, 2.75). Pixel (2, 3) is cell (0, 3): (1.75, 0.25) -> (0.75, 3.75).
    rows, cols = np.array([2, 0]), np.array([1, 3])
    np.testing.assert_allclose(dut.cell_centers(rows, cols), [[-0.25, 2.75], [0.75, 3.75]], atol=1e-12)
    image_rows, image_cols = dut.image_pixel(rows, cols)
    np.testing.assert_array_equal(image_rows, [0, 2])
    np.testing.assert_array_equal(image_cols, [1, 3])
    assert dut.values[2, 1] == 100 and PIXELS[0, 1] == 89  # p = 89: occupied
    # The 2 x 1.5 m rectangle turned by 90 degrees about (1, 2).
    np.testing.assert_allclose(dut.corners(), [[1, 2], [1, 4], [-0.5, 4], [-0.5, 2]], atol=1e-12)
    np.testing.assert_allclose(dut.extent(), [-0.5, 2, 1, 4], atol=1e-12)
    flat = read_map(write_map(tmp_path, "flat", PIXELS, 0.5, origin=(-1.0, -2.0, 0.0)))
    np.testing.assert_allclose(flat.cell_centers(2, 0), [-0.75, -0.75])  # image pixel (0, 0)


def test_cell_at_inverts_cell_centers_and_is_minus_one_outside(tmp_path):
    dut = read_map(write_map(tmp_path, "m", PIXELS, 0.5, origin=(1.0, 2.0, 0.7)))
    rows, cols = np.meshgrid(np.arange(3), np.arange(4), indexing="ij")
    found = dut.cell_at(dut.cell_centers(rows, cols))
    np.testing.assert_array_equal(found[0], rows)
    np.testing.assert_array_equal(found[1], cols)
    np.testing.assert_array_equal(dut.class_at(dut.cell_centers(rows, cols)), dut.classes)
    corners = dut.corners()
    outside = np.array([corners[2] + [0.01, 0.01], [np.nan, 0.0], dut.to_world([[2.0 + 1e-9, 0.2]]).ravel(),
                        dut.to_world([[0.2, -1e-9]]).ravel()])  # past the right edge (x = 2 m), below row 0
    r, c = dut.cell_at(outside)
    np.testing.assert_array_equal(r, -1)
    np.testing.assert_array_equal(c, -1)
    np.testing.assert_array_equal(dut.class_at(outside), UNKNOWN)
    # Unturned, exact edges: a cell holds its lower and left edges, so the map's top and right edges are outside.
    flat = read_map(write_map(tmp_path, "flat", PIXELS, 0.5, origin=(1.0, 2.0, 0.0)))
    r, c = flat.cell_at(np.array([[1.0, 2.0], [2.5, 3.0], [3.0, 2.0], [1.0, 3.5], [2.999, 3.499]]))
    np.testing.assert_array_equal(r, [0, 2, -1, -1, 2])
    np.testing.assert_array_equal(c, [0, 3, -1, -1, 3])


def test_a_png_transparency_chunk_is_read_as_alpha(tmp_path):
    # Grey PNG whose tRNS chunk makes level 255 transparent: white becomes (255, alpha 0).
    Image.fromarray(np.array([[255, 0, 128]], np.uint8), "L").save(tmp_path / "t.png", format="PNG",
                                                                    transparency=255)
    # trinary averages alpha in: (3 * 255 + 0) / 4 / 255 = 0.75 -> occ 0.25: unknown, not free;
    # black opaque: (0 + 255) / 4 / 255 = 0.25 -> occ 0.75 > 0.65: occupied; 128: occ 0.374: unknown.
    dut = read_map(_yaml(tmp_path / "t.yaml", "t.png", mode="trinary"))
    np.testing.assert_array_equal(dut.values, [[-1, 100, -1]])
    # scale: a pixel that is not opaque is unknown; the others as without alpha.
    dut = read_map(_yaml(tmp_path / "s.yaml", "t.png", mode="scale"))
    assert dut.values[0, 0] == -1 and dut.values[0, 1] == 100
