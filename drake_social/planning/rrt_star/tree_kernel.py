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

__all__ = ["AVAILABLE", "GrowParams", "InformedParams", "Motions", "ObjectiveParams", "ParentChoice", "PeopleGrid",
           "SocialParams", "TimedParams", "TreeState", "grow", "init_state", "reserve", "seed_chain"]


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
    safety_slots: int  #: the first samples the safety check considers (the safety horizon)


class ObjectiveParams(NamedTuple):
    """The objective's compiled form (:class:`drake_social.planning.objective.Objective`'s
    motion cost): what the motion costs read."""

    kind: int  #: 0 = path length, 1 = social
    length_weight: float  #: lambda
    distance_weights: np.ndarray  #: (4,) the objective's distance weights
    social: SocialParams  #: the social cost's inputs (empty for the length objective)
    grid: PeopleGrid  #: the standing people bucketed in cells


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
    objective: ObjectiveParams  #: what a motion's cost reads
    lazy: bool  #: lazy motion costs
    scene: PlanarScene  #: the checker's compiled scene
    informed: InformedParams
    timed: TimedParams  #: the timed mode (disabled: the static loop)


class TreeState(NamedTuple):
    """A run's tree between chunks of :func:`grow` (arrays grow at least
    doubling, before each chunk: :func:`reserve`)."""

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


class Motions(NamedTuple):
    """The candidate motions near -> new of one sample (slot s: from ``near[s]``)."""

    near: np.ndarray  #: (m,) int64 the near nodes, ascending (the nearest node last when outside r)
    q_a: np.ndarray  #: (m, 4) their configurations
    q_b: np.ndarray  #: (m, 4) the new configuration in every row
    t_a: np.ndarray  #: (m,) the motions' times, seconds (timed mode; zeros otherwise)
    t_b: np.ndarray
    f_near: np.ndarray  #: (m,) the near nodes' costs from the start


class ParentChoice(NamedTuple):
    """One sample's parent choice (:func:`_choose_parent`)."""

    slot: int  #: the chosen slot of the :class:`Motions`, -1 when none is valid
    phi: np.ndarray  #: (m,) the motions' costs (inf where the lazy choice never integrated one)
    bound: np.ndarray  #: (m,) lower bounds of phi (lazy: lambda * length), or phi itself
    checked: np.ndarray  #: (m,) int8 their static checks: 0 not made, 1 valid, 2 invalid


# ---- the loop ---------------------------------------------------------------------------------
#
# The compile time shapes the helpers. numba counts every array of a tuple
# argument in and out at each call, so a helper takes the records it reads
# (ObjectiveParams, PlanarScene, TimedParams), not GrowParams whole. Every
# compiled function re-optimises the kernels it calls (the social costs,
# the planar and the people's checks), so the steps of an iteration are
# inlined into the loop (``inline="always"``) and only the costs, the
# people's check, the timed rewiring and the timed goal connections' redo
# are compiled apart, as they were when the loop was one function.


@njit(cache=True)
def grow(rng, it_start, it_stop, params, state):
    """Iterations ``it_start .. it_stop - 1`` of the RRT* run (-1: the start's
    goal connection, before the first sample) with the :class:`GrowParams`
    ``params`` on the :class:`TreeState` ``state`` from :func:`init_state` or
    the previous chunk; returns the new state (its arrays are replaced when
    they need room: :func:`reserve`). Each iteration is OMPL's
    ``RRTstar::solve``'s: sample, nearest, steer, check, near set, choose
    parent, insert, rewire, goal connection, best solution."""
    obj, scene, tp, lazy = params.objective, params.scene, params.timed, params.lazy
    goal, w, r_near = params.goal, params.weights, params.near_radius
    state = reserve(state, it_stop - max(it_start, 0) + 1)  # at most one node and one goal connection per iteration
    near = np.empty(state.q.shape[0], dtype=np.int64)  # the near set's work array
    stack = np.empty(state.q.shape[0], dtype=np.int64)  # the cost propagation's
    for it in range(it_start, it_stop):
        i_new = 0  # before the first sample: the start's goal connection
        if it >= 0:
            q_rand = _sample(rng, goal, params.lower, params.upper, params.goal_bias, params.informed,
                             state.floats[1])
            i_near, d = _nearest(state.q, q_rand, w, state.g_head, state.g_next, state.g_geom)
            i_new = -1
            if d != 0.0:
                q_new = _steer(state.q[i_near], q_rand, d, params.planning_range)
                state.counts[0] += 1
                caps = _clearances(q_new, scene)
                if _valid(q_new, caps, scene.lower, scene.upper):
                    r = _near_radius(state.ints[0], r_near, params.shrinking, params.gamma)
                    m = _near(q_new, i_near, r, state, w, near)
                    motions = _motions_to(near[:m].copy(), q_new, state, tp)
                    choice = _choose_parent(motions, q_new, caps, state, obj, lazy, scene, tp)
                    if choice.slot >= 0:
                        s = choice.slot
                        i_new = _add_node(q_new, caps, motions.near[s], choice.phi[s], motions.t_b[s], state, w)
                        _rewire(i_new, motions, choice, caps, state, obj, lazy, scene, tp, stack)
        if i_new >= 0:
            _connect_goal(i_new, state, goal, w, r_near, obj, scene, tp)
        if it >= 0:
            _update_best(it, i_new, state, goal, w, params.informed, obj, scene, tp)
    return state


