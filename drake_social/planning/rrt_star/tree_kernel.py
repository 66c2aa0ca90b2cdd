"""The RRT* tree loop compiled (numba), for checkers with a compiled planar scene.

:meth:`drake_social.planning.rrt_star.RrtStar.solve`'s Python loop
(:mod:`~drake_social.planning.rrt_star.reference`) stays the tested
reference; :func:`grow` runs the same iterations (uniform or informed
sampling with goal bias, fixed or shrinking near radius, eager or lazy
motion costs, choose parent in order of F + Msc, rewiring with cost
propagation, goal connections within r_near) with the random numbers drawn
from the same ``numpy.random.Generator`` in the same order, and returns the
same tree bit for bit. It runs a chunk of iterations per call on a state
from :func:`init_state` (the caller loops, so Ctrl-C and progress callbacks
get a turn between chunks). Squared distances
are summed as numpy's ``einsum`` sums four terms on this platform,
``(s0 + s2) + (s1 + s3)``; the equality tests against the reference guard it.

Motion checks call :mod:`drake_social.collision.planar_kernel` (the planar
checker's compiled functions), motion costs :func:`drake_social.cost.kernel.msc_sums`.

**Timed mode** (``GrowParams.timed.enabled``, for the replanner among walking
people; :class:`TimedParams`): every node has a time ``tnode`` (the root's
``t_root``; a child's its parent's plus the motion's nominal duration,
:func:`drake_social.kinematics.nominal_durations`' formula), the social part
of a motion's cost is :func:`drake_social.cost.timed_kernel.msc_sums_timed`
at the motion's times, and a motion is valid when the static check passes
and the robot stays clear of the predicted people by more than the safety
distance (:func:`drake_social.collision.people_kernel.people_clearance` at
the motion's end, then
:func:`~drake_social.collision.people_kernel.motion_clear_of_people`).
Rewiring costs and people-checks the motion new -> near at ``tnode[new]``
(the parent choice's cost was at the near node's time: not reused; the
static part of its check is); a re-parented subtree's times are recomputed
as its costs are propagated, its edges' costs kept (approximate during the
search: the replanner re-evaluates what it uses), its edges' people checks
redone at the new times: an edge that fails is cut off (cost inf, so its
subtree is never a parent nor a solution until a rewiring reattaches it).
A goal connection is costed and checked at its node's time; when that time
has moved, the connection is redone before it can be the best. So every
finite tree cost belongs to a path valid at its nodes' current times, and
the best cost, unlike the static loop's, may rise (or become inf again)
when a rewiring cuts the best path off. Lazy costs stay exact (the social
part is >= 0). Disabled, the loop runs exactly as without it, bit for bit.
:func:`seed_chain` inserts a warm start's path as a chain from the root
before the first sample.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from drake_social.cost import kernel as cost_kernel
from drake_social.collision import planar_kernel
from drake_social.collision import people_kernel
from drake_social.collision.validity import PlanarScene
from drake_social.cost import timed_kernel

njit = cost_kernel.njit
AVAILABLE = cost_kernel.AVAILABLE

__all__ = ["AVAILABLE", "GrowParams", "InformedParams", "PeopleGrid", "SocialParams", "TimedParams", "TreeState",
           "grow", "init_state", "seed_chain"]


class SocialParams(NamedTuple):
    """The social cost's inputs of :func:`drake_social.cost.kernel.msc_sums`
    (empty arrays and zeros for the length objective)."""

    people: np.ndarray  #: (P, 3) float: x, y (metres), heading (radians)
    l1: float  #: link lengths, metres
    l2: float
    object_interest: np.ndarray  #: (n, 2) float: the object's interest points in the gripper frame, metres
    active: np.ndarray  #: (K,) int64: the weighted interest points
    weights: np.ndarray  #: (K,) float: their weights
    lever: np.ndarray  #: (2,) float: lever arms of the displacement bound, metres
    resolution: float  #: trapezoid step bound, metres
    reaches: np.ndarray  #: (P,) float: each person's AGF reach, metres
    inv_front: np.ndarray  #: (P,) float: each person's 1 / (2 sigma^2) of the front, rear and side Gaussians, 1 / m^2
    inv_rear: np.ndarray
    inv_side: np.ndarray
    threshold: float  #: the AGF's threshold tau


class PeopleGrid(NamedTuple):
    """The people bucketed in square cells (:func:`drake_social.cost.kernel.people_grid`)."""

    point_reach: float  #: reach of the weighted points from the base, metres
    cell: float  #: cell side, metres
    x0: float  #: the grid's corner, metres
    y0: float
    nx: int  #: cells along x and y
    ny: int
    start: np.ndarray  #: (nx ny + 1,) int64: first entry of each cell in ``order``
    order: np.ndarray  #: (P,) int64: people by cell


class InformedParams(NamedTuple):
    """The informed sampler (:class:`drake_social.planning.sampling.EllipseSampler`)."""

    informed: bool  #: sample in the ellipse once a solution exists
    mode: int  #: 0 = "paper", 1 = "admissible"
    f1: np.ndarray  #: (2,) foci: start and goal base positions, metres
    f2: np.ndarray
    centre: np.ndarray  #: (2,) the ellipse's centre, metres
    rotation: np.ndarray  #: (2, 2) its axes in the world
    focal: float  #: the foci's distance, metres
    xy_scale: float  #: lambda min(w_x, w_y) of the admissible diameter


class TimedParams(NamedTuple):
    """The timed mode's inputs (see the module docstring): the node times'
    model and the predicted people (:class:`drake_social.people.prediction.Prediction`'s
    arrays). ``enabled=False`` (with empty arrays) is the static loop."""

    enabled: bool  #: the timed mode is on
    t_root: float  #: the root's time (the replan's time), seconds
    base_speed: float  #: the base's nominal speed, m/s (execution.max_base_speed)
    arm_speed: np.ndarray  #: (2,) the joints' nominal speeds, rad/s (execution.arm_max_velocity)
    xy: np.ndarray  #: (H, P, 2) the people's predicted positions, metres
    theta: np.ndarray  #: (H, P) their headings, radians
    present: np.ndarray  #: (H, P) bool: in the scene at the sample
    t0: float  #: the first sample's time, seconds
    dt: float  #: seconds between samples
    radii: np.ndarray  #: (P,) body radii, metres
    max_speeds: np.ndarray  #: (P,) each person's largest predicted speed, m/s
    safety: float  #: a motion is invalid where the robot comes within this of a person, metres


class GrowParams(NamedTuple):
    """Everything :func:`grow` reads but never changes (configuration-space units)."""

    goal: np.ndarray  #: (4,) the goal configuration
    lower: np.ndarray  #: (4,) the space's bounds
    upper: np.ndarray
    weights: np.ndarray  #: (4,) the space's distance weights
    planning_range: float  #: Steer distance delta
    near_radius: float  #: r_near (also the goal-connection radius)
    goal_bias: float  #: probability of sampling the goal
    shrinking: bool  #: the near radius shrinks as min(r_near, gamma (log n / n)^(1/4))
    gamma: float
    kind: int  #: objective: 0 = path length, 1 = social
    length_weight: float  #: lambda
    distance_weights: np.ndarray  #: (4,) the objective's distance weights
    social: SocialParams
    grid: PeopleGrid
    scene: PlanarScene  #: the checker's compiled scene
    informed: InformedParams
    lazy: bool  #: lazy motion costs
    timed: TimedParams  #: the timed mode (disabled: the static loop)


class TreeState(NamedTuple):
    """A run's tree between chunks of :func:`grow` (arrays grow by doubling)."""

    q: np.ndarray  #: (cap, 4) node configurations
    parent: np.ndarray  #: (cap,) int64, -1 for the start
    cost: np.ndarray  #: (cap,) cost from the start
    edge: np.ndarray  #: (cap,) cost of the motion from the parent
    first_child: np.ndarray  #: (cap,) int64 children as linked lists
    next_sib: np.ndarray
    prev_sib: np.ndarray
    clear: np.ndarray  #: (cap, S) every node's capsule clearances, metres
    g_next: np.ndarray  #: (cap,) int64 the node grid's linked lists
    goal_nodes: np.ndarray  #: int64 nodes with a valid, costed motion to the goal
    goal_edges: np.ndarray  #: their motion costs
    counts: np.ndarray  #: (3,) int64 configurations checked, motions checked, motions costed
    history: np.ndarray  #: (K,) best cost after each iteration
    diameters: np.ndarray  #: (K,) or (0,) the informed ellipse's diameter after each iteration
    g_head: np.ndarray  #: int64 the node grid's first node per cell
    g_geom: np.ndarray  #: (5,) the node grid: x0, y0, cell side, nx, ny
    goal_clear: np.ndarray  #: (S,) the goal's capsule clearances
    ints: np.ndarray  #: (4,) int64 nodes, goal nodes, best node, first solution iteration (-1: none)
    floats: np.ndarray  #: (2,) best cost, ellipse diameter
    tnode: np.ndarray  #: (cap,) node times, seconds (timed mode; the root's t_root, 0 when disabled)
    goal_t: np.ndarray  #: the node time at which each goal connection was checked and costed (timed mode)


