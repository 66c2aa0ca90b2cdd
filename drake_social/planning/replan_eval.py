"""The replanner's exact judge of a path: its time-indexed cost and safety.

A path is driven from ``t0`` at the execution limits
(:func:`~drake_social.kinematics.nominal_path_times`); each motion's social
cost is integrated against the people predicted at the time the robot is
there (:meth:`~drake_social.cost.social.SocialCost.timed_motion_cost`), its
length term is the objective's, and it is safe when the room's checker
accepts it and no predicted person comes within the safety distance of the
robot along it (:class:`~drake_social.collision.people_safety.PeopleSafety`).
The search's tree costs are approximate once rewiring has moved a subtree in
time; this module gives the numbers the replanner decides with, and how many
of the search's paths it judges (:data:`VERIFY_PATHS`, :data:`MAX_JUDGED`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from drake_social.collision.people_safety import PeopleSafety
from drake_social.collision.validity import CompiledSceneChecker
from drake_social.cost.social import SocialCost
from drake_social.kinematics import config_distance, nominal_path_times
from drake_social.people.prediction import Prediction
from drake_social.planning.objective import Objective

__all__ = ["MAX_JUDGED", "VERIFY_PATHS", "PathEvaluation", "PathJudge"]

#: Goal connections of the search judged exactly, in ascending tree cost ...
VERIFY_PATHS = 4
#: ... and at most this many when none of the first ones is safe (within the budget).
MAX_JUDGED = 16


class PathEvaluation(NamedTuple):
    """A path judged at its nominal times.

    Attributes:
        times: (N,) the time each waypoint is reached, seconds.
        cost: the objective along the path: the time-indexed social cost
            (the objective's weights; 0 for the length objective), its
            length term and the time term (``time_weight`` times the
            seconds from the first waypoint to the last); 0 for a single
            waypoint.
        social: the time-indexed social part of ``cost``.
        length: the weighted configuration-space length (the length term
            before ``length_weight``).
        static_bad: the first motion the room's checker rejects, -1 when none.
        people_bad: the first motion that comes within the safety distance of
            a predicted person, -1 when none.
        courtesy: under the interactive prediction, why the path asks too
            much of a person (:mod:`.replan_interactive`); empty when it
            does not, and for the other predictions.
        effort: under the interactive prediction, the people's effort the
            path induces (m^2 s; ``cost`` includes it times
            ``planner.courtesy_weight``); 0 for the other predictions.
    """

    times: np.ndarray
    cost: float
    social: float
    length: float
    static_bad: int
    people_bad: int
    courtesy: str = ""
    effort: float = 0.0

    @property
    def safe(self) -> bool:
        """Valid in the room, clear of every predicted person, and courteous."""
        return self.static_bad < 0 and self.people_bad < 0 and not self.courtesy

    @property
    def first_bad(self) -> int:
        """The first motion that fails either check, -1 when none."""
        bad = [i for i in (self.static_bad, self.people_bad) if i >= 0]
        return min(bad) if bad else -1


class PathJudge:
    """Judges paths against one prediction (built once per replan).

    Args:
        objective: the planner's objective (its length weight, distance
            weights and, for a social one, its interest-point weights).
        social: the time-indexed social cost for this prediction
            (:meth:`SocialCost.for_prediction`), None for the length objective.
        checker: the room's checker (no people in it).
        prediction: the people predicted over the horizon.
        safety: the smallest allowed robot-to-body distance, metres.
        max_base_speed, arm_max_velocity: the execution limits that time a path.
        safety_horizon: seconds of ``prediction`` over which a path must keep
            ``safety`` from everyone (:meth:`Prediction.until`); the cost
            looks over all of it.
        time_weight: cost per second the path takes (``planner.time_weight``, >= 0).
    """

    def __init__(self, objective: Objective, social: SocialCost | None, checker: CompiledSceneChecker,
                 prediction: Prediction, safety: float, max_base_speed: float, arm_max_velocity, *,
                 safety_horizon: float = math.inf, time_weight: float = 0.0) -> None:
        self.objective = objective
        self.social = social
        self.checker = checker
        self.prediction = prediction
        self.safety = float(safety)
        self.max_base_speed = float(max_base_speed)
        self.arm_max_velocity = np.asarray(arm_max_velocity, float).reshape(2)
        self.safety_horizon = float(safety_horizon)
        self.time_weight = float(time_weight)
        self.people_safety = PeopleSafety(checker.compiled_scene(), prediction.until(self.safety_horizon), self.safety)

    def times(self, waypoints: np.ndarray, t0: float) -> np.ndarray:
        """The nominal time (N,) of each waypoint, driven from ``t0``."""
        return nominal_path_times(waypoints, self.max_base_speed, self.arm_max_velocity, t0)

    def motion_costs(self, waypoints: np.ndarray, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The social part (E,) and the weighted length (E,) of every motion."""
        a, b = waypoints[:-1], waypoints[1:]
        length = config_distance(a, b, self.objective.distance_weights)
        if self.social is None or len(a) == 0:
            return np.zeros(len(a)), length
        social = np.asarray(self.social.timed_motion_cost(a, b, times[:-1], times[1:], self.prediction), float)
        return social.reshape(len(a)), length

    def evaluate(self, waypoints: np.ndarray, t0: float) -> PathEvaluation:
        """The exact time-indexed cost and safety of ``waypoints`` (N, 4) driven from ``t0``."""
        wp = np.ascontiguousarray(waypoints, float)
        times = self.times(wp, t0)
        if len(wp) < 2:
            return PathEvaluation(times, 0.0, 0.0, 0.0, -1, -1)
        social, length = self.motion_costs(wp, times)
        lw = float(self.objective.length_weight)
        # The objective's own sum: social + lambda * length per motion (the length term only when lambda > 0,
        # as SocialObjective.motion_cost adds it), summed over the motions.
        per_motion = social + lw * length if lw > 0 else social
        spent = self.time_weight * (float(times[-1]) - float(times[0]))
        ok = np.asarray(self.checker.are_motions_valid(wp[:-1], wp[1:]), bool)
        static_bad = int(np.argmin(ok)) if not ok.all() else -1
        clear, people_bad = self.people_safety.path_clear(wp, times)
        return PathEvaluation(times, float(per_motion.sum()) + spent, float(social.sum()), float(length.sum()),
                              static_bad, -1 if clear else int(people_bad))

    def unsafe_words(self, ev: PathEvaluation) -> str:
        """Why a judged path is not safe, in words."""
        k = ev.first_bad
        if k < 0:
            return ev.courtesy or "safe"
        span = f"motion {k}, t = {ev.times[k]:.2f} .. {ev.times[k + 1]:.2f} s"
        if ev.static_bad == k:
            return f"{span} collides with the room"
        return f"{span} comes within {self.safety:g} m of a predicted person"

    def wait_words(self, q: np.ndarray, t: float, candidate: PathEvaluation | None, search: str) -> str:
        """Why the robot waits at ``q`` at time ``t``, in words: a person
        within the safety distance now, or the candidate's first unsafe
        motion (None: no candidate) and the search's account ``search``."""
        clearance = float(self.people_safety.clearance(q, t))
        if clearance <= self.safety:
            return f"waiting: a person is {clearance:.3f} m from the robot now (safety distance {self.safety:g} m)"
        now = "no current path" if candidate is None else \
            f"the current path is not safe ({self.unsafe_words(candidate)})"
        return f"waiting: {now}, and the search found no safe path to the goal ({search})"