# ---- one iteration's steps ----------------------------------------------------------------------


@njit(inline="always", cache=True)
def _sample(rng, goal, lower, upper, goal_bias, informed, ellipse_c):
    """The sample: the goal with probability goal_bias, else uniform in the
    bounds, its base position in the informed ellipse of diameter
    ``ellipse_c`` once there is one (RrtStar's draws, in its order)."""
    if rng.random() < goal_bias:
        return goal.copy()
    q_rand = np.empty(4)
    for c in range(4):
        q_rand[c] = rng.random()
    q_rand = lower + q_rand * (upper - lower)
    if informed.informed and math.isfinite(ellipse_c):
        _ellipse_xy(rng, q_rand, ellipse_c, informed.centre, informed.rotation, informed.focal, lower, upper)
    return q_rand


@njit(inline="always", cache=True)
def _steer(q_near, q_rand, d, delta):
    """q_rand, or the point ``delta`` from q_near towards it (d: their distance)."""
    if d <= delta:
        return q_rand.copy()
    return q_near + (q_rand - q_near) * (delta / d)


@njit(inline="always", cache=True)
def _near_radius(n, r_near, shrinking, gamma):
    """The near set's radius in a tree of n nodes: r_near, or with the
    shrinking radius ``min(r_near, gamma (log(n + 1) / (n + 1))^(1/4))``."""
    if shrinking and n + 1 > 1:
        return min(r_near, gamma * (math.log(n + 1) / (n + 1)) ** 0.25)
    return r_near


@njit(inline="always", cache=True)
def _near(q_new, i_near, r, state, w, out):
    """The near set of q_new into ``out``, its size returned: the nodes within
    r, ascending, then the nearest node ``i_near`` when it is not among them."""
    m = _within(state.q, q_new, w, r, r * r, state.g_head, state.g_next, state.g_geom, out)
    for s in range(m):
        if out[s] == i_near:
            return m
    out[m] = i_near
    return m + 1


@njit(inline="always", cache=True)
def _motions_to(near, q_new, state, tp):
    """The :class:`Motions` from the ``near`` nodes to q_new (timed mode: from
    each near node's time, for its nominal duration)."""
    m = near.shape[0]
    q_a = np.empty((m, 4))
    q_b = np.empty((m, 4))
    for s in range(m):
        q_a[s] = state.q[near[s]]
        q_b[s] = q_new
    t_a = np.zeros(m)
    t_b = np.zeros(m)
    if tp.enabled:
        for s in range(m):
            t_a[s] = state.tnode[near[s]]
            t_b[s] = t_a[s] + _duration(q_a[s], q_new, tp.base_speed, tp.arm_speed)
    f_near = np.empty(m)
    for s in range(m):
        f_near[s] = state.cost[near[s]]
    return Motions(near, q_a, q_b, t_a, t_b, f_near)


@njit(inline="always", cache=True)
def _choose_parent(mo, q_new, caps, state, obj, lazy, scene, tp):
    """The :class:`ParentChoice`: the candidate of least F + Msc (the lowest
    slot on ties) whose motion to q_new (capsule clearances ``caps``) is
    valid, statically and, in timed mode, against the predicted people. The
    motions are all costed, then checked in that order; with ``lazy`` costs
    (social, lambda > 0) a motion is costed only when its bound F + lambda *
    length can still win (the same choice, fewer integrals)."""
    m = mo.near.shape[0]
    checked = np.zeros(m, dtype=np.int8)
    if lazy and obj.kind == 1 and obj.length_weight > 0:
        return _choose_parent_lazy(mo, q_new, caps, checked, state, obj, scene, tp)
    phi = _motion_costs(mo.q_a, mo.q_b, mo.t_a, mo.t_b, obj, tp)
    state.counts[2] += m
    order = np.argsort(mo.f_near + phi, kind="mergesort")
    for o in range(m):
        if _parent_ok(order[o], mo, q_new, caps, checked, state.clear, state.counts, scene, tp):
            return ParentChoice(order[o], phi, phi, checked)
    return ParentChoice(-1, phi, phi, checked)


