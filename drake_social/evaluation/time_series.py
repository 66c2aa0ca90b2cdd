"""Time series of a logged run reduced to numbers: held integrals, episodes,
trapezoid means and finite-difference motion statistics.

Conventions (the ones :func:`drake_social.evaluation.metrics.run_metrics`
states in its table):

* **sample-and-hold** for a flag or a class sampled at ``t_0 < ... < t_{T-1}``:
  sample k's value holds over ``[t_k, t_{k+1})``; the last sample holds for
  no time (the run ends there). This is how a discrete-time monitor's flag
  behaves and how HuNavSim counts time steps.
* **trapezoid rule** for a continuous quantity (a distance, an AGF value).
* **divided differences** for derivatives: the k-th derivative of a track
  from k + 1 consecutive samples is ``k!`` times their k-th divided
  difference, exact for polynomials of degree <= k at any sample spacing
  (a cubic's third derivative ``6 a3`` comes out exactly).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["derivative_magnitudes", "episodes", "held_time", "motion_profile", "motion_stats", "run_starts",
           "trapezoid_mean"]


def _steps(times: np.ndarray) -> np.ndarray:
    """The hold time of every sample (T,): t_{k+1} - t_k, 0 for the last, seconds."""
    times = np.asarray(times, float).reshape(-1)
    return np.append(np.diff(times), 0.0) if len(times) else np.zeros(0)


def held_time(mask: np.ndarray, times: np.ndarray) -> float:
    """Seconds during which ``mask`` (T,) holds, sample-and-hold."""
    mask = np.asarray(mask, bool).reshape(-1)
    return float(_steps(times)[mask].sum())


def run_starts(mask: np.ndarray) -> np.ndarray:
    """The sample indices (int array) where maximal runs of consecutive True
    samples of ``mask`` (T,) begin: k with ``mask[k]`` and (k = 0 or not ``mask[k - 1]``)."""
    mask = np.asarray(mask, bool).reshape(-1)
    return np.flatnonzero(mask & ~np.concatenate([[False], mask[:-1]]))


def episodes(mask: np.ndarray, times: np.ndarray) -> tuple[int, float]:
    """Maximal runs of consecutive True samples of ``mask`` (T,).

    Returns:
        (number of runs, their total duration in seconds, sample-and-hold).
        A run that starts at the first sample counts; a run made of the last
        sample alone counts with duration 0.
    """
    return len(run_starts(mask)), held_time(mask, times)


def trapezoid_mean(values: np.ndarray, times: np.ndarray) -> float:
    """Time average of ``values`` (T,) by the trapezoid rule over the steps
    whose two ends are finite (a step with an infinite end, e.g. nobody
    present, is left out of both the integral and the duration); NaN when
    no such step has a positive duration."""
    values = np.asarray(values, float).reshape(-1)
    times = np.asarray(times, float).reshape(-1)
    if len(values) < 2:
        return math.nan
    ok = np.isfinite(values[:-1]) & np.isfinite(values[1:])
    dt = np.diff(times)[ok]
    if not dt.sum() > 0:
        return math.nan
    return float((0.5 * (values[:-1][ok] + values[1:][ok]) * dt).sum() / dt.sum())


def derivative_magnitudes(times: np.ndarray, xy: np.ndarray, order: int) -> np.ndarray:
    """|d^order xy / dt^order| at each window of ``order + 1`` consecutive
    samples (T - order,), by divided differences (``order!`` times the
    order-th divided difference); units of xy per second^order.

    Args:
        times: (T,) strictly increasing seconds.
        xy: (T, D) positions.
        order: 1 (speed), 2 (acceleration) or 3 (jerk).
    """
    t = np.asarray(times, float).reshape(-1)
    d = np.asarray(xy, float).reshape(len(t), -1)
    for k in range(1, order + 1):
        d = (d[1:] - d[:-1]) / (t[k:] - t[:-k])[:, None]
    return math.factorial(order) * np.linalg.norm(d, axis=-1)


def motion_stats(times: np.ndarray, xy: np.ndarray) -> dict[str, float]:
    """Mean and max of |v| (m/s), |a| (m/s^2) and |j| (m/s^3) of a track.

    Args:
        times: (T,) strictly increasing seconds.
        xy: (T, D) positions, metres; or (T, N, D) for N tracks pooled (the
            mean and max over every window of every track).

    Returns:
        ``speed_mean``, ``speed_max``, ``accel_mean``, ``accel_max``,
        ``jerk_mean``, ``jerk_max``: arithmetic mean and max over the
        finite-difference windows, and ``jerk_p95``, their 95th percentile
        (numpy's linear interpolation: a few jerks of a hard stop do not
        move it); NaN when there are fewer samples than the derivative's
        order + 1.
    """
    t = np.asarray(times, float).reshape(-1)
    xy = np.asarray(xy, float)
    tracks = xy[:, None, :] if xy.ndim == 2 else xy
    out: dict[str, float] = {}
    for order, name in ((1, "speed"), (2, "accel"), (3, "jerk")):
        if len(t) <= order:
            out[f"{name}_mean"] = out[f"{name}_max"] = math.nan
            continue
        mags = np.concatenate([derivative_magnitudes(t, tracks[:, n], order) for n in range(tracks.shape[1])])
        out[f"{name}_mean"] = float(mags.mean())
        out[f"{name}_max"] = float(mags.max())
    out["jerk_p95"] = float(np.percentile(mags, 95.0)) if len(t) > 3 else math.nan
    return out


def motion_profile(times: np.ndarray, xy: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """|v|, |a| and |j| of a track over time, for a figure.

    Args:
        times: (T,) strictly increasing seconds.
        xy: (T, D) positions, metres; or (T, N, D) for N tracks (the largest
            of the N at each window: the fastest point).

    Returns:
        ``{"speed": (t, |v|), "accel": (t, |a|), "jerk": (t, |j|)}``, each
        value at the middle of its window of samples (as
        :func:`derivative_magnitudes`); empty arrays when the track is too short.
    """
    t = np.asarray(times, float).reshape(-1)
    xy = np.asarray(xy, float)
    tracks = xy[:, None, :] if xy.ndim == 2 else xy
    out = {}
    for order, name in ((1, "speed"), (2, "accel"), (3, "jerk")):
        if len(t) <= order:
            out[name] = (np.zeros(0), np.zeros(0))
            continue
        mags = np.max([derivative_magnitudes(t, tracks[:, n], order) for n in range(tracks.shape[1])], axis=0)
        out[name] = (0.5 * (t[order:] + t[:-order]), mags)
    return out
