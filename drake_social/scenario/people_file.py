"""Reading a scenario's recorded pedestrians (``people_file``), with every error named.

The file is CSV text (quoted fields as :mod:`csv` reads them; errors give the
line where the row starts): a header line naming the columns, then one row per person
and time, in any order. Columns (the header may give them in any order):

* ``t`` (seconds), ``id`` (any text; in double quotes when it holds a comma or a
  quote, as :mod:`csv` writes it), ``x``, ``y`` (metres): required;
* ``theta`` (radians): the facing direction; without it the heading follows the
  direction of motion (:mod:`drake_social.people.recorded`);
* ``radius`` (metres, > 0, the same on every row of an id; default
  :data:`DEFAULT_RADIUS`);
* ``v`` (m/s): accepted and ignored (the speed is derived from the positions),
  so that a ``people.csv`` written by ``simulate`` reads back.

Refused, each with the file, the line and what is allowed: a missing, empty or
oversized file (at most :data:`MAX_PEOPLE_FILE_BYTES`), a first line that is
not a header or names an unknown or repeated column or lacks a required one
(a first line that names none of the columns is not repeated in the message:
the file may be any file, :mod:`drake_social.io.textfile`),
a row with another number of fields than the header (ragged), a value that is
not a number, NaN or infinite, an empty id, two rows of one id at one time,
a radius <= 0 or changing within an id.

This module sits with the scenario (not with the people models) because the
file is read and checked when the scenario is loaded, before anything runs;
:mod:`drake_social.people.recorded` builds the people model from the result.
"""

from __future__ import annotations

import csv
import dataclasses as dc
import functools
import io
import math
from pathlib import Path

import numpy as np

from drake_social.errors import ScenarioError
from drake_social.io.textfile import SHOWN_PATH_CHARACTERS, check_regular_file, read_text_file, shorten

__all__ = ["DEFAULT_RADIUS", "MAX_PEOPLE_FILE_BYTES", "PEOPLE_FILE_COLUMNS", "PeopleRecording", "RecordedTrack",
           "read_people_file"]

#: Largest people file, bytes: 32 MiB, about 800,000 rows of 40 bytes (the
#: largest ETH/UCY recording converted has about 20,000 rows).
MAX_PEOPLE_FILE_BYTES = 32 * 1024 * 1024
#: The required columns, then the optional ones.
PEOPLE_FILE_COLUMNS = ("t", "id", "x", "y", "theta", "radius", "v")
_REQUIRED = PEOPLE_FILE_COLUMNS[:4]
#: Body radius of a recorded person when the file has no ``radius`` column, metres.
DEFAULT_RADIUS = 0.25


@dc.dataclass(frozen=True)
class RecordedTrack:
    """One id's samples, sorted by time.

    Attributes:
        id: the id as written in the file.
        times: (n,) strictly increasing times, seconds.
        positions: (n, 2) body centres, metres.
        thetas: (n,) facing directions, radians, or None (no ``theta`` column).
        radius: body radius, metres.
        first_line: the file's line of the id's earliest sample (1-based).
        lines: (n,) the file's line of each sample (1-based; ``lines[0] == first_line``).
    """

    id: str
    times: np.ndarray
    positions: np.ndarray
    thetas: np.ndarray | None
    radius: float
    first_line: int
    lines: np.ndarray | None = None


@dc.dataclass(frozen=True)
class PeopleRecording:
    """A people file read: its tracks by id.

    Attributes:
        path: the file, as it was named.
        tracks: id -> track; ids in numeric order when every id is a number,
            else in text order.
    """

    path: str
    tracks: dict[str, RecordedTrack]


def _fail(path, line: int | None, message: str) -> ScenarioError:
    where = "" if line is None else f"line {line}: "
    return ScenarioError(f"{shorten(str(path), SHOWN_PATH_CHARACTERS)}: {where}{message}")


def _header_text() -> str:
    return "t,id,x,y (required) and theta, radius, v (optional), in any order"


def read_people_file(path: str | Path) -> PeopleRecording:
    """Reads and checks a people file (see the module docstring).

    The result is cached per file (path, size, modification time): loading
    a scenario validates it more than once.

    Args:
        path: the CSV file.

    Returns:
        The recording.

    Raises:
        ScenarioError: ``<file>: line <n>: <what is wrong and what is allowed>``.
    """
    st = check_regular_file(path, "people")
    return _read_cached(str(path), st.st_size, st.st_mtime_ns, st.st_ino)