@njit(inline="always", cache=True)
def _choose_parent_lazy(mo, q_new, caps, checked, state, obj, scene, tp):
    """:func:`_choose_parent` with lazy costs (RrtStar._extend's): a candidate
    is integrated once its bound F + lambda * length is no larger than the
    cheapest integrated candidate not yet checked; the same candidates, order
    and checks."""
    m = mo.near.shape[0]
    phi = np.full(m, np.inf)
    bound = np.empty(m)
    for s in range(m):
        bound[s] = obj.length_weight * math.sqrt(_d2(q_new, mo.q_a[s], obj.distance_weights))
    low = mo.f_near + bound
    by_bound = np.argsort(low, kind="mergesort")
    is_open = np.zeros(m, dtype=np.bool_)
    n_open, pos = 0, 0
    while True:
        if n_open == 0:
            if pos == m:
                break
            _cost_slots(by_bound[pos:pos + 1], phi, mo.q_a, mo.q_b, mo.t_a, mo.t_b, state.counts, obj, tp)
            is_open[by_bound[pos]] = True
            n_open += 1
            pos += 1
        t_min = np.inf
        for s in range(m):
            if is_open[s]:
                t_min = min(t_min, mo.f_near[s] + phi[s])
        stop = pos
        while stop < m and low[by_bound[stop]] <= t_min:
            stop += 1
        if stop > pos:
            _cost_slots(by_bound[pos:stop], phi, mo.q_a, mo.q_b, mo.t_a, mo.t_b, state.counts, obj, tp)
            for t in range(pos, stop):
                is_open[by_bound[t]] = True
            n_open += stop - pos
            pos = stop
        slot, best_total = -1, np.inf
        for s in range(m):  # the cheapest open candidate, the lowest slot on ties
            if is_open[s] and (slot < 0 or mo.f_near[s] + phi[s] < best_total):
                slot, best_total = s, mo.f_near[s] + phi[s]
        is_open[slot] = False
        n_open -= 1
        if _parent_ok(slot, mo, q_new, caps, checked, state.clear, state.counts, scene, tp):
            return ParentChoice(slot, phi, bound, checked)
    return ParentChoice(-1, phi, bound, checked)


@njit(inline="always", cache=True)
def _parent_ok(s, mo, q_new, caps, checked, clear, counts, scene, tp):
    """Whether the motion of slot s (near -> q_new) is valid: statically
    (the verdict kept in ``checked[s]``), then in timed mode against the people."""
    counts[1] += 1
    ok = _static_ok(mo.q_a[s], q_new, clear[mo.near[s]], caps, scene)
    checked[s] = 1 if ok else 2
    if ok and tp.enabled:
        ok = _people_ok(mo.q_a[s], q_new, mo.t_a[s], mo.t_b[s], scene, tp)
    return ok


@njit(inline="always", cache=True)
def _add_node(q_new, caps, p, c, t, state, w):
    """Adds q_new (capsule clearances ``caps``) as the child of node p by a
    motion of cost c, reached at time t (timed mode); returns its index.
    The arrays must have room (:func:`reserve`)."""
    i = state.ints[0]
    state.ints[0] = i + 1
    state.q[i] = q_new
    _insert(i, state.q, w, state.g_head, state.g_next, state.g_geom)
    state.clear[i] = caps
    state.parent[i] = p
    state.edge[i] = c
    state.cost[i] = state.cost[p] + c
    _link(i, p, state.first_child, state.next_sib, state.prev_sib)
    state.tnode[i] = t
    return i


@njit(inline="always", cache=True)
def _rewire(i_new, mo, choice, caps, state, obj, lazy, scene, tp, stack):
    """OMPL's rewiring of the near nodes through the new node ``i_new``
    (capsule clearances ``caps``; ``mo`` and ``choice`` from its parent
    choice): :func:`_rewire_static`, or :func:`_rewire_timed` in timed mode."""
    if tp.enabled:
        _rewire_timed(i_new, mo, choice, caps, state, obj, scene, tp, stack)
    else:
        _rewire_static(i_new, mo, choice, caps, state, obj, lazy, scene, tp, stack)