@njit(cache=True)
def _d2(a, b, w):
    d0 = (a[0] - b[0]) * w[0]
    d1 = (a[1] - b[1]) * w[1]
    d2 = (a[2] - b[2]) * w[2]
    d3 = (a[3] - b[3]) * w[3]
    return (d0 * d0 + d2 * d2) + (d1 * d1 + d3 * d3)


@njit(cache=True)
def _costs(q_a, q_b, kind, lam, dw, soc, grid):
    """Objective motion costs (E,) of q_a[e] -> q_b[e], as Objective.motion_cost."""
    e_count = q_a.shape[0]
    out = np.zeros(e_count)
    length = np.empty(e_count)
    for e in range(e_count):
        length[e] = math.sqrt(_d2(q_b[e], q_a[e], dw))
    if kind == 1:
        (people, l1, l2, obj, active, weights, lever, resolution, reaches, inv_f, inv_r, inv_s, tau) = soc
        if people.shape[0] > 0 and active.shape[0] > 0:
            point_reach, cell, gx0, gy0, gnx, gny, gstart, gorder = grid
            sums, n = cost_kernel.msc_sums(
                q_a, q_b, people, l1, l2, obj, active, weights, lever, resolution, reaches, inv_f, inv_r, inv_s, tau,
                point_reach, cell, gx0, gy0, gnx, gny, gstart, gorder,
            )
            for e in range(e_count):
                out[e] += sums[e] * (length[e] / n[e])
        if lam > 0:
            for e in range(e_count):
                out[e] = out[e] + lam * length[e]
    else:
        for e in range(e_count):
            out[e] = lam * length[e]
    return out


@njit(cache=True)
def _duration(q_a, q_b, base_speed, arm_speed):
    """The nominal duration of the motion q_a -> q_b, seconds: exactly
    :func:`drake_social.kinematics.nominal_durations` (the same operations)."""
    base = math.hypot(q_b[0] - q_a[0], q_b[1] - q_a[1]) / base_speed
    arm = max(abs(q_b[2] - q_a[2]) / arm_speed[0], abs(q_b[3] - q_a[3]) / arm_speed[1])
    return max(base, arm)


@njit(cache=True)
def _timed_costs(q_a, q_b, t_a, t_b, kind, lam, dw, soc, grid, tp):
    """Objective motion costs (E,) of q_a[e] -> q_b[e] driven from t_a[e] to
    t_b[e]: :func:`_costs` with the social integral against the predicted
    people (:func:`drake_social.cost.timed_kernel.msc_sums_timed`)."""
    e_count = q_a.shape[0]
    out = np.zeros(e_count)
    length = np.empty(e_count)
    for e in range(e_count):
        length[e] = math.sqrt(_d2(q_b[e], q_a[e], dw))
    if kind == 1:
        (people, l1, l2, obj, active, weights, lever, resolution, reaches, inv_f, inv_r, inv_s, tau) = soc
        if tp.xy.shape[1] > 0 and active.shape[0] > 0:
            sums, n = timed_kernel.msc_sums_timed(
                q_a, q_b, t_a, t_b, tp.xy, tp.theta, tp.present, tp.t0, tp.dt, tp.max_speeds, l1, l2, obj, active,
                weights, lever, resolution, reaches, inv_f, inv_r, inv_s, tau, grid.point_reach,
            )
            for e in range(e_count):
                out[e] += sums[e] * (length[e] / n[e])
        if lam > 0:
            for e in range(e_count):
                out[e] = out[e] + lam * length[e]
    else:
        for e in range(e_count):
            out[e] = lam * length[e]
    return out


