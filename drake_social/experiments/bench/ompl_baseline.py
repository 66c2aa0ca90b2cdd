"""OMPL's geometric RRTstar on our problem: same space, checks and cost code.

The baseline of ``drake-social bench`` (needs the ``bench`` extra, ``pip
install ompl``). Everything that decides the answer is ours; OMPL only
searches:

* **space**: ``RealVectorStateSpace(4)`` over OMPL coordinates ``u = W q``
  (``W`` = ``planner.distance_weights``), so OMPL's Euclidean distance is our
  ``||W (q_b - q_a)||`` and ``range`` means the same Steer distance; bounds
  from :meth:`ConfigurationSpace.from_scenario`.
* **validity**: a ``StateValidityChecker`` calling ``checker.is_valid`` and a
  ``MotionValidator`` calling ``checker.is_motion_valid`` (ends included).
  RRTstar checks a new state only through the motion from its nearest node,
  so it calls the state checker for the start alone.
* **cost**: :class:`ObjectiveAdapter`, an ``ob.OptimizationObjective`` whose
  ``motionCost`` is ``objective.motion_cost`` on one edge (the ompl 2.0.1
  wheel ignores a Python ``stateCost`` override on
  ``StateCostIntegralObjective``, so the integral cannot be expressed there).
  Costs add (OMPL's default ``combineCosts``), the identity is 0.
* **neighbours**: radius-based (``setKNearest(False)``). OMPL's radius at a
  tree of ``n - 1`` vertices is
  ``r(n) = min(range, r_rrt (ln n / n)^(1/d))`` with
  ``r_rrt = rewire_factor (2 (1 + 1/d) mu / zeta_d)^(1/d)``, ``mu`` the space
  measure (product of the side lengths) and ``zeta_d`` the unit d-ball volume
  (``RRTstar::getNeighbors``, ``calculateRewiringLowerBounds``). It never
  exceeds ``range``: when our ``near_radius`` is larger than the Steer
  distance OMPL cannot match it. :func:`rewire_factor_for_radius` picks the
  smallest factor for which ``r(n) = min(range, near_radius)`` at every tree
  size the run can reach, a constant radius like ours.
* **goal**: a ``GoalState`` at the exact goal with threshold machine epsilon
  (OMPL's default; its test is ``distance < threshold``, so 0 would never be
  met). A path therefore ends exactly at the goal, reached by a goal sample
  (``goal_bias``) within ``range`` of the tree; OMPL samples the goal only
  until it is in the tree, later improvements come from rewiring. (Ours also
  connects any node within ``near_radius`` of the goal.)
* **termination**: after ``iterations`` samples, counted by
  ``RRTstar.numIterations()`` (one sample per iteration, as ours) in a
  ``PlannerTerminationCondition`` evaluated before every iteration, which
  also records the best cost after each one (the anytime curve).
* **randomness**: ``ompl.util.RNG.setSeed(seed + 1)`` (OMPL rejects 0)
  before the space and planner are built, so every OMPL generator of the run
  is seeded from it; the same seed gives the same path.

OMPL's log messages are silenced during a run (they go to stdout otherwise;
re-seeding also logs an error that does not apply: every generator is
created after the new seed).
"""

from __future__ import annotations

import contextlib
import dataclasses as dc
import math
import time
from typing import Iterator

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from drake_social.planning.objective import Objective
from drake_social.planning.result import PlannerResult, PlanningInputError
from drake_social.planning.space import ConfigurationSpace
from drake_social.collision.validity import ValidityChecker

__all__ = [
    "ObjectiveAdapter",
    "OmplSettings",
    "ompl_radius",
    "plan_ompl",
    "rewire_factor_for_radius",
    "unit_ball_measure",
]

#: OMPL's goal threshold: its GoalRegion test is ``distance < threshold``.
GOAL_THRESHOLD = float(np.finfo(float).eps)


def unit_ball_measure(dim: int) -> float:
    """Volume of the unit ball in ``dim`` dimensions, ``pi^(d/2) / Gamma(d/2 + 1)``."""
    return math.pi ** (dim / 2) / math.gamma(dim / 2 + 1)


def ompl_radius(rewire_factor: float, measure: float, dim: int, n: float, max_distance: float) -> float:
    """OMPL RRTstar's neighbour radius with ``n = tree size + 1`` (its ``cardDbl``).

    Args:
        rewire_factor: ``RRTstar.setRewireFactor``.
        measure: the space measure (``SpaceInformation.getSpaceMeasure``).
        dim: state dimension.
        n: tree size plus one (>= 2).
        max_distance: the planner's range.
    """
    r_rrt = rewire_factor * (2 * (1 + 1 / dim) * measure / unit_ball_measure(dim)) ** (1 / dim)
    return min(max_distance, r_rrt * (math.log(n) / n) ** (1 / dim))


