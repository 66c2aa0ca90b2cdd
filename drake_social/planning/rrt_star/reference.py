"""The reference RRT* loop in Python, and the planner that runs it or the compiled one.

:class:`RrtStar` checks its inputs and asks
:func:`~drake_social.planning.rrt_star.compiled.compiled_support` whether
the compiled loop (:mod:`~drake_social.planning.rrt_star.compiled`) can plan
the configuration; otherwise, and with ``RrtStarOptions(compiled=False)``,
it runs the loop written here, which is the reference the compiled one is
tested against bit for bit (the algorithm: :mod:`drake_social.planning.rrt_star`).
Either way ``PlannerResult.wall_time`` starts once the inputs are checked and
the kernels loaded: it is the search alone (the optimiser's time, when asked,
is ``optimize_time``).
"""

from __future__ import annotations

import dataclasses as dc
import logging
import math
import time
from typing import Callable

import numpy as np

from drake_social.arguments import real_array, require_callable, require_checker, require_instance
from drake_social.collision.validity import ValidityChecker
from drake_social.limits import MAX_ITERATIONS
from drake_social.planning.objective import Objective
from drake_social.planning.result import PlannerResult, PlanningInputError
from drake_social.planning.rrt_star import compiled
from drake_social.planning.rrt_star.options import NEAR_RADIUS_MODES, RrtStarOptions, default_gamma
from drake_social.planning.sampling import EllipseSampler, transverse_diameter
from drake_social.planning.space import ConfigurationSpace

__all__ = ["KD_TREE_MIN_NODES", "RrtStar"]

_log = logging.getLogger(__name__)

#: The KD-tree serves neighbour queries from this many nodes on.
KD_TREE_MIN_NODES = 2048


