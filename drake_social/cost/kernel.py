"""The motion social cost Msc as one compiled loop (numba).

:meth:`drake_social.cost.social.SocialCost.motion_cost` batches the same
computation with numpy; in the planner that batch is small (about 25 motions
of about 30 samples each) and numpy's per-operation overhead dominates. This
kernel does the same computation in one pass: for every motion, the step
count from the displacement bound, every (person, point) window from
distance bounds at the motion's ends, and the threshold-aware trapezoid
areas of every (sample step, point) inside it. The exponentials and the
trapezoids of a motion's windows run as two long loops that LLVM vectorises
(:func:`exp_neg` is a polynomial exp within 3 ulp of libm's). ``SocialCost``
uses it when numba is importable and keeps the numpy path as the reference
it is tested against.
"""

from __future__ import annotations

import math

import numpy as np

from drake_social import _kernel_cache
from drake_social.limits import MAX_MOTION_STEPS  # validate_scenario keeps every room's motions within it

_kernel_cache.ensure_fresh()  # before any cached kernel is loaded

try:  # numba is a runtime dependency; the numpy path stays usable without it.
    from numba import njit

    AVAILABLE = True
except ImportError:  # pragma: no cover - exercised only where numba is missing
    AVAILABLE = False

    def njit(*args, **kwargs):
        return lambda f: f


__all__ = ["AVAILABLE", "MAX_MOTION_STEPS", "exp_neg", "msc_sums", "people_grid"]


@njit(cache=True)
def _points(q0, q1, q2, q3, l1, l2, obj, active, xs, ys):
    """Interest points ``active`` of configuration q into xs, ys (as
    ArmGeometry.interest_xy: the gripper angle by angle addition)."""
    c1, s1 = math.cos(q2), math.sin(q2)
    c2, s2 = math.cos(q3), math.sin(q3)
    c12 = c1 * c2 - s1 * s2
    s12 = s1 * c2 + c1 * s2
    ex, ey = q0 + l1 * c1, q1 + l1 * s1
    gx, gy = ex + l2 * c12, ey + l2 * s12
    for j in range(active.shape[0]):
        p = active[j]
        if p == 0:
            xs[j], ys[j] = q0, q1
        elif p == 1:
            xs[j], ys[j] = ex, ey
        elif p == 2:
            xs[j], ys[j] = gx, gy
        else:
            px, py = obj[p - 3, 0], obj[p - 3, 1]
            xs[j] = gx + c12 * px - s12 * py
            ys[j] = gy + s12 * px + c12 * py


@njit(cache=True)
def motion_samples(x, y, psi1, psi2, d0, d1, d2, d3, n, k_lo, k_hi, l1, l2, obj, active, xs, ys):
    """Interest points ``active`` at the samples k = k_lo .. k_hi of the
    motion from [x, y, psi1, psi2] by [d0, d1, d2, d3] in n steps (u = k / n)
    into xs[:, k], ys[:, k]; the arm's angles by rotation steps from the first
    (angle addition, ~1e-15 from cos/sin)."""
    t = k_lo / n
    th1, th12 = psi1 + t * d2, psi1 + psi2 + t * (d2 + d3)
    c1, s1, c12, s12 = math.cos(th1), math.sin(th1), math.cos(th12), math.sin(th12)
    cd1, sd1 = math.cos(d2 / n), math.sin(d2 / n)
    cd12, sd12 = math.cos((d2 + d3) / n), math.sin((d2 + d3) / n)
    for k in range(k_lo, k_hi + 1):
        t = k / n
        x0, y0 = x + t * d0, y + t * d1
        ex, ey = x0 + l1 * c1, y0 + l1 * s1
        gx, gy = ex + l2 * c12, ey + l2 * s12
        for j in range(active.shape[0]):
            p = active[j]
            if p == 0:
                xs[j, k], ys[j, k] = x0, y0
            elif p == 1:
                xs[j, k], ys[j, k] = ex, ey
            elif p == 2:
                xs[j, k], ys[j, k] = gx, gy
            else:
                ox, oy = obj[p - 3, 0], obj[p - 3, 1]
                xs[j, k] = gx + c12 * ox - s12 * oy
                ys[j, k] = gy + s12 * ox + c12 * oy
        c1, s1 = c1 * cd1 - s1 * sd1, s1 * cd1 + c1 * sd1
        c12, s12 = c12 * cd12 - s12 * sd12, s12 * cd12 + c12 * sd12