@njit(cache=True)
def _people_ok(q_a, q_b, t_a, t_b, scene, tp):
    """The motion q_a -> q_b driven from t_a to t_b keeps the robot farther
    than ``tp.safety`` from every considered predicted person (its end
    first: the cheap rejection)."""
    if tp.xy.shape[1] == 0:
        return True
    bodies, robot, levers = scene.bodies, scene.robot, scene.levers
    if not people_kernel.people_clearance(q_b, t_b, bodies, robot, tp.xy, tp.present, tp.radii, tp.max_speeds,
                                          tp.t0, tp.dt) > tp.safety:
        return False
    return people_kernel.motion_clear_of_people(q_a, q_b, t_a, t_b, bodies, robot, levers, tp.xy, tp.present,
                                                tp.radii, tp.max_speeds, tp.t0, tp.dt, tp.safety)


@njit(cache=True)
def grow(rng, it_start, it_stop, params, state):
    """Iterations ``it_start .. it_stop - 1`` of the RRT* run (-1: the start's
    goal connection, before the first sample) with the :class:`GrowParams`
    ``params`` on the :class:`TreeState` ``state`` from :func:`init_state` or
    the previous chunk; returns the new state (arrays may be replaced as they grow)."""
    goal, lower, upper, w = params.goal, params.lower, params.upper, params.weights
    delta, r_near, goal_bias = params.planning_range, params.near_radius, params.goal_bias
    shrinking, gamma, lazy = params.shrinking, params.gamma, params.lazy
    kind, lam, dw, soc, grid = params.kind, params.length_weight, params.distance_weights, params.social, params.grid
    c_lower, c_upper, bodies, robot, env, levers, env_grid = params.scene
    (informed, mode, f1, f2, centre, rot, focal, xy_scale) = params.informed
    tp = params.timed
    timed = tp.enabled
    (q, parent, cost, edge, first_child, next_sib, prev_sib, clear, g_next, goal_nodes, goal_edges,
     counts, history, diameters, g_head, g_geom, goal_clear, ints, floats, tnode, goal_t) = state
    n, n_goal, best_node, first_iteration = ints[0], ints[1], ints[2], ints[3]
    best_cost, ellipse_c = floats[0], floats[1]
    cap = q.shape[0]
    s_count = robot.shape[0]
    one = np.empty((1, 4))
    gq = np.empty((1, 4))
    gq[0] = goal
    tg_a = np.empty(1)
    tg_b = np.empty(1)
    near = np.empty(cap, dtype=np.int64)
    stack = np.empty(cap, dtype=np.int64)

    for it in range(it_start, it_stop):
        i_new = 0
        if it >= 0:
            # ---- sample
            if rng.random() < goal_bias:
                q_rand = goal.copy()
            else:
                q_rand = np.empty(4)
                for c in range(4):
                    q_rand[c] = rng.random()
                q_rand = lower + q_rand * (upper - lower)
                if informed and math.isfinite(ellipse_c):
                    _ellipse_xy(rng, q_rand, ellipse_c, centre, rot, focal, lower, upper)
            # ---- nearest, steer, check
            i_near, d_best = _nearest(q, q_rand, w, g_head, g_next, g_geom)
            i_new = -1
            if d_best != 0.0:
                if d_best <= delta:
                    q_new = q_rand.copy()
                else:
                    q_new = q[i_near] + (q_rand - q[i_near]) * (delta / d_best)
                counts[0] += 1
                c_new_caps = planar_kernel.capsule_clearances(q_new, bodies, robot, env, env_grid)
                if _valid(q_new, c_new_caps, c_lower, c_upper):
                    # ---- near set
                    r = r_near
                    if shrinking and n + 1 > 1:
                        r = min(r, gamma * (math.log(n + 1) / (n + 1)) ** 0.25)
                    r2 = r * r
                    m = _within(q, q_new, w, r, r2, g_head, g_next, g_geom, near)
                    has_nearest = False
                    for s in range(m):
                        if near[s] == i_near:
                            has_nearest = True
                    if not has_nearest:
                        near[m] = i_near
                        m += 1
                    near_idx = near[:m].copy()
                    q_a = np.empty((m, 4))
                    q_b = np.empty((m, 4))
                    for s in range(m):
                        q_a[s] = q[near[s]]
                        q_b[s] = q_new
                    t_a = np.zeros(m)  # the motions' times near -> new (timed mode)
                    t_b = np.zeros(m)
                    if timed:
                        for s in range(m):
                            t_a[s] = tnode[near[s]]
                            t_b[s] = t_a[s] + _duration(q_a[s], q_new, tp.base_speed, tp.arm_speed)
                    checked = np.zeros(m, dtype=np.int8)  # 0 unknown, 1 valid, 2 invalid (the static check)
                    p_slot = -1
                    f_near = np.empty(m)
                    for s in range(m):
                        f_near[s] = cost[near[s]]
                    if lazy and kind == 1 and lam > 0:
                        # Lazy costs (RrtStar._extend): integrate a candidate only once its
                        # bound F + lambda * length is no larger than the cheapest integrated
                        # candidate not yet checked; the same candidates, order and checks.
                        phi = np.full(m, np.inf)
                        bound = np.empty(m)
                        for s in range(m):
                            bound[s] = lam * math.sqrt(_d2(q_new, q_a[s], dw))
                        low = f_near + bound
                        by_bound = np.argsort(low, kind="mergesort")
                        is_open = np.zeros(m, dtype=np.bool_)
                        n_open, pos = 0, 0
                        while True:
                            if n_open == 0:
                                if pos == m:
                                    break
                                _cost_slots(by_bound[pos:pos + 1], phi, q_a, q_b, t_a, t_b, kind, lam, dw, soc, grid,
                                            tp, counts)
                                is_open[by_bound[pos]] = True
                                n_open += 1
                                pos += 1
                            t_min = np.inf
                            for s in range(m):
                                if is_open[s]:
                                    t_min = min(t_min, f_near[s] + phi[s])
                            stop = pos
                            while stop < m and low[by_bound[stop]] <= t_min:
                                stop += 1
                            if stop > pos:
                                _cost_slots(by_bound[pos:stop], phi, q_a, q_b, t_a, t_b, kind, lam, dw, soc, grid, tp,
                                            counts)
                                for t in range(pos, stop):
                                    is_open[by_bound[t]] = True
                                n_open += stop - pos
                                pos = stop
                            slot, best_total = -1, np.inf
                            for s in range(m):  # the cheapest open candidate, the lowest slot on ties
                                if is_open[s] and (slot < 0 or f_near[s] + phi[s] < best_total):
                                    slot, best_total = s, f_near[s] + phi[s]
                            is_open[slot] = False
                            n_open -= 1
                            counts[1] += 1
                            ok = planar_kernel.motion_valid_ends(q_a[slot], q_new, clear[near[slot]], c_new_caps,
                                                                 c_lower, c_upper, bodies, robot, env, env_grid, levers)
                            checked[slot] = 1 if ok else 2
                            if ok and timed:
                                ok = _people_ok(q_a[slot], q_new, t_a[slot], t_b[slot], params.scene, tp)
                            if ok:
                                p_slot = slot
                                break
                    else:
                        if timed:
                            phi = _timed_costs(q_a, q_b, t_a, t_b, kind, lam, dw, soc, grid, tp)
                        else:
                            phi = _costs(q_a, q_b, kind, lam, dw, soc, grid)
                        bound = phi
                        counts[2] += m
                        order = np.argsort(f_near + phi, kind="mergesort")
                        for o in range(m):
                            s = order[o]
                            counts[1] += 1
                            ok = planar_kernel.motion_valid_ends(q_a[s], q_new, clear[near[s]], c_new_caps, c_lower,
                                                                 c_upper, bodies, robot, env, env_grid, levers)
                            checked[s] = 1 if ok else 2
                            if ok and timed:
                                ok = _people_ok(q_a[s], q_new, t_a[s], t_b[s], params.scene, tp)
                            if ok:
                                p_slot = s
                                break
                    if p_slot >= 0:
                        # ---- insert
                        if n == cap:
                            cap *= 2
                            q2 = np.empty((cap, 4))
                            q2[:n] = q[:n]
                            q = q2
                            c2 = np.empty((cap, s_count))
                            c2[:n] = clear[:n]
                            clear = c2
                            parent = np.concatenate((parent, np.full(cap - n, -1, dtype=np.int64)))
                            cost = np.concatenate((cost, np.zeros(cap - n)))
                            edge = np.concatenate((edge, np.zeros(cap - n)))
                            first_child = np.concatenate((first_child, np.full(cap - n, -1, dtype=np.int64)))
                            next_sib = np.concatenate((next_sib, np.full(cap - n, -1, dtype=np.int64)))
                            prev_sib = np.concatenate((prev_sib, np.full(cap - n, -1, dtype=np.int64)))
                            near = np.empty(cap, dtype=np.int64)
                            g_next = np.concatenate((g_next, np.full(cap - n, -1, dtype=np.int64)))
                            stack = np.empty(cap, dtype=np.int64)
                            tnode = np.concatenate((tnode, np.zeros(cap - n)))
                        i_new = n
                        n += 1
                        p = near_idx[p_slot]
                        q[i_new] = q_new
                        _insert(i_new, q, w, g_head, g_next, g_geom)
                        clear[i_new] = c_new_caps
                        parent[i_new] = p
                        edge[i_new] = phi[p_slot]
                        cost[i_new] = cost[p] + phi[p_slot]
                        _link(i_new, p, first_child, next_sib, prev_sib)
                        tnode[i_new] = t_b[p_slot]
                        # ---- rewire
                        c_new = cost[i_new]
                        if timed:
                            _rewire_timed(i_new, m, near_idx, q_a, q_b, bound, checked, c_new_caps, q, parent, cost,
                                          edge, first_child, next_sib, prev_sib, clear, tnode, stack, counts, params)
                        elif lazy and kind == 1 and lam > 0:
                            todo = np.empty(m, dtype=np.int64)
                            nt = 0
                            for s in range(m):
                                if c_new + bound[s] < cost[near_idx[s]] and np.isinf(phi[s]):
                                    todo[nt] = s
                                    nt += 1
                            if nt > 0:
                                _cost_slots(todo[:nt], phi, q_a, q_b, t_a, t_b, kind, lam, dw, soc, grid, tp, counts)
                        if not timed:
                            cand = np.empty(m, dtype=np.int64)
                            nc = 0
                            for s in range(m):
                                if c_new + phi[s] < cost[near_idx[s]]:
                                    cand[nc] = s
                                    nc += 1
                            for ci in range(nc):
                                s = cand[ci]
                                j = near_idx[s]
                                if j == parent[i_new] or not cost[i_new] + phi[s] < cost[j]:
                                    continue
                                if checked[s] == 0:
                                    counts[1] += 1
                                    ok = planar_kernel.motion_valid_ends(q_new, q[j], c_new_caps, clear[j], c_lower,
                                                                         c_upper, bodies, robot, env, env_grid, levers)
                                else:
                                    ok = checked[s] == 1
                                if ok:
                                    _unlink(j, parent[j], first_child, next_sib, prev_sib)
                                    _link(j, i_new, first_child, next_sib, prev_sib)
                                    parent[j] = i_new
                                    edge[j] = phi[s]
                                    top = 0
                                    stack[0] = j
                                    top = 1
                                    while top > 0:
                                        top -= 1
                                        k = stack[top]
                                        if k == i_new:
                                            raise RuntimeError("rewiring a node under its descendant")
                                        cost[k] = cost[parent[k]] + edge[k]
                                        c = first_child[k]
                                        while c >= 0:
                                            stack[top] = c
                                            top += 1
                                            c = next_sib[c]
                    else:
                        i_new = -1
                else:
                    i_new = -1
        # ---- goal connection of node i_new (the start before the first iteration)
        if i_new >= 0:
            d = math.sqrt(_d2(goal, q[i_new], w))
            if d <= r_near:
                c_goal = 0.0
                ok = True
                if d != 0.0:
                    counts[2] += 1
                    one[0] = q[i_new]
                    if timed:
                        tg_a[0] = tnode[i_new]
                        tg_b[0] = tnode[i_new] + _duration(q[i_new], goal, tp.base_speed, tp.arm_speed)
                        c_goal = _timed_costs(one, gq, tg_a, tg_b, kind, lam, dw, soc, grid, tp)[0]
                    else:
                        c_goal = _costs(one, gq, kind, lam, dw, soc, grid)[0]
                    counts[1] += 1
                    ok = planar_kernel.motion_valid_ends(q[i_new], goal, clear[i_new], goal_clear, c_lower, c_upper,
                                                         bodies, robot, env, env_grid, levers)
                    if ok and timed:
                        ok = _people_ok(q[i_new], goal, tg_a[0], tg_b[0], params.scene, tp)
                if ok:
                    if n_goal == goal_nodes.shape[0]:
                        goal_nodes = np.concatenate((goal_nodes, np.empty(n_goal, dtype=np.int64)))
                        goal_edges = np.concatenate((goal_edges, np.empty(n_goal)))
                        goal_t = np.concatenate((goal_t, np.zeros(n_goal)))
                    goal_nodes[n_goal] = i_new
                    goal_edges[n_goal] = c_goal
                    goal_t[n_goal] = tnode[i_new]
                    n_goal += 1
        # The best goal connection, when the tree changed, or when the start's own
        # connection (made before the first sample) is not yet reported.
        if timed and it >= 0 and n_goal > 0 and (i_new >= 0 or best_node < 0):
            # The cheapest goal connection whose check and cost are at its node's
            # time now (a connection made before its node's time moved is redone
            # first: invalid => inf); none finite => no solution (yet, again).
            while True:
                g_best, g = np.inf, -1
                for t in range(n_goal):
                    tot = cost[goal_nodes[t]] + goal_edges[t]
                    if tot < g_best:
                        g_best, g = tot, t
                if g < 0 or goal_t[g] == tnode[goal_nodes[g]]:
                    break
                goal_edges[g] = _goal_edge(goal_nodes[g], q, tnode, counts, params)
                goal_t[g] = tnode[goal_nodes[g]]
            if g < 0:
                best_cost, best_node = np.inf, -1
            else:
                best_cost, best_node = g_best, goal_nodes[g]
                if first_iteration < 0:
                    first_iteration = it + 1
            if informed:
                if g < 0:
                    ellipse_c = np.inf
                elif mode == 0:
                    ellipse_c = _xy_length(q, parent, best_node, goal)
                else:
                    ellipse_c = best_cost / xy_scale if xy_scale > 0 else np.inf
        elif it >= 0 and n_goal > 0 and (i_new >= 0 or best_node < 0):
            g_best, g = np.inf, -1
            for t in range(n_goal):
                tot = cost[goal_nodes[t]] + goal_edges[t]
                if tot < g_best:
                    g_best, g = tot, t
            best_cost, best_node = g_best, goal_nodes[g]
            if first_iteration < 0:
                first_iteration = it + 1
            if informed:
                if mode == 0:  # "paper": the XY length of the best path's base
                    ellipse_c = _xy_length(q, parent, best_node, goal)
                else:  # "admissible": best cost / (lambda min(w_x, w_y))
                    ellipse_c = best_cost / xy_scale if xy_scale > 0 else np.inf
        if it >= 0:
            history[it] = best_cost
            if informed:
                diameters[it] = ellipse_c
    ints[0], ints[1], ints[2], ints[3] = n, n_goal, best_node, first_iteration
    floats[0], floats[1] = best_cost, ellipse_c
    return TreeState(q, parent, cost, edge, first_child, next_sib, prev_sib, clear, g_next, goal_nodes, goal_edges,
                     counts, history, diameters, g_head, g_geom, goal_clear, ints, floats, tnode, goal_t)


