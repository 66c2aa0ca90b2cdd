"""The paper's planners as configurations of the one RRT* core.

=========================  ======================  ==============
algorithm                  objective               sampling
=========================  ======================  ==============
rrt_star                   path length             uniform
social_rrt_star            multi-point social      uniform
base_rrt_star              base-only social        uniform
informed_social_rrt_star   multi-point social      XY ellipse
informed_base_rrt_star     base-only social        XY ellipse
=========================  ======================  ==============

Social objectives add ``social.length_weight * length`` (lambda) when > 0.
"""

from __future__ import annotations

import numpy as np

from drake_social.arguments import (
    real_array,
    require_callable,
    require_checker,
    require_choice,
    require_instance,
    require_int,
    require_scenario,
)
from drake_social.cost.social import SocialCost
from drake_social.kinematics import config_distance
from drake_social.planning.objective import Objective, PathLengthObjective, SocialObjective
from drake_social.planning.result import PlannerResult
from drake_social.planning.rrt_star import RrtStar, RrtStarOptions
from drake_social.planning.space import ConfigurationSpace
from drake_social.collision.validity import ValidityChecker
from drake_social.limits import MAX_ITERATIONS
from drake_social.scenario import ALGORITHMS

__all__ = ["base_only_weights", "evaluate_path", "make_objective", "make_planner", "plan"]


def base_only_weights(num_points: int) -> np.ndarray:
    """Weight 1 on the base, 0 on the arm and object (the paper's base-only baseline)."""
    w = np.zeros(num_points)
    w[0] = 1.0
    return w


def make_objective(scenario, algorithm: str) -> Objective:
    """The objective of ``algorithm`` for ``scenario``.

    Raises:
        TypeError: ``scenario`` is not a Scenario, ``algorithm`` not a string.
        ValueError: an unknown algorithm.
    """
    require_scenario(scenario, "make_objective")
    require_choice(algorithm, "make_objective", "algorithm", ALGORITHMS)
    if algorithm == "rrt_star":
        return PathLengthObjective(scenario.planner.distance_weights)
    social = SocialCost.from_scenario(scenario)
    if "base" in algorithm:
        social = social.with_weights(base_only_weights(social.geometry.num_interest_points))
    return SocialObjective(social, scenario.social.length_weight)


def make_planner(scenario, checker: ValidityChecker, algorithm: str | None = None) -> RrtStar:
    """An :class:`RrtStar` configured as ``algorithm`` (default: the scenario's).

    Raises:
        TypeError, ValueError: an argument is not what is allowed (named).
    """
    require_scenario(scenario, "make_planner")
    require_checker(checker, "make_planner")
    require_choice(algorithm, "make_planner", "algorithm", ALGORITHMS, optional=True)
    algorithm = algorithm or scenario.planner.algorithm
    objective = make_objective(scenario, algorithm)
    options = RrtStarOptions.from_scenario(scenario.planner, informed=algorithm.startswith("informed"))
    return RrtStar(ConfigurationSpace.from_scenario(scenario), checker, objective, options, name=algorithm)


def evaluate_path(scenario, waypoints: np.ndarray, objective: Objective | None = None) -> dict[str, float]:
    """The parts of a path's cost, recomputed from its waypoints.

    Returns:
        ``social_cost_full`` (the scenario's weights), ``social_cost_planner``
        (the objective's own social weights; equal to full for rrt_star),
        ``objective`` (when given), ``path_length`` (plain configuration
        norm) and ``base_length`` (metres).
    """
    require_scenario(scenario, "evaluate_path")
    wp = real_array(waypoints, "evaluate_path", "waypoints", (None, 4), layout="rows [x, y, psi1, psi2]",
                    rows=(1, None), row_name="waypoint")
    a, b = wp[:-1], wp[1:]
    full = SocialCost.from_scenario(scenario)
    out = {
        "social_cost_full": float(full.motion_cost(a, b).sum()) if len(a) else 0.0,
        "path_length": float(config_distance(a, b).sum()),
        "base_length": float(np.hypot(*(b - a)[:, :2].T).sum()),
    }
    planner_social = objective.social if isinstance(objective, SocialObjective) else full
    out["social_cost_planner"] = float(planner_social.motion_cost(a, b).sum()) if len(a) else 0.0
    if objective is not None:
        out["objective"] = float(objective.motion_cost(a, b).sum()) if len(a) else 0.0
    return out


def plan(
    scenario,
    checker: ValidityChecker,
    *,
    algorithm: str | None = None,
    iterations: int | None = None,
    seed: int | None = None,
    progress=None,
) -> PlannerResult:
    """Plans ``scenario`` and fills in the cost parts of the result.

    Args:
        scenario: a validated :class:`drake_social.scenario.Scenario`.
        checker: the validity checker (Drake or numpy).
        algorithm: overrides ``scenario.planner.algorithm``.
        iterations: overrides ``scenario.planner.iterations``.
        seed: overrides ``scenario.random_seed``; the planner's generator is
            ``numpy.random.default_rng(seed)``.
        progress: optional ``progress(iteration, best_cost)`` callback.

    Raises:
        TypeError: an argument of the wrong kind (a checker's name instead
            of a checker, a file name instead of a Scenario, ...), named.
        ValueError: an unknown algorithm, a negative seed, iterations
            outside [1, MAX_ITERATIONS].
        PlanningInputError: the start or goal is unusable (from the planner).
    """
    import copy

    require_scenario(scenario, "plan")
    require_checker(checker, "plan")
    require_choice(algorithm, "plan", "algorithm", ALGORITHMS, optional=True)
    require_int(seed, "plan", "seed", minimum=0, optional=True)
    require_callable(progress, "plan", "progress")
    require_int(iterations, "plan", "iterations", minimum=1, maximum=MAX_ITERATIONS, optional=True)
    if iterations is not None:
        scenario = copy.deepcopy(scenario)
        scenario.planner.iterations = int(iterations)
    planner = make_planner(scenario, checker, algorithm)
    seed = scenario.random_seed if seed is None else int(seed)
    result = planner.solve(
        np.asarray(scenario.start, float), np.asarray(scenario.goal, float), np.random.default_rng(seed), progress
    )
    result.seed = seed
    if result.success:
        parts = evaluate_path(scenario, result.waypoints, planner.objective)
        result.social_cost_full = parts["social_cost_full"]
        result.social_cost_planner = parts["social_cost_planner"]
        result.path_length = parts["path_length"]
        result.base_length = parts["base_length"]
    return result