@njit(cache=True)
def _point_levers(l1, l2, obj, active):
    """(K, 2) per interest point ``(c_shoulder, c_gripper)``: the base centre
    moves with the base only, the elbow also turns about the shoulder (l1),
    the gripper and the object's points also about the elbow (their distance
    from it); see :meth:`ArmGeometry.lever`."""
    out = np.zeros((active.shape[0], 2))
    for j in range(active.shape[0]):
        p = active[j]
        if p == 1:
            out[j, 0] = l1
        elif p == 2:
            out[j, 0], out[j, 1] = l1, l2
        elif p >= 3:
            out[j, 0], out[j, 1] = l1, math.hypot(l2 + obj[p - 3, 0], obj[p - 3, 1])
    return out


@njit(cache=True)
def _exponent(dx, dy, c, s, inv_front, inv_rear, inv_side):
    """a of the AGF value exp(-a) at offset (dx, dy) from a person facing (c, s)."""
    u = c * dx + s * dy
    v = c * dy - s * dx
    return u * u * (inv_front if u > 0 else inv_rear) + v * v * inv_side


@njit(cache=True)
def people_grid(people, cell):
    """Buckets people (H, 3) into square cells of side ``cell`` metres.

    Returns (x0, y0, nx, ny, start, order): person ``order[start[c]:start[c + 1]]``
    stand in cell ``c = iy * nx + ix``, counted from the corner (x0, y0).
    """
    h = people.shape[0]
    if h == 0:
        return 0.0, 0.0, 1, 1, np.zeros(2, dtype=np.int64), np.zeros(0, dtype=np.int64)
    x0, y0 = people[:, 0].min(), people[:, 1].min()
    nx = int((people[:, 0].max() - x0) / cell) + 1
    ny = int((people[:, 1].max() - y0) / cell) + 1
    cells = np.empty(h, dtype=np.int64)
    for i in range(h):
        ix = min(int((people[i, 0] - x0) / cell), nx - 1)
        iy = min(int((people[i, 1] - y0) / cell), ny - 1)
        cells[i] = iy * nx + ix
    order = np.argsort(cells, kind="mergesort")
    start = np.zeros(nx * ny + 1, dtype=np.int64)
    for i in range(h):
        start[cells[i] + 1] += 1
    for c in range(nx * ny):
        start[c + 1] += start[c]
    return x0, y0, nx, ny, start, order


@njit(cache=True)
def _segment_distance(px, py, ax, ay, bx, by):
    dx, dy = bx - ax, by - ay
    dd = dx * dx + dy * dy
    t = 0.0 if dd == 0.0 else min(max(((px - ax) * dx + (py - ay) * dy) / dd, 0.0), 1.0)
    ex, ey = px - (ax + t * dx), py - (ay + t * dy)
    return math.sqrt(ex * ex + ey * ey)  # not hypot: slower, and a culling bound has margin


#: exp_neg flushes exp(-x) to 0 from here on (exp(-64) = 1.6e-28).
EXP_CAP = 64.0
#: exp_neg's binary digits of x and their correctly rounded exp(-digit).
_DIGITS = np.array([32.0, 16.0, 8.0, 4.0, 2.0, 1.0])
_DIGIT_EXP = np.array([math.exp(-d) for d in _DIGITS])
_EXP_HALF = math.exp(-0.5)
#: Taylor coefficients 1 / i! of exp(y), highest first: degree 15 leaves a
#: remainder below 2e-18 for |y| <= 0.5.
_TAYLOR = np.array([1.0 / math.factorial(i) for i in range(15, -1, -1)])
#: The least threshold for exp_neg in msc_sums: its values are exact to 3 ulp
#: or flushed from exp(-64) = 1.6e-28 on, and a flushed value (the low end of
#: a threshold crossing) then moves a step's area by at most 1.6e-28 /
#: threshold < 2e-17 relative. Lower thresholds (0 included) take libm's exp.
VECTOR_EXP_MIN_THRESHOLD = 1e-11
#: LLVM flags of the vector loops: FMA contraction, and reassociation for the
#: trapezoids' sum (a vectorised reduction: its order follows the vector width).
_VEC = {"contract", "reassoc"}


