"""The robot's clearance to predicted people over time, and a sound motion check, compiled (numba).

The robot is the planar scene's capsules (base disc, links, object; formats in
:mod:`drake_social.collision.planar_kernel`), a person a body disc whose centre
follows a :class:`~drake_social.people.prediction.Prediction` given as plain
arrays: ``xy`` (H, P, 2) centres at the sample times ``t0 + k dt``,
``present`` (H, P), ``radii`` (P,), ``max_speeds`` (P,).

The rules (those of the prediction and of issue 21's time-indexed safety):

* at time t the sample k is ``floor((t - t0) / dt)`` clamped to [0, H - 1];
  a person's centre is interpolated linearly between samples k and k + 1
  (the first / last sample holds before t0 / after the horizon): the
  prediction's own lookup, :mod:`drake_social.people.prediction_kernel`;
* a person is *considered* at t when present at sample k and, beyond the
  horizon (``t > t0 + (H - 1) dt``), only when standing (``max_speeds == 0``):
  later replans see the moving ones;
* the clearance is the least surface distance of a robot capsule to a
  considered person's disc (+inf with nobody considered); a configuration
  at time t is safe when its clearance is > ``safety``.

:func:`motion_clear_of_people` certifies a motion by conservative advancement
(see there). It calls the planar kernel's compiled functions; the tree kernel
calls it.
"""

from __future__ import annotations

import math

import numpy as np

from drake_social import _kernel_cache

_kernel_cache.ensure_fresh()  # before any cached kernel is loaded

from numba import njit  # noqa: E402  (a dependency)

from drake_social.collision.planar_kernel import (  # noqa: E402
    capsule_spans, queue_pop, queue_split, queue_start, segment_disc_distance, world_capsules)
from drake_social.people.prediction_kernel import centre, slot  # noqa: E402

__all__ = ["MAX_STEPS", "STEP_MARGIN", "TIME_SLACK", "TOLERANCE", "motion_clear_of_people", "people_clearance"]

#: A motion is rejected where a reached configuration's clearance is within
#: this of ``safety``, metres (it keeps the advancement steps from shrinking to zero).
TOLERANCE = 1e-9
#: Each advancement step is shortened by this distance, metres (rounding of
#: the distances, poses and interpolated centres, ~1e-14 m).
STEP_MARGIN = 1e-10
#: A motion needing more clearance queries than this is rejected (conservative).
MAX_STEPS = 100_000
#: Seconds by which the motion's time interval is widened when choosing the
#: samples whose presence counts and the part within the horizon, so that the
#: rounding of ``t_a + u (t_b - t_a)`` never reaches a sample left out.
TIME_SLACK = 1e-9


@njit(cache=True)
def _pair(cap, j, cx, cy, radius):
    """Surface distance of world capsule j to the disc (c, radius)."""
    return segment_disc_distance(cap[j, 0], cap[j, 1], cap[j, 2], cap[j, 3], cx, cy, radius) - cap[j, 4]


@njit(cache=True)
def people_clearance(q, t, bodies, robot, xy, present, radii, max_speeds, t0, dt):
    """The least surface distance (metres) of the robot at q (4,) to the people
    considered at time t (module docstring); +inf when nobody is considered.

    Args:
        q: (4,) configuration; t: seconds.
        bodies, robot: the planar scene's chain and capsules.
        xy: (H, P, 2) predicted centres; present: (H, P) bool; radii,
            max_speeds: (P,); t0, dt: the first sample's time and the step, seconds.
    """
    h = xy.shape[0]
    horizon = t0 + (h - 1) * dt
    beyond = t > horizon
    k, f = slot(t, t0, dt, h)
    cap = world_capsules(q, bodies, robot)
    best = np.inf
    for p in range(xy.shape[1]):
        if not present[k, p] or (beyond and max_speeds[p] != 0.0):
            continue
        cx, cy = centre(xy, p, k, f)
        for j in range(cap.shape[0]):
            best = min(best, _pair(cap, j, cx, cy, radii[p]))
    return best


