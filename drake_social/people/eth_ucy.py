"""Converting an ETH/UCY pedestrian recording into a people CSV (``people_file``).

The ETH (Pellegrini et al. 2009) and UCY (Lerner et al. 2007) data sets, in
the layout most trajectory-prediction code ships them, have one row per
annotated pedestrian and frame, columns separated by tabs or spaces:

* layout ``xy`` (the default): ``frame id x y`` or ``frame id x y vx vy``
  (4 or 6 columns);
* layout ``xzy`` (ETH's ``obsmat.txt``): ``frame id x z y`` or
  ``frame id x z y vx vz vy`` (5 or 8 columns); z, the height, is ignored.

Frames are those of a 25 fps video annotated every ten frames, so
``t = frame / fps`` (fps 25 by default: rows 0.4 s apart); x, y in metres.
Velocity columns are read (they must be numbers) but not used: headings come
from the positions. Every row of a file has the same number of columns;
blank lines are skipped.

:func:`convert` then, in this order: keeps the selected ids (all by
default), keeps the rows with ``start <= frame / fps <= end`` (inclusive;
the whole recording by default), re-bases time so that the window starts at
t = 0 (``t = frame / fps - start``, with ``start`` the first kept row's time
when no start is given), rotates the positions by ``rotate`` radians about
the origin and then adds ``offset``. :func:`people_csv_text` writes the rows
as ``t,id,x,y,theta`` (or ``t,id,x,y``), sorted by time and then by the
order in which ids first appear in the file. ``theta`` is the direction of
motion of the transformed track: of ``p[k+1] - p[k-1]`` (one-sided at a
track's ends); where the person does not move it keeps the previous
heading (the next one at the start of a track), and a person who never
moves faces +x (0).

Every time and position written is a finite number: options that would
overflow one (an ``fps`` so small that ``frame / fps`` is infinite, a
``start`` or ``offset`` beyond the floats' range) are refused.

Nothing here reads or writes files (the ``people import`` command does,
:func:`drake_social.app.run_people_import`); errors are
:class:`~drake_social.errors.ScenarioError` naming the file and the line.
"""

from __future__ import annotations

import dataclasses as dc
import math
import sys
from typing import Sequence

import numpy as np

from drake_social.errors import ScenarioError

__all__ = ["ETH_UCY_FPS", "ETH_UCY_LAYOUTS", "MAX_RECORDING_BYTES", "Recording", "convert", "parse_eth_ucy",
           "people_csv_text"]

#: Frames per second of the ETH/UCY videos: t = frame / fps.
ETH_UCY_FPS = 25.0
#: Layout name -> (allowed column counts, column of x, column of y).
ETH_UCY_LAYOUTS = {"xy": ((4, 6), 2, 3), "xzy": ((5, 8), 2, 4)}
#: Largest recording accepted, bytes (the largest ETH/UCY file is about 1 MB).
MAX_RECORDING_BYTES = 64 * 1024 * 1024


@dc.dataclass(frozen=True)
class Recording:
    """The rows of a recording, in file order.

    Attributes:
        source: the file's name, for messages.
        frames: (N,) frame numbers.
        ids: N pedestrian ids (as text: ``"3"`` for ``3`` or ``3.0``).
        xy: (N, 2) positions, metres.
        lines: (N,) the 1-based line of each row in the file.
    """

    source: str
    frames: np.ndarray
    ids: tuple[str, ...]
    xy: np.ndarray
    lines: np.ndarray

    def id_order(self) -> list[str]:
        """The ids in the order of their first row."""
        return list(dict.fromkeys(self.ids))


def _id_text(value: float) -> str:
    return str(int(value)) if value.is_integer() and abs(value) < 2**53 else repr(value)


def _user_id(text) -> str:
    """An id as given (--ids 3 or 3.0) in the form of :attr:`Recording.ids`."""
    try:
        value = float(text)
    except (TypeError, ValueError):
        return str(text)
    return _id_text(value) if math.isfinite(value) else str(text)