@njit(cache=True)
def _rewire_timed(i_new, m, near_idx, q_a, q_b, bound, checked, c_new_caps, q, parent, cost, edge, first_child,
                  next_sib, prev_sib, clear, tnode, stack, counts, params):
    """The timed mode's rewiring of the near nodes (slots 0 .. m - 1 of
    ``near_idx``, configurations ``q_a``; ``q_b`` rows are the new node's)
    through the new node ``i_new``: each motion new -> near is costed and
    people-checked from ``tnode[i_new]``, only where ``c_new + lambda *
    length`` (a lower bound of its cost, the social part >= 0) can improve
    the near node, lazy or not (the same rewiring, fewer integrals); the
    static checks of the parent choice (``checked``) are reused. A
    re-parented subtree's costs and times are recomputed from its parents
    (its edge costs kept); a moved descendant's motion is people-checked
    again at its new times and cut off (edge cost inf) when invalid, so every
    node of finite cost has a tree path valid at its current times."""
    tp = params.timed
    kind, lam, dw, soc, grid = params.kind, params.length_weight, params.distance_weights, params.social, params.grid
    c_lower, c_upper, bodies, robot, env, levers, env_grid = params.scene
    q_new = q[i_new]
    c_new = cost[i_new]
    t_new = tnode[i_new]
    ta = np.full(m, t_new)
    tb = np.empty(m)
    for s in range(m):
        tb[s] = t_new + _duration(q_new, q_a[s], tp.base_speed, tp.arm_speed)
    phi = np.full(m, np.inf)
    todo = np.empty(m, dtype=np.int64)
    nt = 0
    for s in range(m):
        j = near_idx[s]
        if j != parent[i_new] and c_new + lam * math.sqrt(_d2(q_new, q_a[s], dw)) < cost[j]:
            todo[nt] = s
            nt += 1
    if nt > 0:
        _cost_slots(todo[:nt], phi, q_b, q_a, ta, tb, kind, lam, dw, soc, grid, tp, counts)
    cand = np.empty(m, dtype=np.int64)
    nc = 0
    for s in range(m):
        if c_new + phi[s] < cost[near_idx[s]]:
            cand[nc] = s
            nc += 1
    for ci in range(nc):
        s = cand[ci]
        j = near_idx[s]
        if j == parent[i_new] or not cost[i_new] + phi[s] < cost[j]:
            continue
        counts[1] += 1
        if checked[s] == 0:
            ok = planar_kernel.motion_valid_ends(q_new, q[j], c_new_caps, clear[j], c_lower, c_upper, bodies, robot,
                                                 env, env_grid, levers)
        else:
            ok = checked[s] == 1
        if ok:
            ok = _people_ok(q_new, q[j], ta[s], tb[s], params.scene, tp)
        if ok:
            _unlink(j, parent[j], first_child, next_sib, prev_sib)
            _link(j, i_new, first_child, next_sib, prev_sib)
            parent[j] = i_new
            edge[j] = phi[s]
            stack[0] = j
            top = 1
            while top > 0:
                top -= 1
                k = stack[top]
                if k == i_new:
                    raise RuntimeError("rewiring a node under its descendant")
                t_old = tnode[k]
                tnode[k] = tnode[parent[k]] + _duration(q[parent[k]], q[k], tp.base_speed, tp.arm_speed)
                if k != j and tnode[k] != t_old and edge[k] < np.inf:
                    # A moved descendant's motion, checked again at its new times: cut off when invalid.
                    counts[1] += 1
                    if not _people_ok(q[parent[k]], q[k], tnode[parent[k]], tnode[k], params.scene, tp):
                        edge[k] = np.inf
                cost[k] = cost[parent[k]] + edge[k]
                c = first_child[k]
                while c >= 0:
                    stack[top] = c
                    top += 1
                    c = next_sib[c]


