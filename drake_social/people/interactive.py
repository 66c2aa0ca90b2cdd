"""Interaction-aware prediction: people reacting to the robot's planned motion.

:func:`predict_interactive` rolls out a social-force crowd
(:mod:`drake_social.people.interactive_kernel`: the terms of
:mod:`drake_social.people.social_force` with the scenario's ``crowd``
parameters, or the :class:`~drake_social.scenario.schema.Crowd` defaults)
over a prediction's sample times, from each person's position and velocity
now, with the robot driving a given motion: its base disc, links and object
repel the people as they repel the simulated crowd. Nobody's goal is known
(scripted and recorded people included): a person faster than
:data:`~drake_social.people.crowd.STANDING_SPEED` walks towards a point
:data:`GOAL_DISTANCE` metres straight ahead along their velocity, at their
speed now; anyone slower stands (pushed, they step aside and stop again).
Everyone may walk at up to ``crowd.max_speed_factor`` times the larger of
their speed now and ``crowd.speed_mean``. People react to each other within
:data:`INTERACTION_RANGE` metres. A person not present now goes on at their
velocity, unseen (as :func:`~drake_social.people.prediction.constant_velocity`
predicts them). The rollout has no randomness.

:func:`demands` says what one rollout asks of each person compared with
another (the robot-free one): their largest deceleration beyond the
reference's and their largest deviation off their way, and the effort
``sum over people and samples of |deviation|^2 dt``.
"""

from __future__ import annotations

import dataclasses as dc
import math
from typing import NamedTuple

import numba
import numpy as np

from drake_social.interrupts import DeferredSignals
from drake_social.kinematics import ArmGeometry
from drake_social.people.crowd import HEADING_SPEED, STANDING_SPEED
from drake_social.people.interactive_kernel import rollout
from drake_social.people.model import PeopleState
from drake_social.people.prediction import DEFAULT_PREDICTION_STEP, Prediction, sample_times
from drake_social.scenario.geometry import arm_geometry
from drake_social.scenario.schema import Crowd
from drake_social.world import world_model

__all__ = ["GOAL_DISTANCE", "INTERACTION_RANGE", "Demands", "InteractiveModel", "InteractivePeople", "demands",
           "predict_interactive", "robot_samples"]

#: How far straight ahead (metres) the goal inferred from a walker's velocity lies: far beyond any horizon.
GOAL_DISTANCE = 1000.0
#: People react to others whose centres are within this many metres (the interaction term at 4 m,
#: two people meeting head on at 1.3 m/s: below 0.2 m/s^2).
INTERACTION_RANGE = 4.0


@dc.dataclass(frozen=True)
class InteractiveModel:
    """What the rollout knows of the world: the social force parameters, the room and the robot.

    Attributes:
        crowd: the social force parameters (a :class:`~drake_social.scenario.schema.Crowd`;
            its people are not read).
        boxes: (K, 6) rows [cx, cy, half x, half y, cos yaw, sin yaw]: obstacles and walls.
        geometry: the robot and its object.
    """

    crowd: Crowd
    boxes: np.ndarray
    geometry: ArmGeometry

    @classmethod
    def from_scenario(cls, scenario) -> "InteractiveModel":
        """The scenario's ``crowd`` parameters (defaults without one), its obstacles and walls, its robot."""
        world = world_model(scenario)
        obs, walls = world.boxes, world.walls
        boxes = np.column_stack([np.concatenate([obs.centers, walls.centers]),
                                 np.concatenate([obs.halves, walls.halves]),
                                 np.concatenate([obs.cos, walls.cos]), np.concatenate([obs.sin, walls.sin])])
        return cls(scenario.crowd if scenario.crowd is not None else Crowd(),
                   np.ascontiguousarray(boxes.reshape(-1, 6), float), arm_geometry(scenario))

    def predict(self, state: PeopleState, horizon: float, dt: float = DEFAULT_PREDICTION_STEP) -> Prediction:
        """The people of ``state`` without the robot (:func:`predict_interactive` with no robot motion)."""
        return predict_interactive(state, None, horizon, self, dt)

    def params(self, dt: float) -> np.ndarray:
        """The kernel's parameter vector (:data:`~drake_social.people.interactive_kernel.PARAMS`) at step ``dt``."""
        c, g = self.crowd, self.geometry
        return np.array([dt, c.relaxation_time, c.interaction_lambda, c.interaction_gamma, c.interaction_n,
                         c.interaction_n_prime, c.interaction_strength, c.obstacle_strength, c.obstacle_range,
                         STANDING_SPEED, HEADING_SPEED, INTERACTION_RANGE, g.base_radius, *g.link_lengths,
                         g.link_radius, g.object_radius], float)


