"""Path optimisation after planning: shortcuts and a local descent on the waypoints.

RRT* after K samples returns a path that is still far from the optimum of
its objective (its waypoints are tree nodes). :func:`optimize_path`
improves it locally, in rounds of

1. **shortcut**: from each waypoint, the farthest later waypoint that a
   single straight motion reaches more cheaply (and collision-free) replaces
   the waypoints between them;
2. **subdivide**: a motion longer than ``max_segment`` is split into equal
   parts, kept only if the parts cost no more than the motion (the trapezoid
   rule on the parts samples other points);
3. **descent**: every interior waypoint moves downhill along a central
   finite-difference gradient of the cost of its two motions, with a
   backtracking step, kept only if that cost falls, the waypoint stays in
   the space and valid, and both its motions are collision-free. The
   odd-numbered waypoints move together, then the even-numbered ones
   (red-black ordering: waypoints of one parity share no motion).

After the rounds, **merge**: every interior waypoint that lies on the straight
segment of its neighbours (within
:data:`~drake_social.planning.collinear.COLLINEAR_TOLERANCE`: mostly the
equal parts of a subdivision that the descent left where they were) goes, since
execution comes to rest at every waypoint; each merged motion is checked with
the validity checker (:func:`~drake_social.planning.collinear.merge_collinear`)
and costed with the objective like any other. The trapezoid rule samples a
merged motion at other points than its parts, so the path's cost moves by that
rule's discretisation, both sums estimating the same integral (on office_bar,
seed 0, with the pure social integral: 3.9715648 with the parts, 3.9715871
merged). An optimised path has no
interior waypoint collinear with its neighbours unless the checker refuses the
merged motion.

Every accepted change is checked with the validity checker, so the result
keeps every motion valid, and it never costs more than the input (the input
comes back unless the result is cheaper by the margin below). No randomness:
the same path in gives the same path out.

**The same path on every processor.** The compiled cost kernel sums in the
order of a vectorised reduction, whose width depends on the processor, and
libm's and numpy's exp differ in the last bit between builds, so two machines
compute the same motion's cost to about 1e-13 relative (up to 2e-10 where a
term grazes the threshold, :func:`drake_social.cost.kernel.msc_sums`), not
bit for bit. A decision taken on such a difference flips between machines,
and a flipped decision sends the rest of the optimisation elsewhere (on
office_bar, seed 0: 67, 89 or 91 waypoints, cost 4.31, 3.961 or 3.972 from
the same raw path). Ties are common: a motion and its parts sample the same
points, collinear waypoints cost their direct motion's sum, a finite
difference across a flat cost is rounding alone. So every comparison of
costs has a margin (:func:`cheaper`, :func:`no_dearer`): a change counts as
cheaper only when it saves more than :data:`COST_MARGIN_RELATIVE` of the cost
(plus :data:`COST_MARGIN_ABSOLUTE`), 50 times the largest difference
between processors; a subdivision (which never needs to lower the cost) is
kept when its parts cost no more than the motion within the margin; and a
finite difference within the margin of the waypoint's cost is taken as 0.
Real gains smaller than the margin are given up (the rounds stop at a gain
of 1e-4 anyway). ``tests/planning/test_optimize_margin.py`` perturbs every
motion cost by a few ulp, as another processor would, and gets the same path.

The work is batched: each stage makes a few calls of the objective's
``motion_cost`` and the checker's ``are_valid`` / ``are_motions_valid`` over
many motions at once (one per half-sweep of the descent, one per kept
waypoint of the shortcut), so the compiled kernels behind them (the social
cost's and the planar checker's) run long batches instead of one motion per
Python call.
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np

from drake_social.planning.collinear import merge_collinear
from drake_social.planning.objective import Objective
from drake_social.planning.space import ConfigurationSpace
from drake_social.collision.validity import ValidityChecker

__all__ = ["COST_MARGIN_ABSOLUTE", "COST_MARGIN_RELATIVE", "OptimizeOptions", "cheaper", "no_dearer",
           "optimize_path", "path_cost"]

#: A change is cheaper only when it saves more than this share of the cost
#: it replaces (module docstring): 50 times the largest difference of a
#: motion's cost between processors (2e-10), and far above a sum's rounding
#: (1e-16 a term).
COST_MARGIN_RELATIVE = 1e-8
#: ... plus this much (cost units): costs near 0 compare as equal below it.
COST_MARGIN_ABSOLUTE = 1e-12


def _margin(old):
    return COST_MARGIN_RELATIVE * np.abs(old) + COST_MARGIN_ABSOLUTE


def cheaper(new, old):
    """Whether cost ``new`` is cheaper than ``old`` by more than the margin
    (:data:`COST_MARGIN_RELATIVE` of ``old`` plus :data:`COST_MARGIN_ABSOLUTE`),
    elementwise: a decision that rounding differences between processors do
    not flip."""
    return np.asarray(new) < np.asarray(old) - _margin(old)


def no_dearer(new, old):
    """Whether cost ``new`` is no dearer than ``old`` within the margin of
    :func:`cheaper` (``new <= old + margin``), elementwise."""
    return np.asarray(new) <= np.asarray(old) + _margin(old)


@dc.dataclass
class OptimizeOptions:
    """Options of :func:`optimize_path` (configuration-space units).

    Attributes:
        rounds: shortcut / subdivide / descent rounds (stops early when a
            round improves the cost by no more than ``tolerance``, relative).
        descent_steps: descent sweeps over the waypoints per round (8: on the
            shipped scenarios, 5 seeds each, the mean cost is then below
            that of 4 sweeps at about 1.2x their time).
        max_segment: subdivision length of a motion.
        step: the descent's first step, times the gradient's unit direction.
        epsilon: finite-difference step of the gradient.
        tolerance: relative improvement below which the rounds stop.
    """

    rounds: int = 4
    descent_steps: int = 8
    max_segment: float = 0.5
    step: float = 0.3
    epsilon: float = 1e-3
    tolerance: float = 1e-4


def path_cost(objective: Objective, waypoints: np.ndarray) -> float:
    """The objective along a path: the sum of its motion costs."""
    wp = np.asarray(waypoints, float)
    return float(objective.motion_cost(wp[:-1], wp[1:]).sum()) if len(wp) > 1 else 0.0


def _motion_costs(objective: Objective, wp: np.ndarray) -> np.ndarray:
    """(N - 1,) costs of a path's motions (empty for fewer than two waypoints)."""
    return objective.motion_cost(wp[:-1], wp[1:]) if len(wp) > 1 else np.zeros(0)