@njit(cache=True)
def _goal_edge(i, q, tnode, counts, params):
    """The timed mode's goal connection of node i redone at ``tnode[i]``: its
    cost, or inf when the motion is not valid then (0 for a node at the goal)."""
    goal, tp = params.goal, params.timed
    if _d2(goal, q[i], params.weights) == 0.0:
        return 0.0
    a = np.empty((1, 4))
    b = np.empty((1, 4))
    a[0] = q[i]
    b[0] = goal
    ta = np.full(1, tnode[i])
    tb = np.full(1, tnode[i] + _duration(q[i], goal, tp.base_speed, tp.arm_speed))
    counts[1] += 1
    if not _people_ok(q[i], goal, ta[0], tb[0], params.scene, tp):
        return np.inf
    counts[2] += 1
    return _timed_costs(a, b, ta, tb, params.kind, params.length_weight, params.distance_weights, params.social,
                        params.grid, tp)[0]


@njit(cache=True)
def _cost_slots(slots, phi, q_a, q_b, t_a, t_b, kind, lam, dw, soc, grid, tp, counts):
    """phi[slots] = the motion costs q_a[slots] -> q_b[slots] (RrtStar._extend's
    cost()); in timed mode driven from t_a[slots] to t_b[slots]."""
    k = slots.shape[0]
    a, b = np.empty((k, 4)), np.empty((k, 4))
    for t in range(k):
        a[t], b[t] = q_a[slots[t]], q_b[slots[t]]
    if tp.enabled:
        ta, tb = np.empty(k), np.empty(k)
        for t in range(k):
            ta[t], tb[t] = t_a[slots[t]], t_b[slots[t]]
        out = _timed_costs(a, b, ta, tb, kind, lam, dw, soc, grid, tp)
    else:
        out = _costs(a, b, kind, lam, dw, soc, grid)
    for t in range(k):
        phi[slots[t]] = out[t]
    counts[2] += k