def rewire_factor_for_radius(radius: float, measure: float, dim: int, max_n: float) -> float:
    """The smallest rewire factor whose unclipped OMPL radius is >= ``radius``
    for every ``n`` in ``[2, max_n]``.

    ``ln n / n`` rises up to ``n = e`` and falls after it, so its minimum on
    ``[2, max_n]`` is at one of the ends.
    """
    if max_n < 2:
        raise ValueError(f"max_n must be >= 2, got {max_n}")
    worst = min(math.log(max_n) / max_n, math.log(2) / 2)
    base = (2 * (1 + 1 / dim) * measure / unit_ball_measure(dim)) ** (1 / dim)
    return radius / (base * worst ** (1 / dim))


@dc.dataclass(frozen=True)
class OmplSettings:
    """What the OMPL run was configured with (reported by the bench).

    Attributes:
        planning_range: ``setRange`` (weighted configuration units).
        goal_bias: ``setGoalBias``.
        rewire_factor: ``setRewireFactor``.
        radius: OMPL's neighbour radius at every tree size of the run
            (``min(range, near_radius)``).
        our_near_radius: our ``near_radius``, for comparison.
        space_measure: OMPL's space measure (in ``u = W q`` coordinates).
        goal_threshold: the ``GoalState`` threshold.
        iterations: samples drawn.
    """

    planning_range: float
    goal_bias: float
    rewire_factor: float
    radius: float
    our_near_radius: float
    space_measure: float
    goal_threshold: float
    iterations: int

    def to_json_dict(self) -> dict:
        return dc.asdict(self)


class ObjectiveAdapter(ob.OptimizationObjective):
    """Our :class:`Objective` as an OMPL optimisation objective.

    Args:
        si: the space information (states in ``u = W q`` coordinates).
        objective: the cost code; ``motionCost`` calls its ``motion_cost`` on one edge.
        weights: (4,) the distance weights ``W``.

    Attributes:
        num_motion_costs: ``motionCost`` calls so far.
    """

    def __init__(self, si: ob.SpaceInformation, objective: Objective, weights: np.ndarray):
        super().__init__(si)
        self.objective = objective
        self._inv_w = 1.0 / np.asarray(weights, float)
        self.num_motion_costs = 0

    def q(self, state) -> np.ndarray:
        """Our configuration (4,) of an OMPL state."""
        return np.array([state[0], state[1], state[2], state[3]]) * self._inv_w

    def stateCost(self, state) -> ob.Cost:  # noqa: N802 (OMPL's name)
        """The objective's cost rate at the state (not used by RRTstar)."""
        return ob.Cost(float(self.objective.state_cost(self.q(state))))

    def motionCost(self, s1, s2) -> ob.Cost:  # noqa: N802
        """``objective.motion_cost`` of the straight motion s1 -> s2."""
        self.num_motion_costs += 1
        return ob.Cost(float(self.objective.motion_cost(self.q(s1)[None], self.q(s2)[None])[0]))


class _StateChecker(ob.StateValidityChecker):
    def __init__(self, si, checker: ValidityChecker, inv_w: np.ndarray):
        super().__init__(si)
        self.checker, self.inv_w, self.count = checker, inv_w, 0

    def isValid(self, state) -> bool:  # noqa: N802
        self.count += 1
        return bool(self.checker.is_valid(np.array([state[0], state[1], state[2], state[3]]) * self.inv_w))


class _MotionChecker(ob.MotionValidator):
    def __init__(self, si, checker: ValidityChecker, inv_w: np.ndarray):
        super().__init__(si)
        self.checker, self.inv_w, self.count = checker, inv_w, 0

    def checkMotion(self, s1, s2) -> bool:  # noqa: N802
        self.count += 1
        w = self.inv_w
        q_a = np.array([s1[0], s1[1], s1[2], s1[3]]) * w
        q_b = np.array([s2[0], s2[1], s2[2], s2[3]]) * w
        return bool(self.checker.is_motion_valid(q_a, q_b))


@contextlib.contextmanager
def _quiet_ompl() -> Iterator[None]:
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)
    try:
        yield
    finally:
        ou.setLogLevel(level)


def _state(si: ob.SpaceInformation, u: np.ndarray):
    s = si.allocState()
    for i, v in enumerate(u):
        s[i] = float(v)
    return s