def parse_eth_ucy(text: str, source: str, layout: str = "xy") -> Recording:
    """Parses an ETH/UCY recording (see the module docstring).

    Args:
        text: the file's text.
        source: the file's name, for messages.
        layout: "xy" or "xzy" (:data:`ETH_UCY_LAYOUTS`).

    Raises:
        ScenarioError: an unknown layout; no rows; a line with another
            number of columns than the layout allows or than the first row;
            a value that is not a number, or NaN or infinite; a frame that
            is negative or not after the previous frame of the same id.
    """
    if layout not in ETH_UCY_LAYOUTS:
        raise ScenarioError(f"{source}: unknown layout {layout!r}; allowed: {', '.join(ETH_UCY_LAYOUTS)}")
    counts, col_x, col_y = ETH_UCY_LAYOUTS[layout]
    allowed = " or ".join(str(c) for c in counts)
    frames, ids, xy, lines = [], [], [], []
    width = None
    last_frame: dict[str, tuple[float, int]] = {}
    for number, line in enumerate(text.splitlines(), start=1):
        fields = line.split()
        if not fields:
            continue
        where = f"{source}, line {number}"
        if len(fields) not in counts:
            raise ScenarioError(f"{where}: {len(fields)} columns; layout {layout!r} has {allowed} "
                                f"({'frame id x y [vx vy]' if layout == 'xy' else 'frame id x z y [vx vz vy]'}), "
                                "separated by tabs or spaces")
        if width is None:
            width = len(fields)
        elif len(fields) != width:
            raise ScenarioError(f"{where}: {len(fields)} columns, the rows before have {width}; "
                                "every row must have the same columns")
        values = []
        for k, field in enumerate(fields):
            try:
                value = float(field)
            except ValueError:  # the field is not repeated: any file may be named (io.textfile)
                raise ScenarioError(f"{where}, column {k + 1}: not a number; a recording has numbers only") from None
            if not math.isfinite(value):
                raise ScenarioError(f"{where}, column {k + 1}: {value} is not finite; values must be finite numbers")
            values.append(value)
        frame, person = values[0], _id_text(values[1])
        if frame < 0:
            raise ScenarioError(f"{where}: frame {fields[0]} is negative; frames are >= 0")
        if person in last_frame and not frame > last_frame[person][0]:
            before, at = last_frame[person]
            raise ScenarioError(f"{where}: frame {fields[0]} of id {person} does not come after its frame "
                                f"{before:g} on line {at}; each id's frames must increase")
        last_frame[person] = (frame, number)
        frames.append(frame)
        ids.append(person)
        xy.append((values[col_x], values[col_y]))
        lines.append(number)
    if not frames:
        raise ScenarioError(f"{source}: no rows; an ETH/UCY recording has rows 'frame id x y [vx vy]' "
                            "(or 'frame id x z y ...' with layout xzy)")
    return Recording(source, np.array(frames), tuple(ids), np.array(xy, dtype=float).reshape(-1, 2),
                     np.array(lines, dtype=np.int64))


def _headings(xy: np.ndarray) -> np.ndarray:
    """Directions of motion (radians) of one track (n, 2), see the module docstring."""
    n = len(xy)
    raw = np.full(n, np.nan)
    for k in range(n):
        a, b = xy[max(k - 1, 0)], xy[min(k + 1, n - 1)]
        dx, dy = b[0] - a[0], b[1] - a[1]
        if dx != 0.0 or dy != 0.0:
            raw[k] = math.atan2(dy, dx)
    known = np.flatnonzero(~np.isnan(raw))
    if len(known) == 0:
        return np.zeros(n)
    out = raw.copy()
    out[: known[0]] = raw[known[0]]  # before the first motion: the first heading
    for k in range(known[0] + 1, n):
        if np.isnan(out[k]):
            out[k] = out[k - 1]  # standing: keep the heading
    return out


def _smallest_fps(frame: float) -> float:
    """The smallest fps for which ``frame / fps`` is finite (``frame`` > 0)."""
    fps = frame / sys.float_info.max
    with np.errstate(over="ignore"):
        while not math.isfinite(frame / fps):
            fps = math.nextafter(fps, math.inf)
        while math.isfinite(frame / math.nextafter(fps, 0.0)):
            fps = math.nextafter(fps, 0.0)
    return fps


