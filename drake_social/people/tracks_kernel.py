"""One evaluation of :class:`drake_social.people.tracks.Tracks`, compiled with numba.

:meth:`Tracks.evaluate <drake_social.people.tracks.Tracks.evaluate>` runs every
time step of a simulation with walking people; its numpy form
(:meth:`~drake_social.people.tracks.Tracks.evaluate_reference`) costs a dozen
small-array operations. This loop does the same floating-point operations per
person (the wrap of a looping route is an exact ``fmod`` of positive numbers,
the interval a binary search with the same "keys <= query" rule), so the
numbers are the reference's; the tests compare the two.

The kernel calls no other module's compiled function, so numba's own cache
check (this file's source) keeps its on-disk cache fresh.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["evaluate"]


@njit(cache=True)
def evaluate(t, loop, start, period, lo, hi, key_base, keys, table):
    """Positions (P, 2), velocities (P, 2) and headings (P,) at time ``t``.

    Args:
        t: seconds.
        loop, start, period: (P,) per person: the route repeats with ``period``
            from ``start`` on (when ``loop``).
        lo, hi: the earliest and latest breakpoints of all people, seconds.
        key_base: (P,) person i's offset in ``keys``; keys: all breakpoints, keyed.
        table: one row per interval [x, y, h, vx, vy, dh/dt, start time]
            (person i's first row is their first key's index plus i).
    """
    p = key_base.shape[0]
    positions = np.empty((p, 2))
    velocities = np.empty((p, 2))
    headings = np.empty(p)
    for i in range(p):
        u = t
        if loop[i] and t > start[i]:
            # t - start and period are positive: fmod is exact, as numpy's mod there.
            u = start[i] + np.fmod(t - start[i], period[i])
        query = key_base[i] + (min(max(u, lo - 0.5), hi + 0.5) - lo)
        row = np.searchsorted(keys, query, side="right") + i
        dt = u - table[row, 6]
        positions[i, 0] = table[row, 0] + dt * table[row, 3]
        positions[i, 1] = table[row, 1] + dt * table[row, 4]
        headings[i] = table[row, 2] + dt * table[row, 5]
        velocities[i, 0] = table[row, 3]
        velocities[i, 1] = table[row, 4]
    return positions, velocities, headings