@njit(inline="always", cache=True)
def _rewire_static(i_new, mo, choice, caps, state, obj, lazy, scene, tp, stack):
    """The rewiring through the new node ``i_new`` (capsule clearances
    ``caps``): each near node that the motion new -> near makes cheaper
    (its cost taken as phi's near -> new) gets the new node as its parent,
    its static check reused from the parent choice where made; its subtree's
    costs follow. With lazy costs the motions whose bound can improve a near
    node are integrated first."""
    phi, bound, checked, near = choice.phi, choice.bound, choice.checked, mo.near
    m = near.shape[0]
    c_new = state.cost[i_new]
    if lazy and obj.kind == 1 and obj.length_weight > 0:
        todo = np.empty(m, dtype=np.int64)
        nt = 0
        for s in range(m):
            if c_new + bound[s] < state.cost[near[s]] and np.isinf(phi[s]):
                todo[nt] = s
                nt += 1
        if nt > 0:
            _cost_slots(todo[:nt], phi, mo.q_a, mo.q_b, mo.t_a, mo.t_b, state.counts, obj, tp)
    cand = np.empty(m, dtype=np.int64)
    nc = 0
    for s in range(m):
        if c_new + phi[s] < state.cost[near[s]]:
            cand[nc] = s
            nc += 1
    for ci in range(nc):
        s = cand[ci]
        j = near[s]
        if j == state.parent[i_new] or not state.cost[i_new] + phi[s] < state.cost[j]:
            continue
        if checked[s] == 0:
            state.counts[1] += 1
            ok = _static_ok(state.q[i_new], state.q[j], caps, state.clear[j], scene)
        else:
            ok = checked[s] == 1
        if ok:
            _reparent(j, i_new, phi[s], state, scene, tp, stack)


@njit(cache=True)
def _rewire_timed(i_new, mo, choice, caps, state, obj, scene, tp, stack):
    """The timed mode's rewiring through the new node ``i_new``: each motion
    new -> near is costed and people-checked from ``tnode[i_new]``, only where
    ``c_new + lambda * length`` (a lower bound of its cost, the social part
    >= 0) can improve the near node, lazy or not (the same rewiring, fewer
    integrals); the parent choice's static checks are reused. A re-parented
    subtree's costs and times follow (:func:`_reparent`)."""
    near, checked = mo.near, choice.checked
    m = near.shape[0]
    q_new = state.q[i_new]
    c_new = state.cost[i_new]
    t_new = state.tnode[i_new]
    ta = np.full(m, t_new)
    tb = np.empty(m)
    for s in range(m):
        tb[s] = t_new + _duration(q_new, mo.q_a[s], tp.base_speed, tp.arm_speed)
    phi = np.full(m, np.inf)
    todo = np.empty(m, dtype=np.int64)
    nt = 0
    for s in range(m):
        j = near[s]
        if j != state.parent[i_new] and \
                c_new + obj.length_weight * math.sqrt(_d2(q_new, mo.q_a[s], obj.distance_weights)) < state.cost[j]:
            todo[nt] = s
            nt += 1
    if nt > 0:
        _cost_slots(todo[:nt], phi, mo.q_b, mo.q_a, ta, tb, state.counts, obj, tp)
    cand = np.empty(m, dtype=np.int64)
    nc = 0
    for s in range(m):
        if c_new + phi[s] < state.cost[near[s]]:
            cand[nc] = s
            nc += 1
    for ci in range(nc):
        s = cand[ci]
        j = near[s]
        if j == state.parent[i_new] or not state.cost[i_new] + phi[s] < state.cost[j]:
            continue
        state.counts[1] += 1
        if checked[s] == 0:
            ok = _static_ok(q_new, state.q[j], caps, state.clear[j], scene)
        else:
            ok = checked[s] == 1
        if ok:
            ok = _people_ok(q_new, state.q[j], ta[s], tb[s], scene, tp)
        if ok:
            _reparent(j, i_new, phi[s], state, scene, tp, stack)


@njit(inline="always", cache=True)
def _reparent(j, i_new, c, state, scene, tp, stack):
    """Node j becomes the child of ``i_new`` by a motion of cost c; its
    subtree's costs are recomputed from its parents (edge costs kept). In
    timed mode its times too, and a moved descendant's motion is
    people-checked again at its new times and cut off (edge cost inf) when
    invalid, so every node of finite cost has a tree path valid at its
    current times."""
    _unlink(j, state.parent[j], state.first_child, state.next_sib, state.prev_sib)
    _link(j, i_new, state.first_child, state.next_sib, state.prev_sib)
    state.parent[j] = i_new
    state.edge[j] = c
    parent, tnode, edge, cost, q = state.parent, state.tnode, state.edge, state.cost, state.q
    stack[0] = j
    top = 1
    while top > 0:
        top -= 1
        k = stack[top]
        if k == i_new:
            raise RuntimeError("rewiring a node under its descendant")
        if tp.enabled:
            t_old = tnode[k]
            tnode[k] = tnode[parent[k]] + _duration(q[parent[k]], q[k], tp.base_speed, tp.arm_speed)
            if k != j and tnode[k] != t_old and edge[k] < np.inf:
                # A moved descendant's motion, checked again at its new times: cut off when invalid.
                state.counts[1] += 1
                if not _people_ok(q[parent[k]], q[k], tnode[parent[k]], tnode[k], scene, tp):
                    edge[k] = np.inf
        cost[k] = cost[parent[k]] + edge[k]
        c = state.first_child[k]
        while c >= 0:
            stack[top] = c
            top += 1
            c = state.next_sib[c]


