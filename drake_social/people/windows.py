"""Windows of a pedestrian recording: where it is crowded, and which way the crowd walks.

A recording (:class:`~drake_social.people.eth_ucy.Recording`, time
``t = frame / fps``) holds each id from its first row to its last: the id is
*present* at every time in between, as a people file's person is
(:mod:`drake_social.people.recorded`).

**The sample grid.** Presence is counted on the recording's frame grid:
frames ``f_0 + j * df`` from the first frame ``f_0``, ``df`` the smallest
step between two consecutive rows of an id (10 frames in ETH/UCY: 0.4 s at
25 fps; without such a pair, the smallest step between two distinct frames).
``n_j`` is the number of ids present at sample ``j`` (first frame <= the
sample's frame <= last frame, inclusive, exactly: frames are compared, not
times).

**A window** of ``length`` seconds starts at a sample ``j`` and holds the
samples of ``[t_j, t_j + length]``: ``m = floor(length * fps / df) + 1`` of
them (to a relative 1e-9, so that 60 s at 0.4 s is 151 samples); it fits in
the recording when ``t_j + length`` is not after the last row's time. Its
crowd is the mean of ``n`` over its samples (``people_mean``), with the
least, the most and the count at its first sample (``people_t0``, whom a
planner that plans at t = 0 sees). A window is dense enough when
``people_mean >= min_people``, compared in integers (``sum n >=
min_people * m``), so a threshold holds exactly.

:func:`cut_windows` chooses ``count`` windows that do not overlap (two may
share an end point): the densest first (the largest sum, the earlier start
on a tie), each one kept when it overlaps none kept before; the chosen are
returned in time order. It refuses a recording shorter than one window, a
recording without a window dense enough, and one where fewer than
``count`` are found, each with a :class:`~drake_social.errors.ScenarioError`
naming the file and the option to change.

**The flow.** :func:`flow_angle` is the dominant walking axis of a window:
each step ``d`` between consecutive rows of an id (both in the window)
counts with its length, as the doubled angle (an axis, not a direction: a
crowd walking both ways along a corridor has the corridor's axis):
``0.5 atan2(sum 2 dx dy / |d|, sum (dx^2 - dy^2) / |d|)``, in (-pi/2, pi/2]
(0 when nobody moves, or the steps cancel). :func:`crossing_rotation` turns
that axis onto the y axis (``pi/2 - angle``, in [0, pi)), so that a task
along x crosses the flow at right angles.

Pure numpy; nothing here reads files.
"""

from __future__ import annotations

import bisect
import dataclasses as dc
import math

import numpy as np

from drake_social.errors import ScenarioError
from drake_social.people.eth_ucy import Recording

__all__ = ["MAX_GRID_SAMPLES", "SAMPLE_TOLERANCE", "Window", "crossing_rotation", "cut_windows", "flow_angle", "frame_step",
           "presence_counts"]

#: Relative tolerance of ``length * fps / df`` when counting a window's samples.
SAMPLE_TOLERANCE = 1e-9
#: Most samples of a recording's grid (its span over ``df``): the counts are
#: held in memory (16 bytes a sample); ETH/UCY's longest has about 1,300.
MAX_GRID_SAMPLES = 4_000_000


@dc.dataclass(frozen=True)
class Window:
    """A window of a recording (seconds of the recording, ``t = frame / fps``).

    Attributes:
        index: its place among the chosen windows, in time order (0, 1, ...).
        start, end: ``[start, end]``, seconds; ``end = start + length``.
        samples: the grid samples it holds.
        people_mean: people present, the mean over its samples.
        people_min, people_max: the least and the most present at a sample.
        people_t0: people present at its first sample (t = 0 of an episode).
    """

    index: int
    start: float
    end: float
    samples: int
    people_mean: float
    people_min: int
    people_max: int
    people_t0: int

    def to_json_dict(self) -> dict:
        return dc.asdict(self)


def _id_codes(recording: Recording) -> tuple[np.ndarray, int]:
    """Each row's id as an integer code (N,) and the number of ids."""
    _, codes = np.unique(np.array(recording.ids, dtype=str), return_inverse=True)
    codes = codes.reshape(-1)
    return codes, int(codes.max()) + 1 if len(codes) else 0


def frame_step(recording: Recording) -> float:
    """``df``: the smallest positive frame step between consecutive rows of
    an id; without one (every id a single row), between two distinct frames
    of the recording; 0 when the recording has a single frame."""
    frames = np.asarray(recording.frames, float)
    codes, _ = _id_codes(recording)
    order = np.lexsort((frames, codes))  # by id, then frame
    same = codes[order][1:] == codes[order][:-1]
    steps = np.diff(frames[order])[same]
    steps = steps[steps > 0]
    if len(steps):
        return float(steps.min())
    distinct = np.unique(frames)
    return float(np.diff(distinct).min()) if len(distinct) > 1 else 0.0


def presence_counts(recording: Recording) -> tuple[np.ndarray, np.ndarray]:
    """The sample grid's frames (J,) and the ids present at each (J,) integers
    (see the module docstring); a single sample for a one-frame recording.

    Raises:
        ScenarioError: the grid would have more than :data:`MAX_GRID_SAMPLES` samples.
    """
    frames = np.asarray(recording.frames, float)
    df = frame_step(recording)
    f0, f1 = float(frames.min()), float(frames.max())
    samples = 1 if df == 0 else math.floor((f1 - f0) / df + SAMPLE_TOLERANCE) + 1
    if samples > MAX_GRID_SAMPLES:
        raise ScenarioError(f"{recording.source}: frames {f0:g} .. {f1:g} in steps of {df:g} are {samples:,} samples; "
                            f"a recording may span at most {MAX_GRID_SAMPLES:,} of its steps")
    grid = np.array([f0]) if df == 0 else f0 + df * np.arange(samples)
    codes, n = _id_codes(recording)
    firsts, lasts = np.full(n, np.inf), np.full(n, -np.inf)
    np.minimum.at(firsts, codes, frames)
    np.maximum.at(lasts, codes, frames)
    firsts, lasts = np.sort(firsts), np.sort(lasts)
    # present at g: first <= g and not last < g.
    counts = np.searchsorted(firsts, grid, side="right") - np.searchsorted(lasts, grid, side="left")
    return grid, counts.astype(np.int64)


