"""Where a predicted person is at time t: the prediction's lookup, compiled (numba).

One rule, read by :class:`~drake_social.people.prediction.Prediction` and by
the kernels that take a prediction as plain arrays (the time-indexed social
cost, :mod:`drake_social.cost.timed_kernel`; the people's safety check,
:mod:`drake_social.collision.people_kernel`): the samples are at the times
``t0 + k dt``, k = 0 .. H - 1; at time t the sample is ``k = floor((t - t0) /
dt)`` and the fraction ``f`` the way on to k + 1, both clamped (before ``t0``
the first sample holds, after the horizon the last, with ``f = 0``); a
person's centre is interpolated linearly between samples k and k + 1, their
heading and presence are those of sample k.
"""

from __future__ import annotations

import math

import numpy as np

from drake_social import _kernel_cache

_kernel_cache.ensure_fresh()  # before any cached kernel is loaded

from numba import njit  # noqa: E402  (a dependency)

__all__ = ["centre", "centres", "slot"]


@njit(cache=True)
def slot(t, t0, dt, samples):
    """The sample k (int) at or before time ``t`` (seconds), clamped to
    0 .. samples - 1, and the fraction (float) of the way to k + 1 (0 when clamped)."""
    u = (t - t0) / dt
    if not u > 0.0:
        return 0, 0.0
    if u >= samples - 1:
        return samples - 1, 0.0
    k = int(math.floor(u))
    return k, u - k


@njit(cache=True)
def centre(xy, p, k, f):
    """Person p's centre (x, y) at the slot (k, f) of :func:`slot`: interpolated
    between the samples k and k + 1 of ``xy`` (H, P, 2), metres."""
    x, y = xy[k, p, 0], xy[k, p, 1]
    if k + 1 < xy.shape[0]:
        x = x + f * (xy[k + 1, p, 0] - x)
        y = y + f * (xy[k + 1, p, 1] - y)
    return x, y


@njit(cache=True)
def centres(xy, k, f):
    """Every person's :func:`centre` (P, 2) at the slot (k, f)."""
    out = np.empty((xy.shape[1], 2))
    for p in range(xy.shape[1]):
        out[p, 0], out[p, 1] = centre(xy, p, k, f)
    return out
