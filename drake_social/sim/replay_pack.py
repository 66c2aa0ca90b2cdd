"""Smaller replay pages: the recorded animation's numbers in float32.

``Meshcat.StaticHtml()`` embeds every command as a base64 MessagePack
message; the recording (``set_animation``) is most of a long run's page and
writes each keyframe value as a 9-byte float64. three.js keeps keyframe times
and values in ``Float32Array`` s (``KeyframeTrack.ValueBufferType``), so
writing them as 5-byte float32 (and integral values as integers, one byte for
the zeros of a yaw-only quaternion) changes nothing the page shows while it
shrinks the animation by about 40 %. :func:`compact_page` does that to the
page's ``set_animation`` messages only; geometry and textures are left as
they are.

The MessagePack subset here (nil, booleans, integers, floats, strings,
binary, extension types, arrays and maps) is the whole format; it is written
for this one job rather than adding a dependency.
"""

from __future__ import annotations

import base64
import math
import re
import struct

__all__ = ["ExtType", "compact_animation", "compact_page", "pack", "unpack"]

# A command embedded by StaticHtml(): fetch("data:application/octet-binary;base64,...").
_EMBEDDED = re.compile(r'(fetch\("data:application/octet-binary;base64,)([A-Za-z0-9+/=]+)("\))')
_FLOAT32_MAX = float(struct.unpack(">f", b"\x7f\x7f\xff\xff")[0])


class ExtType(tuple):
    """A MessagePack extension value: (type code, bytes), kept as it is."""

    def __new__(cls, code: int, data: bytes):
        return super().__new__(cls, (int(code), bytes(data)))


def unpack(data: bytes) -> object:
    """The one MessagePack value in ``data``.

    Raises:
        ValueError: a truncated or unknown encoding, or bytes after the value.
    """
    value, end = _read(memoryview(bytes(data)), 0)
    if end != len(data):
        raise ValueError(f"MessagePack: {len(data) - end} byte(s) after the value")
    return value


def _read(buf: memoryview, i: int) -> tuple[object, int]:
    if i >= len(buf):
        raise ValueError("MessagePack: truncated message")
    b = buf[i]
    i += 1
    if b <= 0x7F:
        return b, i
    if b >= 0xE0:
        return b - 0x100, i
    if 0x80 <= b <= 0x8F:
        return _read_map(buf, i, b & 0x0F)
    if 0x90 <= b <= 0x9F:
        return _read_array(buf, i, b & 0x0F)
    if 0xA0 <= b <= 0xBF:
        return _read_str(buf, i, b & 0x1F)
    fixed = {0xC0: None, 0xC2: False, 0xC3: True}
    if b in fixed:
        return fixed[b], i
    formats = {0xCA: ">f", 0xCB: ">d", 0xCC: ">B", 0xCD: ">H", 0xCE: ">I", 0xCF: ">Q",
               0xD0: ">b", 0xD1: ">h", 0xD2: ">i", 0xD3: ">q"}
    if b in formats:
        fmt = formats[b]
        size = struct.calcsize(fmt)
        _need(buf, i, size)
        return struct.unpack_from(fmt, buf, i)[0], i + size
    lengths = {0xC4: ">B", 0xC5: ">H", 0xC6: ">I", 0xD9: ">B", 0xDA: ">H", 0xDB: ">I",
               0xDC: ">H", 0xDD: ">I", 0xDE: ">H", 0xDF: ">I", 0xC7: ">B", 0xC8: ">H", 0xC9: ">I"}
    if b in lengths:
        fmt = lengths[b]
        size = struct.calcsize(fmt)
        _need(buf, i, size)
        n = struct.unpack_from(fmt, buf, i)[0]
        i += size
        if b in (0xC4, 0xC5, 0xC6):
            _need(buf, i, n)
            return bytes(buf[i:i + n]), i + n
        if b in (0xD9, 0xDA, 0xDB):
            return _read_str(buf, i, n)
        if b in (0xDC, 0xDD):
            return _read_array(buf, i, n)
        if b in (0xDE, 0xDF):
            return _read_map(buf, i, n)
        return _read_ext(buf, i, n)
    if 0xD4 <= b <= 0xD8:  # fixext 1, 2, 4, 8, 16
        return _read_ext(buf, i, 1 << (b - 0xD4))
    raise ValueError(f"MessagePack: unknown type byte 0x{b:02x} at {i - 1}")


def _need(buf: memoryview, i: int, n: int) -> None:
    if i + n > len(buf):
        raise ValueError("MessagePack: truncated message")


def _read_str(buf: memoryview, i: int, n: int) -> tuple[str, int]:
    _need(buf, i, n)
    return bytes(buf[i:i + n]).decode("utf-8"), i + n


def _read_array(buf: memoryview, i: int, n: int) -> tuple[list, int]:
    out = []
    for _ in range(n):
        value, i = _read(buf, i)
        out.append(value)
    return out, i


