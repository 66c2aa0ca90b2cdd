"""The replanner's search: the timed RRT* from where the robot is, seeded
with the path being driven, and its best goal connections.

The search reads a :class:`SearchSetup` (the RRT*, the goal, the execution
limits that time the tree's nodes, the safety distance and the static
objective), not the replanner: the replanner builds one and passes it.

The tree's costs are exact for the motions as they were costed; a subtree
that rewiring moved in time keeps its edges' costs (approximate). The
replanner therefore takes the best few goal connections in ascending tree
cost and judges each exactly (:mod:`drake_social.planning.replan_eval`,
whose :data:`~drake_social.planning.replan_eval.VERIFY_PATHS` and
:data:`~drake_social.planning.replan_eval.MAX_JUDGED` say how many).
"""

from __future__ import annotations

import math

from typing import NamedTuple

import numpy as np

from drake_social.collision.validity import CompiledSceneChecker
from drake_social.cost.social import SocialCost
from drake_social.people.prediction import Prediction
from drake_social.planning.algorithms import AlgorithmSpec
from drake_social.planning.objective import Objective, SocialObjective
from drake_social.planning.replan_eval import MAX_JUDGED
from drake_social.planning.result import PlanningInputError
from drake_social.planning.rrt_star import RrtStar, RrtStarOptions
from drake_social.planning.rrt_star import compiled
from drake_social.planning.space import ConfigurationSpace
from drake_social.scenario.schema import ExecutionOptions, PlannerOptions

__all__ = ["SearchOutcome", "SearchSetup", "run_search", "search_objective", "search_planner", "tree_path"]


class SearchSetup(NamedTuple):
    """What every search of one replanner reads (built once, by the replanner)."""

    planner: RrtStar  #: the RRT* every search runs (:func:`search_planner`)
    goal: np.ndarray  #: (4,) the goal configuration
    execution: ExecutionOptions  #: its max_base_speed and arm_max_velocity time the tree's nodes
    safety: float  #: a motion coming within this many metres of a predicted person is invalid
    objective: Objective  #: the static objective (a length objective's search runs it as it is)
    length_weight: float  #: lambda of a social search's objective (:func:`search_objective`)
    safety_horizon: float = math.inf  #: seconds of the prediction the safety check considers


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


def search_planner(options: PlannerOptions, spec: AlgorithmSpec, space: ConfigurationSpace,
                   checker: CompiledSceneChecker, objective: Objective) -> RrtStar:
    """The RRT* of the replans: the algorithm ``spec`` with the scenario's
    planner ``options`` in the room (``space``, ``checker``), no
    optimisation (each search passes its own objective and iteration cap)."""
    rrt_options = RrtStarOptions.from_scenario(options, informed=spec.informed)
    rrt_options.optimize = False
    return RrtStar(space, checker, objective, rrt_options, name=spec.name)


def search_objective(setup: SearchSetup, social: SocialCost | None) -> Objective:
    """The objective of one search: the static one for the length objective
    (``social`` None), else the social cost of this search's prediction
    (:meth:`SocialCost.for_prediction`) with the setup's length weight."""
    return setup.objective if social is None else SocialObjective(social, setup.length_weight)


def run_search(setup: SearchSetup, social: SocialCost | None, q: np.ndarray, t_now: float, prediction: Prediction,
               candidate: np.ndarray | None, iterations: int, stop: float | None,
               rng: np.random.Generator) -> SearchOutcome:
    """The timed search from ``q`` at ``t_now`` to the goal among the people
    of ``prediction`` (``social``: their social cost, None for the length
    objective), seeded with ``candidate`` (or not), stopped at ``iterations``
    samples or at the ``time.perf_counter()`` value ``stop``; its best goal
    connections (at most :data:`~drake_social.planning.replan_eval.MAX_JUDGED`)."""
    goal = setup.goal
    timed = compiled.timed_params(prediction, setup.execution, t_now, setup.safety, setup.safety_horizon)
    try:
        tree = setup.planner.solve_timed(q, goal, rng, timed, seed_path=candidate, deadline=stop,
                                         iterations=iterations, objective=search_objective(setup, social))
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
