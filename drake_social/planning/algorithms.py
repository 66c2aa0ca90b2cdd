"""The paper's planners as configurations of the one RRT* core: one table.

Every algorithm is an :class:`AlgorithmSpec` in :data:`ALGORITHM_SPECS`:
its objective (path length or the social integral), the social weights
(the scenario's on every interest point, or the base alone) and its sampler
(uniform, or informed: an XY ellipse once a solution exists). Code that
needs to tell algorithms apart looks their spec up (:func:`algorithm_spec`);
nothing reads meaning from a name.

Social objectives add ``social.length_weight * length`` (lambda) when > 0.
"""

from __future__ import annotations

import dataclasses as dc
from types import MappingProxyType
from typing import Literal, Mapping

import numpy as np

from drake_social.arguments import (
    real_array,
    require_callable,
    require_checker,
    require_choice,
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

__all__ = [
    "ALGORITHM_SPECS",
    "AlgorithmSpec",
    "algorithm_spec",
    "base_only_weights",
    "evaluate_path",
    "make_objective",
    "make_planner",
    "plan",
]

#: Values of :attr:`AlgorithmSpec.objective`.
OBJECTIVES = ("length", "social")
#: Values of :attr:`AlgorithmSpec.weights`.
WEIGHTS = ("all_points", "base_only")
#: Values of :attr:`AlgorithmSpec.sampler`.
SAMPLERS = ("uniform", "informed")


@dc.dataclass(frozen=True)
class AlgorithmSpec:
    """What one planner of the family is: a configuration of :class:`RrtStar`.

    Attributes:
        name: the name users give (``planner.algorithm``, ``--algorithm``).
        objective: ``"length"`` (configuration-space path length, weighted by
            ``planner.distance_weights``) or ``"social"`` (the motion social
            cost Msc plus ``social.length_weight`` times the length).
        weights: the social weights of a social objective: ``"all_points"``
            (the scenario's ``social.weights``, the paper's multi-point cost)
            or ``"base_only"`` (weight 1 on the base, 0 elsewhere). Must be
            ``"all_points"`` for the length objective (it has no weights).
        sampler: ``"uniform"`` over the configuration space, or
            ``"informed"`` (base positions in an XY ellipse once a solution
            exists; see :mod:`drake_social.planning.sampling`).
        description: one line for listings and documentation.

    Raises:
        ValueError: a field outside its allowed values (named).
    """

    name: str
    objective: Literal["length", "social"]
    weights: Literal["all_points", "base_only"]
    sampler: Literal["uniform", "informed"]
    description: str

    def __post_init__(self):
        for field, allowed in (("objective", OBJECTIVES), ("weights", WEIGHTS), ("sampler", SAMPLERS)):
            if getattr(self, field) not in allowed:
                raise ValueError(f"AlgorithmSpec {self.name!r}: unknown {field} {getattr(self, field)!r}; "
                                 f"allowed: {', '.join(allowed)}")
        if self.objective == "length" and self.weights != "all_points":
            raise ValueError(f"AlgorithmSpec {self.name!r}: the length objective has no social weights "
                             f"(weights must be 'all_points', got {self.weights!r})")

    @property
    def informed(self) -> bool:
        """Whether the planner samples in the informed ellipse."""
        return self.sampler == "informed"


def _table(*specs: AlgorithmSpec) -> Mapping[str, AlgorithmSpec]:
    return MappingProxyType({s.name: s for s in specs})


#: Every planner, by name, in the order of ``drake_social.scenario.ALGORITHMS``
#: (a test keeps the two equal).
ALGORITHM_SPECS: Mapping[str, AlgorithmSpec] = _table(
    AlgorithmSpec("rrt_star", "length", "all_points", "uniform",
                  "RRT*: the shortest path in configuration space (the paper's baseline)"),
    AlgorithmSpec("social_rrt_star", "social", "all_points", "uniform",
                  "Social Risk-RRT*: the social cost of every interest point (base, arm, object)"),
    AlgorithmSpec("base_rrt_star", "social", "base_only", "uniform",
                  "Risk-RRT* with the social cost of the base alone (the paper's base-only baseline)"),
    AlgorithmSpec("informed_social_rrt_star", "social", "all_points", "informed",
                  "Risk-Informed-RRT*: the multi-point social cost, ellipse sampling after the first solution"),
    AlgorithmSpec("informed_base_rrt_star", "social", "base_only", "informed",
                  "Risk-Informed-RRT* with the base-only social cost"),
)


def algorithm_spec(algorithm: str | AlgorithmSpec, who: str = "algorithm_spec",
                   specs: Mapping[str, AlgorithmSpec] = ALGORITHM_SPECS) -> AlgorithmSpec:
    """The spec of ``algorithm`` (a spec is returned as it is).

    Args:
        algorithm: a name of ``specs`` or an :class:`AlgorithmSpec`.
        who: the caller's name, for the error message.
        specs: the table to look the name up in.

    Raises:
        TypeError: neither a string nor a spec.
        ValueError: an unknown name; the message lists the known ones.
    """
    if isinstance(algorithm, AlgorithmSpec):
        return algorithm
    require_choice(algorithm, who, "algorithm", tuple(specs))
    return specs[algorithm]


def base_only_weights(num_points: int) -> np.ndarray:
    """Weight 1 on the base, 0 on the arm and object (the paper's base-only baseline)."""
    w = np.zeros(num_points)
    w[0] = 1.0
    return w


def make_objective(scenario, algorithm: str | AlgorithmSpec) -> Objective:
    """The objective of ``algorithm`` (a name or a spec) for ``scenario``.

    Raises:
        TypeError: ``scenario`` is not a Scenario, ``algorithm`` not a string or spec.
        ValueError: an unknown algorithm.
    """
    require_scenario(scenario, "make_objective")
    spec = algorithm_spec(algorithm, "make_objective")
    if spec.objective == "length":
        return PathLengthObjective(scenario.planner.distance_weights)
    social = SocialCost.from_scenario(scenario)
    if spec.weights == "base_only":
        social = social.with_weights(base_only_weights(social.geometry.num_interest_points))
    return SocialObjective(social, scenario.social.length_weight)


def make_planner(scenario, checker: ValidityChecker, algorithm: str | AlgorithmSpec | None = None) -> RrtStar:
    """An :class:`RrtStar` configured as ``algorithm`` (a name or a spec;
    default: the scenario's ``planner.algorithm``).

    Raises:
        TypeError, ValueError: an argument is not what is allowed (named).
    """
    require_scenario(scenario, "make_planner")
    require_checker(checker, "make_planner")
    spec = algorithm_spec(scenario.planner.algorithm if algorithm is None else algorithm, "make_planner")
    objective = make_objective(scenario, spec)
    options = RrtStarOptions.from_scenario(scenario.planner, informed=spec.informed)
    return RrtStar(ConfigurationSpace.from_scenario(scenario), checker, objective, options, name=spec.name)


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
    algorithm: str | AlgorithmSpec | None = None,
    iterations: int | None = None,
    seed: int | None = None,
    progress=None,
) -> PlannerResult:
    """Plans ``scenario`` and fills in the cost parts of the result.

    Args:
        scenario: a validated :class:`drake_social.scenario.Scenario`.
        checker: the validity checker (Drake or numpy).
        algorithm: overrides ``scenario.planner.algorithm``: a name of
            :data:`ALGORITHM_SPECS` or an :class:`AlgorithmSpec`.
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
    if algorithm is not None:
        algorithm_spec(algorithm, "plan")
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