@njit(inline="always", cache=True)
def _connect_goal(i, state, goal, w, r_near, obj, scene, tp):
    """Tries the motion node i -> goal when the goal is within r_near: costed
    (in timed mode from node i's time), then checked statically and against
    the people; a valid one is a goal connection (0 for a node at the goal;
    the goal arrays must have room: :func:`reserve`)."""
    d = math.sqrt(_d2(goal, state.q[i], w))
    if not d <= r_near:
        return
    c_goal = 0.0
    ok = True
    if d != 0.0:
        state.counts[2] += 1
        a = np.empty((1, 4))
        b = np.empty((1, 4))
        a[0] = state.q[i]
        b[0] = goal
        ta = np.full(1, state.tnode[i])
        tb = np.full(1, state.tnode[i])
        if tp.enabled:
            tb[0] = state.tnode[i] + _duration(state.q[i], goal, tp.base_speed, tp.arm_speed)
        c_goal = _motion_costs(a, b, ta, tb, obj, tp)[0]
        state.counts[1] += 1
        ok = _static_ok(state.q[i], goal, state.clear[i], state.goal_clear, scene)
        if ok and tp.enabled:
            ok = _people_ok(state.q[i], goal, ta[0], tb[0], scene, tp)
    if ok:
        g = state.ints[1]
        state.goal_nodes[g] = i
        state.goal_edges[g] = c_goal
        state.goal_t[g] = state.tnode[i]
        state.ints[1] = g + 1


@njit(inline="always", cache=True)
def _update_best(it, i_new, state, goal, w, informed, obj, scene, tp):
    """After iteration ``it`` (``i_new``: its new node, -1 for none): the best
    goal connection, when the tree changed or the start's own connection
    (made before the first sample) is not yet reported; the informed
    ellipse's diameter; the history. In timed mode a connection made before
    its node's time moved is redone before it can be the best (invalid =>
    inf), and none finite means no solution (yet, or again)."""
    ints, floats = state.ints, state.floats
    if ints[1] > 0 and (i_new >= 0 or ints[2] < 0):
        if tp.enabled:
            g, total = _best_goal_timed(state, goal, w, obj, scene, tp)
        else:
            g, total = _best_goal(state.cost, state.goal_nodes, state.goal_edges, ints[1])
        if g < 0:
            floats[0], ints[2] = np.inf, -1
        else:
            floats[0], ints[2] = total, state.goal_nodes[g]
            if ints[3] < 0:
                ints[3] = it + 1
        if informed.informed:
            if g < 0:
                floats[1] = np.inf
            elif informed.mode == 0:  # "paper": the XY length of the best path's base
                floats[1] = _xy_length(state.q, state.parent, ints[2], goal)
            else:  # "admissible": best cost / (lambda min(w_x, w_y))
                floats[1] = floats[0] / informed.xy_scale if informed.xy_scale > 0 else np.inf
    state.history[it] = floats[0]
    if informed.informed:
        state.diameters[it] = floats[1]


@njit(inline="always", cache=True)
def _best_goal(cost, goal_nodes, goal_edges, count):
    """(slot, total): the goal connection (of the first ``count``) of least
    tree cost + motion cost (the first on ties), (-1, inf) when none is finite."""
    best, g = np.inf, -1
    for t in range(count):
        total = cost[goal_nodes[t]] + goal_edges[t]
        if total < best:
            best, g = total, t
    return g, best


@njit(cache=True)
def _best_goal_timed(state, goal, w, obj, scene, tp):
    """:func:`_best_goal` of the connections checked and costed at their
    node's time now: the best one made at an earlier time is redone first
    (its cost, or inf when the motion is not valid then; 0 at the goal)."""
    while True:
        g, total = _best_goal(state.cost, state.goal_nodes, state.goal_edges, state.ints[1])
        if g < 0 or state.goal_t[g] == state.tnode[state.goal_nodes[g]]:
            return g, total
        i = state.goal_nodes[g]
        state.goal_t[g] = state.tnode[i]
        state.goal_edges[g] = 0.0
        if _d2(goal, state.q[i], w) != 0.0:
            a = np.empty((1, 4))
            b = np.empty((1, 4))
            a[0] = state.q[i]
            b[0] = goal
            ta = np.full(1, state.tnode[i])
            tb = np.full(1, state.tnode[i] + _duration(state.q[i], goal, tp.base_speed, tp.arm_speed))
            state.counts[1] += 1
            if not _people_ok(state.q[i], goal, ta[0], tb[0], scene, tp):
                state.goal_edges[g] = np.inf
            else:
                state.counts[2] += 1
                state.goal_edges[g] = _timed_costs(a, b, ta, tb, obj, tp)[0]


