"""The replanner's search: the timed RRT* from where the robot is, seeded
with the path being driven, and its best goal connections.

The tree's costs are exact for the motions as they were costed; a subtree
that rewiring moved in time keeps its edges' costs (approximate). The
replanner therefore takes the best few goal connections in ascending tree
cost (:data:`VERIFY_PATHS`, more up to :data:`MAX_JUDGED` while none is
safe) and judges each exactly
(:mod:`drake_social.planning.replan_eval`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from drake_social.people.prediction import Prediction
from drake_social.planning.objective import Objective, SocialObjective
from drake_social.planning.result import PlanningInputError
from drake_social.planning.rrt_star import RrtStar, RrtStarOptions
from drake_social.planning.rrt_star import compiled

if TYPE_CHECKING:
    from drake_social.planning.replan import Replanner

__all__ = ["MAX_JUDGED", "VERIFY_PATHS", "SearchOutcome", "run_search", "search_objective", "search_planner",
           "tree_path"]

#: Goal connections of the search judged exactly, in ascending tree cost ...
VERIFY_PATHS = 4
#: ... and at most this many when none of the first ones is safe (within the budget).
MAX_JUDGED = 16


class SearchOutcome(NamedTuple):
    """What one replan's search gives the judge."""

    paths: list  #: up to MAX_JUDGED paths (N, 4) from the root to the goal, in ascending tree cost
    iterations: int  #: samples drawn
    deadline_hit: bool  #: stopped by the wall clock before the iteration cap
    message: str  #: what it did, in words


def tree_path(nodes: np.ndarray, parents: np.ndarray, node: int, goal: np.ndarray) -> np.ndarray:
    """The path (N, 4) from the tree's root to ``node`` and on to ``goal``
    (the goal is not repeated when ``node`` is the goal itself)."""
    chain = []
    i = int(node)
    while i >= 0:
        chain.append(i)
        i = int(parents[i])
    path = np.asarray(nodes)[chain[::-1]]
    if not np.array_equal(path[-1], goal):
        path = np.vstack([path, goal[None]])
    return np.ascontiguousarray(path, float)


def search_planner(replanner: "Replanner") -> RrtStar:
    """The RRT* of the replans: the replanner's algorithm and room, no
    optimisation (each search passes its own objective and iteration cap)."""
    options = RrtStarOptions.from_scenario(replanner.scenario.planner, informed=replanner.spec.informed)
    options.optimize = False
    return RrtStar(replanner.space, replanner.checker, replanner.objective, options, name=replanner.spec.name)


def search_objective(replanner: "Replanner", prediction: Prediction) -> Objective:
    """The objective of one search: the replanner's, with this prediction's
    people in its social cost (:meth:`SocialCost.for_prediction`)."""
    social = replanner.social_for(prediction)
    return replanner.objective if social is None else \
        SocialObjective(social, replanner.scenario.social.length_weight)


def run_search(replanner: "Replanner", q: np.ndarray, t_now: float, prediction: Prediction,
               candidate: np.ndarray | None, iterations: int, stop: float | None,
               rng: np.random.Generator) -> SearchOutcome:
    """The timed search from ``q`` at ``t_now`` to the goal, seeded with
    ``candidate`` (or not), stopped at ``iterations`` samples or at the
    ``time.perf_counter()`` value ``stop``; its best goal connections."""
    goal = replanner.goal
    timed = compiled.timed_params(prediction, replanner.scenario.execution, t_now, replanner.safety)
    try:
        tree = replanner.planner.solve_timed(q, goal, rng, timed, seed_path=candidate, deadline=stop,
                                             iterations=iterations, objective=search_objective(replanner, prediction))
    except PlanningInputError as e:
        return SearchOutcome([], 0, False, f"no search: {e}")
    goal_nodes = np.asarray(tree.goal_nodes, np.int64)
    totals = np.asarray(tree.costs)[goal_nodes] + np.asarray(tree.goal_edges, float)
    paths, seen = [], set()
    for g in np.argsort(totals, kind="stable"):
        node = int(goal_nodes[g])
        if node in seen or not np.isfinite(totals[g]):
            continue
        seen.add(node)
        paths.append(tree_path(tree.nodes, tree.parents, node, goal))
        if len(paths) == MAX_JUDGED:
            break
    words = (f"{tree.iterations} samples, {len(tree.nodes)} nodes, {len(goal_nodes)} goal connections"
             + (", stopped at the deadline" if tree.deadline_hit else ""))
    return SearchOutcome(paths, int(tree.iterations), bool(tree.deadline_hit), words)