def convert(recording: Recording, *, fps: float = ETH_UCY_FPS, offset: Sequence[float] = (0.0, 0.0),
            rotate: float = 0.0, start: float | None = None, end: float | None = None,
            ids: Sequence[str] | None = None) -> list[tuple[float, str, float, float, float]]:
    """The people CSV's rows (t, id, x, y, theta) of a recording.

    Args:
        recording: from :func:`parse_eth_ucy`.
        fps: frames per second (> 0): t = frame / fps.
        offset: (dx, dy) added after the rotation, metres.
        rotate: rotation about the origin, radians (counter-clockwise).
        start, end: the time window, seconds of the recording (inclusive;
            None = from the first row / to the last).
        ids: the ids to keep (None = all).

    Returns:
        Rows sorted by time, then by the ids' first appearance in the file.

    Raises:
        ScenarioError: a bad option, an id not in the file, a selected id
            without rows in the window, an empty window, or options that
            make a time or a position infinite.
    """
    src = recording.source
    offset = tuple(float(v) for v in offset)
    if not (math.isfinite(fps) and fps > 0):
        raise ScenarioError(f"{src}: --fps must be a finite number > 0, got {fps}")
    if len(offset) != 2 or not all(math.isfinite(v) for v in offset) or not math.isfinite(rotate):
        raise ScenarioError(f"{src}: --offset needs two finite numbers (metres) and --rotate a finite angle (radians)")
    for name, value in (("--start", start), ("--end", end)):
        if value is not None and not math.isfinite(value):
            raise ScenarioError(f"{src}: {name} must be a finite time in seconds, got {value}")
    if start is not None and end is not None and not start < end:
        raise ScenarioError(f"{src}: the window --start {start:g} s .. --end {end:g} s is empty; --start must be "
                            "before --end")
    order = recording.id_order()
    keep = np.ones(len(recording.frames), dtype=bool)
    if ids is not None:
        wanted = [_user_id(i) for i in ids]
        unknown = [i for i in wanted if i not in order]
        if unknown:
            known = ", ".join(order[:20]) + (f", ... ({len(order)} ids)" if len(order) > 20 else "")
            raise ScenarioError(f"{src}: id {unknown[0]} is not in the recording (its ids: {known})")
        chosen_ids = set(wanted)
        keep = np.array([i in chosen_ids for i in recording.ids], dtype=bool)
    with np.errstate(over="ignore"):
        times = recording.frames / fps
    if not np.isfinite(times).all():  # a tiny fps: frame / fps overflows
        last = float(recording.frames.max())
        raise ScenarioError(f"{src}: --fps {fps!r} makes frame {last:g} at t = frame / fps = inf s; times must be "
                            f"finite: --fps must be at least {_smallest_fps(last)!r} for this recording")
    if start is not None:
        keep &= times >= start
    if end is not None:
        keep &= times <= end
    if not keep.any():
        span = f"{times.min():g} .. {times.max():g} s"
        raise ScenarioError(f"{src}: no rows in the window [{'start' if start is None else f'{start:g}'}, "
                            f"{'end' if end is None else f'{end:g}'}] s of the selected ids; the recording spans "
                            f"{span} (t = frame / {fps:g})")
    kept_ids = {recording.ids[k] for k in np.flatnonzero(keep)}
    if ids is not None:
        missing = [i for i in dict.fromkeys(wanted) if i not in kept_ids]
        if missing:
            raise ScenarioError(f"{src}: id {missing[0]} has no rows in the window; choose a window where it walks "
                                "or leave it out of --ids")
    t0 = float(start) if start is not None else float(times[keep].min())
    # Whole frames from the window's start where it falls on a frame: t = 0.4, not 0.40000000000000213.
    f0 = t0 * fps
    on_frame = abs(f0 - round(f0)) < 1e-9
    c, s = math.cos(rotate), math.sin(rotate)
    with np.errstate(over="ignore", invalid="ignore"):
        t = (recording.frames - round(f0)) / fps if on_frame else times - t0
        x = c * recording.xy[:, 0] - s * recording.xy[:, 1] + offset[0]
        y = s * recording.xy[:, 0] + c * recording.xy[:, 1] + offset[1]
    if not np.isfinite(t[keep]).all():  # frame / fps and the start finite, their difference not
        raise ScenarioError(f"{src}: --start {t0:g} s puts the rows at t = frame / fps - start beyond the finite "
                            "numbers; times must be finite")
    if not (np.isfinite(x[keep]).all() and np.isfinite(y[keep]).all()):
        raise ScenarioError(f"{src}: --offset {offset[0]:g} {offset[1]:g} and --rotate {rotate:g} put positions "
                            "beyond the finite numbers; positions must be finite")
    theta = np.zeros(len(t))
    person = np.array(recording.ids, dtype=object)
    for i in kept_ids:
        rows = np.flatnonzero(keep & (person == i))  # in file order: increasing frames
        theta[rows] = _headings(np.column_stack([x[rows], y[rows]]))
    rank = {name: k for k, name in enumerate(order)}
    chosen = sorted(np.flatnonzero(keep), key=lambda k: (t[k], rank[recording.ids[k]]))
    return [(float(t[k]), recording.ids[k], float(x[k]), float(y[k]), float(theta[k])) for k in chosen]


def people_csv_text(rows: Sequence[tuple], theta: bool = True) -> str:
    """The people CSV: header ``t,id,x,y,theta`` (``t,id,x,y`` without theta)
    and one line per row, numbers written exactly (shortest round-trip)."""
    lines = ["t,id,x,y,theta" if theta else "t,id,x,y"]
    for t, i, x, y, h in rows:
        lines.append(f"{t!r},{i},{x!r},{y!r}" + (f",{h!r}" if theta else ""))
    return "\n".join(lines) + "\n"