# ---- costs and checks ---------------------------------------------------------------------------


@njit(cache=True)
def _d2(a, b, w):
    d0 = (a[0] - b[0]) * w[0]
    d1 = (a[1] - b[1]) * w[1]
    d2 = (a[2] - b[2]) * w[2]
    d3 = (a[3] - b[3]) * w[3]
    return (d0 * d0 + d2 * d2) + (d1 * d1 + d3 * d3)


@njit(cache=True)
def _duration(q_a, q_b, base_speed, arm_speed):
    """The nominal duration of the motion q_a -> q_b, seconds: exactly
    :func:`drake_social.kinematics.nominal_durations` (the same operations)."""
    base = math.hypot(q_b[0] - q_a[0], q_b[1] - q_a[1]) / base_speed
    arm = max(abs(q_b[2] - q_a[2]) / arm_speed[0], abs(q_b[3] - q_a[3]) / arm_speed[1])
    return max(base, arm)


@njit(inline="always", cache=True)
def _motion_costs(q_a, q_b, t_a, t_b, obj, tp):
    """Objective motion costs (E,) of q_a[e] -> q_b[e], as Objective.motion_cost:
    :func:`_static_costs`, or in timed mode :func:`_timed_costs` (the motions
    driven from t_a[e] to t_b[e])."""
    if tp.enabled:
        return _timed_costs(q_a, q_b, t_a, t_b, obj, tp)
    return _static_costs(q_a, q_b, obj)


@njit(cache=True)
def _static_costs(q_a, q_b, obj):
    """Objective motion costs (E,) of q_a[e] -> q_b[e]: lambda times the
    weighted length, plus for the social objective the motion social cost
    against the standing people (:func:`drake_social.cost.kernel.msc_sums`)."""
    s, g = obj.social, obj.grid
    if obj.kind == 1 and s.people.shape[0] > 0 and s.active.shape[0] > 0:
        sums, n = cost_kernel.msc_sums(q_a, q_b, s.people, s.l1, s.l2, s.object_interest, s.active, s.weights,
                                       s.lever, s.resolution, s.reaches, s.inv_front, s.inv_rear, s.inv_side,
                                       s.threshold, g.point_reach, g.cell, g.x0, g.y0, g.nx, g.ny, g.start, g.order)
        return _objective(q_a, q_b, sums, n, obj.kind, obj.length_weight, obj.distance_weights)
    return _objective(q_a, q_b, np.zeros(0), np.zeros(0, dtype=np.int64), obj.kind, obj.length_weight,
                      obj.distance_weights)


@njit(cache=True)
def _timed_costs(q_a, q_b, t_a, t_b, obj, tp):
    """:func:`_static_costs` with the social cost against the predicted
    people, the motions driven from t_a[e] to t_b[e]
    (:func:`drake_social.cost.timed_kernel.msc_sums_timed`)."""
    s = obj.social
    if obj.kind == 1 and tp.xy.shape[1] > 0 and s.active.shape[0] > 0:
        sums, n = timed_kernel.msc_sums_timed(q_a, q_b, t_a, t_b, tp.xy, tp.theta, tp.present, tp.t0, tp.dt,
                                              tp.max_speeds, s.l1, s.l2, s.object_interest, s.active, s.weights,
                                              s.lever, s.resolution, s.reaches, s.inv_front, s.inv_rear, s.inv_side,
                                              s.threshold, obj.grid.point_reach)
        return _objective(q_a, q_b, sums, n, obj.kind, obj.length_weight, obj.distance_weights)
    return _objective(q_a, q_b, np.zeros(0), np.zeros(0, dtype=np.int64), obj.kind, obj.length_weight,
                      obj.distance_weights)


@njit(inline="always", cache=True)
def _objective(q_a, q_b, sums, n, kind, lam, dw):
    """The objective's costs (E,) of the motions given their social sums and
    step counts (empty: no social part): the social objective's (``kind``
    1) ``sums * (length / n)`` plus lambda times the length when lambda > 0,
    the length objective's lambda times the length."""
    e_count = q_a.shape[0]
    out = np.zeros(e_count)
    length = np.empty(e_count)
    for e in range(e_count):
        length[e] = math.sqrt(_d2(q_b[e], q_a[e], dw))
    if kind == 1:
        if sums.shape[0] > 0:
            for e in range(e_count):
                out[e] += sums[e] * (length[e] / n[e])
        if lam > 0:
            for e in range(e_count):
                out[e] = out[e] + lam * length[e]
    else:
        for e in range(e_count):
            out[e] = lam * length[e]
    return out