def plan_ompl(
    space: ConfigurationSpace,
    checker: ValidityChecker,
    objective: Objective,
    start: np.ndarray,
    goal: np.ndarray,
    *,
    iterations: int,
    planning_range: float,
    near_radius: float,
    goal_bias: float,
    seed: int,
    name: str = "ompl_rrt_star",
) -> tuple[PlannerResult, OmplSettings]:
    """Runs OMPL's RRTstar for ``iterations`` samples (see the module docstring).

    Args:
        space: bounds and distance weights.
        checker: our validity checker (called once per state / motion OMPL checks).
        objective: our objective (its ``motion_cost`` is OMPL's motion cost).
        start, goal: configurations (4,).
        iterations: samples drawn, K.
        planning_range: Steer distance (OMPL's range).
        near_radius: our near radius; OMPL's radius is ``min(range, near_radius)``.
        goal_bias: probability of sampling the goal.
        seed: the run's seed (OMPL's seed is ``seed + 1``).
        name: ``PlannerResult.algorithm``.

    Returns:
        The result (waypoints in our coordinates, ``cost`` = OMPL's best cost,
        counts of our checker and cost calls, ``wall_time`` = ``solve`` only;
        the ``social_cost_*`` and length fields are left for the caller to
        recompute with its own code) and the settings used.

    Raises:
        PlanningInputError: start or goal invalid by ``checker``.
    """
    if iterations < 1:
        raise ValueError(f"iterations must be >= 1, got {iterations}")
    if not (planning_range > 0 and near_radius > 0 and 0 <= goal_bias < 1):
        raise ValueError(
            f"need planning_range > 0, near_radius > 0, 0 <= goal_bias < 1; "
            f"got {planning_range}, {near_radius}, {goal_bias}"
        )
    if seed < 0:
        raise ValueError(f"seed must be >= 0, got {seed}")
    start, goal = np.asarray(start, float), np.asarray(goal, float)
    for label, q in (("start", start), ("goal", goal)):
        if not (space.contains(q) and checker.is_valid(q)):
            raise PlanningInputError(f"{label} configuration {q.tolist()} is outside the space or in collision")
    w = np.asarray(space.weights, float)
    inv_w = 1.0 / w
    with _quiet_ompl():
        ou.RNG.setSeed(int(seed) + 1)
        state_space = ob.RealVectorStateSpace(4)
        bounds = ob.RealVectorBounds(4)
        for i, (lo, hi) in enumerate(zip(space.lower * w, space.upper * w)):
            bounds.setLow(i, float(lo))
            bounds.setHigh(i, float(hi))
        state_space.setBounds(bounds)
        si = ob.SpaceInformation(state_space)
        state_checker = _StateChecker(si, checker, inv_w)
        motion_checker = _MotionChecker(si, checker, inv_w)
        si.setStateValidityChecker(state_checker)
        si.setMotionValidator(motion_checker)
        si.setup()

        pdef = ob.ProblemDefinition(si)
        pdef.addStartState(_state(si, start * w))
        goal_region = ob.GoalState(si)
        goal_region.setState(_state(si, goal * w))
        goal_region.setThreshold(GOAL_THRESHOLD)
        pdef.setGoal(goal_region)
        adapter = ObjectiveAdapter(si, objective, w)
        pdef.setOptimizationObjective(adapter)

        measure = float(si.getSpaceMeasure())
        radius = min(planning_range, near_radius)
        # cardDbl = tree size + 1 <= iterations + 2.
        rewire = rewire_factor_for_radius(radius, measure, 4, iterations + 2)
        planner = og.RRTstar(si)
        planner.setProblemDefinition(pdef)
        planner.setRange(planning_range)
        planner.setGoalBias(goal_bias)
        planner.setKNearest(False)
        planner.setRewireFactor(rewire)
        planner.setup()

        history = np.full(iterations, np.inf)

        def done() -> bool:
            k = planner.numIterations()
            if k > 0:
                history[k - 1] = planner.bestCost().value()
            return k >= iterations

        t0 = time.perf_counter()
        planner.solve(ob.PlannerTerminationCondition(done))
        wall = time.perf_counter() - t0

        data = ob.PlannerData(si)
        planner.getPlannerData(data)
        tree_size = int(data.numVertices())
        success = bool(pdef.hasExactSolution())
        waypoints = np.zeros((0, 4))
        if success:
            path = pdef.getSolutionPath()
            waypoints = np.array([[s[0], s[1], s[2], s[3]] for s in path.getStates()]) * inv_w
        cost = float(planner.bestCost().value()) if success else np.inf

        # OMPL's approximate solution ends at the tree's state closest to the goal.
        closest = 0.0 if success else float(pdef.getSolutionDifference()) if pdef.hasSolution() else float("nan")

    finite = np.flatnonzero(np.isfinite(history))
    result = PlannerResult(
        algorithm=name,
        success=success,
        message="path found" if success else f"no exact solution after {iterations} iterations",
        waypoints=waypoints,
        cost=cost,
        first_solution_iteration=int(finite[0]) + 1 if len(finite) else None,
        cost_history=history,
        tree_size=tree_size,
        num_config_checks=state_checker.count,
        num_motion_checks=motion_checker.count,
        num_cost_evaluations=adapter.num_motion_costs,
        wall_time=wall,
        seed=int(seed),
        closest_distance_to_goal=closest,
    )
    settings = OmplSettings(
        planning_range=float(planning_range),
        goal_bias=float(goal_bias),
        rewire_factor=float(rewire),
        radius=ompl_radius(rewire, measure, 4, iterations + 2, planning_range),
        our_near_radius=float(near_radius),
        space_measure=measure,
        goal_threshold=GOAL_THRESHOLD,
        iterations=int(iterations),
    )
    return result, settings
