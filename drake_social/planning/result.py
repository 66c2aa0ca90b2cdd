"""What a planner returns."""

from __future__ import annotations

import dataclasses as dc
from typing import Any

import numpy as np

__all__ = ["PlannerResult", "NoPathError", "PlanningInputError"]


class PlanningInputError(ValueError):
    """Start or goal is unusable (in collision, outside the space)."""


class NoPathError(RuntimeError):
    """Raised only on request (``result.raise_if_failed()``); planners return results."""


@dc.dataclass
class PlannerResult:
    """A planned path and how it was found.

    Attributes:
        algorithm: the planner's name (one of ``scenario.ALGORITHMS``).
        success: whether a path from start to exactly the goal was found.
        message: a human-readable summary (why it failed, when it did).
        waypoints: (N, 4) configurations from start to goal; (0, 4) on failure.
        cost: the planner's objective along the returned path (inf on
            failure): the optimised path's when ``optimized``, else the
            tree's (then equal to ``raw_cost``).
        social_cost_full: the social integral with the scenario's full
            multi-point weights (comparable across planners).
        social_cost_planner: the social integral with the planner's own weights.
        path_length: configuration-space length (plain norm).
        base_length: XY length of the base's path, metres.
        first_solution_iteration: 1-based iteration of the first solution, or None.
        cost_history: (K,) best objective after each iteration (inf before a solution).
        tree_size: number of nodes in the tree.
        num_config_checks: configurations checked for validity.
        num_motion_checks: motions checked for validity.
        num_cost_evaluations: motions whose cost was computed.
        wall_time: seconds spent in the search (the compiled loop: not the
            one-off load of its machine code from numba's cache at its first
            call in a process); the optimiser's time is ``optimize_time``.
        seed: the seed the random generator came from, when known.
        closest_distance_to_goal: configuration distance of the tree's closest
            node to the goal (useful on failure).
        tree_nodes: (n, 4) tree configurations; tree_parents: (n,) parent index
            (-1: root); tree_costs: (n,) cost from the start F of every node.
        informed_diameters: (K,) the informed ellipse's transverse diameter in
            force after each iteration (inf: uniform sampling); empty when the
            planner is not informed.
        optimized: whether the path was optimised after planning
            (``planner.optimize``); ``cost`` and ``waypoints`` are then the
            optimised ones and ``cost_history`` stays the tree's.
        raw_cost: the tree path's cost before optimisation (= cost when not
            optimised; inf on failure).
        optimize_time: seconds spent optimising the path after the search
            (0 when not optimised).
        near_radius_mode: "fixed" or "shrinking" (see ``planning.rrt_star``).
    """

    algorithm: str
    success: bool
    message: str
    waypoints: np.ndarray
    cost: float
    social_cost_full: float = float("nan")
    social_cost_planner: float = float("nan")
    path_length: float = float("nan")
    base_length: float = float("nan")
    first_solution_iteration: int | None = None
    cost_history: np.ndarray = dc.field(default_factory=lambda: np.zeros(0))
    tree_size: int = 0
    num_config_checks: int = 0
    num_motion_checks: int = 0
    num_cost_evaluations: int = 0
    wall_time: float = 0.0
    seed: int | None = None
    closest_distance_to_goal: float = float("nan")
    tree_nodes: np.ndarray = dc.field(default_factory=lambda: np.zeros((0, 4)))
    tree_parents: np.ndarray = dc.field(default_factory=lambda: np.zeros(0, dtype=int))
    tree_costs: np.ndarray = dc.field(default_factory=lambda: np.zeros(0))
    informed_diameters: np.ndarray = dc.field(default_factory=lambda: np.zeros(0))
    optimized: bool = False
    raw_cost: float = float("nan")
    optimize_time: float = 0.0
    near_radius_mode: str = "fixed"

    def raise_if_failed(self) -> "PlannerResult":
        if not self.success:
            raise NoPathError(self.message)
        return self

    def summary(self) -> str:
        """One line for the terminal."""
        if not self.success:
            return f"{self.algorithm}: no path ({self.message})"
        cost = f"cost {self.cost:.4g}" + (f" (raw {self.raw_cost:.4g})" if self.optimized else "")
        seconds = f"{self.wall_time:.3f} s" + (f" + {self.optimize_time:.3f} s optimising" if self.optimized else "")
        return (
            f"{self.algorithm}: {len(self.waypoints)} waypoints, {cost}, "
            f"social (full weights) {self.social_cost_full:.4g}, base path {self.base_length:.2f} m, "
            f"first solution at iteration {self.first_solution_iteration}, tree {self.tree_size} nodes, "
            f"{seconds}"
        )

    def to_record(self) -> dict[str, Any]:
        """The planner's part of a run record, JSON-ready (the tree is left out).

        Keys and units: ``drake_social.io.records.PLANNER_FIELDS`` (``planning_time`` is
        :attr:`wall_time`); non-finite numbers become None.
        """

        def num(x):
            return None if x is None or not np.isfinite(x) else float(x)

        return {
            "algorithm": self.algorithm,
            "success": self.success,
            "message": self.message,
            "seed": self.seed,
            "planning_time": float(self.wall_time),
            "optimize_time": float(self.optimize_time),
            "cost": num(self.cost),
            "raw_cost": num(self.raw_cost),
            "optimized": self.optimized,
            "near_radius_mode": self.near_radius_mode,
            "first_solution_iteration": self.first_solution_iteration,
            "tree_size": int(self.tree_size),
            "num_config_checks": int(self.num_config_checks),
            "num_motion_checks": int(self.num_motion_checks),
            "num_cost_evaluations": int(self.num_cost_evaluations),
            "num_waypoints": int(len(self.waypoints)),
            "closest_distance_to_goal": num(self.closest_distance_to_goal),
            "waypoints": np.asarray(self.waypoints).tolist(),
            "cost_history": [num(c) for c in np.asarray(self.cost_history)],
        }
