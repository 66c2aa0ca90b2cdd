"""The time-indexed motion social cost as one compiled loop (numba).

The replanner costs a motion against the people *predicted* at the time the
robot would be there: along a motion ``q(u) = q_a + u (q_b - q_a)`` the robot
is at ``t(u) = t_a + u (t_b - t_a)``, and each trapezoid sample k (u = k / n,
the step count n of :func:`drake_social.cost.kernel.msc_sums`) is evaluated
against the people of a :class:`~drake_social.people.prediction.Prediction`
at t(u): positions interpolated linearly between its samples, heading and
presence those of the sample at or before t(u) (clamped to the first and the
last sample: before ``t0`` and beyond the horizon the people hold; the
prediction's own lookup, :mod:`drake_social.people.prediction_kernel`). An absent
person adds nothing at that sample (their raw Gaussian counts as 0 there, so
a step from an absent to a present sample is a threshold crossing). A
static prediction gives :func:`msc_sums`'s sums to rounding (about 1e-14
relative), not bit for bit: the static kernel skips more samples that add
exactly nothing (its people grid, and a window bound in the AGF's own
metric), and a motion's vectorised sum is ordered by the samples in its run.
So the two kernels stay two, and share their stages: the step counts, the
points' spans, the windows' steps and the run's areas
(:mod:`drake_social.cost.kernel`).

:meth:`drake_social.cost.social.SocialCost.timed_motion_cost` calls this
kernel and keeps an independent numpy path as its reference; the tree's
compiled loop calls it directly with the arguments of
:meth:`~drake_social.cost.social.SocialCost.timed_kernel_args`.
"""

from __future__ import annotations

import math

import numpy as np

from drake_social.cost import kernel
from drake_social.people.prediction_kernel import centre, slot

njit = kernel.njit
AVAILABLE = kernel.AVAILABLE

__all__ = ["AVAILABLE", "msc_sums_timed"]