@njit(fastmath=_VEC, error_model="numpy", cache=True)
def exp_neg(x, count):
    """``x[:count] = exp(-x[:count])`` in place, for ``x >= 0``, within 3 ulp
    of ``math.exp`` (tested) below :data:`EXP_CAP`, and 0 from there on (a
    flush to zero: no AGF term that small can matter, and none is overstated).

    Written so that LLVM vectorises it (libm's exp is a call, which a vector
    loop cannot hold; the inner loops have constant trip counts and unroll):
    x's binary digits 32 .. 1 are taken out by exact subtractions, each
    multiplying in its correctly rounded exp(-digit), and the rest r in
    [0, 1) is exp(-0.5) exp(0.5 - r) by a Taylor polynomial.
    """
    for t in range(count):
        a = x[t]
        r = min(a, EXP_CAP)
        m = _EXP_HALF
        for d in range(_DIGITS.shape[0]):
            take = r >= _DIGITS[d]
            m = m * _DIGIT_EXP[d] if take else m
            r = r - _DIGITS[d] if take else r
        y = 0.5 - r
        p = _TAYLOR[0]
        for i in range(1, _TAYLOR.shape[0]):
            p = p * y + _TAYLOR[i]
        x[t] = m * p if a < EXP_CAP else 0.0


@njit(fastmath=_VEC, error_model="numpy", cache=True)
def _trapezoids(g, w, count, tau):
    """sum_k w[k] * (the threshold-aware trapezoid area of samples g[k], g[k + 1])."""
    acc = 0.0
    for k in range(count):
        g0 = g[k]
        g1 = g[k + 1]
        hi = g0 if g0 > g1 else g1
        lo = g1 if g0 > g1 else g0
        both = 0.5 * (g0 + g1)
        cross = 0.5 * (hi + tau) * (hi - tau) / (hi - lo)  # one end above the threshold: hi > lo
        area = cross if hi > tau else 0.0
        area = both if lo > tau else area
        acc += w[k] * area
    return acc


@njit(cache=True)
def _step_counts(q_a, q_b, lever, resolution):
    """Per motion (E,) int64: the trapezoid step count n, the displacement
    bound (``lever``: (c_shoulder, c_gripper)) over ``resolution``, at least 1;
    and the largest of them. Raises ValueError beyond MAX_MOTION_STEPS
    (SocialCost names the motion; the scenario check keeps planners clear)."""
    steps = np.ones(q_a.shape[0], dtype=np.int64)
    n_max = 1
    max_span = MAX_MOTION_STEPS * resolution
    for e in range(q_a.shape[0]):
        d0, d1 = q_b[e, 0] - q_a[e, 0], q_b[e, 1] - q_a[e, 1]
        d2, d3 = q_b[e, 2] - q_a[e, 2], q_b[e, 3] - q_a[e, 3]
        span = math.hypot(d0, d1) + lever[0] * abs(d2) + lever[1] * abs(d2 + d3)
        if not span <= max_span:
            raise ValueError("a motion's displacement bound is not finite or needs more than MAX_MOTION_STEPS steps")
        steps[e] = max(1, int(math.ceil(span / resolution - 1e-9)))
        n_max = max(n_max, steps[e])
    return steps, n_max


