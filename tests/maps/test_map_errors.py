"""Each bad map is refused with a ScenarioError naming the file and the field."""

from __future__ import annotations

import struct
import time
import zlib

import numpy as np
import pytest
from PIL import Image

from drake_social.errors import ScenarioError
from drake_social.maps import MAX_MAP_CELLS, MAX_MAP_YAML_BYTES, read_map, write_map

GOOD = {"image": "m.pgm", "resolution": "0.05", "origin": "[0.0, 0.0, 0.0]", "negate": "0",
        "occupied_thresh": "0.65", "free_thresh": "0.196"}


@pytest.fixture
def folder(tmp_path):
    Image.fromarray(np.array([[0, 255], [205, 255]], np.uint8), "L").save(tmp_path / "m.pgm")
    return tmp_path


def _yaml(folder, **changes):
    fields = {**GOOD, **changes}
    path = folder / "m.yaml"
    path.write_text("".join(f"{k}: {v}\n" for k, v in fields.items() if v is not None))
    return path


def _refused(path, *parts, source=None):
    with pytest.raises(ScenarioError) as e:
        read_map(path, source=source)
    message = str(e.value)
    assert message.startswith(f"{source or path}: "), message
    for part in parts:
        assert part in message, message
    return message


def test_the_good_yaml_reads(folder):
    assert read_map(_yaml(folder)).shape == (2, 2)


def test_a_missing_yaml_file(tmp_path):
    _refused(tmp_path / "none.yaml", "no such map YAML file")


def test_source_names_the_file_in_errors(folder):
    _refused(_yaml(folder, resolution="0"), "resolution:", source="room.yaml: world.map")
    _refused(folder / "none.yaml", "room.yaml: world.map: ", "no such map YAML file", source="room.yaml: world.map")


def test_a_missing_image(folder):
    _refused(_yaml(folder, image="x.pgm"), f"image: file 'x.pgm' not found (resolved to {folder / 'x.pgm'})")


def test_an_image_that_is_a_directory(folder):
    (folder / "d.pgm").mkdir()
    _refused(_yaml(folder, image="d.pgm"), "image:", "is a directory, not an image file")


@pytest.mark.parametrize("value, shown", [('""', "''"), ("3", "3"), ("[a.pgm]", "['a.pgm']")])
def test_an_image_name_that_is_not_a_file_name(folder, value, shown):
    _refused(_yaml(folder, image=value), f"image: must be the image's file name", f"got {shown}")


def test_a_file_that_is_not_an_image(folder):
    (folder / "t.pgm").write_text("hello\n")
    _refused(_yaml(folder, image="t.pgm"), "image: ", "is not a PGM, PNG or BMP image Pillow can read: ")


def test_a_jpeg_is_not_read(folder):
    Image.new("L", (4, 4), 255).save(folder / "j.pgm", format="JPEG")  # named .pgm: the content decides
    _refused(_yaml(folder, image="j.pgm"), "is not a PGM, PNG or BMP image Pillow can read")


def test_a_ppm_is_not_a_pgm(folder):
    Image.new("RGB", (4, 4), (255, 255, 255)).save(folder / "c.ppm")
    _refused(_yaml(folder, image="c.ppm"), "is not a PGM, PNG or BMP image Pillow can read", "P6")


def test_a_truncated_image(folder):
    (folder / "cut.pgm").write_bytes(b"P5\n10 10\n255\n" + bytes(5))
    _refused(_yaml(folder, image="cut.pgm"), "image: ", "is not a PGM, PNG or BMP image Pillow can read: ")


def test_a_16_bit_image(folder):
    Image.fromarray(np.full((3, 3), 40000, np.uint16)).save(folder / "deep.png")
    _refused(_yaml(folder, image="deep.png"), "image: ", "Pillow mode 'I;16'", "8-bit")


