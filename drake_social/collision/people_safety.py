"""Time-indexed safety against predicted people, for Python callers (the replanner).

:class:`PeopleSafety` binds a planar scene (the robot's capsules, from
``checker.compiled_scene()``), a :class:`~drake_social.people.prediction.Prediction`
and a safety distance, and answers with the compiled kernels of
:mod:`drake_social.collision.people_kernel` (the rules are there): the
clearance at a configuration and time, whether a timed motion or a timed
path stays more than the safety distance from every considered person.
"""

from __future__ import annotations

import numpy as np

from drake_social.arguments import real_array, require_instance, require_number
from drake_social.collision import people_kernel
from drake_social.collision.validity import PlanarScene
from drake_social.people.prediction import Prediction

__all__ = ["PeopleSafety"]

#: A prediction's max_speeds may fall short of its samples' step speeds by
#: this relative amount (rounding); more is refused (the check would be unsound).
SPEED_TOLERANCE = 1e-9


def _step_speeds(prediction: Prediction) -> np.ndarray:
    """The largest speed (P,) of each person's interpolated motion, m/s."""
    if prediction.samples < 2:
        return np.zeros(prediction.count)
    step = np.diff(prediction.positions, axis=0)
    return np.hypot(step[..., 0], step[..., 1]).max(axis=0) / prediction.dt


class PeopleSafety:
    """Whether the robot keeps more than ``safety`` metres from predicted people.

    Args:
        scene: the robot's planar scene (:meth:`PlanarChecker.compiled_scene`;
            only the chain, the capsules and their levers are read: the room
            is the static checker's business).
        prediction: the people over the horizon.
        safety: the safety distance, metres (>= 0; the scenario's
            ``execution.safety_distance``).

    Raises:
        TypeError: a wrong kind of argument.
        ValueError: a negative safety distance, or a prediction whose
            ``max_speeds`` fall short of its own samples' speeds.
    """

    def __init__(self, scene: PlanarScene, prediction: Prediction, safety: float):
        require_instance(scene, PlanarScene, "PeopleSafety", "scene",
                         "a PlanarScene (checker.compiled_scene() of a planar checker)")
        require_instance(prediction, Prediction, "PeopleSafety", "prediction",
                         "a drake_social.people.prediction.Prediction")
        require_number(safety, "PeopleSafety", "safety", unit="metres")
        if safety < 0:
            raise ValueError(f"PeopleSafety: safety must be >= 0 metres, got {safety}")
        measured = _step_speeds(prediction)
        short = measured > prediction.max_speeds * (1 + SPEED_TOLERANCE) + SPEED_TOLERANCE
        if np.any(short):
            p = int(np.argmax(short))
            raise ValueError(f"PeopleSafety: prediction.max_speeds[{p}] = {prediction.max_speeds[p]} m/s is below "
                             f"the speed {measured[p]} m/s of person {prediction.names[p]!r}'s predicted motion")
        self.scene = scene
        self.prediction = prediction
        self.safety = float(safety)
        self._bodies = np.ascontiguousarray(scene.bodies, float)
        self._robot = np.ascontiguousarray(scene.robot, float)
        self._levers = np.ascontiguousarray(scene.levers, float)
        self._people = (np.ascontiguousarray(prediction.positions), np.ascontiguousarray(prediction.present),
                        np.ascontiguousarray(prediction.radii), np.ascontiguousarray(prediction.max_speeds),
                        float(prediction.t0), float(prediction.dt))

    @staticmethod
    def _time(value, who: str, argument: str) -> float:
        require_number(value, who, argument, unit="seconds")
        return float(value)

    def clearance(self, q: np.ndarray, t: float) -> float:
        """The least surface distance (metres) of the robot at q (4,) to the
        people considered at time ``t`` seconds; +inf when nobody is."""
        q = real_array(q, "PeopleSafety.clearance", "q", (4,), layout="[x, y, psi1, psi2]")
        t = self._time(t, "PeopleSafety.clearance", "t")
        xy, present, radii, max_speeds, t0, dt = self._people
        return float(people_kernel.people_clearance(q, t, self._bodies, self._robot, xy, present, radii, max_speeds,
                                                    t0, dt))

    def clearances(self, q: np.ndarray, t: np.ndarray) -> np.ndarray:
        """:meth:`clearance` of each configuration q[i] (M, 4) at time t[i] (M,), metres."""
        who = "PeopleSafety.clearances"
        q = real_array(q, who, "q", (None, 4), layout="rows [x, y, psi1, psi2]")
        t = real_array(t, who, "t", (len(q),), layout="one time per configuration, seconds")
        xy, present, radii, max_speeds, t0, dt = self._people
        return np.array([people_kernel.people_clearance(q[i], float(t[i]), self._bodies, self._robot, xy, present,
                                                        radii, max_speeds, t0, dt) for i in range(len(q))], float)

    def _motion(self, q_a: np.ndarray, q_b: np.ndarray, t_a: float, t_b: float) -> bool:
        xy, present, radii, max_speeds, t0, dt = self._people
        return bool(people_kernel.motion_clear_of_people(q_a, q_b, t_a, t_b, self._bodies, self._robot, self._levers,
                                                         xy, present, radii, max_speeds, t0, dt, self.safety))

    def motion_clear(self, q_a: np.ndarray, q_b: np.ndarray, t_a: float, t_b: float) -> bool:
        """Whether the straight motion q_a -> q_b, driven from time ``t_a`` to
        ``t_b`` (>= t_a) seconds, keeps the clearance > safety throughout
        (sound: False for any motion that does not; conservative near it)."""
        who = "PeopleSafety.motion_clear"
        q_a = real_array(q_a, who, "q_a", (4,), layout="[x, y, psi1, psi2]")
        q_b = real_array(q_b, who, "q_b", (4,), layout="[x, y, psi1, psi2]")
        t_a, t_b = self._time(t_a, who, "t_a"), self._time(t_b, who, "t_b")
        if t_b < t_a:
            raise ValueError(f"{who}: t_b must be >= t_a, got t_a={t_a}, t_b={t_b}")
        return self._motion(q_a, q_b, t_a, t_b)

    def path_clear(self, waypoints: np.ndarray, times: np.ndarray) -> tuple[bool, int]:
        """Whether the path through ``waypoints`` (N, 4), reaching waypoint i at
        ``times[i]`` (non-decreasing seconds), is clear; with the index of its
        first motion that is not (motion i: waypoint i -> i + 1), or -1.

        A path of one waypoint is that configuration at ``times[0]``: clear
        when its clearance is > safety (else index 0)."""
        who = "PeopleSafety.path_clear"
        wp = real_array(waypoints, who, "waypoints", (None, 4), layout="rows [x, y, psi1, psi2]", rows=(1, None),
                        row_name="waypoint")
        times = real_array(times, who, "times", (len(wp),), layout="one time per waypoint, seconds")
        if np.any(np.diff(times) < 0):
            i = int(np.argmax(np.diff(times) < 0))
            raise ValueError(f"{who}: times must be non-decreasing, got times[{i}] = {times[i]} > "
                             f"times[{i + 1}] = {times[i + 1]}")
        if len(wp) == 1:
            ok = self.clearance(wp[0], float(times[0])) > self.safety
            return ok, -1 if ok else 0
        for i in range(len(wp) - 1):
            if not self._motion(wp[i], wp[i + 1], float(times[i]), float(times[i + 1])):
                return False, i
        return True, -1