@njit(cache=True)
def _point_spans(d0, d1, d2, d3, point_levers, spans):
    """spans[j] = how far interest point j moves at most per unit of t along
    the motion (d0, d1, d2, d3) (:func:`_point_levers`' lever arms)."""
    dxy, a1, a12 = math.sqrt(d0 * d0 + d1 * d1), abs(d2), abs(d2 + d3)
    for j in range(spans.shape[0]):
        spans[j] = dxy + point_levers[j, 0] * a1 + point_levers[j, 1] * a12


@njit(cache=True)
def _window_steps(t0, t1, n):
    """The samples k0 < k1 of a motion of n steps that bracket the part [t0,
    t1] of it (fractions, clamped to [0, 1]): at least one step, never past
    the motion's end (t0 = 1: the last step)."""
    t0 = min(max(t0, 0.0), 1.0)
    t1 = min(max(t1, 0.0), 1.0)
    k0 = int(math.floor(t0 * n))
    k1 = min(int(math.ceil(t1 * n)), n)
    k1 = min(max(k1, k0 + 1), n)
    k0 = min(k0, k1 - 1)
    return k0, k1


@njit(cache=True)
def _run_area(g, w, count, tau, vector_exp):
    """The weighted threshold-aware trapezoid areas of a flat run of
    ``count`` exponents ``g`` (exp(-g) taken in place first: :func:`exp_neg`,
    or libm's where ``vector_exp`` is False) with step weights ``w``."""
    if vector_exp:
        exp_neg(g, count)
    else:
        for t in range(count):
            g[t] = math.exp(-g[t])
    return _trapezoids(g, w, count - 1, tau)