def cut_windows(recording: Recording, *, fps: float, length: float, count: int, min_people: int,
                options: dict[str, str] | None = None) -> list[Window]:
    """``count`` windows of ``length`` seconds with at least ``min_people``
    present on average, the densest first (see the module docstring).

    Args:
        recording: the parsed recording.
        fps: frames per second (t = frame / fps), > 0.
        length: the windows' length, seconds (> 0).
        count: how many windows (>= 1).
        min_people: the least mean number of people present (>= 0).
        options: the command's option of each setting, for messages
            (``{"length": "--window-length", ...}``); default the settings' names.

    Returns:
        The windows in time order (``index`` 0, 1, ...).

    Raises:
        ScenarioError: the recording is shorter than one window; no window
            is dense enough; fewer than ``count`` are found.
    """
    names = {"length": "length", "count": "count", "min_people": "min_people", **(options or {})}
    src = recording.source
    grid, counts = presence_counts(recording)
    f0, f1 = float(grid[0]), float(np.max(recording.frames))
    span, window = f1 - f0, float(length) * fps  # frames
    if window > span * (1 + SAMPLE_TOLERANCE):
        raise ScenarioError(f"{src}: the recording spans {span / fps:g} s (t = {f0 / fps:g} .. {f1 / fps:g} s): "
                            f"shorter than one window; {names['length']} must be at most {span / fps:g} s, "
                            f"got {length:g}")
    df = float(grid[1] - grid[0]) if len(grid) > 1 else 0.0
    samples = min(int(math.floor(window / df * (1 + SAMPLE_TOLERANCE))) + 1 if df > 0 else 1, len(grid))
    # The starts whose window ends within the recording.
    starts = np.flatnonzero(grid - f0 + window <= span * (1 + SAMPLE_TOLERANCE))
    starts = starts[starts + samples <= len(grid)]
    cumulative = np.concatenate([[0], np.cumsum(counts)])
    sums = cumulative[starts + samples] - cumulative[starts]
    dense = sums >= min_people * samples
    best = float(sums.max()) / samples if len(sums) else 0.0
    if not dense.any():
        raise ScenarioError(f"{src}: no window of {length:g} s has {names['min_people']} {min_people} people present "
                            f"on average; the densest has {best:.3g}: lower {names['min_people']} or "
                            f"{names['length']}")
    order = sorted(np.flatnonzero(dense), key=lambda k: (-int(sums[k]), int(starts[k])))
    chosen: list[float] = []  # sorted start times
    picked: list[int] = []
    for k in order:
        s = float(grid[starts[k]]) / fps
        i = bisect.bisect_left(chosen, s)
        if (i < len(chosen) and chosen[i] - s < length * (1 - SAMPLE_TOLERANCE)) or \
                (i > 0 and s - chosen[i - 1] < length * (1 - SAMPLE_TOLERANCE)):
            continue
        chosen.insert(i, s)
        picked.append(int(k))
        if len(picked) == count:
            break
    if len(picked) < count:
        raise ScenarioError(f"{src}: {names['count']} {count}: the recording has {len(picked)} windows of "
                            f"{length:g} s that do not overlap with {names['min_people']} {min_people} people present "
                            f"on average (chosen densest first); lower {names['count']}, {names['min_people']} or "
                            f"{names['length']}")
    windows = []
    for index, k in enumerate(sorted(picked, key=lambda k: int(starts[k]))):
        j = int(starts[k])
        window_counts = counts[j:j + samples]
        start = float(grid[j]) / fps
        windows.append(Window(index=index, start=start, end=start + float(length), samples=samples,
                              people_mean=float(sums[k]) / samples, people_min=int(window_counts.min()),
                              people_max=int(window_counts.max()), people_t0=int(window_counts[0])))
    return windows


def flow_angle(steps: np.ndarray) -> float:
    """The dominant axis (radians, in (-pi/2, pi/2]) of walking steps (N, 2),
    metres: each step counts with its length, as a doubled angle (see the
    module docstring); 0 without steps or when they cancel."""
    d = np.asarray(steps, float).reshape(-1, 2)
    length = np.hypot(d[:, 0], d[:, 1])
    moving = length > 0
    d, length = d[moving], length[moving]
    c = float(np.sum((d[:, 0] ** 2 - d[:, 1] ** 2) / length)) if len(d) else 0.0
    s = float(np.sum(2.0 * d[:, 0] * d[:, 1] / length)) if len(d) else 0.0
    if c == 0.0 and s == 0.0:
        return 0.0
    angle = 0.5 * math.atan2(s, c)
    return angle if angle > -math.pi / 2 else angle + math.pi


def crossing_rotation(angle: float) -> float:
    """The rotation (radians, counter-clockwise, in [0, pi)) that turns a flow
    axis at ``angle`` (in (-pi/2, pi/2]) onto the y axis: ``pi/2 - angle``."""
    rotation = math.pi / 2 - float(angle)
    return rotation - math.pi if rotation >= math.pi else rotation