def robot_samples(waypoints: np.ndarray, times: np.ndarray, at: np.ndarray) -> np.ndarray:
    """The robot's configuration (H, 4) at the times ``at`` along ``waypoints`` (N, 4) reached at ``times``
    (N,), linear in time between waypoints (the motion the judge costs); before the first time at the
    first waypoint, after the last at the last."""
    wp = np.asarray(waypoints, float).reshape(-1, 4)
    tt = np.asarray(times, float).reshape(len(wp))
    if len(wp) == 1:
        return np.repeat(wp, len(at), axis=0)
    return np.column_stack([np.interp(at, tt, wp[:, j]) for j in range(4)])


class InteractivePeople:
    """The people now, packed for rollouts over ``samples`` times ``dt`` apart (goals inferred, see the module).

    Args:
        model: the world of the rollouts.
        state: the people now (``state.t`` is the first sample's time).
        horizon: seconds ahead (> 0).
        dt: seconds between samples (> 0).
    """

    def __init__(self, model: InteractiveModel, state: PeopleState, horizon: float,
                 dt: float = DEFAULT_PREDICTION_STEP) -> None:
        self.model = model
        self.state = state
        self.times = sample_times(state.t, horizon, dt)
        self.dt = float(dt)
        speed = state.speeds()
        self.walking = speed > STANDING_SPEED
        direction = np.divide(state.velocities, np.where(speed > 0, speed, 1.0)[:, None])
        self.goals = np.ascontiguousarray(state.positions + GOAL_DISTANCE * direction, float)
        self.preferred = np.where(self.walking, speed, 0.0)
        self.max_speeds = float(model.crowd.max_speed_factor) * np.maximum(speed, float(model.crowd.speed_mean))
        self._params = model.params(self.dt)
        self._active = np.ascontiguousarray(state.present, bool)

    def rollout(self, robot_q: np.ndarray | None) -> tuple[Prediction, np.ndarray]:
        """The people with the robot at ``robot_q`` (H, 4) at each sample (None: no robot).

        Returns:
            ``(prediction, velocities (H, P, 2))``.
        """
        s, h = self.state, len(self.times)
        has = robot_q is not None
        q = np.ascontiguousarray(robot_q if has else np.zeros((h, 4)), float).reshape(h, 4)
        args = (np.ascontiguousarray(s.positions, float), np.ascontiguousarray(s.velocities, float),
                np.ascontiguousarray(s.headings, float), self._active, np.ascontiguousarray(s.radii, float),
                self.preferred, self.max_speeds, self.goals, self.walking, self.model.boxes, q, has,
                np.ascontiguousarray(self.model.geometry.object_points, float), self._params)
        # A Ctrl-C raised inside numba's boxing of the result comes out as a SystemError: SIGINT and
        # SIGTERM are held over the call (drake_social.interrupts), after compiling (or loading) the
        # kernel, so that Ctrl-C stays live while that takes its tens of seconds.
        if not rollout.signatures:
            rollout.compile(tuple(numba.typeof(a) for a in args))
        held = DeferredSignals()
        try:
            with held:
                pos, vel, head = rollout(*args)
        finally:  # also when the kernel raised: a Ctrl-C is not lost
            held.reraise()
        step = np.diff(pos, axis=0)
        max_speeds = np.hypot(step[..., 0], step[..., 1]).max(axis=0) / self.dt if h > 1 else np.zeros(s.count)
        prediction = Prediction(t0=float(s.t), dt=self.dt, positions=pos, headings=head,
                                present=np.broadcast_to(s.present, (h, s.count)), radii=s.radii,
                                speeds=s.speeds(), max_speeds=max_speeds, names=s.names)
        return prediction, vel

    def driving(self, waypoints: np.ndarray, times: np.ndarray) -> tuple[Prediction, np.ndarray]:
        """:meth:`rollout` with the robot driving ``waypoints`` reached at ``times`` (:func:`robot_samples`)."""
        return self.rollout(robot_samples(waypoints, times, self.times))