@njit(inline="always", cache=True)
def _cost_slots(slots, phi, q_a, q_b, t_a, t_b, counts, obj, tp):
    """phi[slots] = the motion costs q_a[slots] -> q_b[slots] (RrtStar._extend's
    cost()); in timed mode driven from t_a[slots] to t_b[slots]."""
    k = slots.shape[0]
    a, b = np.empty((k, 4)), np.empty((k, 4))
    ta, tb = np.empty(k), np.empty(k)
    for t in range(k):
        a[t], b[t] = q_a[slots[t]], q_b[slots[t]]
        ta[t], tb[t] = t_a[slots[t]], t_b[slots[t]]
    out = _motion_costs(a, b, ta, tb, obj, tp)
    for t in range(k):
        phi[slots[t]] = out[t]
    counts[2] += k


@njit(inline="always", cache=True)
def _clearances(q, scene):
    """The capsule clearances (S,) of q in the planar scene."""
    return planar_kernel.capsule_clearances(q, scene.bodies, scene.robot, scene.env, scene.grid)


@njit(inline="always", cache=True)
def _static_ok(q_a, q_b, c_a, c_b, scene):
    """The planar check of the motion q_a -> q_b given its ends' capsule clearances."""
    return planar_kernel.motion_valid_ends(q_a, q_b, c_a, c_b, scene.lower, scene.upper, scene.bodies, scene.robot,
                                           scene.env, scene.grid, scene.levers)


@njit(cache=True)
def _people_ok(q_a, q_b, t_a, t_b, scene, tp):
    """The motion q_a -> q_b driven from t_a to t_b keeps the robot farther
    than ``tp.safety`` from every considered predicted person over the
    first ``tp.safety_slots`` samples (its end first: the cheap rejection)."""
    if tp.xy.shape[1] == 0:
        return True
    bodies, robot, levers = scene.bodies, scene.robot, scene.levers
    xy, present = tp.xy[:tp.safety_slots], tp.present[:tp.safety_slots]  # the safety horizon's samples
    if not people_kernel.people_clearance(q_b, t_b, bodies, robot, xy, present, tp.radii, tp.max_speeds,
                                          tp.t0, tp.dt) > tp.safety:
        return False
    return people_kernel.motion_clear_of_people(q_a, q_b, t_a, t_b, bodies, robot, levers, xy, present,
                                                tp.radii, tp.max_speeds, tp.t0, tp.dt, tp.safety)


# ---- the tree's state -----------------------------------------------------------------------------


@njit(cache=True)
def init_state(start, iterations, params):
    """The :class:`TreeState` of a run of ``iterations`` iterations with the
    :class:`GrowParams` ``params`` before its first chunk: the tree of the
    start alone."""
    w, scene, tp, informed = params.weights, params.scene, params.timed, params.informed.informed
    cap = 256
    # Nodes bucketed by their weighted (x, y) in square cells (linked lists),
    # so that nearest and near queries visit the nodes of nearby cells only.
    g_geom = _grid_geometry(params.lower, params.upper, w, params.near_radius)
    diameters = np.full(iterations if informed else 0, np.inf)
    state = TreeState(
        q=np.empty((cap, 4)), parent=np.full(cap, -1, dtype=np.int64), cost=np.zeros(cap), edge=np.zeros(cap),
        first_child=np.full(cap, -1, dtype=np.int64), next_sib=np.full(cap, -1, dtype=np.int64),
        prev_sib=np.full(cap, -1, dtype=np.int64), clear=np.empty((cap, scene.robot.shape[0])),
        g_next=np.full(cap, -1, dtype=np.int64), goal_nodes=np.empty(16, dtype=np.int64), goal_edges=np.empty(16),
        counts=np.zeros(3, dtype=np.int64), history=np.full(iterations, np.inf), diameters=diameters,
        g_head=np.full(int(g_geom[3]) * int(g_geom[4]), -1, dtype=np.int64), g_geom=g_geom,
        goal_clear=_clearances(params.goal, scene),
        ints=np.array([1, 0, -1, -1], dtype=np.int64),  # n, goal nodes, best node, first solution iteration
        floats=np.array([np.inf, np.inf]),  # best cost, ellipse diameter
        tnode=np.zeros(cap), goal_t=np.zeros(16),
    )
    state.q[0] = start
    _insert(0, state.q, w, state.g_head, state.g_next, g_geom)
    state.clear[0] = _clearances(start, scene)
    if tp.enabled:
        state.tnode[0] = tp.t_root
    return state


