"""One RRT* core for the whole family (the paper's Algorithm 2).

Per iteration: draw one sample (the goal with probability ``goal_bias``),
find the nearest node, Steer by ``planning_range``, check the new
configuration, gather the near set within ``near_radius``, cost *all* near
motions in one batched call, then check motions lazily in order of
``F(near) + Msc(near, new)`` and stop at the first collision-free one (the
paper's choose-parent loop visits the same candidates in any order and keeps
the same minimum). The new node then rewires its near set: a node whose cost
drops through the new node is re-parented, and the change is propagated to
all its descendants. Motion costs are symmetric (the trapezoid rule is), so
the rewiring reuses the batch computed for the parent choice.

Iteration k draws exactly one sample, valid or not, as in the paper.
"""

from __future__ import annotations

import dataclasses as dc
import time
from typing import Callable

import numpy as np

from drake_social.planning.objective import Objective
from drake_social.planning.result import PlannerResult, PlanningInputError
from drake_social.planning.sampling import EllipseSampler, transverse_diameter
from drake_social.planning.space import ConfigurationSpace
from drake_social.planning.validity import ValidityChecker

__all__ = ["RrtStar", "RrtStarOptions"]

@dc.dataclass
class RrtStarOptions:
    """Options of :class:`RrtStar` (configuration-space units).

    Attributes:
        iterations: samples drawn, K.
        planning_range: Steer distance delta.
        near_radius: near-set radius r_near (also the goal-connection radius).
        goal_bias: probability of sampling the goal.
        informed: sample base positions in an XY ellipse after the first solution.
        informed_mode: "paper" or "admissible" (see ``planning.sampling``).
    """

    iterations: int = 2000
    planning_range: float = 1.5
    near_radius: float = 2.5
    goal_bias: float = 0.05
    informed: bool = False
    informed_mode: str = "paper"

    @classmethod
    def from_scenario(cls, planner_options, informed: bool = False) -> "RrtStarOptions":
        p = planner_options
        return cls(p.iterations, p.planning_range, p.near_radius, p.goal_bias, informed, p.informed_mode)


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
    """

    def __init__(
        self,
        space: ConfigurationSpace,
        checker: ValidityChecker,
        objective: Objective,
        options: RrtStarOptions = RrtStarOptions(),
        name: str = "rrt_star",
    ):
        if options.iterations < 1:
            raise ValueError(f"iterations must be >= 1, got {options.iterations}")
        if not (options.planning_range > 0 and options.near_radius > 0):
            raise ValueError("planning_range and near_radius must be > 0")
        if not 0 <= options.goal_bias < 1:
            raise ValueError(f"goal_bias must be in [0, 1), got {options.goal_bias}")
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
            progress: optional ``progress(iteration, best_cost)`` called every
                iteration (for progress bars; keep it cheap).

        Raises:
            PlanningInputError: start or goal invalid. A goal that cannot be
                reached is *not* an error: the result says ``success=False``.
        """
        t0 = time.perf_counter()
        opt = self.options
        start = np.asarray(start, dtype=float)
        goal = np.asarray(goal, dtype=float)
        self._check_endpoints(start, goal)
        space, checker, objective = self.space, self.checker, self.objective

        tree = _Tree()
        tree.add(start, -1, 0.0)
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
            i_new = self._extend(tree, q_rand, counts)
            if i_new >= 0:
                connect_to_goal(i_new)
                if goal_nodes:
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
        return result

    def _extend(self, tree: _Tree, q_rand: np.ndarray, counts: "_Counts") -> int:
        """Steer towards q_rand, choose the parent, insert, rewire (Algorithm 2,
        lines 4-25). Returns the new node's index, or -1 when nothing was added."""
        opt, w, checker = self.options, self.space.weights, self.checker
        nodes = tree.q[: tree.n]
        diff = (nodes - q_rand) * w
        d_rand = np.sqrt(np.einsum("ij,ij->i", diff, diff))
        i_nearest = int(np.argmin(d_rand))
        if d_rand[i_nearest] == 0.0:
            return -1  # already a node (the goal, drawn again by the goal bias)
        q_new = self.space.steer(nodes[i_nearest], q_rand, opt.planning_range, float(d_rand[i_nearest]))
        counts.config += 1
        if not checker.is_valid(q_new):
            return -1

        # Choose the parent: all near costs in one batch, motions checked lazily.
        near = self._near(tree, q_new, i_nearest)
        phi = self.objective.motion_cost(nodes[near], q_new)
        counts.cost += len(near)
        total = tree.cost[near] + phi
        checked: dict[int, bool] = {}
        parent_slot = -1
        for slot in np.argsort(total, kind="stable"):
            counts.motion += 1
            ok = checker.is_motion_valid(nodes[near[slot]], q_new)
            checked[int(slot)] = ok
            if ok:
                parent_slot = int(slot)
                break
        if parent_slot < 0:
            return -1
        i_new = tree.add(q_new, int(near[parent_slot]), float(phi[parent_slot]))

        # Rewire the nodes the new one improves; costs are re-read because an
        # earlier re-parenting may already have lowered a later candidate.
        for slot in np.flatnonzero(tree.cost[i_new] + phi < tree.cost[near]):
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

    def _near(self, tree: _Tree, q_new: np.ndarray, i_nearest: int) -> np.ndarray:
        """Indices of the nodes within ``near_radius`` of q_new (ascending),
        then ``i_nearest`` when it is not among them (r_near < delta), so the
        tree stays connected."""
        diff = (tree.q[: tree.n] - q_new) * self.space.weights
        near = np.flatnonzero(np.einsum("ij,ij->i", diff, diff) <= self.options.near_radius**2)
        if i_nearest not in near:
            near = np.append(near, i_nearest)
        return near

    @staticmethod
    def _xy_length(tree: _Tree, node: int, goal: np.ndarray) -> float:
        pts = np.vstack([tree.q[tree.path_to(node), :2], goal[:2]])
        return float(np.hypot(*np.diff(pts, axis=0).T).sum())

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