class Demands(NamedTuple):
    """What a rollout asks of the people compared with a reference rollout (:func:`demands`).

    Attributes:
        deceleration: (P,) each person's largest rate of speed loss beyond the reference's, m/s^2 (>= 0).
        deviation: (P,) each person's largest distance off their way, metres: from their reference
            position across the reference's walking direction at the same sample (the whole distance
            while the reference stands).
        effort: ``sum over people and samples of |deviation|^2 dt``, m^2 s.
    """

    deceleration: np.ndarray
    deviation: np.ndarray
    effort: float


def demands(induced: Prediction, induced_velocities: np.ndarray, reference: Prediction,
            reference_velocities: np.ndarray) -> Demands:
    """What ``induced`` asks of each present person compared with ``reference`` (the same people and times).

    Lagging behind along their way is braking (the deceleration), not a
    deviation; the effort counts both (the whole displacement). The speed deficit ``d_k = |v_ref,k| - |v_k|`` at each sample; the
    deceleration is the largest ``(d_(k+1) - d_k) / dt`` (0 when the deficit
    never grows): how hard the person brakes beyond what they do anyway.
    People not present count for nothing.
    """
    if induced.positions.shape != reference.positions.shape:
        raise ValueError(f"demands: the rollouts differ in shape: {induced.positions.shape} and "
                         f"{reference.positions.shape}")
    present = induced.present[0]
    gap = induced.positions - reference.positions
    dev = np.hypot(gap[..., 0], gap[..., 1])
    ref_speed = np.hypot(reference_velocities[..., 0], reference_velocities[..., 1])
    moving = ref_speed > STANDING_SPEED
    safe = np.where(moving, ref_speed, 1.0)
    # Off their way: across the reference's walking direction (all of it for who stands there).
    across = np.abs(gap[..., 0] * reference_velocities[..., 1] - gap[..., 1] * reference_velocities[..., 0]) / safe
    deviation = np.where(present, np.where(moving, across, dev).max(axis=0), 0.0)
    deficit = (np.hypot(reference_velocities[..., 0], reference_velocities[..., 1])
               - np.hypot(induced_velocities[..., 0], induced_velocities[..., 1]))
    if len(deficit) > 1:
        braking = np.maximum(np.diff(deficit, axis=0).max(axis=0) / induced.dt, 0.0)
    else:
        braking = np.zeros(induced.count)
    deceleration = np.where(present, braking, 0.0)
    effort = float((dev[:, present] ** 2).sum() * induced.dt)
    return Demands(deceleration, deviation, effort)


def predict_interactive(state: PeopleState, robot_motion: tuple[np.ndarray, np.ndarray] | None, horizon: float,
                        params: InteractiveModel, dt: float = DEFAULT_PREDICTION_STEP) -> Prediction:
    """The people of ``state`` over ``horizon`` seconds, reacting to the robot driving ``robot_motion``.

    Args:
        state: the people now.
        robot_motion: ``(waypoints (N, 4), times (N,))``: the robot's path and
            the time it reaches each waypoint
            (:func:`~drake_social.kinematics.nominal_path_times`); it stands
            at the last waypoint after the last time. None: no robot (each
            person reacts only to the others and the room).
        horizon: seconds ahead (> 0).
        params: the world of the rollout (:meth:`InteractiveModel.from_scenario`).
        dt: seconds between samples (> 0).
    """
    people = InteractivePeople(params, state, horizon, dt)
    if robot_motion is None:
        return people.rollout(None)[0]
    waypoints, times = robot_motion
    if not math.isfinite(float(np.asarray(times, float).sum())):
        raise ValueError("predict_interactive: the robot's times must be finite")
    return people.driving(waypoints, times)[0]