@njit(cache=True)
def init_state(start, iterations, params):
    """The :class:`TreeState` of a run of ``iterations`` iterations with the
    :class:`GrowParams` ``params`` before its first chunk: the tree of the
    start alone."""
    goal, lower, upper, w, r_near = params.goal, params.lower, params.upper, params.weights, params.near_radius
    informed = params.informed.informed
    bodies, robot, env, env_grid = params.scene.bodies, params.scene.robot, params.scene.env, params.scene.grid
    s_count = robot.shape[0]
    cap = 256
    q = np.empty((cap, 4))
    parent = np.full(cap, -1, dtype=np.int64)
    cost = np.zeros(cap)
    edge = np.zeros(cap)
    first_child = np.full(cap, -1, dtype=np.int64)
    next_sib = np.full(cap, -1, dtype=np.int64)
    prev_sib = np.full(cap, -1, dtype=np.int64)
    clear = np.empty((cap, s_count))  # every node's capsule clearances (motion ends)
    counts = np.zeros(3, dtype=np.int64)
    history = np.full(iterations, np.inf)
    diameters = np.full(iterations if informed else 0, np.inf)
    goal_nodes = np.empty(16, dtype=np.int64)
    goal_edges = np.empty(16)
    # Nodes bucketed by their weighted (x, y) in square cells (linked lists),
    # so that nearest and near queries visit the nodes of nearby cells only.
    g_geom = _grid_geometry(lower, upper, w, r_near)
    g_head = np.full(int(g_geom[3]) * int(g_geom[4]), -1, dtype=np.int64)
    g_next = np.full(cap, -1, dtype=np.int64)
    q[0] = start
    _insert(0, q, w, g_head, g_next, g_geom)
    clear[0] = planar_kernel.capsule_clearances(start, bodies, robot, env, env_grid)
    goal_clear = planar_kernel.capsule_clearances(goal, bodies, robot, env, env_grid)
    ints = np.array([1, 0, -1, -1], dtype=np.int64)  # n, goal nodes, best node, first solution iteration
    floats = np.array([np.inf, np.inf])  # best cost, ellipse diameter
    tnode = np.zeros(cap)
    goal_t = np.zeros(16)
    if params.timed.enabled:
        tnode[0] = params.timed.t_root
    return TreeState(q, parent, cost, edge, first_child, next_sib, prev_sib, clear, g_next, goal_nodes, goal_edges,
                     counts, history, diameters, g_head, g_geom, goal_clear, ints, floats, tnode, goal_t)