@njit(inline="always", cache=True)
def reserve(state, count):
    """``state`` with room for ``count`` more nodes and as many more goal
    connections (an array that grows at least doubles, so that a run's
    copies stay linear in its size); the same state when it has the room."""
    if state.ints[0] + count > state.q.shape[0]:
        state = _enlarge(state, max(2 * state.q.shape[0], state.ints[0] + count))
    if state.ints[1] + count > state.goal_nodes.shape[0]:
        state = _enlarge_goals(state, max(2 * state.goal_nodes.shape[0], state.ints[1] + count))
    return state


@njit(cache=True)
def _enlarge(state, cap):
    """``state`` with room for ``cap`` nodes (the node arrays copied into larger ones)."""
    n = state.ints[0]
    q = np.empty((cap, 4))
    q[:n] = state.q[:n]
    clear = np.empty((cap, state.clear.shape[1]))
    clear[:n] = state.clear[:n]
    extra = cap - n
    none = np.full(extra, -1, dtype=np.int64)
    return TreeState(
        q=q, parent=np.concatenate((state.parent[:n], none)), cost=np.concatenate((state.cost[:n], np.zeros(extra))),
        edge=np.concatenate((state.edge[:n], np.zeros(extra))),
        first_child=np.concatenate((state.first_child[:n], none)),
        next_sib=np.concatenate((state.next_sib[:n], none)), prev_sib=np.concatenate((state.prev_sib[:n], none)),
        clear=clear, g_next=np.concatenate((state.g_next[:n], none)), goal_nodes=state.goal_nodes,
        goal_edges=state.goal_edges, counts=state.counts, history=state.history, diameters=state.diameters,
        g_head=state.g_head, g_geom=state.g_geom, goal_clear=state.goal_clear, ints=state.ints, floats=state.floats,
        tnode=np.concatenate((state.tnode[:n], np.zeros(extra))), goal_t=state.goal_t,
    )


@njit(cache=True)
def _enlarge_goals(state, cap):
    """``state`` with room for ``cap`` goal connections (the goal arrays copied into larger ones)."""
    g = state.ints[1]
    nodes = np.empty(cap, dtype=np.int64)
    nodes[:g] = state.goal_nodes[:g]
    edges = np.empty(cap)
    edges[:g] = state.goal_edges[:g]
    times = np.zeros(cap)
    times[:g] = state.goal_t[:g]
    return TreeState(
        q=state.q, parent=state.parent, cost=state.cost, edge=state.edge, first_child=state.first_child,
        next_sib=state.next_sib, prev_sib=state.prev_sib, clear=state.clear, g_next=state.g_next, goal_nodes=nodes,
        goal_edges=edges, counts=state.counts, history=state.history, diameters=state.diameters, g_head=state.g_head,
        g_geom=state.g_geom, goal_clear=state.goal_clear, ints=state.ints, floats=state.floats, tnode=state.tnode,
        goal_t=times,
    )


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
    obj, scene, tp, w = params.objective, params.scene, params.timed, params.weights
    state = reserve(state, seed.shape[0])
    a = np.empty((1, 4))
    b = np.empty((1, 4))
    ta = np.zeros(1)
    tb = np.zeros(1)
    prev = 0
    for k in range(1, seed.shape[0]):
        qk = seed[k].copy()
        if _d2(qk, state.q[prev], w) == 0.0:
            continue
        state.counts[0] += 1
        caps = _clearances(qk, scene)
        if not _valid(qk, caps, scene.lower, scene.upper):
            break
        a[0] = state.q[prev]
        b[0] = qk
        if tp.enabled:
            ta[0] = state.tnode[prev]
            tb[0] = ta[0] + _duration(state.q[prev], qk, tp.base_speed, tp.arm_speed)
        state.counts[1] += 1
        ok = _static_ok(state.q[prev], qk, state.clear[prev], caps, scene)
        if ok and tp.enabled:
            ok = _people_ok(state.q[prev], qk, ta[0], tb[0], scene, tp)
        if not ok:
            break
        state.counts[2] += 1
        prev = _add_node(qk, caps, prev, _motion_costs(a, b, ta, tb, obj, tp)[0], tb[0], state, w)
    if prev > 0:  # the chain's last node's goal connection
        _connect_goal(prev, state, params.goal, w, params.near_radius, obj, scene, tp)
    return state


# ---- geometry and the node grid ---------------------------------------------------------------------


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