#: Shortcut candidates checked per batched call of ``are_motions_valid``.
_CHECK_CHUNK = 8


def _shortcut(wp: np.ndarray, objective: Objective, checker: ValidityChecker,
              seg: np.ndarray | None = None) -> np.ndarray:
    """Greedy shortcut: from each kept waypoint u, the farthest later waypoint
    v whose direct motion is valid and costs less than the path from u to v
    replaces the waypoints between them; the walk goes on from v. Only
    waypoints after u are compared, and those are still the input's, so the
    costs of the input's motions (``seg``) serve every step. The costs of the
    motions from u go in one batched call; the cheaper ones are checked
    farthest first, :data:`_CHECK_CHUNK` per batched call, so that a slow
    checker (Drake's) checks few motions past the first valid one. Cheaper
    means by the margin of :func:`cheaper` (a direct motion over collinear
    waypoints costs their sum up to rounding: they stay)."""
    n = len(wp)
    if n < 3:
        return wp
    seg = _motion_costs(objective, wp) if seg is None else seg
    keep, u = [0], 0
    while u < n - 2:
        later = np.arange(n - 1, u + 1, -1)  # farthest first
        direct = objective.motion_cost(np.repeat(wp[u : u + 1], len(later), axis=0), wp[later])
        shorter = later[cheaper(direct, np.cumsum(seg[u:])[later - u - 1])]
        nxt = u + 1
        for at in range(0, len(shorter), _CHECK_CHUNK):
            chunk = shorter[at : at + _CHECK_CHUNK]
            ok = checker.are_motions_valid(np.repeat(wp[u : u + 1], len(chunk), axis=0), wp[chunk])
            if ok.any():
                nxt = int(chunk[np.argmax(ok)])
                break
        keep.append(nxt)
        u = nxt
    keep.extend(range(u + 1, n))
    return wp[keep]