@njit(cache=True)
def _enlarge(state, cap):
    """``state`` with room for ``cap`` nodes (the node arrays copied into larger ones)."""
    (q, parent, cost, edge, first_child, next_sib, prev_sib, clear, g_next, goal_nodes, goal_edges,
     counts, history, diameters, g_head, g_geom, goal_clear, ints, floats, tnode, goal_t) = state
    n = ints[0]
    q2 = np.empty((cap, 4))
    q2[:n] = q[:n]
    c2 = np.empty((cap, clear.shape[1]))
    c2[:n] = clear[:n]
    extra = cap - n
    return TreeState(q2, np.concatenate((parent[:n], np.full(extra, -1, dtype=np.int64))),
                     np.concatenate((cost[:n], np.zeros(extra))), np.concatenate((edge[:n], np.zeros(extra))),
                     np.concatenate((first_child[:n], np.full(extra, -1, dtype=np.int64))),
                     np.concatenate((next_sib[:n], np.full(extra, -1, dtype=np.int64))),
                     np.concatenate((prev_sib[:n], np.full(extra, -1, dtype=np.int64))), c2,
                     np.concatenate((g_next[:n], np.full(extra, -1, dtype=np.int64))), goal_nodes, goal_edges, counts,
                     history, diameters, g_head, g_geom, goal_clear, ints, floats,
                     np.concatenate((tnode[:n], np.zeros(extra))), goal_t)


@njit(cache=True)
def seed_chain(seed, params, state):
    """Inserts the warm start's path ``seed`` (M, 4; ``seed[0]`` the root's
    configuration) into a tree of the root alone, before the first sample:
    each waypoint becomes the child of the previous one (repeated waypoints
    skipped), its configuration and its motion checked (static, and the
    people in timed mode at the motion's times) and costed as the loop
    would; the chain stops before the first invalid waypoint. The last
    inserted node's goal connection is tried as :func:`grow` tries a new
    node's. Counted in ``counts`` as the loop counts. Returns the new state."""
    goal, w, r_near = params.goal, params.weights, params.near_radius
    kind, lam, dw, soc, grid = params.kind, params.length_weight, params.distance_weights, params.social, params.grid
    c_lower, c_upper, bodies, robot, env, levers, env_grid = params.scene
    tp = params.timed
    timed = tp.enabled
    if state.ints[0] + seed.shape[0] > state.q.shape[0]:
        state = _enlarge(state, state.ints[0] + seed.shape[0])
    (q, parent, cost, edge, first_child, next_sib, prev_sib, clear, g_next, goal_nodes, goal_edges,
     counts, history, diameters, g_head, g_geom, goal_clear, ints, floats, tnode, goal_t) = state
    n, n_goal = ints[0], ints[1]
    a = np.empty((1, 4))
    b = np.empty((1, 4))
    ta = np.zeros(1)
    tb = np.zeros(1)
    prev = 0
    for k in range(1, seed.shape[0]):
        qk = seed[k].copy()
        if _d2(qk, q[prev], w) == 0.0:
            continue
        counts[0] += 1
        caps = planar_kernel.capsule_clearances(qk, bodies, robot, env, env_grid)
        if not _valid(qk, caps, c_lower, c_upper):
            break
        a[0] = q[prev]
        b[0] = qk
        if timed:
            ta[0] = tnode[prev]
            tb[0] = ta[0] + _duration(q[prev], qk, tp.base_speed, tp.arm_speed)
        counts[1] += 1
        ok = planar_kernel.motion_valid_ends(q[prev], qk, clear[prev], caps, c_lower, c_upper, bodies, robot, env,
                                             env_grid, levers)
        if ok and timed:
            ok = _people_ok(q[prev], qk, ta[0], tb[0], params.scene, tp)
        if not ok:
            break
        counts[2] += 1
        if timed:
            c = _timed_costs(a, b, ta, tb, kind, lam, dw, soc, grid, tp)[0]
        else:
            c = _costs(a, b, kind, lam, dw, soc, grid)[0]
        i = n
        n += 1
        q[i] = qk
        _insert(i, q, w, g_head, g_next, g_geom)
        clear[i] = caps
        parent[i] = prev
        edge[i] = c
        cost[i] = cost[prev] + c
        _link(i, prev, first_child, next_sib, prev_sib)
        tnode[i] = tb[0]
        prev = i
    if prev > 0:  # the chain's last node's goal connection
        d = math.sqrt(_d2(goal, q[prev], w))
        if d <= r_near:
            c_goal = 0.0
            ok = True
            if d != 0.0:
                counts[2] += 1
                a[0] = q[prev]
                b[0] = goal
                if timed:
                    ta[0] = tnode[prev]
                    tb[0] = ta[0] + _duration(q[prev], goal, tp.base_speed, tp.arm_speed)
                    c_goal = _timed_costs(a, b, ta, tb, kind, lam, dw, soc, grid, tp)[0]
                else:
                    c_goal = _costs(a, b, kind, lam, dw, soc, grid)[0]
                counts[1] += 1
                ok = planar_kernel.motion_valid_ends(q[prev], goal, clear[prev], goal_clear, c_lower, c_upper, bodies,
                                                     robot, env, env_grid, levers)
                if ok and timed:
                    ok = _people_ok(q[prev], goal, ta[0], tb[0], params.scene, tp)
            if ok:
                if n_goal == goal_nodes.shape[0]:
                    goal_nodes = np.concatenate((goal_nodes, np.empty(n_goal, dtype=np.int64)))
                    goal_edges = np.concatenate((goal_edges, np.empty(n_goal)))
                    goal_t = np.concatenate((goal_t, np.zeros(n_goal)))
                goal_nodes[n_goal] = prev
                goal_edges[n_goal] = c_goal
                goal_t[n_goal] = tnode[prev]
                n_goal += 1
    ints[0], ints[1] = n, n_goal
    return TreeState(q, parent, cost, edge, first_child, next_sib, prev_sib, clear, g_next, goal_nodes, goal_edges,
                     counts, history, diameters, g_head, g_geom, goal_clear, ints, floats, tnode, goal_t)