class _Neighbors:
    """Exact nearest and near queries: a KD-tree over ``q * w`` of the first
    ``kd_n`` nodes (rebuilt when the nodes added since exceed a sixteenth of
    them, so rebuilds cost O(n log n) in all), the rest scanned directly. KD candidates are taken with a small
    margin and re-measured with the direct scan's arithmetic, so the answers
    are the direct scan's, ties included (lowest index first)."""

    _MARGIN = 1e-9

    def __init__(self, weights: np.ndarray, enabled: bool, min_nodes: int = KD_TREE_MIN_NODES):
        self.w = weights
        self.enabled = enabled
        self.min_nodes = min_nodes
        self.kd = None
        self.kd_n = 0

    def _distances2(self, tree: "_Tree", index: np.ndarray | None, q: np.ndarray) -> np.ndarray:
        diff = ((tree.q[: tree.n] if index is None else tree.q[index]) - q) * self.w
        return np.einsum("ij,ij->i", diff, diff)

    def _update(self, tree: "_Tree") -> bool:
        if not self.enabled or tree.n < self.min_nodes:
            return False
        if self.kd is None or tree.n - self.kd_n > max(256, self.kd_n // 16):
            from scipy.spatial import cKDTree

            self.kd = cKDTree(tree.q[: tree.n] * self.w)
            self.kd_n = tree.n
        return True

    def nearest(self, tree: "_Tree", q: np.ndarray) -> tuple[int, float]:
        """(index, distance) of the node nearest to q (the lowest index on ties)."""
        if not self._update(tree):
            d = np.sqrt(self._distances2(tree, None, q))
            i = int(np.argmin(d))
            return i, float(d[i])
        d_kd, i_kd = self.kd.query(q * self.w, k=2)
        if d_kd[1] > d_kd[0] * (1 + self._MARGIN) + 1e-12:  # a clear KD winner
            cand = i_kd[:1]
        else:  # near-ties: every KD node as near as the first, re-measured exactly
            cand = self.kd.query_ball_point(q * self.w, d_kd[0] * (1 + self._MARGIN) + 1e-12)
        index = np.concatenate([np.sort(np.asarray(cand, dtype=np.int64)), np.arange(self.kd_n, tree.n)])
        d = np.sqrt(self._distances2(tree, index, q))
        k = int(np.argmin(d))
        return int(index[k]), float(d[k])

    def within(self, tree: "_Tree", q: np.ndarray, radius: float) -> np.ndarray:
        """Ascending indices of the nodes within ``radius`` of q."""
        if not self._update(tree):
            return np.flatnonzero(self._distances2(tree, None, q) <= radius**2)
        cand = self.kd.query_ball_point(q * self.w, radius * (1 + self._MARGIN) + 1e-12)
        index = np.concatenate([np.sort(np.asarray(cand, dtype=np.int64)), np.arange(self.kd_n, tree.n)])
        return index[self._distances2(tree, index, q) <= radius**2]


class _Tree:
    """Nodes in arrays that grow geometrically; children as lists for cost propagation.

    The arrays start at ``capacity`` rows and double when full, so memory
    follows the nodes actually added, not the iteration budget K.

    Every node keeps the cost of the motion from its parent, and a node's
    cost is always recomputed as ``cost[parent] + edge`` (as OMPL does)
    rather than shifted by a difference: with non-negative edges a
    descendant is then never cheaper than its ancestor, not even by one ulp,
    so the strict rewiring test can never pick an ancestor of the new node.
    """

    def __init__(self, capacity: int = 256):
        capacity = max(int(capacity), 1)
        self.q = np.empty((capacity, 4))
        self.parent = np.full(capacity, -1, dtype=np.int64)
        self.cost = np.empty(capacity)  # F: cost from the start
        self.edge = np.empty(capacity)  # cost of the motion from the parent
        self.children: list[list[int]] = []
        self.n = 0

    @property
    def capacity(self) -> int:
        return len(self.q)

    def _grow(self) -> None:
        size = 2 * self.capacity
        self.q = np.concatenate([self.q, np.empty((size - len(self.q), 4))])
        self.parent = np.concatenate([self.parent, np.full(size - len(self.parent), -1, dtype=np.int64)])
        self.cost = np.concatenate([self.cost, np.empty(size - len(self.cost))])
        self.edge = np.concatenate([self.edge, np.empty(size - len(self.edge))])

    def add(self, q: np.ndarray, parent: int, edge: float) -> int:
        i = self.n
        if i == self.capacity:
            self._grow()
        self.q[i], self.parent[i], self.edge[i] = q, parent, edge
        self.cost[i] = self.cost[parent] + edge if parent >= 0 else edge
        self.children.append([])
        if parent >= 0:
            self.children[parent].append(i)
        self.n += 1
        return i

    def reparent(self, i: int, new_parent: int, edge: float) -> None:
        """Moves node i under new_parent and updates its whole subtree's cost.

        Raises:
            RuntimeError: new_parent lies in i's subtree (a cycle); the
                planner's strict improvement test rules this out.
        """
        self.children[self.parent[i]].remove(i)
        self.children[new_parent].append(i)
        self.parent[i], self.edge[i] = new_parent, edge
        stack = [i]
        while stack:
            j = stack.pop()
            if j == new_parent:
                raise RuntimeError(f"rewiring node {i} under its descendant {new_parent}")
            self.cost[j] = self.cost[self.parent[j]] + self.edge[j]
            stack.extend(self.children[j])

    def path_to(self, i: int) -> list[int]:
        path = []
        while i >= 0:
            path.append(i)
            i = int(self.parent[i])
        return path[::-1]


@dc.dataclass
class _Counts:
    config: int = 0  # configurations checked
    motion: int = 0  # motions checked
    cost: int = 0  # motions costed


class RrtStar:
    """RRT* over a configuration space with a pluggable objective and checker.

    Args:
        space: bounds, distance and steering.
        checker: configuration and motion validity.
        objective: state and motion costs (path length or social).
        options: iterations, ranges, goal bias, informed sampling.
        name: reported as ``PlannerResult.algorithm``.

    Raises:
        TypeError: an argument of the wrong kind (a checker's name instead of
            a checker, ...), named.
        ValueError: an option outside its range.
    """

    def __init__(
        self,
        space: ConfigurationSpace,
        checker: ValidityChecker,
        objective: Objective,
        options: RrtStarOptions = RrtStarOptions(),
        name: str = "rrt_star",
    ):
        require_instance(options, RrtStarOptions, "RrtStar", "options", "an RrtStarOptions")
        if not 1 <= options.iterations <= MAX_ITERATIONS:
            raise ValueError(f"planner.iterations must be in [1, {MAX_ITERATIONS}], got {options.iterations}")
        if options.near_radius_mode not in NEAR_RADIUS_MODES:
            raise ValueError(
                f"unknown near_radius_mode {options.near_radius_mode!r}; allowed: {', '.join(NEAR_RADIUS_MODES)}"
            )
        if not (np.isfinite(options.near_radius_gamma) and options.near_radius_gamma >= 0):
            raise ValueError(f"near_radius_gamma must be >= 0, got {options.near_radius_gamma}")
        if not (options.planning_range > 0 and options.near_radius > 0):
            raise ValueError("planning_range and near_radius must be > 0")
        if not 0 <= options.goal_bias < 1:
            raise ValueError(f"goal_bias must be in [0, 1), got {options.goal_bias}")
        require_instance(space, ConfigurationSpace, "RrtStar", "space", "a ConfigurationSpace")
        require_checker(checker, "RrtStar")
        require_instance(objective, Objective, "RrtStar", "objective",
                         "an Objective (PathLengthObjective or SocialObjective)")
        if options.informed:
            transverse_diameter(options.informed_mode, 1.0, 1.0, objective)  # validates the mode
            if options.informed_mode == "admissible" and not np.isfinite(objective.xy_length_bound(1.0)):
                raise PlanningInputError(
                    "informed_mode 'admissible' needs an objective that bounds the path length "
                    "(social.length_weight > 0); without it the ellipse would never shrink"
                )
        self.space = space
        self.checker = checker
        self.objective = objective
        self.options = options
        self.name = name

    # ------------------------------------------------------------------

    def _check_endpoints(self, start: np.ndarray, goal: np.ndarray) -> None:
        for label, q in (("start", start), ("goal", goal)):
            if q.shape != (4,) or not np.all(np.isfinite(q)):
                raise PlanningInputError(f"{label} must be 4 finite numbers, got {q}")
            if not self.space.contains(q):
                raise PlanningInputError(
                    f"{label} {q.tolist()} is outside the configuration space "
                    f"[{self.space.lower.tolist()}, {self.space.upper.tolist()}]"
                )
            if not self.checker.is_valid(q):
                raise PlanningInputError(f"{label} configuration {q.tolist()} is in collision")
        if np.array_equal(start, goal):
            raise PlanningInputError(f"start and goal are the same configuration {start.tolist()}: "
                                     "nothing to plan (give a goal different from the start)")

    def solve(
        self,
        start: np.ndarray,
        goal: np.ndarray,
        rng: np.random.Generator,
        progress: Callable[[int, float], None] | None = None,
    ) -> PlannerResult:
        """Runs K iterations and returns the best path to exactly ``goal``.

        Args:
            start, goal: configurations (4,).
            rng: the only source of randomness.
            progress: optional ``progress(iteration, best_cost)`` called for
                every iteration (for progress bars; keep it cheap). The
                compiled loop runs in chunks of ``PROGRESS_CHUNK`` iterations
                and calls it after each chunk for each of the chunk's
                iterations (so at most a chunk late); without a callback the
                chunks are ``CHUNK`` long. Ctrl-C is noticed between chunks.

        Raises:
            TypeError: ``rng`` is not a numpy Generator, ``progress`` not
                callable, start or goal not real numbers.
            PlanningInputError: start or goal not 4 finite numbers, invalid, or the same
                configuration (nothing to plan). A goal that cannot be
                reached is *not* an error: the result says ``success=False``.
        """
        opt = self.options
        require_instance(rng, np.random.Generator, "RrtStar.solve", "rng",
                         "a numpy.random.Generator (numpy.random.default_rng(seed))")
        require_callable(progress, "RrtStar.solve", "progress")
        start = real_array(start, "RrtStar.solve", "start", (4,), layout="[x, y, psi1, psi2]", error=PlanningInputError)
        goal = real_array(goal, "RrtStar.solve", "goal", (4,), layout="[x, y, psi1, psi2]", error=PlanningInputError)
        self._check_endpoints(start, goal)
        space, checker, objective = self.space, self.checker, self.objective

        supported, reason = compiled.compiled_support(checker, objective, opt)
        if supported:
            return self._solve_compiled(start, goal, rng, progress)
        _log.info("%s plans with the Python loop: %s", self.name, reason)
        self._load_python_kernels(start)
        t0 = time.perf_counter()
        tree = _Tree()
        tree.add(start, -1, 0.0)
        neighbors = _Neighbors(space.weights, opt.kd_tree, KD_TREE_MIN_NODES)
        sampler = EllipseSampler(space, start[:2], goal[:2]) if opt.informed else None
        goal_nodes: list[int] = []  # nodes with a valid, costed motion to the goal
        goal_edge_costs: list[float] = []
        history = np.full(opt.iterations, np.inf)
        diameters = np.full(opt.iterations if opt.informed else 0, np.inf)
        best_cost, best_node, first_iteration = np.inf, -1, None
        ellipse_c = np.inf
        counts = _Counts()

        def connect_to_goal(i: int) -> None:
            d = float(space.distance(tree.q[i], goal))
            if d > opt.near_radius:
                return
            if d == 0.0:
                goal_nodes.append(i)
                goal_edge_costs.append(0.0)
                return
            counts.cost += 1
            c = float(objective.motion_cost(tree.q[i], goal)[0])
            counts.motion += 1
            if checker.is_motion_valid(tree.q[i], goal):
                goal_nodes.append(i)
                goal_edge_costs.append(c)

        connect_to_goal(0)
        for k in range(opt.iterations):
            if rng.random() < opt.goal_bias:
                q_rand = goal
            elif sampler is not None and np.isfinite(ellipse_c):
                q_rand = sampler.sample(rng, ellipse_c)
            else:
                q_rand = space.sample_uniform(rng)
            i_new = self._extend(tree, q_rand, counts, neighbors)
            if i_new >= 0:
                connect_to_goal(i_new)
            # The best goal connection, when the tree changed, or when the start's
            # own connection (made before the first sample) is not yet reported.
            if goal_nodes and (i_new >= 0 or best_node < 0):
                totals = tree.cost[goal_nodes] + np.asarray(goal_edge_costs)
                g = int(np.argmin(totals))  # rewiring only lowers costs: never worse
                best_cost, best_node = float(totals[g]), goal_nodes[g]
                if first_iteration is None:
                    first_iteration = k + 1
                if sampler is not None:
                    ellipse_c = transverse_diameter(
                        opt.informed_mode, best_cost, self._xy_length(tree, best_node, goal), objective
                    )
            history[k] = best_cost
            if sampler is not None:
                diameters[k] = ellipse_c
            if progress:
                progress(k + 1, best_cost)

        result = self._result(tree, goal, best_node, best_cost, first_iteration, history, counts, t0)
        result.informed_diameters = diameters
        return self._finish(result)

    def solve_timed(self, start: np.ndarray, goal: np.ndarray, rng: np.random.Generator, timed, *,
                    seed_path: np.ndarray | None = None, deadline: float | None = None,
                    iterations: int | None = None, objective: Objective | None = None) -> compiled.CompiledTree:
        """One search of the replanner: the compiled loop in timed mode.

        Node times start at ``timed.t_root`` at ``start`` and add each
        motion's nominal duration (:func:`drake_social.kinematics.nominal_durations`);
        a motion's social cost is integrated against the predicted people at
        those times, and a motion is valid when the static checker's check
        passes and the robot stays farther than ``timed.safety`` from every
        considered predicted person (:mod:`~drake_social.planning.rrt_star.tree_kernel`'s
        docstring has the rules; rewiring keeps a moved subtree's edge costs,
        so tree costs are approximate: re-evaluate what you use).

        Args:
            start, goal: configurations (4,) (the robot's now, the goal).
            rng: the only source of randomness (same generator state, same
                inputs, iteration cap binding => the same tree bit for bit).
            timed: :class:`~.tree_kernel.TimedParams` from
                :func:`drake_social.planning.rrt_star.compiled.timed_params`
                ``(prediction, scenario.execution, t_now, safety)``.
            seed_path: (M, 4) a warm start's path from ``start`` (e.g. the
                remainder of the current path, ``[q_now] + old[index:]``):
                inserted as a chain before the first sample, up to its first
                invalid motion, its last node's goal connection tried; so
                ``best_cost`` never exceeds that chain's cost when it reaches
                the goal.
            deadline: a ``time.perf_counter()`` value: stop at the first
                chunk (``compiled.DEADLINE_CHUNK`` samples) past it.
            iterations: the cap of samples (None: ``options.iterations``).
            objective: this search's objective (None: the planner's). A
                social objective's per-person parameters must be the
                prediction's people (``SocialCost.for_prediction``).

        Returns:
            The :class:`~drake_social.planning.rrt_star.compiled.CompiledTree`:
            ``nodes``, ``parents``, ``costs``, ``tnode`` (node times),
            ``best_node`` / ``best_cost`` (-1 / inf: no goal connection),
            ``goal_nodes`` / ``goal_edges`` (every goal connection: a
            candidate path is ``nodes[path_to(g)]`` then the goal unless that
            node is the goal, tree cost ``costs[g] + edge``), ``iterations``
            (samples drawn), ``deadline_hit``, ``history`` (best cost per
            sample drawn), ``counts``.

        Raises:
            TypeError: ``rng`` not a numpy Generator, ``timed`` not TimedParams.
            PlanningInputError: start or goal not 4 finite numbers, outside
                the space, invalid for the static checker, or equal; or the
                configuration cannot run compiled (the timed mode has no
                Python loop), with the reason.
            ValueError: ``iterations`` out of range, ``seed_path`` malformed,
                a social objective not for the prediction's people.
        """
        from drake_social.planning.rrt_star.tree_kernel import TimedParams

        require_instance(rng, np.random.Generator, "RrtStar.solve_timed", "rng",
                         "a numpy.random.Generator (numpy.random.default_rng(seed))")
        require_instance(timed, TimedParams, "RrtStar.solve_timed", "timed",
                         "a TimedParams (drake_social.planning.rrt_star.compiled.timed_params)")
        objective = self.objective if objective is None else objective
        require_instance(objective, Objective, "RrtStar.solve_timed", "objective", "an Objective")
        k = self.options.iterations if iterations is None else int(iterations)
        if not 1 <= k <= MAX_ITERATIONS:
            raise ValueError(f"RrtStar.solve_timed: iterations must be in [1, {MAX_ITERATIONS}], got {iterations}")
        start = real_array(start, "RrtStar.solve_timed", "start", (4,), layout="[x, y, psi1, psi2]",
                           error=PlanningInputError)
        goal = real_array(goal, "RrtStar.solve_timed", "goal", (4,), layout="[x, y, psi1, psi2]",
                          error=PlanningInputError)
        self._check_endpoints(start, goal)
        supported, reason = compiled.compiled_support(self.checker, objective, self.options)
        if not supported:
            raise PlanningInputError(f"RrtStar.solve_timed needs the compiled loop: {reason}")
        run = compiled.prepare(self.space, self.checker, objective, self.options, self.gamma, start, goal, timed, k)
        return run.run(rng, deadline=deadline, seed_path=seed_path)

    @property
    def gamma(self) -> float:
        """gamma of the shrinking radius (unused in "fixed" mode)."""
        return self.options.near_radius_gamma or default_gamma(self.space)

    def _solve_compiled(self, start: np.ndarray, goal: np.ndarray, rng: np.random.Generator,
                        progress: Callable[[int, float], None] | None) -> PlannerResult:
        """The compiled loop (:mod:`.compiled`): inputs packed and kernels
        loaded before the clock starts, so ``wall_time`` is the search alone."""
        run = compiled.prepare(self.space, self.checker, self.objective, self.options, self.gamma, start, goal)
        t0 = time.perf_counter()
        out = run.run(rng, progress)
        n = len(out.nodes)
        tree = _Tree(max(n, 1))
        tree.q[:n], tree.parent[:n], tree.cost[:n] = out.nodes, out.parents, out.costs
        tree.n = n
        result = self._result(tree, goal, out.best_node, out.best_cost, out.first_iteration, out.history,
                              _Counts(*out.counts), t0)
        result.informed_diameters = out.diameters
        return self._finish(result)

    def _load_python_kernels(self, start: np.ndarray) -> None:
        """Has numba load (or compile) the social cost's kernel before the
        Python loop's clock starts: one zero-length motion, which costs 0."""
        social = getattr(self.objective, "social", None)
        if self.objective.compiled_form == "social" and social.backend == "numba":
            social.motion_cost(start[None], start[None])

    def _finish(self, result: PlannerResult) -> PlannerResult:
        """Records the raw cost and, when asked, optimises the path (kept only
        when cheaper by the optimiser's margin, :func:`~drake_social.planning.optimize.cheaper`,
        so neither rounding in the recomputed sum nor a processor's last bits
        decide, and the cost reported is never above the planner's own)."""
        result.raw_cost = result.cost
        result.near_radius_mode = self.options.near_radius_mode
        if self.options.optimize and result.success:
            from drake_social.planning.optimize import cheaper, optimize_path

            t_opt = time.perf_counter()
            waypoints, cost = optimize_path(result.waypoints, self.objective, self.checker, self.space)
            if cheaper(cost, result.cost):
                result.waypoints, result.cost = waypoints, cost
            result.optimized = True
            result.optimize_time = time.perf_counter() - t_opt
        return result

    def near_radius(self, n: int) -> float:
        """The near-set radius for a tree of n nodes (the new one included)."""
        r = self.options.near_radius
        if self.options.near_radius_mode == "shrinking" and n > 1:
            r = min(r, self.gamma * (math.log(n) / n) ** 0.25)
        return r

    def _extend(self, tree: _Tree, q_rand: np.ndarray, counts: "_Counts", neighbors: "_Neighbors | None" = None) -> int:
        """Steer towards q_rand, choose the parent, insert, rewire (Algorithm 2,
        lines 4-25). Returns the new node's index, or -1 when nothing was added."""
        opt, checker, objective = self.options, self.checker, self.objective
        if neighbors is None:
            neighbors = _Neighbors(self.space.weights, False)
        i_nearest, d_nearest = neighbors.nearest(tree, q_rand)
        if d_nearest == 0.0:
            return -1  # already a node (the goal, drawn again by the goal bias)
        nodes = tree.q
        q_new = self.space.steer(nodes[i_nearest], q_rand, opt.planning_range, d_nearest)
        counts.config += 1
        if not checker.is_valid(q_new):
            return -1

        near = self._near(tree, q_new, i_nearest, neighbors)
        q_near = nodes[near]
        phi = np.full(len(near), np.inf)  # motion costs near <-> new; inf = not integrated
        lazy = opt.lazy_costs and objective.length_weight > 0  # without lambda the bound prunes nothing
        if not lazy:
            phi[:] = objective.motion_cost(q_near, q_new)
            counts.cost += len(near)
            bound = phi
        elif objective.length_is_cost:
            phi[:] = bound = objective.length_bound(q_near, q_new)
            counts.cost += len(near)
        else:
            bound = objective.length_bound(q_near, q_new)

        def cost(slots: np.ndarray) -> None:
            slots = slots[np.isinf(phi[slots])]
            if len(slots):
                phi[slots] = objective.motion_cost(q_near[slots], q_new)
                counts.cost += len(slots)

        # Choose the parent: motions checked in order of F + Msc (ties: near
        # order), the first collision-free one wins. Lazily, a candidate is
        # integrated only once its bound F + lambda * length is no larger than
        # the cheapest integrated candidate not yet checked, which visits the
        # candidates in exactly the eager order.
        f_near = tree.cost[near]
        checked: dict[int, bool] = {}
        parent_slot = -1
        if lazy and not objective.length_is_cost:
            low = f_near + bound
            by_bound = np.argsort(low, kind="stable")
            pos = 0  # by_bound[:pos] are integrated
            open_ = np.zeros(len(near), dtype=bool)  # integrated, not yet checked
            while True:
                if not open_.any():
                    if pos == len(near):
                        break
                    cost(by_bound[pos : pos + 1])
                    open_[by_bound[pos]] = True
                    pos += 1
                total = f_near + phi
                t_min = total[open_].min()
                stop = pos + int(np.searchsorted(low[by_bound[pos:]], t_min, side="right"))
                if stop > pos:
                    cost(by_bound[pos:stop])
                    open_[by_bound[pos:stop]] = True
                    pos = stop
                    total = f_near + phi
                candidates = np.flatnonzero(open_)
                slot = int(candidates[np.lexsort((candidates, total[candidates]))[0]])
                open_[slot] = False
                counts.motion += 1
                ok = checker.is_motion_valid(q_near[slot], q_new)
                checked[slot] = ok
                if ok:
                    parent_slot = slot
                    break
        else:
            for slot in np.argsort(f_near + phi, kind="stable"):
                counts.motion += 1
                ok = checker.is_motion_valid(q_near[slot], q_new)
                checked[int(slot)] = ok
                if ok:
                    parent_slot = int(slot)
                    break
        if parent_slot < 0:
            return -1
        i_new = tree.add(q_new, int(near[parent_slot]), float(phi[parent_slot]))

        # Rewire the nodes the new one improves; costs are re-read because an
        # earlier re-parenting may already have lowered a later candidate.
        # Costs only fall while rewiring, so the bound test on the costs before
        # it selects every node that can pass the exact test.
        c_new = tree.cost[i_new]
        if lazy:
            cost(np.flatnonzero(c_new + bound < tree.cost[near]))
        for slot in np.flatnonzero(c_new + phi < tree.cost[near]):
            j = int(near[slot])
            if j == tree.parent[i_new] or not tree.cost[i_new] + phi[slot] < tree.cost[j]:
                continue
            ok = checked.get(int(slot))
            if ok is None:
                counts.motion += 1
                ok = checker.is_motion_valid(q_new, nodes[j])
            if ok:
                tree.reparent(j, i_new, float(phi[slot]))
        return i_new

    def _near(self, tree: _Tree, q_new: np.ndarray, i_nearest: int, neighbors: "_Neighbors | None" = None) -> np.ndarray:
        """Indices of the nodes within the near radius of q_new (ascending),
        then ``i_nearest`` when it is not among them (radius < delta), so the
        tree stays connected."""
        if neighbors is None:
            neighbors = _Neighbors(self.space.weights, False)
        near = neighbors.within(tree, q_new, self.near_radius(tree.n + 1))
        if i_nearest not in near:
            near = np.append(near, i_nearest)
        return near

    @staticmethod
    def _xy_length(tree: _Tree, node: int, goal: np.ndarray) -> float:
        pts = np.vstack([tree.q[tree.path_to(node), :2], goal[:2]])
        total = 0.0
        for step in np.hypot(*np.diff(pts, axis=0).T):  # summed in order (the compiled loop's order)
            total += float(step)
        return total

    def _result(self, tree, goal, best_node, best_cost, first_iteration, history, counts, t0):
        nodes = tree.q[: tree.n].copy()
        closest = float(np.min(self.space.distance(nodes, goal)))
        common = dict(
            algorithm=self.name,
            first_solution_iteration=first_iteration,
            cost_history=history,
            tree_size=tree.n,
            num_config_checks=counts.config,
            num_motion_checks=counts.motion,
            num_cost_evaluations=counts.cost,
            closest_distance_to_goal=closest,
            tree_nodes=nodes,
            tree_parents=tree.parent[: tree.n].copy(),
            tree_costs=tree.cost[: tree.n].copy(),
        )
        if best_node < 0:
            msg = (
                f"no collision-free connection to the goal after {self.options.iterations} iterations; "
                f"tree of {tree.n} nodes, closest node {closest:.3g} from the goal "
                f"(near radius {self.options.near_radius})"
            )
            return PlannerResult(
                success=False, message=msg, waypoints=np.zeros((0, 4)), cost=np.inf,
                wall_time=time.perf_counter() - t0, **common,
            )
        waypoints = tree.q[tree.path_to(best_node)]
        if self.space.distance(waypoints[-1], goal) > 0:
            waypoints = np.vstack([waypoints, goal])
        return PlannerResult(
            success=True, message="path found", waypoints=waypoints, cost=best_cost,
            wall_time=time.perf_counter() - t0, **common,
        )
