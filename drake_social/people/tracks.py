"""Piecewise-linear tracks of people in time: positions, velocities, headings.

The shared core of the scripted (:mod:`drake_social.people.scripted`) and the
recorded (:mod:`drake_social.people.recorded`) people. Each person has timed
knots ``t_0 < t_1 < ... < t_{n-1}`` with positions, walked in straight lines at
constant speed between them; before ``t_0`` the person stands at the first
knot, after ``t_{n-1}`` at the last, and a looping person repeats the knots
with period ``t_{n-1} - t_0``. Velocities are the segments' exact velocities
(0 while standing).

Headings follow :func:`~drake_social.scenario.heading.heading_knots`
(re-exported here): the facing direction turns toward the direction of motion
at a bounded rate (:data:`TURN_RATE`) from the moment a segment of motion
starts, so it never flips at a corner or a stop.

All people of a :class:`Tracks` are evaluated together (vectorised over
people): :meth:`Tracks.evaluate` costs a few numpy operations whatever the
number of knots.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from drake_social.people import tracks_kernel
from drake_social.scenario.heading import MAX_LOOP_PASSES, TURN_RATE, heading_knots

__all__ = ["MAX_LOOP_PASSES", "TURN_RATE", "Tracks", "heading_knots"]


class Tracks:
    """People on piecewise-linear tracks, evaluated together.

    Each person's breakpoints (the union of their position and heading knots)
    cut time into intervals on which position and heading are linear; each
    interval stores its start time, the values there and their rates (the
    segment's exact velocity, 0 while standing). :meth:`evaluate` finds every
    person's interval with one ``searchsorted`` over all people's
    breakpoints (each person's offset by their index times a span longer
    than all times), then evaluates ``value + (t - start) * rate``: exact at
    the breakpoints and while standing.

    Args:
        times: one (n_i,) array of strictly increasing knot times per person, seconds (n_i >= 1).
        points: one (n_i, 2) array of knot positions per person, metres.
        headings: one (knot times, headings) pair per person (as
            :func:`heading_knots` gives, or sampled headings; times strictly
            increasing), radians.
        loops: per person, the knots repeat with period ``t_{n-1} - t_0``.
        steady: per person with a loop, the time (``t_0`` plus a whole number
            of periods) from which the heading knots repeat with that period
            (see :func:`heading_knots`); ignored without a loop.
    """

    def __init__(self, times: Sequence[np.ndarray], points: Sequence[np.ndarray],
                 headings: Sequence[tuple[np.ndarray, np.ndarray]], loops: Sequence[bool],
                 steady: Sequence[float]) -> None:
        p = len(times)
        self._count = p
        loop = np.zeros(p, bool)
        start = np.zeros(p)
        period = np.ones(p)
        tables = []
        for i in range(p):
            t = np.asarray(times[i], float).reshape(-1)
            x = np.asarray(points[i], float).reshape(-1, 2)
            ht, hv = (np.asarray(a, float).reshape(-1) for a in headings[i])
            if loops[i] and len(t) > 1:
                loop[i] = True
                length = t[-1] - t[0]
                start[i], period[i] = steady[i], length
                passes = int(round((steady[i] - t[0]) / length)) + 1
                # The route unrolled over the passes the heading's knots cover.
                t = np.concatenate([t[:1]] + [t[1:] + k * length for k in range(passes)])
                x = np.concatenate([x[:1]] + [x[1:]] * passes)
            tables.append(self._intervals(t, x, ht, hv))
        self._loop = loop
        self._any_loop = bool(loop.any())
        self._start, self._period = start, period
        lo = min((b[0] for b, *_ in tables), default=0.0)
        hi = max((b[-1] for b, *_ in tables), default=0.0)
        # Person i's breakpoints are keyed i * span + (b - lo); queries are clipped to
        # [lo - 0.5, hi + 0.5], so a person's keys and queries never reach the next person's.
        self._lo, self._hi = lo, hi
        span = (hi - lo) + 2.0
        self._keys = np.concatenate([i * span + (b - lo) for i, (b, *_) in enumerate(tables)]) if p else np.zeros(0)
        self._key_base = np.arange(p) * span
        self._rows = np.arange(p)
        # One row per interval: value [x, y, h], rate [vx, vy, dh/dt], start time (one gather per call).
        self._table = (np.concatenate([np.column_stack([value, rate, base]) for _, base, value, rate in tables])
                       if p else np.zeros((0, 7)))

    @staticmethod
    def _intervals(t: np.ndarray, x: np.ndarray, ht: np.ndarray, hv: np.ndarray):
        """One person's breakpoints (m,) and, for the m + 1 intervals (before the
        first, between, after the last), start times, values [x, y, h] and rates."""
        b = np.union1d(t, ht)
        m = len(b)
        value = np.empty((m, 3))
        value[:, 0] = np.interp(b, t, x[:, 0])
        value[:, 1] = np.interp(b, t, x[:, 1])
        value[:, 2] = np.interp(b, ht, hv)
        rate = np.zeros((m + 1, 3))
        if m > 1:
            mid = 0.5 * (b[:-1] + b[1:])
            if len(t) > 1:
                k = np.clip(np.searchsorted(t, mid) - 1, 0, len(t) - 2)
                inside = (mid > t[0]) & (mid < t[-1])
                rate[1:m, :2] = np.where(inside[:, None], (x[k + 1] - x[k]) / (t[k + 1] - t[k])[:, None], 0.0)
            if len(ht) > 1:
                k = np.clip(np.searchsorted(ht, mid) - 1, 0, len(ht) - 2)
                inside = (mid > ht[0]) & (mid < ht[-1])
                rate[1:m, 2] = np.where(inside, (hv[k + 1] - hv[k]) / (ht[k + 1] - ht[k]), 0.0)
        base = np.concatenate([b[:1], b])
        value = np.concatenate([value[:1], value])
        return b, base, value, rate

    @property
    def count(self) -> int:
        """The number of people P."""
        return self._count

    def evaluate(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions (P, 2), velocities (P, 2) and headings (P,) at time ``t``
        (seconds), fresh C-contiguous arrays: :meth:`evaluate_reference`'s
        numbers by the compiled loop of :mod:`drake_social.people.tracks_kernel`."""
        return tracks_kernel.evaluate(float(t), self._loop, self._start, self._period, self._lo, self._hi,
                                      self._key_base, self._keys, self._table)

    def evaluate_reference(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`evaluate` in numpy, vectorised over people (the reference)."""
        t = float(t)
        if self._any_loop:
            u = np.where(self._loop & (t > self._start),
                         self._start + np.mod(t - self._start, self._period), t)
            query = self._key_base + (np.minimum(np.maximum(u, self._lo - 0.5), self._hi + 0.5) - self._lo)
        else:
            u = t
            query = self._key_base + (min(max(t, self._lo - 0.5), self._hi + 0.5) - self._lo)
        # Interval j of person i (j breakpoints <= u) is row (i's first key index) + i + j.
        rows = self._table[np.searchsorted(self._keys, query, side="right") + self._rows]
        out = rows[:, :3] + (u - rows[:, 6])[:, None] * rows[:, 3:6]
        # Fresh C-contiguous arrays (a caller may keep them without copying).
        return out[:, :2].copy(), rows[:, 3:5].copy(), out[:, 2].copy()