@njit(cache=True)
def msc_sums_timed(
    q_a, q_b, t_a, t_b, xy, theta, present, t0, dt, max_speeds, l1, l2, obj, active, weights, lever, resolution,
    reaches, inv_front, inv_rear, inv_side, tau, point_reach,
):
    """Per motion (E,): the sum over steps of the weighted trapezoid areas
    against the predicted people (multiply by h = length / n for Msc) and the
    step count n (that of :func:`~drake_social.cost.kernel.msc_sums`).

    Args:
        q_a, q_b: (E, 4) motion ends.
        t_a, t_b: (E,) the times at the ends, seconds (t_b >= t_a).
        xy: (S, P) x 2 predicted positions at the times t0 + k dt, metres.
        theta: (S, P) headings, radians; present: (S, P) bool.
        t0, dt: the first sample's time and the step between samples, seconds.
        max_speeds: (P,) a bound on each person's speed along the
            interpolated prediction, m/s (:attr:`Prediction.max_speeds`; the
            culling is exact only when it holds).
        l1, l2, obj, active, weights, lever, resolution, tau, point_reach:
            as :func:`msc_sums` (the arm, the weighted interest points, the
            step length, the threshold, the weighted points' largest distance
            from the base centre).
        reaches, inv_front, inv_rear, inv_side: (P,) each person's AGF reach
            and ``1 / (2 sigma^2)`` (:meth:`SocialCost.person_parameters`).

    People are culled exactly before any sample is taken: over [t_a, t_b] a
    person stays within ``max_speeds * (t_b - t_a)`` of where they are at
    t_a, and every weighted point within point_reach of the base, so a person
    farther than ``reach + point_reach + that`` from the base's segment has
    every term <= threshold and adds nothing; so does a person absent at every
    sample of the prediction the motion's times fall in. For each remaining
    (person, point) the samples are taken only inside a window: the distance
    between the point and the person changes by at most ``span + max_speed
    (t_b - t_a)`` per unit of u, so outside it both are farther apart than the
    reach at both ends of every step there (which adds exactly 0). The robot's
    samples are computed once per motion, the people's once per (person,
    sample) and shared by the points, their headings' cos and sin once per
    (prediction sample, person) of a call.

    The sums equal the numpy reference's
    (:meth:`SocialCost.timed_motion_cost` with ``backend = "numpy"``) to about
    1e-13 relative, for the reasons :func:`msc_sums` gives (the exp, the arm's
    angles by rotation steps, the order of the sum). The sample times are
    computed as the reference does (no contraction), so the prediction sample
    a time falls in is the same.
    """
    e_count, k_count = q_a.shape[0], active.shape[0]
    s_count, p_count = xy.shape[0], xy.shape[1]
    sums = np.zeros(e_count)
    cos_t = np.empty((s_count, p_count))  # per (sample, person), computed when first needed
    sin_t = np.empty((s_count, p_count))
    have = np.zeros((s_count, p_count), dtype=np.bool_)
    xa, ya = np.empty(k_count), np.empty(k_count)
    xb, yb = np.empty(k_count), np.empty(k_count)
    spans = np.empty(k_count)
    point_levers = kernel._point_levers(l1, l2, obj, active)
    vector_exp = tau >= kernel.VECTOR_EXP_MIN_THRESHOLD
    cand = np.empty(p_count, dtype=np.int64)
    k0s = np.empty((p_count, k_count), dtype=np.int64)
    k1s = np.empty((p_count, k_count), dtype=np.int64)
    pa = np.empty((p_count, 2))  # each person at t_a and t_b
    pb = np.empty((p_count, 2))
    steps, n_max = kernel._step_counts(q_a, q_b, lever, resolution)  # SocialCost.timed_motion_cost names a bad motion
    xs = np.empty((k_count, n_max + 1))
    ys = np.empty((k_count, n_max + 1))
    slots = np.empty(n_max + 1, dtype=np.int64)  # each sample's prediction sample and fraction
    fracs = np.empty(n_max + 1)
    px = np.empty((p_count, n_max + 1))  # each candidate at each sample of its windows
    py = np.empty((p_count, n_max + 1))
    pc = np.empty((p_count, n_max + 1))  # cos, sin of the heading
    ps = np.empty((p_count, n_max + 1))
    pin = np.empty((p_count, n_max + 1), dtype=np.bool_)  # present
    g_buf = np.empty(256)  # exponents, then AGF values, of the flat run
    w_buf = np.empty(256)  # the weight of the step from each sample to the next (0: none)
    for e in range(e_count):
        d0, d1 = q_b[e, 0] - q_a[e, 0], q_b[e, 1] - q_a[e, 1]
        d2, d3 = q_b[e, 2] - q_a[e, 2], q_b[e, 3] - q_a[e, 3]
        n = steps[e]
        if (d0 == 0.0 and d1 == 0.0 and d2 == 0.0 and d3 == 0.0) or p_count == 0:
            continue
        # The samples' times are ta + u dtime (the last, ta + dtime, may
        # differ from t_b in the last bit: its slot is the one that counts).
        ta, dtime = t_a[e], t_b[e] - t_a[e]
        duration = abs(dtime)
        slot_a, frac_a = slot(ta, t0, dt, s_count)
        slot_b, frac_b = slot(ta + dtime, t0, dt, s_count)
        lo_slot, hi_slot = min(slot_a, slot_b), max(slot_a, slot_b)
        # Candidate people, in ascending order.
        ax, ay, bx, by = q_a[e, 0], q_a[e, 1], q_b[e, 0], q_b[e, 1]
        m = 0
        for h in range(p_count):
            seen = False
            for s in range(lo_slot, hi_slot + 1):
                if present[s, h]:
                    seen = True
                    break
            if not seen:
                continue
            pa[h, 0], pa[h, 1] = centre(xy, h, slot_a, frac_a)
            if math.isfinite(reaches[h]):
                radius = reaches[h] + point_reach + max_speeds[h] * duration + 1e-9
                if kernel._segment_distance(pa[h, 0], pa[h, 1], ax, ay, bx, by) > radius:
                    continue
            pb[h, 0], pb[h, 1] = centre(xy, h, slot_b, frac_b)
            cand[m] = h
            m += 1
        if m == 0:
            continue
        kernel._points(q_a[e, 0], q_a[e, 1], q_a[e, 2], q_a[e, 3], l1, l2, obj, active, xa, ya)
        kernel._points(q_b[e, 0], q_b[e, 1], q_b[e, 2], q_b[e, 3], l1, l2, obj, active, xb, yb)
        kernel._point_spans(d0, d1, d2, d3, point_levers, spans)
        # The window of samples where each (candidate, point) can matter: the
        # point-person distance moves by at most rate per unit of u, so
        # outside it both are farther apart than the reach.
        k_lo, k_hi = n + 1, -1
        for i in range(m):
            h = cand[i]
            reach_h, move = reaches[h], max_speeds[h] * duration
            bounded = math.isfinite(reach_h)
            for j in range(k_count):
                if not bounded:
                    w0, w1 = 0.0, 1.0
                else:
                    ex_, ey_ = xa[j] - pa[h, 0], ya[j] - pa[h, 1]
                    fx_, fy_ = xb[j] - pb[h, 0], yb[j] - pb[h, 1]
                    da = math.sqrt(ex_ * ex_ + ey_ * ey_) - reach_h - 1e-9
                    db = math.sqrt(fx_ * fx_ + fy_ * fy_) - reach_h - 1e-9
                    rate = spans[j] + move
                    if rate > 0.0:
                        if da + db > rate:
                            k0s[i, j], k1s[i, j] = 0, -1
                            continue
                        w0, w1 = da / rate, 1.0 - db / rate
                    elif da <= 0.0:  # neither moves, within reach
                        w0, w1 = 0.0, 1.0
                    else:
                        k0s[i, j], k1s[i, j] = 0, -1
                        continue
                k0, k1 = kernel._window_steps(w0, w1, n)
                k0s[i, j], k1s[i, j] = k0, k1
                k_lo, k_hi = min(k_lo, k0), max(k_hi, k1)
        if k_hi < 0:
            continue
        # The robot's samples k_lo..k_hi, as msc_sums takes them, and their times.
        kernel.motion_samples(q_a[e, 0], q_a[e, 1], q_a[e, 2], q_a[e, 3], d0, d1, d2, d3, n, k_lo, k_hi, l1, l2,
                              obj, active, xs, ys)
        for k in range(k_lo, k_hi + 1):
            slots[k], fracs[k] = slot(ta + (k / n) * dtime, t0, dt, s_count)
        # Each candidate at the samples of its windows.
        count = 0
        for i in range(m):
            h = cand[i]
            lo, hi = n + 1, -1
            for j in range(k_count):
                if k1s[i, j] >= k0s[i, j]:
                    count += k1s[i, j] - k0s[i, j] + 1
                    lo, hi = min(lo, k0s[i, j]), max(hi, k1s[i, j])
            for k in range(lo, hi + 1):
                s = slots[k]
                pin[i, k] = present[s, h]
                if not pin[i, k]:
                    continue
                px[i, k], py[i, k] = centre(xy, h, s, fracs[k])
                if not have[s, h]:
                    cos_t[s, h], sin_t[s, h], have[s, h] = math.cos(theta[s, h]), math.sin(theta[s, h]), True
                pc[i, k], ps[i, k] = cos_t[s, h], sin_t[s, h]
        # The samples of every (candidate, point) window in one run: their
        # exponents (inf where the person is absent), then exp and the
        # trapezoids in two long vector loops.
        if count > g_buf.shape[0]:
            g_buf = np.empty(2 * count)
            w_buf = np.empty(2 * count)
        t = 0
        for i in range(m):
            h = cand[i]
            inv_f, inv_r, inv_s = inv_front[h], inv_rear[h], inv_side[h]
            for j in range(k_count):
                k0, k1 = k0s[i, j], k1s[i, j]
                w = weights[j]
                for k in range(k0, k1 + 1):
                    if pin[i, k]:
                        g_buf[t] = kernel._exponent(xs[j, k] - px[i, k], ys[j, k] - py[i, k], pc[i, k], ps[i, k],
                                                    inv_f, inv_r, inv_s)
                    else:
                        g_buf[t] = math.inf
                    w_buf[t] = w
                    t += 1
                if k1 >= k0:
                    w_buf[t - 1] = 0.0  # no step from a window's last sample to the next window's first
        sums[e] = kernel._run_area(g_buf, w_buf, count, tau, vector_exp)
    return sums, steps