@njit(cache=True)
def _xy_length(q, parent, node, goal):
    """The XY length of the tree path start -> node, then to the goal, summed
    from the start (as RrtStar._xy_length)."""
    path = []
    i = node
    while i >= 0:
        path.append(i)
        i = parent[i]
    total = 0.0
    for k in range(len(path) - 1, 0, -1):
        a, b = path[k], path[k - 1]
        total += math.hypot(q[b, 0] - q[a, 0], q[b, 1] - q[a, 1])
    last = path[0]
    return total + math.hypot(goal[0] - q[last, 0], goal[1] - q[last, 1])


@njit(cache=True)
def _ellipse_xy(rng, q, c, centre, rot, focal, lower, upper):
    """EllipseSampler.sample's base position into q[:2] (the same draws)."""
    c = max(c, focal)
    a = 0.5 * c
    b = 0.5 * math.sqrt(max(c * c - focal * focal, 0.0))
    for _ in range(1000):
        r = math.sqrt(rng.random())
        phi = 2 * math.pi * rng.random()
        u, v = a * r * math.cos(phi), b * r * math.sin(phi)
        x = centre[0] + (rot[0, 0] * u + rot[0, 1] * v)
        y = centre[1] + (rot[1, 0] * u + rot[1, 1] * v)
        if lower[0] <= x <= upper[0] and lower[1] <= y <= upper[1]:
            q[0], q[1] = x, y
            return
    raise RuntimeError("no ellipse sample inside the room bounds after 1000 attempts")


@njit(cache=True)
def _grid_geometry(lower, upper, w, r_near):
    """(x0, y0, h, nx, ny): square cells of side h over the weighted (x, y)
    box; h = r_near / 4, larger if that would make more than 4096 cells."""
    x0, y0 = lower[0] * w[0], lower[1] * w[1]
    width, height = max((upper[0] - lower[0]) * w[0], 1e-12), max((upper[1] - lower[1]) * w[1], 1e-12)
    h = max(r_near / 4.0, math.sqrt(width * height / 4096.0), 1e-9)
    return np.array([x0, y0, h, min(int(width / h) + 1, 4096), min(int(height / h) + 1, 4096)])


@njit(cache=True)
def _cell(x, y, geom):
    ix = min(max(int(math.floor((x - geom[0]) / geom[2])), 0), int(geom[3]) - 1)
    iy = min(max(int(math.floor((y - geom[1]) / geom[2])), 0), int(geom[4]) - 1)
    return ix, iy


@njit(cache=True)
def _insert(i, q, w, head, nxt, geom):
    ix, iy = _cell(q[i, 0] * w[0], q[i, 1] * w[1], geom)
    c = iy * int(geom[3]) + ix
    nxt[i] = head[c]
    head[c] = i


@njit(cache=True)
def _nearest(q, x, w, head, nxt, geom):
    """(index, distance) of the node nearest to x, the lowest index on ties:
    exactly the direct scan's answer. Cells are visited in square rings
    around x's cell; every node of ring k + 1 is at least k h from x in
    (x, y) alone, so the search stops once that exceeds the best distance."""
    nx, ny, h = int(geom[3]), int(geom[4]), geom[2]
    cx, cy = _cell(x[0] * w[0], x[1] * w[1], geom)
    best_i, best_d = -1, np.inf
    k = 0
    while True:
        for iy in range(max(cy - k, 0), min(cy + k, ny - 1) + 1):
            edge_y = iy == cy - k or iy == cy + k
            step = 1 if edge_y else 2 * k
            ix = cx - k
            while ix <= cx + k:
                if 0 <= ix < nx:
                    i = head[iy * nx + ix]
                    while i >= 0:
                        d = math.sqrt(_d2(q[i], x, w))
                        if d < best_d or (d == best_d and i < best_i):
                            best_i, best_d = i, d
                        i = nxt[i]
                ix += step if step > 0 else 1
        if (k * h - 1e-9 > best_d) or (cx - k <= 0 and cy - k <= 0 and cx + k >= nx - 1 and cy + k >= ny - 1):
            return best_i, best_d
        k += 1


@njit(cache=True)
def _within(q, x, w, r, r2, head, nxt, geom, out):
    """The nodes with _d2 <= r2 (r2 = r * r), ascending, into out; returns their count."""
    nx = int(geom[3])
    ix0, iy0 = _cell(x[0] * w[0] - r - 1e-9, x[1] * w[1] - r - 1e-9, geom)
    ix1, iy1 = _cell(x[0] * w[0] + r + 1e-9, x[1] * w[1] + r + 1e-9, geom)
    m = 0
    for iy in range(iy0, iy1 + 1):
        for ix in range(ix0, ix1 + 1):
            i = head[iy * nx + ix]
            while i >= 0:
                if _d2(q[i], x, w) <= r2:
                    out[m] = i
                    m += 1
                i = nxt[i]
    out[:m].sort()
    return m


@njit(cache=True)
def _valid(q, caps, lower, upper):
    """planar_kernel.valid of q given its capsule clearances."""
    if not planar_kernel._in_limits(q, lower, upper):
        return False
    for j in range(caps.shape[0]):
        if not caps[j] > 0.0:
            return False
    return True


@njit(cache=True)
def _link(i, p, first_child, next_sib, prev_sib):
    next_sib[i] = first_child[p]
    prev_sib[i] = -1
    if first_child[p] >= 0:
        prev_sib[first_child[p]] = i
    first_child[p] = i


@njit(cache=True)
def _unlink(i, p, first_child, next_sib, prev_sib):
    if prev_sib[i] >= 0:
        next_sib[prev_sib[i]] = next_sib[i]
    else:
        first_child[p] = next_sib[i]
    if next_sib[i] >= 0:
        prev_sib[next_sib[i]] = prev_sib[i]
    next_sib[i] = -1
    prev_sib[i] = -1