@functools.lru_cache(maxsize=8)
def _read_cached(path: str, size: int, mtime_ns: int, inode: int) -> PeopleRecording:
    del size, mtime_ns, inode  # the cache's key only
    text = read_text_file(path, "people", limit=MAX_PEOPLE_FILE_BYTES)
    numbered = _csv_rows(path, text)
    if not numbered:
        raise _fail(path, None, f"empty; a people file needs a header ({_header_text()}) and a row per person and "
                                "time")
    header_line, header = numbered[0]
    names = [c.strip() for c in header]
    if all(_is_number(c) for c in names):
        raise _fail(path, header_line, f"no header; the first line must name the columns: {_header_text()}")
    if not any(c in PEOPLE_FILE_COLUMNS for c in names):
        # Not a people file (a scenario may name any file): its line is not repeated.
        raise _fail(path, header_line, f"not a people file: the first line must name the columns ({_header_text()}); "
                                       f"none of its {len(names)} fields is one")
    seen: set[str] = set()
    for c in names:
        if c not in PEOPLE_FILE_COLUMNS:
            raise _fail(path, header_line, f"unknown column {shorten(repr(c))}; allowed: {_header_text()}")
        if c in seen:
            raise _fail(path, header_line, f"column {c!r} twice; each column once: {_header_text()}")
        seen.add(c)
    missing = [c for c in _REQUIRED if c not in seen]
    if missing:
        raise _fail(path, header_line, f"no column {', '.join(missing)}; the header needs {_header_text()}")
    if len(numbered) == 1:
        raise _fail(path, None, "no rows after the header; a people file needs a row per person and time")
    col = {c: k for k, c in enumerate(names)}
    numeric = [c for c in names if c not in ("id", "v")]
    rows: dict[str, list[tuple[float, int, tuple[float, ...]]]] = {}
    for line_no, row in numbered[1:]:
        fields = [f.strip() for f in row]
        if len(fields) != len(names):
            raise _fail(path, line_no, f"{len(fields)} fields; every row needs {len(names)}, one per column of the "
                                       f"header ({','.join(names)})")
        ident = fields[col["id"]]
        if not ident:
            raise _fail(path, line_no, "empty id; every row needs the id of its person")
        values = {}
        for c in numeric + (["v"] if "v" in col else []):
            text_value = fields[col[c]]
            try:
                value = float(text_value)
            except ValueError:
                raise _fail(path, line_no, f"{c}: must be a number, got {shorten(repr(text_value))}") from None
            if not math.isfinite(value):
                raise _fail(path, line_no, f"{c}: must be a finite number, got {text_value}")
            values[c] = value
        if "radius" in values and not values["radius"] > 0:
            raise _fail(path, line_no, f"radius: must be > 0 metres, got {fields[col['radius']]}")
        rows.setdefault(ident, []).append((values["t"], line_no, (values["x"], values["y"], values.get("theta", 0.0),
                                                                  values.get("radius", DEFAULT_RADIUS))))
    tracks = {}
    for ident in sorted(rows, key=_id_key(rows)):
        samples = sorted(rows[ident], key=lambda r: (r[0], r[1]))
        for (t_a, line_a, _), (t_b, line_b, _) in zip(samples, samples[1:]):
            if t_a == t_b:
                raise _fail(path, max(line_a, line_b), f"id {shorten(repr(ident))} at t = {t_b:g} s again (first "
                                                       f"at line {min(line_a, line_b)}); one row per id and time")
        data = np.array([s[2] for s in samples], float)
        radii = data[:, 3]
        if (radii != radii[0]).any():
            k = int(np.argmax(radii != radii[0]))
            raise _fail(path, samples[k][1], f"radius: id {shorten(repr(ident))} has radius {radii[k]:g} here and "
                                             f"{radii[0]:g} at line {samples[0][1]}; one radius per id")
        times, positions = np.array([s[0] for s in samples], float), data[:, :2].copy()
        thetas = data[:, 2].copy() if "theta" in col else None
        for a in (times, positions) + (() if thetas is None else (thetas,)):
            a.flags.writeable = False
        lines = np.array([s[1] for s in samples], dtype=np.int64)
        lines.flags.writeable = False
        tracks[ident] = RecordedTrack(id=ident, times=times, positions=positions, thetas=thetas,
                                      radius=float(radii[0]), first_line=samples[0][1], lines=lines)
    return PeopleRecording(path=path, tracks=tracks)


def _csv_rows(path, text: str) -> list[tuple[int, list[str]]]:
    """The non-blank rows of ``text`` as CSV fields (double quotes around a
    field with commas or quotes, doubled quotes inside, as :mod:`csv` writes),
    each with the file's line number (1-based) where the row starts."""
    out = []
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    line = 1
    try:
        for row in reader:
            if any(f.strip() for f in row):
                out.append((line, row))
            line = reader.line_num + 1
    except csv.Error as e:
        raise _fail(path, line, f"not CSV ({e}); a field with a comma or a quote must be in double quotes, "
                                'with its quotes doubled ("a ""b"", c")') from None
    return out


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _id_key(rows: dict):
    if all(_is_number(i) for i in rows):
        return lambda i: (float(i), i)
    return lambda i: i
