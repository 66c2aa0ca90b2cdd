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
   the space and valid, and both its motions are collision-free.

Every accepted change lowers the objective strictly and is checked with the
validity checker, so the result never costs more than the input and keeps
every motion valid. No randomness: the same path in gives the same path out.
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np

from drake_social.planning.objective import Objective
from drake_social.planning.space import ConfigurationSpace
from drake_social.collision.validity import ValidityChecker

__all__ = ["OptimizeOptions", "optimize_path", "path_cost"]


@dc.dataclass
class OptimizeOptions:
    """Options of :func:`optimize_path` (configuration-space units).

    Attributes:
        rounds: shortcut / subdivide / descent rounds (stops early when a
            round improves the cost by no more than ``tolerance``, relative).
        descent_steps: descent sweeps over the waypoints per round.
        max_segment: subdivision length of a motion.
        step: the descent's first step, times the gradient's unit direction.
        epsilon: finite-difference step of the gradient.
        tolerance: relative improvement below which the rounds stop.
    """

    rounds: int = 4
    descent_steps: int = 4
    max_segment: float = 0.5
    step: float = 0.3
    epsilon: float = 1e-3
    tolerance: float = 1e-4


def path_cost(objective: Objective, waypoints: np.ndarray) -> float:
    """The objective along a path: the sum of its motion costs."""
    wp = np.asarray(waypoints, float)
    return float(objective.motion_cost(wp[:-1], wp[1:]).sum()) if len(wp) > 1 else 0.0


def _shortcut(wp: np.ndarray, objective: Objective, checker: ValidityChecker) -> np.ndarray:
    i = 0
    seg = objective.motion_cost(wp[:-1], wp[1:])
    while i < len(wp) - 2:
        later = np.arange(len(wp) - 1, i + 1, -1)  # farthest first
        direct = objective.motion_cost(np.repeat(wp[i : i + 1], len(later), axis=0), wp[later])
        along = np.cumsum(seg[i:])[later - i - 1]
        for j, c, path in zip(later, direct, along):
            if c < path and checker.is_motion_valid(wp[i], wp[j]):
                wp = np.vstack([wp[: i + 1], wp[j:]])
                seg = np.concatenate([seg[:i], [c], seg[j:]])
                break
        i += 1
    return wp


def _subdivide(wp: np.ndarray, objective: Objective, checker: ValidityChecker, space, max_segment: float):
    out = [wp[0]]
    for a, b in zip(wp[:-1], wp[1:]):
        parts = int(np.ceil(float(space.distance(a, b)) / max_segment))
        if parts > 1:
            t = np.linspace(0.0, 1.0, parts + 1)[:, None]
            pts = a + t * (b - a)
            pts[-1] = b
            if objective.motion_cost(pts[:-1], pts[1:]).sum() <= objective.motion_cost(a, b)[0] and all(
                checker.is_motion_valid(p, r) for p, r in zip(pts[:-1], pts[1:])
            ):
                out.extend(pts[1:-1])
        out.append(b)
    return np.array(out)


def _descent(wp: np.ndarray, objective: Objective, checker: ValidityChecker, space, opt: OptimizeOptions):
    eye = np.eye(4) * opt.epsilon
    for k in range(1, len(wp) - 1):
        prev, q, nxt = wp[k - 1], wp[k], wp[k + 1]
        local = objective.motion_cost(np.array([prev, q]), np.array([q, nxt])).sum()
        probes = np.concatenate([q + eye, q - eye])  # (8, 4)
        c = objective.motion_cost(np.repeat(prev[None], 8, 0), probes) + objective.motion_cost(
            probes, np.repeat(nxt[None], 8, 0)
        )
        grad = (c[:4] - c[4:]) / (2 * opt.epsilon)
        norm = float(np.linalg.norm(grad))
        if not norm > 0:
            continue
        step = opt.step
        for _ in range(6):  # backtracking
            cand = np.clip(q - step * grad / norm, space.lower, space.upper)
            new = objective.motion_cost(np.array([prev, cand]), np.array([cand, nxt])).sum()
            if new < local and checker.is_valid(cand) and checker.is_motion_valid(prev, cand) and (
                checker.is_motion_valid(cand, nxt)
            ):
                wp[k] = cand
                break
            step *= 0.5
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
        (waypoints, cost) with cost <= the input's cost; the input itself
        when nothing improved it.
    """
    best = np.array(waypoints, dtype=float)
    best_cost = path_cost(objective, best)
    if len(best) < 2:
        return best, best_cost
    for _ in range(options.rounds):
        start_cost = best_cost
        for stage in ("shortcut", "subdivide", "descent"):
            if stage == "shortcut":
                wp = _shortcut(best.copy(), objective, checker)
            elif stage == "subdivide":
                wp = _subdivide(best.copy(), objective, checker, space, options.max_segment)
            else:
                wp = best.copy()
                for _ in range(options.descent_steps):
                    wp = _descent(wp, objective, checker, space, options)
            cost = path_cost(objective, wp)
            if cost <= best_cost:  # every step only lowers its own part; guard the sum's rounding
                best, best_cost = wp, cost
        if start_cost - best_cost <= options.tolerance * max(start_cost, 1e-12):
            break
    return best, best_cost