@njit(cache=True)
def msc_sums(
    q_a, q_b, people, l1, l2, obj, active, weights, lever, resolution, reaches, inv_front, inv_rear, inv_side, tau,
    point_reach, grid_cell, grid_x0, grid_y0, grid_nx, grid_ny, grid_start, grid_order,
):
    """Per motion (E,): the sum over steps of the weighted trapezoid areas
    (multiply by h = length / n for Msc) and the step count n.

    Args mirror SocialCost: people (H, 3); obj (P, 2) object interest points
    in the gripper frame; active (K,) interest-point indices with weights (K,);
    lever (c_shoulder, c_gripper); reaches (H,): each person's AGF's largest
    reach (inf for no culling); inv_front, inv_rear, inv_side (H,): each
    person's 1 / (2 sigma^2) (per person: Kirby's speed scaling gives walkers
    wider Gaussians; equal values for a static scenario); point_reach: the
    largest distance of a weighted point from the base centre; grid_*:
    :func:`people_grid` with cell side grid_cell.

    People are culled in two exact steps before any sample is taken: the
    grid gives those standing within ``reach + point_reach`` (reach: the
    largest of ``reaches``) of the base's
    segment's bounding box, and a person farther than that from the segment
    itself has every term <= threshold (every weighted point stays within
    point_reach of the base), so it adds exactly nothing. The interest
    points of a motion's samples are computed once and shared by its people.
    Each (person, point) is then sampled only inside its window: outside it
    the point is farther than reach from the person (a Euclidean bound), or
    the exponent's square root, a norm of the offset with Lipschitz constant
    ``lip``, is above the threshold's (a bound in the AGF's own metric,
    tighter beside and behind a person), so both ends of every step there
    are below the threshold and it adds exactly 0.

    The sums equal the numpy path's to about 1e-13 relative, not bit for bit
    (more where a term grazes the threshold: a crossing's interpolation is
    ill-conditioned there, up to 2e-10 on adversarial motions, as with
    libm's exp): the arm's angles along a motion come from rotation steps,
    exp is :func:`exp_neg` (libm's for thresholds below
    :data:`VECTOR_EXP_MIN_THRESHOLD`, where its flush to zero could matter),
    and the steps are summed in the order of a vectorised reduction. The
    order depends on the processor's vector width, so two processors may
    differ in the last bits (so do numpy's own SIMD loops); on one machine
    the sums are deterministic.
    """
    e_count, h_count, k_count = q_a.shape[0], people.shape[0], active.shape[0]
    sums = np.zeros(e_count)
    cos_t = np.empty(h_count)  # of the candidates only (far people cost nothing)
    sin_t = np.empty(h_count)
    have = np.zeros(h_count, dtype=np.bool_)
    xa, ya = np.empty(k_count), np.empty(k_count)
    xb, yb = np.empty(k_count), np.empty(k_count)
    spans = np.empty(k_count)
    point_levers = _point_levers(l1, l2, obj, active)
    # exp(-a) <= tau with margin beyond this exponent (tau > 0; 1e-9 relative
    # is far more than exp's and log's rounding).
    a_cut = -math.log(tau) * (1.0 + 1e-9) + 1e-12 if tau > 0.0 else math.inf
    root_cut = math.sqrt(a_cut) * (1.0 + 1e-9) + 1e-12 if math.isfinite(a_cut) else math.inf
    reach = 0.0  # the largest reach: the grid's culling radius
    for h in range(h_count):
        reach = max(reach, reaches[h])
    vector_exp = tau >= VECTOR_EXP_MIN_THRESHOLD
    cand = np.empty(h_count, dtype=np.int64)
    k0s = np.empty((h_count, k_count), dtype=np.int64)
    k1s = np.empty((h_count, k_count), dtype=np.int64)
    cull = math.isfinite(reach)
    radius = reach + point_reach + 1e-9
    steps, n_max = _step_counts(q_a, q_b, lever, resolution)
    xs = np.empty((k_count, n_max + 1))
    ys = np.empty((k_count, n_max + 1))
    g_buf = np.empty(256)  # exponents, then AGF values, of the flat run
    w_buf = np.empty(256)  # the weight of the step from each sample to the next (0: none)
    for e in range(e_count):
        d0, d1 = q_b[e, 0] - q_a[e, 0], q_b[e, 1] - q_a[e, 1]
        d2, d3 = q_b[e, 2] - q_a[e, 2], q_b[e, 3] - q_a[e, 3]
        n = steps[e]
        if d0 == 0.0 and d1 == 0.0 and d2 == 0.0 and d3 == 0.0:
            continue
        # Candidate people, in ascending order.
        m = 0
        if cull:
            ax, ay, bx, by = q_a[e, 0], q_a[e, 1], q_b[e, 0], q_b[e, 1]
            ix0 = max(int(math.floor((min(ax, bx) - radius - grid_x0) / grid_cell)), 0)
            ix1 = min(int(math.floor((max(ax, bx) + radius - grid_x0) / grid_cell)), grid_nx - 1)
            iy0 = max(int(math.floor((min(ay, by) - radius - grid_y0) / grid_cell)), 0)
            iy1 = min(int(math.floor((max(ay, by) + radius - grid_y0) / grid_cell)), grid_ny - 1)
            for iy in range(iy0, iy1 + 1):
                for ix in range(ix0, ix1 + 1):
                    c = iy * grid_nx + ix
                    for r in range(grid_start[c], grid_start[c + 1]):
                        h = grid_order[r]
                        if _segment_distance(people[h, 0], people[h, 1], ax, ay, bx, by) <= radius:
                            cand[m] = h
                            m += 1
            for i in range(1, m):  # insertion sort: few candidates
                v, j = cand[i], i - 1
                while j >= 0 and cand[j] > v:
                    cand[j + 1] = cand[j]
                    j -= 1
                cand[j + 1] = v
        else:
            for h in range(h_count):
                cand[m] = h
                m += 1
        if m == 0:
            continue
        for i in range(m):
            h = cand[i]
            if not have[h]:
                cos_t[h], sin_t[h], have[h] = math.cos(people[h, 2]), math.sin(people[h, 2]), True
        _points(q_a[e, 0], q_a[e, 1], q_a[e, 2], q_a[e, 3], l1, l2, obj, active, xa, ya)
        _points(q_b[e, 0], q_b[e, 1], q_b[e, 2], q_b[e, 3], l1, l2, obj, active, xb, yb)
        _point_spans(d0, d1, d2, d3, point_levers, spans)  # each point moves at most spans[j] per unit of t
        # The window of samples where each (candidate, point) can matter:
        # outside it the point is farther than reach from the person, so the
        # term is <= threshold at both ends of every step and adds nothing.
        k_lo, k_hi = n + 1, -1
        for i in range(m):
            h = cand[i]
            px, py, c_t, s_t = people[h, 0], people[h, 1], cos_t[h], sin_t[h]
            inv_f, inv_r, inv_s, reach_h = inv_front[h], inv_rear[h], inv_side[h], reaches[h]
            # sqrt of the exponent is a norm of the offset, Lipschitz with constant lip.
            lip = math.sqrt(max(inv_f, inv_r, inv_s))
            bounded = math.isfinite(root_cut) and lip > 0.0
            for j in range(k_count):
                ax_, ay_, bx_, by_ = xa[j] - px, ya[j] - py, xb[j] - px, yb[j] - py
                da = math.sqrt(ax_ * ax_ + ay_ * ay_) - reach_h - 1e-9
                db = math.sqrt(bx_ * bx_ + by_ * by_) - reach_h - 1e-9
                if spans[j] > 0.0:
                    if da + db > spans[j]:
                        k0s[i, j], k1s[i, j] = 0, -1
                        continue
                    t0 = da / spans[j]
                    t1 = 1.0 - db / spans[j]
                    ls = lip * spans[j]  # 0 for a span so small that it underflows
                    if bounded and ls > 0.0:
                        # sqrt(a) moves at most lip * spans[j] along the motion
                        # (per unit of t): above root_cut outside [t0, t1].
                        ra = math.sqrt(_exponent(ax_, ay_, c_t, s_t, inv_f, inv_r, inv_s)) - root_cut
                        rb = math.sqrt(_exponent(bx_, by_, c_t, s_t, inv_f, inv_r, inv_s)) - root_cut
                        if ra + rb > ls:
                            k0s[i, j], k1s[i, j] = 0, -1
                            continue
                        t0, t1 = max(t0, ra / ls), min(t1, 1.0 - rb / ls)
                elif da <= 0.0:  # a point that does not move, within reach (or no culling)
                    t0, t1 = 0.0, 1.0
                else:
                    k0s[i, j], k1s[i, j] = 0, -1
                    continue
                k0, k1 = _window_steps(t0, t1, n)
                k0s[i, j], k1s[i, j] = k0, k1
                k_lo, k_hi = min(k_lo, k0), max(k_hi, k1)
        if k_hi < 0:
            continue
        # The samples k_lo..k_hi, once for all people.
        motion_samples(q_a[e, 0], q_a[e, 1], q_a[e, 2], q_a[e, 3], d0, d1, d2, d3, n, k_lo, k_hi, l1, l2, obj,
                       active, xs, ys)
        # The samples of every (candidate, point) window in one run: their
        # exponents, then exp and the trapezoids in two long vector loops.
        count = 0
        for i in range(m):
            for j in range(k_count):
                if k1s[i, j] >= k0s[i, j]:
                    count += k1s[i, j] - k0s[i, j] + 1
        if count > g_buf.shape[0]:
            g_buf = np.empty(2 * count)
            w_buf = np.empty(2 * count)
        t = 0
        for i in range(m):
            h = cand[i]
            px, py, c, s = people[h, 0], people[h, 1], cos_t[h], sin_t[h]
            inv_f, inv_r, inv_s = inv_front[h], inv_rear[h], inv_side[h]
            for j in range(k_count):
                k0, k1 = k0s[i, j], k1s[i, j]
                w = weights[j]
                for k in range(k0, k1 + 1):
                    g_buf[t] = _exponent(xs[j, k] - px, ys[j, k] - py, c, s, inv_f, inv_r, inv_s)
                    w_buf[t] = w
                    t += 1
                if k1 >= k0:
                    w_buf[t - 1] = 0.0  # no step from a window's last sample to the next window's first
        sums[e] = _run_area(g_buf, w_buf, count, tau, vector_exp)
    return sums, steps