def _read_map(buf: memoryview, i: int, n: int) -> tuple[dict, int]:
    out = {}
    for _ in range(n):
        key, i = _read(buf, i)
        value, i = _read(buf, i)
        out[key] = value
    return out, i


def _read_ext(buf: memoryview, i: int, n: int) -> tuple[ExtType, int]:
    _need(buf, i, n + 1)
    return ExtType(struct.unpack_from(">b", buf, i)[0], bytes(buf[i + 1:i + 1 + n])), i + 1 + n


def pack(value: object, *, float32: bool = False) -> bytes:
    """``value`` as MessagePack (the smallest encoding of each integer, string
    and container length).

    Args:
        float32: write each float that is not integral as float32 (rounded
            to nearest, as ``Float32Array`` stores it) and each integral
            float (|x| < 2^53) as an integer; non-finite floats and floats
            beyond float32's range stay float64.
    """
    out = bytearray()
    _write(out, value, float32)
    return bytes(out)


def _write_length(out: bytearray, n: int, fix: int | None, fix_max: int, codes: tuple[int, ...]) -> None:
    if fix is not None and n <= fix_max:
        out.append(fix | n)
        return
    for code, fmt in zip(codes, (">B", ">H", ">I")):
        if code and n < 1 << (8 * struct.calcsize(fmt)):
            out.append(code)
            out += struct.pack(fmt, n)
            return
    raise ValueError(f"MessagePack: length {n} too large")


def _write(out: bytearray, v: object, float32: bool) -> None:
    if v is None:
        out.append(0xC0)
    elif v is True or v is False:
        out.append(0xC3 if v else 0xC2)
    elif isinstance(v, ExtType):
        code, data = v
        n = len(data)
        if n in (1, 2, 4, 8, 16):
            out.append(0xD4 + n.bit_length() - 1)
        else:
            _write_length(out, n, None, 0, (0xC7, 0xC8, 0xC9))
        out += struct.pack(">b", code) + data
    elif isinstance(v, int):
        _write_int(out, v)
    elif isinstance(v, float):
        if float32 and math.isfinite(v) and v == math.floor(v) and abs(v) < 2.0**53:
            _write_int(out, int(v))
        elif float32 and math.isfinite(v) and abs(v) <= _FLOAT32_MAX:
            out.append(0xCA)
            out += struct.pack(">f", v)
        else:
            out.append(0xCB)
            out += struct.pack(">d", v)
    elif isinstance(v, str):
        data = v.encode("utf-8")
        _write_length(out, len(data), 0xA0, 31, (0xD9, 0xDA, 0xDB))
        out += data
    elif isinstance(v, (bytes, bytearray)):
        _write_length(out, len(v), None, 0, (0xC4, 0xC5, 0xC6))
        out += v
    elif isinstance(v, (list, tuple)):
        _write_length(out, len(v), 0x90, 15, (0, 0xDC, 0xDD))
        for item in v:
            _write(out, item, float32)
    elif isinstance(v, dict):
        _write_length(out, len(v), 0x80, 15, (0, 0xDE, 0xDF))
        for key, item in v.items():
            _write(out, key, float32)
            _write(out, item, float32)
    else:
        raise TypeError(f"MessagePack: cannot pack {type(v).__name__}")


def _write_int(out: bytearray, n: int) -> None:
    if 0 <= n <= 0x7F:
        out.append(n)
    elif -32 <= n < 0:
        out.append(n & 0xFF)
    elif n > 0:
        for code, fmt in ((0xCC, ">B"), (0xCD, ">H"), (0xCE, ">I"), (0xCF, ">Q")):
            if n < 1 << (8 * struct.calcsize(fmt)):
                out.append(code)
                out += struct.pack(fmt, n)
                return
        raise ValueError(f"MessagePack: integer {n} too large")
    else:
        for code, fmt in ((0xD0, ">b"), (0xD1, ">h"), (0xD2, ">i"), (0xD3, ">q")):
            if n >= -(1 << (8 * struct.calcsize(fmt) - 1)):
                out.append(code)
                out += struct.pack(fmt, n)
                return
        raise ValueError(f"MessagePack: integer {n} too large")


def compact_animation(message: bytes) -> bytes:
    """A ``set_animation`` message with its numbers in float32 (see the
    module's docstring); any other message is returned as it is."""
    if b"set_animation" not in message[:32]:
        return message
    value = unpack(message)
    if not (isinstance(value, dict) and value.get("type") == "set_animation"):
        return message
    return pack(value, float32=True)


def compact_page(html: str) -> str:
    """``StaticHtml()`` text with each embedded ``set_animation`` message
    compacted by :func:`compact_animation`."""

    def one(match: re.Match) -> str:
        data = match.group(2)
        if b"set_animation" not in base64.b64decode(data[:64]):
            return match.group(0)
        message = compact_animation(base64.b64decode(data))
        return match.group(1) + base64.b64encode(message).decode("ascii") + match.group(3)

    return _EMBEDDED.sub(one, html)