def _png_header(width: int, height: int) -> bytes:
    """A PNG signature, an IHDR chunk (8-bit grey) and an empty IDAT chunk: no pixel data."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)) + \
        chunk(b"IDAT", b"")


@pytest.mark.parametrize("name, data", [("big.pgm", b"P5\n20000 20000\n255\n"),
                                        ("big.png", _png_header(20000, 20000))])
def test_a_huge_image_is_refused_from_its_header(folder, name, data):
    (folder / name).write_bytes(data)
    start = time.perf_counter()
    _refused(_yaml(folder, image=name), "image: ", "400,000,000 pixels", f"MAX_MAP_CELLS ({MAX_MAP_CELLS:,})")
    assert time.perf_counter() - start < 5  # nothing decoded: no data to decode, no 400 MB allocated


def test_an_image_over_the_limit_but_under_pillows_is_refused_from_its_header(folder):
    (folder / "wide.pgm").write_bytes(b"P5\n6000 5000\n255\n")
    _refused(_yaml(folder, image="wide.pgm"), f"image: {folder / 'wide.pgm'} is 6000 x 5000 pixels = 30,000,000 "
                                              f"cells; a map may have at most MAX_MAP_CELLS ({MAX_MAP_CELLS:,}) cells")


@pytest.mark.parametrize("value, shown", [("0", "0"), ("-0.05", "-0.05"), (".nan", "nan"), (".inf", "inf"),
                                          ('"0.05"', "'0.05'"), ("true", "True"), ("[]", "[]")])
def test_a_bad_resolution(folder, value, shown):
    _refused(_yaml(folder, resolution=value),
             f"resolution: must be a finite number > 0 metres per cell, got {shown}")


@pytest.mark.parametrize("value", ["[0, 0]", "[0, 0, 0, 0]", "[0, a, 0]", "[0, .inf, 0]", "0", "{x: 0}"])
def test_a_bad_origin(folder, value):
    _refused(_yaml(folder, origin=value), "origin: must be 3 finite numbers [x, y, yaw]")


@pytest.mark.parametrize("value", ["2", "-1", "0.5", "maybe", "[0]"])
def test_a_bad_negate(folder, value):
    _refused(_yaml(folder, negate=value), "negate: must be 0, 1, true or false, got ")


@pytest.mark.parametrize("value", ["true", "false", "1", "0"])
def test_negate_may_be_a_number_or_a_boolean(folder, value):
    assert read_map(_yaml(folder, negate=value)).negate == (value in ("true", "1"))


@pytest.mark.parametrize("key, value", [("occupied_thresh", "1.5"), ("occupied_thresh", "-0.1"),
                                        ("free_thresh", "-0.1"), ("free_thresh", "nan"), ("free_thresh", ".nan")])
def test_a_threshold_outside_zero_one(folder, key, value):
    _refused(_yaml(folder, **{key: value}), f"{key}: must be in [0, 1], got ")


def test_free_thresh_must_be_below_occupied_thresh(folder):
    _refused(_yaml(folder, free_thresh="0.9"), "free_thresh: must be below occupied_thresh (0.65), got 0.9")
    _refused(_yaml(folder, free_thresh="0.65"), "free_thresh: must be below occupied_thresh (0.65), got 0.65")


def test_an_unknown_mode(folder):
    _refused(_yaml(folder, mode="foo"), "mode: 'foo' is not one of trinary, scale, raw")


def test_an_unknown_key(folder):
    path = _yaml(folder)
    path.write_text(path.read_text() + "name: office\n")
    _refused(path, "line 7: unknown key 'name'; allowed: image, resolution, origin, negate, occupied_thresh, "
                   "free_thresh (required) and mode (optional, one of trinary, scale, raw)")


@pytest.mark.parametrize("key", list(GOOD))
def test_a_missing_key(folder, key):
    _refused(_yaml(folder, **{key: None}), f"no {key}; a map YAML needs image, resolution")


def test_a_repeated_key(folder):
    path = _yaml(folder)
    path.write_text(path.read_text() + "resolution: 0.1\n")
    _refused(path, "line 7: resolution: given twice (first at line 2); each key once")


@pytest.mark.parametrize("text, part", [
    ("", "empty; a map YAML is a mapping of"),
    ("- image: m.pgm\n", "line 1: a map YAML is a mapping of"),
    ("image: [m.pgm\n", "not valid YAML: "),
    ("image: m.pgm\nresolution: &r 0.05\norigin: [*r, 0, 0]\n",
     "line 3, column 10: an alias; a map YAML gives each value once"),
    ("origin: [[0], 0, 0]\n", "line 1: nested too deeply"),
    ("image: !!python/name:os.system m\n" + "".join(f"{k}: {v}\n" for k, v in GOOD.items() if k != "image"),
     "not valid YAML: "),
    ("image: m.pgm\x00\n", "not valid YAML: "),
])
def test_malformed_yaml(folder, text, part):
    path = folder / "bad.yaml"
    path.write_text(text)
    _refused(path, part)


def test_a_yaml_file_over_the_limit(folder):
    path = _yaml(folder)
    path.write_text(path.read_text() + "#" * MAX_MAP_YAML_BYTES + "\n")
    _refused(path, f"a map YAML file may have at most {MAX_MAP_YAML_BYTES:,} bytes")


def test_write_map_refuses_what_read_map_would(tmp_path):
    image = np.zeros((2, 2), np.uint8)
    for kwargs, part in [({"resolution": 0.0}, "resolution: must be a finite number > 0"),
                         ({"free_thresh": 0.7}, "free_thresh: must be below occupied_thresh"),
                         ({"mode": "foo"}, "mode: 'foo' is not one of"), ({"negate": 2}, "negate: must be 0, 1"),
                         ({"fmt": "jpg"}, "fmt: must be one of pgm, png, bmp"),
                         ({"origin": (0.0, 0.0)}, "origin: must be 3 finite numbers")]:
        with pytest.raises(ValueError, match=part.replace("(", r"\(")):
            write_map(tmp_path, "m", image, **{"resolution": 0.1, **kwargs})
    with pytest.raises(ValueError, match="image_u8: must be a non-empty uint8 array"):
        write_map(tmp_path, "m", image.astype(float), 0.1)
    with pytest.raises(ValueError, match="image_u8"):
        write_map(tmp_path, "m", np.zeros((2, 2, 3), np.uint8), 0.1)  # colour is not PGM
    with pytest.raises(ValueError, match="name: must be a file name stem"):
        write_map(tmp_path, "a/b", image, 0.1)
    assert list(tmp_path.iterdir()) == []  # nothing written


# ---- numbers in exponent form are numbers, as map_server (yaml-cpp) reads them (issue 29, item 13)


@pytest.mark.parametrize("field, text, value", [
    ("resolution", "5e-2", 0.05), ("resolution", "5E-2", 0.05), ("resolution", "+5.0e-2", 0.05),
    ("resolution", ".5e-1", 0.05), ("resolution", "1e0", 1.0), ("resolution", "5.e-2", 0.05),
    ("occupied_thresh", "6.5e-1", 0.65), ("free_thresh", "1.96e-1", 0.196), ("free_thresh", "0e0", 0.0),
])
def test_a_number_in_exponent_form_is_a_number(folder, field, text, value):
    dut = read_map(_yaml(folder, **{field: text}))
    assert getattr(dut, field) == value  # the text's float, exactly as float() reads it
    assert getattr(dut, field) == float(text)


def test_an_origin_in_exponent_form_is_read_and_a_huge_yaw_turns_the_map(folder):
    dut = read_map(_yaml(folder, origin="[1e1, -2.5E+0, 1e300]"))
    assert dut.origin == (10.0, -2.5, 1e300)
    c, s = np.cos(1e300), np.sin(1e300)  # any finite yaw is a turn
    np.testing.assert_allclose(dut.rotation(), [[c, -s], [s, c]], rtol=0, atol=0)
    np.testing.assert_allclose(dut.corners()[1], [10.0 + 0.1 * c, -2.5 + 0.1 * s], rtol=0, atol=1e-15)
    assert np.isfinite(dut.extent()).all()


@pytest.mark.parametrize("changes, message", [
    (dict(resolution="1e400"), "resolution: must be a finite number > 0 metres per cell, got inf"),
    (dict(resolution="-5e-2"), "resolution: must be a finite number > 0 metres per cell, got -0.05"),
    (dict(resolution='"5e-2"'), "resolution: must be a finite number > 0 metres per cell, got '5e-2'"),
    (dict(resolution="5e"), "resolution: must be a finite number > 0 metres per cell, got '5e'"),
    (dict(resolution="1_0e-2"), "resolution: must be a finite number > 0 metres per cell, got '1_0e-2'"),
    (dict(origin="[0, 0, 1e400]"), "origin: must be 3 finite numbers [x, y, yaw] (metres, metres, radians), got "
                                   "[0, 0, inf]"),
    (dict(occupied_thresh="1.5e0"), "occupied_thresh: must be in [0, 1], got 1.5"),
    (dict(negate="1e0"), "negate: must be 0, 1, true or false, got 1.0"),  # map_server reads negate as an integer
])
def test_exponent_forms_out_of_range_are_refused_naming_the_field(folder, changes, message):
    _refused(_yaml(folder, **changes), message)


def test_the_maps_size_and_corners_must_be_finite_too(folder):
    """The 2 x 2 map: its size is 2 * resolution, finite up to the largest float (at half of it and below)."""
    top = float(np.finfo(float).max)
    for resolution in (top / 2, float(np.nextafter(top / 2, 0.0))):
        assert read_map(_yaml(folder, resolution=repr(resolution))).width_m == 2 * resolution <= top
    over = np.nextafter(top / 2, np.inf)
    _refused(_yaml(folder, resolution=repr(float(over))), f"resolution: {float(over)!r} m per cell makes the map's "
                                                          "2 x 2 cells inf x inf m; the map's size must be finite")
    _refused(_yaml(folder, origin="[1.7976931348623157e308, 0, 0]", resolution="1e300"),
             "origin: [1.7976931348623157e+308, 0.0, 0.0] puts the map's corners beyond the floats; they must be "
             "finite")
