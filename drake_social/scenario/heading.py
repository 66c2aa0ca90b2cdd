"""The heading rule of a walking person: turning toward the motion at a bounded rate.

What a scenario's ``trajectory`` means for the facing direction, in one
place: the people models (:mod:`drake_social.people.tracks`) evaluate it, and
the validation (:mod:`drake_social.scenario.people_rules`) refuses a looping
route whose heading never repeats, before anything runs.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["MAX_LOOP_PASSES", "TURN_RATE", "heading_knots"]

#: Largest turning rate of a walking person's facing direction, rad/s: a
#: half turn takes one second (people turn at about 100-200 degrees per
#: second while walking).
TURN_RATE = math.pi
#: Periods of a looping route simulated to find where the heading repeats
#: (it repeats after the first period as soon as one turn of the route
#: completes within it).
MAX_LOOP_PASSES = 8


def _wrap(a: float) -> float:
    """``a`` in (-pi, pi]."""
    w = math.remainder(a, 2 * math.pi)
    return math.pi if w == -math.pi else w


class _Turner:
    """The bounded-rate heading along the unrolled timeline: knots (t, h),
    linear between them, constant after the last."""

    def __init__(self, t: float, h: float, rate: float) -> None:
        self.t = [t]
        self.h = [h]
        self.rate = rate

    def at(self, s: float) -> float:
        if s >= self.t[-1]:
            return self.h[-1]
        t0, t1, h0, h1 = self.t[-2], self.t[-1], self.h[-2], self.h[-1]
        return h0 + (h1 - h0) * (s - t0) / (t1 - t0)

    def turn(self, s: float, direction: float) -> None:
        """Start turning at time ``s`` toward ``direction`` (the shortest way;
        a half turn counter-clockwise), cutting short a turn still under way."""
        h = self.at(s)
        while len(self.t) > 1 and self.t[-1] > s:  # a turn under way stops at s
            self.t.pop()
            self.h.pop()
        if self.t[-1] < s:
            self.t.append(s)
            self.h.append(h)
        delta = _wrap(direction - h)
        if delta != 0.0:
            self.t.append(s + abs(delta) / self.rate)
            self.h.append(h + delta)

    def state(self, s: float) -> tuple[float, float, float]:
        """(heading at s, remaining turn in radians, its end time minus s)."""
        h = self.at(s)
        if s >= self.t[-1]:
            return h, 0.0, 0.0
        return h, self.h[-1] - h, self.t[-1] - s


def heading_knots(times: np.ndarray, points: np.ndarray, theta: float, loop: bool = False,
                  rate: float = TURN_RATE) -> tuple[np.ndarray, np.ndarray, float]:
    """The heading of a person walking ``points`` at ``times``, as knots of a
    piecewise-linear function of time.

    The rule: before the first motion the person faces ``theta``. When a
    segment of motion starts (at its first knot's time), the heading turns
    toward the segment's direction, the shortest way (a half turn
    counter-clockwise), at ``rate`` rad/s, and then holds it; a turn not
    finished when the next segment starts is cut short there and the new
    turn starts from where it got to. While standing between motions and
    after the last knot the heading keeps the last walking direction (a turn
    under way completes). So the heading is continuous and never changes
    faster than ``rate``.

    Args:
        times: (n,) knot times, seconds, strictly increasing (n >= 1).
        points: (n, 2) knot positions, metres.
        theta: the heading before the first motion, radians.
        loop: the route repeats with period ``times[-1] - times[0]`` (its last
            point is its first).
        rate: the turning rate, rad/s (> 0).

    Returns:
        (knot times (K,), unwrapped headings (K,), ``steady``): for a loop,
        the knots cover ``[times[0], steady + period]`` and from ``steady`` on
        the heading repeats with the period (equal modulo 2 pi); without a
        loop ``steady`` is +inf and the heading holds after the last knot.

    Raises:
        ValueError: a loop's heading does not repeat within
            :data:`MAX_LOOP_PASSES` periods (every turn of the route is cut
            short by the next: segments shorter than their turns).
    """
    times = np.asarray(times, float)
    points = np.asarray(points, float).reshape(-1, 2)
    d = np.diff(points, axis=0)
    moving = [(float(times[k]), math.atan2(d[k, 1], d[k, 0])) for k in range(len(d)) if d[k].any()]
    turner = _Turner(float(times[0]), float(theta), rate)
    if not loop or not moving:
        for s, direction in moving:
            turner.turn(s, direction)
        return np.array(turner.t), np.array(turner.h), math.inf
    t0 = float(times[0])
    period = float(times[-1]) - t0
    starts = [turner.state(t0)]
    for j in range(MAX_LOOP_PASSES):
        for s, direction in moving:
            turner.turn(s + j * period, direction)
        start = turner.state(t0 + (j + 1) * period)
        previous = starts[-1]
        if (abs(_wrap(start[0] - previous[0])) <= 1e-9 and abs(start[1] - previous[1]) <= 1e-9
                and abs(start[2] - previous[2]) <= 1e-9):  # pass j starts as pass j + 1 does: it repeats
            steady = t0 + j * period
            end = steady + period
            kt, kh = np.array(turner.t), np.array(turner.h)
            keep = kt < end
            return np.append(kt[keep], end), np.append(kh[keep], np.interp(end, kt, kh)), steady
        starts.append(start)
    raise ValueError(f"the heading of the looping route does not repeat within {MAX_LOOP_PASSES} periods: every "
                     f"turn (at {rate:.3g} rad/s) is cut short by the next segment; make the segments longer")
