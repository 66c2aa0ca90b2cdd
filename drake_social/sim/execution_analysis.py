"""The analysis of an executed trajectory: collisions, limits, cost and deviation.

:func:`analyze_execution` checks and measures what a run did, beside what
was planned (:class:`~drake_social.sim.results.ExecutionReport`): the
collisions of the executed configurations at the checker's resolution
(geometry only), the limits of a valid configuration
(:func:`limit_violations`: which joint, when, by how much), its social cost
integrated with the planner's cost code, the deviation of every body point
from the planned path (:mod:`drake_social.sim.analysis`) and the minimum
clearance. When the people move, the collision check covers the obstacles
and walls only (the people at t = 0 are not where the robot met them): the
distances to people are measured over time from the people log
(:mod:`drake_social.evaluation.metrics`), and
:attr:`~drake_social.sim.results.ExecutionReport.collision_checked` names
what was checked.
"""

from __future__ import annotations

import logging
import math
from typing import Callable

import numpy as np

from drake_social.arguments import real_array, require_checker, require_scenario
from drake_social.collision.validity import ValidityChecker
from drake_social.cost.social import SocialCost
from drake_social.scenario.geometry import arm_geometry, configuration_limits
from drake_social.model.plant import ACTUATED_JOINTS
from drake_social.people import people_model, without_people
from drake_social.scenario import Scenario, ScenarioError
from drake_social.sim.analysis import config_deviation, densify, point_deviation
from drake_social.sim.results import CHECKED_ROOM, CHECKED_ROOM_AND_PEOPLE, ExecutionReport, LimitViolation
from drake_social.waypoints import waypoint_array

__all__ = ["analyze_execution", "limit_violations"]

_log = logging.getLogger(__name__)


def limit_violations(scenario: Scenario, times: np.ndarray, q: np.ndarray) -> list[LimitViolation]:
    """Where the executed configurations ``q`` (T, 4) at ``times`` (T,) pass a limit.

    The configurations are compared with the limits exactly (as the
    checkers do); between two logged samples the executed trajectory is
    taken as straight, whose extremes are at the samples.

    Returns:
        One :class:`LimitViolation` per joint and bound passed, in joint
        order, lower before upper; empty when every sample is within.
    """
    lower, upper = configuration_limits(scenario)
    q = np.asarray(q, float).reshape(-1, 4)
    times = np.asarray(times, float).reshape(-1)
    found = []
    for j, joint in enumerate(ACTUATED_JOINTS):
        for bound, excess, limit in (("lower", lower[j] - q[:, j], lower[j]), ("upper", q[:, j] - upper[j], upper[j])):
            beyond = np.flatnonzero(excess > 0)
            if len(beyond):
                worst = int(np.argmax(excess))
                found.append(LimitViolation(joint=joint, bound=bound, limit=float(limit),
                                            first_time=float(times[beyond[0]]), worst_time=float(times[worst]),
                                            max_excess=float(excess[worst])))
    return found


def _collision_free(are_valid: Callable[[np.ndarray], np.ndarray], clearance: Callable[[np.ndarray], float],
                    lower: np.ndarray, upper: np.ndarray, qs: np.ndarray) -> np.ndarray:
    """(N,) bool: each configuration's geometry is clear (signed distance > 0).

    A checker's ``are_valid`` also refuses configurations beyond the limits;
    those (found separately, :func:`limit_violations`) are judged here by
    their ``clearance`` alone.
    """
    inside = np.all((qs >= lower) & (qs <= upper), axis=1)
    free = np.zeros(len(qs), bool)
    if inside.any():
        free[inside] = np.asarray(are_valid(qs[inside]), bool)
    for i in np.flatnonzero(~inside):
        free[i] = clearance(qs[i]) > 0.0
    return free


