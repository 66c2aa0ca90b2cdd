"""Who made a path unsafe: the person a replan's reason points at.

A replan that replaced its path because it was not safe any more, waited or
stepped aside says why in words (:mod:`drake_social.planning.replan_eval`):
"motion k, t = a .. b s comes within d m of a predicted person", or "a
person is x m from the robot now". :func:`culprit` names that person for
the replay and the figures: the predicted person with the least surface
distance to the robot

* driving the replaced path (timed from the replan at the execution limits,
  as the replanner times it) at :data:`WINDOW_SAMPLES` times over the
  reason's ``t = a .. b s``;
* or, when the reason is a courtesy bound (the interactive prediction:
  "courtesy: NAME would have to brake ..." or "... would be moved ..."), the
  person it names (``person i`` for one without a name);
* or, when the reason says a person is near the robot now, where it is at
  the replan's time;
* or, when the reason names no such window but a person (or the robot
  steps aside: standing was not clear of them), standing where it is from
  the replan's time over :data:`STANDING_LOOKAHEAD` seconds.

A path that collides with the room, or a cheaper route, has no culprit.

The distances are those of the replanner's safety check
(:func:`drake_social.collision.people_kernel.people_clearance`, one person
at a time, over the safety horizon: beyond it only people who stand), so
the person named is the one whose prediction came within the safety
distance (the check itself is sound and a little conservative: at the
sampled times the least distance may be a little above it).
"""

from __future__ import annotations

import math
import re

import numpy as np

from drake_social.collision import people_kernel
from drake_social.kinematics import nominal_path_times
from drake_social.people.interactive import robot_samples
from drake_social.people.prediction import Prediction
from drake_social.planning.decisions import decision

__all__ = ["STANDING_LOOKAHEAD", "WINDOW_SAMPLES", "culprit", "robot_along"]

#: Times sampled over the reason's window (its ends included).
WINDOW_SAMPLES = 9
#: Seconds ahead the robot is taken to stand when the reason names no window.
STANDING_LOOKAHEAD = 3.0
_WINDOW = re.compile(r"t = (-?\d+(?:\.\d+)?) \.\. (-?\d+(?:\.\d+)?) s comes within")
_COURTESY = re.compile(r"courtesy: (.*?) would (?:have to brake at|be moved) ")
_UNNAMED = re.compile(r"person (\d+)")


def _named(name: str, names: tuple[str, ...]) -> int:
    """The index of the person a courtesy reason names (the first of that
    name; ``person i`` is the unnamed person i), -1 when none matches."""
    if name in names:
        return names.index(name)
    unnamed = _UNNAMED.fullmatch(name)
    if unnamed is not None and int(unnamed.group(1)) < len(names) and not names[int(unnamed.group(1))]:
        return int(unnamed.group(1))
    return -1


def robot_along(path: np.ndarray, t0: float, times: np.ndarray, max_base_speed: float,
                arm_max_velocity) -> np.ndarray:
    """The configurations (T, 4) of the robot driving ``path`` (N, 4) from
    ``t0`` at the execution limits, at ``times`` (T,) seconds (linear in
    each motion; the first and last waypoints before and after)."""
    wp = np.asarray(path, float).reshape(-1, 4)
    return robot_samples(wp, nominal_path_times(wp, max_base_speed, arm_max_velocity, t0), np.asarray(times, float))


def culprit(result, prediction: Prediction, replaced: np.ndarray | None, q: np.ndarray, scene,
            max_base_speed: float, arm_max_velocity, *, standing: Prediction | None = None,
            safety_horizon: float = math.inf) -> int:
    """The index (among ``prediction``'s people) of the person who made the
    replan ``result`` replace its path or hold, -1 when it was not a person
    (a cheaper route, the room, nobody present) or no scene is given.

    Args:
        result: the ReplanResult (``status``, ``reason``, ``t``, ``candidate_cost``).
        prediction: the people the replan judged against.
        replaced: (N, 4) the path being driven at the replan, from ``q``
            (None: none).
        q: (4,) the robot's configuration at the replan.
        scene: the robot's planar scene (``checker.compiled_scene()``), None: no culprit.
        max_base_speed, arm_max_velocity: the execution limits that time a path.
        standing: the people the replan predicted with the robot standing at
            ``q`` (the interactive prediction: they react to where it is),
            read when the robot's standing is the question; None: ``prediction``.
        safety_horizon: ``planner.safety_horizon``: as in the replanner's
            safety check, beyond it only people who stand are considered
            (:meth:`~drake_social.people.prediction.Prediction.until`).
    """
    kind = decision(result)
    if scene is None or prediction.count == 0 or kind in ("initial", "cheaper", "kept"):
        return -1
    reason = str(result.reason)
    courtesy = _COURTESY.search(reason)
    if courtesy is not None:
        return _named(courtesy.group(1), tuple(prediction.names))
    window = _WINDOW.search(reason)
    t0 = float(result.t)
    if window is not None and replaced is not None:
        a, b = float(window.group(1)), float(window.group(2))
        times = np.linspace(a, max(a, b), WINDOW_SAMPLES)
        configs = robot_along(replaced, t0, times, max_base_speed, arm_max_velocity)
    elif "person" in reason or kind == "evade":  # a person near the robot now, or standing would not be clear
        times = np.array([t0]) if "from the robot now" in reason else \
            np.linspace(t0, t0 + STANDING_LOOKAHEAD, WINDOW_SAMPLES)
        configs = np.repeat(np.asarray(q, float).reshape(1, 4), len(times), axis=0)
        prediction = prediction if standing is None else standing
    else:
        return -1
    prediction = prediction.until(safety_horizon)
    bodies, robot = np.ascontiguousarray(scene.bodies, float), np.ascontiguousarray(scene.robot, float)
    xy, radii, speeds = prediction.positions, prediction.radii, prediction.max_speeds
    best, who = math.inf, -1
    for p in range(prediction.count):
        present = np.zeros_like(prediction.present)
        present[:, p] = prediction.present[:, p]
        present.flags.writeable = False  # the prediction's arrays are read-only: the kernel's compiled signature
        d = min(people_kernel.people_clearance(c, float(t), bodies, robot, xy, present, radii, speeds,
                                               float(prediction.t0), float(prediction.dt))
                for c, t in zip(configs, times))
        if d < best:
            best, who = d, p
    return who
