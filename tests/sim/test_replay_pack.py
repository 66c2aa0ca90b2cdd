"""The replay page's float32 animation (drake_social.sim.replay_pack).

Hand-written MessagePack bytes (the format's specification) and a round trip
through Drake's own recording: the compacted message holds the same values
as float32 rounds them, the page's other messages are left byte for byte.
"""

from __future__ import annotations

import base64
import re
import struct

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw

from drake_social.sim import replay
from drake_social.sim.replay_pack import ExtType, compact_animation, compact_page, pack, unpack


def test_pack_matches_the_specification():
    assert pack(None) == b"\xc0" and pack(True) == b"\xc3" and pack(False) == b"\xc2"
    assert pack(5) == b"\x05" and pack(-3) == b"\xfd" and pack(200) == b"\xcc\xc8"
    assert pack(-200) == b"\xd1\xff\x38" and pack(70000) == b"\xce\x00\x01\x11\x70"
    assert pack("ab") == b"\xa2ab" and pack(b"\x01") == b"\xc4\x01\x01"
    assert pack([1, 2]) == b"\x92\x01\x02" and pack({"a": 1}) == b"\x81\xa1a\x01"
    assert pack(0.5) == b"\xcb" + struct.pack(">d", 0.5)
    assert pack(0.1, float32=True) == b"\xca" + struct.pack(">f", 0.1)
    assert pack(3.0, float32=True) == b"\x03" and pack(-0.0, float32=True) == b"\x00"
    assert pack(1e300, float32=True) == b"\xcb" + struct.pack(">d", 1e300)
    assert pack(float("inf"), float32=True)[0] == 0xCB
    assert pack(ExtType(7, b"abcd")) == b"\xd6\x07abcd" and pack(ExtType(7, b"abc")) == b"\xc7\x03\x07abc"
    assert pack(list(range(16)))[:3] == b"\xdc\x00\x10"


def test_unpack_round_trips_and_checks():
    value = {"type": "x", "n": [0, -1, 127, 128, -33, 2**40, -(2**40)], "f": [0.25, -1e10], "b": b"\x00\xff",
             "e": ExtType(-2, b"\x01" * 12), "s": "é" * 40, "t": True, "none": None, "big": list(range(20))}
    assert unpack(pack(value)) == value
    assert unpack(b"\xca" + struct.pack(">f", 0.1)) == pytest.approx(0.1, rel=1e-7)
    with pytest.raises(ValueError, match="truncated"):
        unpack(b"\x92\x01")
    with pytest.raises(ValueError, match="after the value"):
        unpack(b"\x01\x02")
    with pytest.raises(ValueError, match="unknown type byte 0xc1"):
        unpack(b"\xc1")


def _animation_message(page: str) -> bytes:
    for data in re.findall(r'base64,([A-Za-z0-9+/=]+)"\)', page):
        message = base64.b64decode(data)
        if b"set_animation" in message[:32]:
            return message
    raise AssertionError("no set_animation message in the page")


def test_compact_page_rounds_the_animation_to_float32_only():
    meshcat = replay.make_meshcat()
    meshcat.SetObject("/box", replay.textured_quad((0, 0, 1, 1), b"\x89PNG-not-read"))
    animation = meshcat.get_mutable_recording()
    rng = np.random.default_rng(3)
    poses = rng.uniform(-10, 10, (20, 3))
    for k, (x, y, yaw) in enumerate(poses):
        animation.SetTransform(k, "/box", RigidTransform(RollPitchYaw(0, 0, yaw), [x, y, 0.0]))
    meshcat.PublishRecording()
    page = meshcat.StaticHtml()
    compact = compact_page(page)
    before, after = _animation_message(page), _animation_message(compact)
    assert len(after) < 0.7 * len(before)
    # Every number equals float32's rounding of the original.
    old, new = unpack(before), unpack(after)

    def numbers(v):
        if isinstance(v, dict):
            return [n for key in v for n in numbers(v[key])]
        if isinstance(v, list):
            return [n for item in v for n in numbers(item)]
        return [v] if isinstance(v, (int, float)) and not isinstance(v, bool) else []

    a, b = np.array(numbers(old), float), np.array(numbers(new), float)
    assert a.shape == b.shape and len(a) > 20 * 7
    np.testing.assert_array_equal(b, a.astype(np.float32).astype(float))
    assert old.keys() == new.keys()
    # The other messages are byte for byte the same.
    rest = lambda text: [m for m in re.findall(r'base64,([A-Za-z0-9+/=]+)"\)', text)
                         if b"set_animation" not in base64.b64decode(m[:64])]
    assert rest(page) == rest(compact)
    assert compact_animation(b"\x81\xa4type\xa3foo") == b"\x81\xa4type\xa3foo"