def _subdivide(wp: np.ndarray, objective: Objective, checker: ValidityChecker, space, max_segment: float,
               seg: np.ndarray | None = None) -> np.ndarray:
    """Splits every motion longer than ``max_segment`` into equal parts where
    the parts cost no more than the motion (within the margin of
    :func:`no_dearer`: parts that sample the motion's own points cost the
    same up to rounding) and are all valid; the costs of every part, then the
    checks of every candidate split, go in one call each."""
    if len(wp) < 2:
        return wp
    seg = _motion_costs(objective, wp) if seg is None else seg
    parts = np.ceil(space.distance(wp[:-1], wp[1:]) / max_segment).astype(int)
    long = np.flatnonzero(parts > 1)
    if len(long) == 0:
        return wp
    pieces = []
    for m in long:
        t = np.linspace(0.0, 1.0, parts[m] + 1)[:, None]
        pts = wp[m] + t * (wp[m + 1] - wp[m])
        pts[-1] = wp[m + 1]
        pieces.append(pts)
    starts = np.concatenate([p[:-1] for p in pieces])
    ends = np.concatenate([p[1:] for p in pieces])
    costs = objective.motion_cost(starts, ends)
    bounds = np.concatenate([[0], np.cumsum(parts[long])])
    kept = np.array([no_dearer(costs[bounds[i] : bounds[i + 1]].sum(), seg[m]) for i, m in enumerate(long)],
                    dtype=bool)
    if not kept.any():
        return wp
    rows = np.concatenate([np.arange(bounds[i], bounds[i + 1]) for i in np.flatnonzero(kept)])
    ok = np.zeros(len(starts), dtype=bool)
    ok[rows] = checker.are_motions_valid(starts[rows], ends[rows])
    split = {int(m): pieces[i] for i, m in enumerate(long)
             if kept[i] and ok[bounds[i] : bounds[i + 1]].all()}
    out = [wp[:1]]
    for m in range(len(wp) - 1):
        out.append(split[m][1:] if m in split else wp[m + 1 : m + 2])
    return np.concatenate(out)


#: Step sizes of the descent's backtracking: ``step``, ``step / 2``, ... (six).
_BACKTRACK = 0.5 ** np.arange(6)