@njit(cache=True)
def _reach(cap, bx, by):
    """The farthest distance of a point of the capsules ``cap`` from (bx, by)."""
    out = 0.0
    for j in range(cap.shape[0]):
        out = max(out, math.hypot(cap[j, 0] - bx, cap[j, 1] - by) + cap[j, 4],
                  math.hypot(cap[j, 2] - bx, cap[j, 3] - by) + cap[j, 4])
    return out


@njit(cache=True)
def _probe(u, q_a, dq, t_a, span_t, bodies, robot, spans, span, xy, radii, max_speeds, t0, dt, safety,
           keep, n_keep, tau_max):
    """The step tau of one query at u: for ``|u' - u| < tau`` every kept
    person stays more than ``safety`` from every capsule; -1 when a pair is
    within TOLERANCE of ``safety`` at u. Capsule j moves at most ``spans[j]``
    per unit of u, person p at most ``max_speeds[p] * span_t``."""
    q = q_a + u * dq
    cap = world_capsules(q, bodies, robot)
    reach = _reach(cap, q[0], q[1])
    k, f = slot(t_a + u * span_t, t0, dt, xy.shape[0])
    tau = tau_max
    for i in range(n_keep):
        p = keep[i]
        cx, cy = centre(xy, p, k, f)
        move = max_speeds[p] * span_t
        # Person-level broad phase: every capsule lies within `reach` of the base.
        bound = math.hypot(cx - q[0], cy - q[1]) - reach - radii[p] - safety - STEP_MARGIN
        if bound > TOLERANCE and bound >= tau * (span + move):
            continue
        for j in range(cap.shape[0]):
            d = _pair(cap, j, cx, cy, radii[p]) - safety
            if d <= TOLERANCE:
                return -1.0
            rate = spans[j] + move
            if rate > 0.0:
                tau = min(tau, (d - STEP_MARGIN) / rate)
    return tau


@njit(cache=True)
def _part_clear(q_a, dq, u_lo, u_hi, t_a, span_t, bodies, robot, spans, xy, radii, max_speeds, t0, dt, safety,
                keep, n_keep):
    """Whether u in [u_lo, u_hi] is safe against the people ``keep[:n_keep]``
    (each considered over all of it): both ends, then the rest coarse to fine."""
    if n_keep == 0:
        return True
    span = 0.0
    for j in range(spans.shape[0]):
        span = max(span, spans[j])
    # Cull the people who cannot come within safety anywhere: every robot point
    # stays within reach(q_a) + span of q_a's base, person p within
    # max_speeds[p] * span_t of their centre at t_a.
    cap = world_capsules(q_a, bodies, robot)
    reach = _reach(cap, q_a[0], q_a[1]) + span
    k, f = slot(t_a, t0, dt, xy.shape[0])
    n = 0
    for i in range(n_keep):
        p = keep[i]
        cx, cy = centre(xy, p, k, f)
        lb = math.hypot(cx - q_a[0], cy - q_a[1]) - reach - radii[p] - max_speeds[p] * span_t - safety
        if not lb > TOLERANCE:
            keep[n] = p
            n += 1
    if n == 0:
        return True
    tau_lo = _probe(u_lo, q_a, dq, t_a, span_t, bodies, robot, spans, span, xy, radii, max_speeds, t0, dt, safety,
                    keep, n, u_hi - u_lo + 1.0)
    if tau_lo < 0.0:
        return False
    tau_hi = _probe(u_hi, q_a, dq, t_a, span_t, bodies, robot, spans, span, xy, radii, max_speeds, t0, dt, safety,
                    keep, n, u_hi - u_lo + 1.0)
    if tau_hi < 0.0:
        return False
    lo, hi = u_lo + tau_lo, u_hi - tau_hi  # [u_lo, lo) and (hi, u_hi] are cleared
    if lo > hi:
        return True
    # The part not yet cleared, searched coarse to fine (planar_kernel.queue_start: the planar check's queue).
    buffer, ends = queue_start(lo, hi)
    for _ in range(MAX_STEPS):
        if ends[0] == ends[1]:
            return True
        a, b = queue_pop(buffer, ends)
        u = 0.5 * (a + b)
        tau = _probe(u, q_a, dq, t_a, span_t, bodies, robot, spans, span, xy, radii, max_speeds, t0, dt, safety,
                     keep, n, 0.5 * (b - a) + 1e-12)
        if tau < 0.0:
            return False
        buffer = queue_split(buffer, ends, a, b, u, tau)
    return False