def analyze_execution(
    scenario: Scenario,
    waypoints: np.ndarray,
    times: np.ndarray,
    q: np.ndarray,
    checker: ValidityChecker | None = None,
    *,
    people_move: bool | None = None,
    judged: np.ndarray | None = None,
) -> ExecutionReport:
    """Checks and measures an executed trajectory against its planned path.

    Two separate findings: collisions (the geometry at the checker's
    resolution) and the limits of a valid configuration
    (:func:`limit_violations`).

    Args:
        scenario: the scenario.
        waypoints: (N, 4) planned path; one row (N = 1) for a robot that
            was to hold there (a replanning run that never found a path):
            the deviations are then from that configuration, the planned
            social cost 0.
        times, q: (T,), (T, 4) executed configurations over time.
        checker: the collision checker of the executed configurations;
            None = Drake's (:func:`~drake_social.collision.drake_checker.valid_configurations`:
            SceneGraphCollisionChecker answers from the shapes near the
            trajectory), independent of the planar checker that planned. The minimum
            clearance is the exact planar checker's. A given checker is used
            as given when the people stand still; when they move, a checker
            of the same kind is built for the room alone (a checker built
            with the people at t = 0 would judge the run against where they
            no longer are), and an unknown kind gives way to Drake's.
        people_move: whether the scenario's people move (None = ask its
            people model). When they do, the check and the clearance cover
            the obstacles and walls only (:data:`CHECKED_ROOM`).
        judged: (K, 4) the polyline the deviations are measured from
            (None = ``waypoints``): a replanning run's segments driven on
            (:attr:`~drake_social.sim.results.SimulationResult.judged`).

    Raises:
        TypeError: an argument of the wrong kind (named).
        ScenarioError: ``waypoints`` not an (N, 4) array with 1 <= N <=
            MAX_WAYPOINTS; ``times`` and ``q`` not (T,) and (T, 4) finite.
    """
    from drake_social.collision.drake_checker import make_checker, valid_configurations

    require_scenario(scenario, "analyze_execution")
    require_checker(checker, "analyze_execution", optional=True)
    waypoints = waypoint_array(waypoints, "analyze_execution: waypoints", fewest=1)
    times, q = _trajectory(times, q, "analyze_execution")
    # Clearances from the exact planar checker: Drake's cylinder-box distance
    # can exceed the true one (see drake_social.collision.drake_checker).
    if people_move is None:
        people_move = not people_model(scenario).static
    room = without_people(scenario) if people_move else scenario  # what the collisions are checked against
    planar = make_checker(room, "planar")
    geometry = arm_geometry(scenario)
    social = SocialCost.from_scenario(scenario)
    wp = waypoints
    segments = wp if judged is None else waypoint_array(judged, "analyze_execution: judged", fewest=1)
    planned = float(social.motion_cost(wp[:-1], wp[1:]).sum()) if len(wp) > 1 else 0.0
    executed = float(social.motion_cost(q[:-1], q[1:]).sum()) if len(q) > 1 else 0.0

    resolution = float(scenario.planner.collision_resolution)
    # Which executed sample each densified configuration follows (for the collision time).
    dense, owner = densify(geometry, q, resolution, return_owner=True)
    lower, upper = configuration_limits(scenario)
    if people_move and checker is not None:
        checker = _room_checker(checker, room)
    if checker is None:  # Drake's, from SceneGraphs of the shapes near the trajectory (bounded memory)
        valid = _collision_free(lambda qs: valid_configurations(room, qs), planar.clearance, lower, upper, dense)
    else:
        valid = _collision_free(checker.are_valid, checker.clearance, lower, upper, dense)
    violations = limit_violations(scenario, times, q)
    clearance = float(np.min(planar.clearances(dense))) if len(dense) else math.inf
    first = None if valid.all() else float(times[owner[int(np.argmin(valid))]])
    return ExecutionReport(
        planned_social_cost=planned,
        executed_social_cost=executed,
        max_point_deviation=point_deviation(geometry, segments, q),
        max_config_deviation=config_deviation(segments, q),
        min_clearance=float(clearance),
        collision_free=bool(valid.all()),
        first_collision_time=first,
        checked_configurations=int(len(dense)),
        collision_resolution=resolution,
        within_limits=not violations,
        limit_violations=violations,
        collision_checked=list(CHECKED_ROOM if people_move else CHECKED_ROOM_AND_PEOPLE),
    )


def _room_checker(checker: ValidityChecker, room: Scenario) -> ValidityChecker | None:
    """A checker of ``checker``'s kind for ``room`` (the scenario without its
    people), or None (Drake's) for a kind this module does not know."""
    from drake_social.collision.drake_checker import GeometricChecker, PlanarChecker, SceneGraphChecker, make_checker

    for cls, kind in ((PlanarChecker, "planar"), (GeometricChecker, "numpy"), (SceneGraphChecker, "drake")):
        if isinstance(checker, cls):
            return make_checker(room, kind, parallelism=1) if kind == "drake" else make_checker(room, kind)
    _log.info("analyze_execution: a %s checker of the people at t = 0 replaced by Drake's of the room alone",
              type(checker).__name__)
    return None


def _trajectory(times, q, who: str) -> tuple[np.ndarray, np.ndarray]:
    """``times`` (T,) and ``q`` (T, 4), T >= 1, as finite float arrays, or the error naming them."""
    times = real_array(times, who, "times", (None,), layout="seconds", rows=(1, None), row_name="sample",
                       error=ScenarioError)
    q = real_array(q, who, "q", (None, 4), layout="rows [x, y, psi1, psi2]", rows=(1, None), row_name="sample",
                   error=ScenarioError)
    if len(times) != len(q):
        raise ScenarioError(f"{who}: times and q must have the same T rows, got {len(times)} and {len(q)}")
    return times, q