def _descent(wp: np.ndarray, objective: Objective, checker: ValidityChecker, space, opt: OptimizeOptions,
             seg: np.ndarray | None = None) -> np.ndarray:
    """One sweep of the descent: the odd-numbered interior waypoints move
    together, then the even-numbered ones. Waypoints of one parity share no
    motion, so each one's two motion costs depend on it alone and the path's
    cost falls by the sum of their accepted drops. Each half-sweep costs one
    batched call for the gradients, one for the six backtracking steps of
    every waypoint, and at most six batched validity checks (the largest step
    that both lowers the cost and is valid wins, as in a per-waypoint
    backtracking). A step lowers the cost when :func:`cheaper` says so, and
    a finite difference within the margin of the two motions' cost is taken
    as 0 (across a flat cost it is rounding alone: its direction would be
    the processor's)."""
    if len(wp) < 3:
        return wp
    seg = _motion_costs(objective, wp) if seg is None else seg.copy()
    eye = np.concatenate([np.eye(4), -np.eye(4)]) * opt.epsilon  # (8, 4): +e_i then -e_i
    steps = opt.step * _BACKTRACK
    for first in (1, 2):
        ks = np.arange(first, len(wp) - 1, 2)
        if len(ks) == 0:
            continue
        prev, q, nxt = wp[ks - 1], wp[ks], wp[ks + 1]
        local = seg[ks - 1] + seg[ks]
        m = len(ks)
        probes = (q[:, None, :] + eye[None]).reshape(-1, 4)  # (8m, 4)
        c = objective.motion_cost(np.concatenate([np.repeat(prev, 8, 0), probes]),
                                  np.concatenate([probes, np.repeat(nxt, 8, 0)]))
        c = (c[: 8 * m] + c[8 * m :]).reshape(m, 8)
        diff = c[:, :4] - c[:, 4:]
        diff[np.abs(diff) <= _margin(local)[:, None]] = 0.0
        grad = diff / (2 * opt.epsilon)
        norm = np.linalg.norm(grad, axis=1)
        moving = norm > 0
        if not moving.any():
            continue
        direction = np.zeros_like(grad)
        direction[moving] = grad[moving] / norm[moving, None]
        cand = np.clip(q[:, None, :] - steps[None, :, None] * direction[:, None, :], space.lower, space.upper)
        flat = cand.reshape(-1, 4)  # (6m, 4), waypoint-major
        c = objective.motion_cost(np.concatenate([np.repeat(prev, 6, 0), flat]),
                                  np.concatenate([flat, np.repeat(nxt, 6, 0)]))
        before, after = c[: 6 * m].reshape(m, 6), c[6 * m :].reshape(m, 6)
        total = before + after
        lower = cheaper(total, local[:, None]) & moving[:, None]
        done = np.zeros(m, dtype=bool)
        for level in range(len(steps)):  # the largest step that lowers the cost and is valid
            idx = np.flatnonzero(lower[:, level] & ~done)
            if len(idx) == 0:
                continue
            lv = np.full(len(idx), level)
            p = cand[idx, level]
            ok = checker.are_valid(p)
            if ok.any():
                sub = idx[ok]
                ok[ok] = checker.are_motions_valid(prev[sub], p[ok]) & checker.are_motions_valid(p[ok], nxt[sub])
            won, lv = idx[ok], lv[ok]
            wp[ks[won]] = cand[won, lv]
            seg[ks[won] - 1], seg[ks[won]] = before[won, lv], after[won, lv]
            done[won] = True
    return wp


def optimize_path(
    waypoints: np.ndarray,
    objective: Objective,
    checker: ValidityChecker,
    space: ConfigurationSpace,
    options: OptimizeOptions = OptimizeOptions(),
) -> tuple[np.ndarray, float]:
    """A locally improved path with the same ends, and its cost.

    Args:
        waypoints: (N, 4) a valid path (every motion collision-free).
        objective: the cost to lower.
        checker: validates every changed waypoint and motion.
        space: bounds the moved waypoints.

    Returns:
        (waypoints, cost) with cost < the input's cost by more than the
        margin of :func:`cheaper`, without an interior waypoint collinear
        with its neighbours (unless the checker refuses the merged motion);
        else the input itself and its cost.
    """
    best = np.array(waypoints, dtype=float)
    if len(best) < 2:
        return best, path_cost(objective, best)
    seg = _motion_costs(objective, best)
    best_cost = input_cost = float(seg.sum())
    for _ in range(options.rounds):
        start_cost = best_cost
        for stage in ("shortcut", "subdivide", "descent"):
            if stage == "shortcut":
                wp = _shortcut(best.copy(), objective, checker, seg)
            elif stage == "subdivide":
                wp = _subdivide(best.copy(), objective, checker, space, options.max_segment, seg)
            else:
                wp = best.copy()
                for _ in range(options.descent_steps):
                    wp = _descent(wp, objective, checker, space, options)
            costs = _motion_costs(objective, wp)
            cost = float(costs.sum())
            # Every step only lowers its own part (a subdivision keeps it within the margin); this
            # guards the sum, within the margin, so that rounding does not decide.
            if no_dearer(cost, best_cost):
                best, best_cost, seg = wp, cost, costs
        if start_cost - best_cost <= options.tolerance * max(start_cost, 1e-12):
            break
    # No rest at a waypoint that changes nothing: redundant waypoints go, each merged motion checked, then
    # costed with the rest (the merged motion's trapezoid rule samples other points than its parts').
    merged = merge_collinear(best, checker, space.weights)
    if len(merged) < len(best):
        best, best_cost = merged, path_cost(objective, merged)
    if not cheaper(best_cost, input_cost):  # nothing gained beyond the margin (or only subdivided)
        return np.array(waypoints, dtype=float), input_cost
    return best, best_cost