@njit(cache=True)
def motion_clear_of_people(q_a, q_b, t_a, t_b, bodies, robot, levers, xy, present, radii, max_speeds, t0, dt,
                           safety):
    """Whether the motion ``q(u) = q_a + u (q_b - q_a)`` at ``t(u) = t_a + u (t_b - t_a)``,
    u in [0, 1], keeps the robot's clearance to the considered people > ``safety``.

    Sound (never True for a motion that comes within ``safety`` of a person
    considered at that time), by conservative advancement. The motion is
    split at the horizon: up to it, every person present at some sample
    overlapping that part counts over all of it; beyond it, the standing
    people present at the last sample. A query at u with pair distances
    ``d_jp`` clears ``|u' - u| < (d_jp - safety) / (D_j + v_p (t_b - t_a))``
    for every pair: capsule j moves at most ``D_j = displacement(q_b - q_a,
    levers[j])`` per unit of u (:func:`planar_kernel.capsule_spans`) and
    person p at most ``v_p = max_speeds[p]`` m/s (the interpolated centres'
    speed; they hold outside the samples). People who cannot come within
    ``safety`` anywhere on the motion (bounding circles) are not measured;
    per query, a person whose bound already allows the step is not either.
    Floors (rejecting is always safe): a pair within :data:`TOLERANCE` of
    ``safety`` rejects, each step is :data:`STEP_MARGIN` metres short, more
    than :data:`MAX_STEPS` queries reject.

    Args:
        q_a, q_b: (4,) the ends; t_a <= t_b: their times, seconds.
        bodies, robot, levers: the planar scene's chain, capsules and levers.
        xy, present, radii, max_speeds, t0, dt: the prediction (:func:`people_clearance`).
        safety: metres.
    """
    h, n_people = present.shape[0], present.shape[1]
    horizon = t0 + (h - 1) * dt
    span_t = t_b - t_a
    dq = q_b - q_a
    spans = capsule_spans(dq, levers)
    keep = np.empty(n_people, dtype=np.int64)
    u_lo = 0.0
    if t_a <= horizon:
        # The part within the horizon (widened a little: moving people hold
        # after it, so counting them slightly beyond is conservative).
        u_h = 1.0
        if t_b > horizon + TIME_SLACK:
            u_h = min(1.0, (horizon + TIME_SLACK - t_a) / span_t)
        k_a, _ = slot(t_a - TIME_SLACK, t0, dt, h)
        k_b, _ = slot(min(t_b, horizon) + TIME_SLACK, t0, dt, h)
        n = 0
        for p in range(n_people):
            for k in range(k_a, k_b + 1):
                if present[k, p]:
                    keep[n] = p
                    n += 1
                    break
        if not _part_clear(q_a, dq, 0.0, u_h, t_a, span_t, bodies, robot, spans, xy, radii, max_speeds, t0, dt,
                           safety, keep, n):
            return False
        if u_h >= 1.0:
            return True
        u_lo = max(0.0, (horizon - t_a) / span_t)
    n = 0
    for p in range(n_people):
        if present[h - 1, p] and max_speeds[p] == 0.0:
            keep[n] = p
            n += 1
    return _part_clear(q_a, dq, u_lo, 1.0, t_a, span_t, bodies, robot, spans, xy, radii, max_speeds, t0, dt, safety,
                       keep, n)
