"""The simulated crowd: people walking to their goals by the social force model.

:class:`SocialForceCrowd` is the scenario's :class:`~drake_social.people.compose.CrowdModel`:
a discrete-time system whose state is a flat vector, advanced every
``crowd.time_step`` seconds by semi-implicit Euler on the sum of the forces of
:mod:`drake_social.people.social_force` (goal, the other people, walls and
obstacles, the robot's base, links and object).

The state vector of P people is ``[x (P), y (P), vx (P), vy (P), heading (P),
goal (P)]``: positions (metres), velocities (m/s), headings (radians) and the
index of the goal each person walks to (a float holding an integer; the
number of goals once the last is reached without ``cycle``).
"""

from __future__ import annotations

import math

import numpy as np

from drake_social.kinematics import ArmGeometry
from drake_social.people.model import PeopleState
from drake_social.people.social_force import (cap_speed, capsule_force, desired_velocities, goal_force,
                                              obstacle_force, pedestrian_force)
from drake_social.people.social_force_kernel import crowd_step
from drake_social.scenario.crowd_rules import MAX_WALKING_SPEED, MIN_WALKING_SPEED, crowd_problems
from drake_social.scenario.geometry import arm_geometry
from drake_social.world import world_model

__all__ = ["CROWD_SEED_TAG", "HEADING_SPEED", "STANDING_SPEED", "SocialForceCrowd", "crowd_model",
           "crowd_problems", "draw_speeds"]

#: Second entry of the crowd's ``SeedSequence([random_seed, CROWD_SEED_TAG])``:
#: its draws are independent of the planner's, which use the seed alone.
CROWD_SEED_TAG = 0x43524F57  # "CROW"
#: Below this speed (m/s) a person keeps their heading (no turning on the spot
#: from velocity noise); above it they face where they walk.
HEADING_SPEED = 0.05
#: A person who has reached their last goal stands: after each step, a
#: velocity slower than this (m/s) is set to zero, so they are exactly at
#: rest unless something pushes them (a passer-by, the robot's bar).
STANDING_SPEED = 0.05


def draw_speeds(count: int, mean: float, std: float, rng: np.random.Generator) -> np.ndarray:
    """``count`` preferred speeds from ``rng.normal(mean, std)``, m/s.

    A draw outside (:data:`MIN_WALKING_SPEED`, :data:`MAX_WALKING_SPEED`],
    the range of a given ``desired_speed``, is drawn again (not clamped), so
    the speeds follow the normal law truncated to (0.1, 3]: they are the
    generator's normals that fall in the range, in order, one person at a time.
    """
    out = np.empty(count)
    for i in range(count):
        v = rng.normal(mean, std)
        while not MIN_WALKING_SPEED < v <= MAX_WALKING_SPEED:
            v = rng.normal(mean, std)
        out[i] = v
    return out


class SocialForceCrowd:
    """People driven by the social force model (see the module docstring).

    Args:
        starts: (P, 2) start positions, metres.
        goals: P arrays (G_i, 2) of goals, metres, visited in order.
        cycle: (P,) after the last goal, head for the first again.
        radii: (P,) body radii, metres.
        speeds: (P,) preferred speeds v0, m/s.
        names: P labels.
        params: the scenario's ``crowd`` record (time step, relaxation time,
            goal radius, interaction and obstacle parameters,
            ``max_speed_factor``: each person's speed is capped at
            ``max_speed_factor * v0``).
        boxes: (centers (K, 2), halves (K, 2), cos (K,), sin (K,)) of the
            obstacles and walls.
        geometry: the robot and its object (None: the robot is never seen).
        compiled: step with the compiled kernel
            (:func:`~drake_social.people.social_force_kernel.crowd_step`);
            False steps with :meth:`step_reference` (numpy, the documented
            terms; the same numbers to rounding).
    """

    def __init__(self, starts, goals, cycle, radii, speeds, names, params, boxes, geometry: ArmGeometry | None,
                 compiled: bool = True):
        self._starts = np.asarray(starts, float).reshape(-1, 2)
        p = len(self._starts)
        self._goals = [np.asarray(g, float).reshape(-1, 2) for g in goals]
        self._n_goals = np.array([len(g) for g in self._goals])
        # All goals in one padded table, so a step picks each current goal in one indexing.
        self._goal_table = np.zeros((p, max(1, int(self._n_goals.max(initial=1))), 2))
        for i, g in enumerate(self._goals):
            self._goal_table[i, :len(g)] = g
        self._cycle = np.asarray(cycle, bool).reshape(p)
        self._radii = np.array(radii, float).reshape(p)  # its own, read-only: every people_state shares it
        self._radii.flags.writeable = False
        self._present = np.ones(p, bool)
        self._present.flags.writeable = False
        self._last_people: tuple[bytes, PeopleState] | None = None  # see people_state
        self._speeds = np.asarray(speeds, float).reshape(p)
        self._names = tuple(names)
        self._dt = float(params.time_step)
        self._tau = float(params.relaxation_time)
        self._goal_radius = float(params.goal_radius)
        self._max_speeds = float(params.max_speed_factor) * self._speeds
        self._interaction = dict(lam=float(params.interaction_lambda), gamma=float(params.interaction_gamma),
                                 n=float(params.interaction_n), n_prime=float(params.interaction_n_prime),
                                 strength=float(params.interaction_strength))
        self._a = float(params.obstacle_strength)
        self._b = float(params.obstacle_range)
        self._boxes = tuple(np.asarray(a, float) for a in boxes)
        self._geometry = geometry
        if geometry is not None:
            self._robot_radii = np.concatenate([[geometry.base_radius], geometry.segment_radii])
        self._rows = np.arange(p)
        self._compiled = bool(compiled)
        # The kernel's packed inputs (see drake_social.people.social_force_kernel).
        self._people_table = np.column_stack([self._radii, self._speeds, self._max_speeds, self._n_goals,
                                              self._cycle]).astype(float)
        self._box_table = np.column_stack([self._boxes[0], self._boxes[1], self._boxes[2],
                                           self._boxes[3]]).reshape(-1, 6)
        g = geometry
        robot = [0.0] * 5 if g is None else [g.base_radius, *g.link_lengths, g.link_radius, g.object_radius]
        self._object_points = np.zeros((0, 2)) if g is None else np.ascontiguousarray(g.object_points, float)
        self._kernel_params = {
            has: np.array([self._dt, self._tau, self._goal_radius, *self._interaction.values(), self._a, self._b,
                           STANDING_SPEED, HEADING_SPEED, float(has), *robot], float)
            for has in (False, True)}
        self._no_others = np.zeros((0, 4))
        self._no_q = np.zeros(4)

    # ---- the CrowdModel protocol ------------------------------------------

    @property
    def count(self) -> int:
        """The number of people P."""
        return len(self._starts)

    @property
    def time_step(self) -> float:
        """Seconds between steps."""
        return self._dt

    @property
    def speeds(self) -> np.ndarray:
        """(P,) preferred speeds v0, m/s (a copy)."""
        return self._speeds.copy()

    @property
    def max_speeds(self) -> np.ndarray:
        """(P,) largest speeds, ``max_speed_factor * v0``, m/s (a copy)."""
        return self._max_speeds.copy()

    def initial_state(self) -> np.ndarray:
        """At rest at the starts, facing the first goal, walking to it."""
        first = self._goal_table[:, 0] - self._starts
        heading = np.arctan2(first[:, 1], first[:, 0])
        p = self.count
        return np.concatenate([self._starts[:, 0], self._starts[:, 1], np.zeros(2 * p), heading, np.zeros(p)])

    def unpack(self, state: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(positions (P, 2), velocities (P, 2), headings (P,), goal indices (P,) int) of ``state``."""
        s = np.asarray(state, float).reshape(6, self.count)
        return s[:2].T.copy(), s[2:4].T.copy(), s[4].copy(), s[5].astype(int)

    def step(self, state: np.ndarray, t: float, others: PeopleState, robot_q: np.ndarray | None) -> np.ndarray:
        """The state ``time_step`` later (as :meth:`step_reference` says), by the compiled kernel.

        The kernel is compiled at its first call (tens of seconds) and
        cached on disk by numba for the next runs.
        """
        if not self._compiled:
            return self.step_reference(state, t, others, robot_q)
        if others is not None and others.count:
            seen = others.visible()
            table = np.concatenate([seen.positions, seen.velocities], 1)
        else:
            table = self._no_others
        has_robot = robot_q is not None and self._geometry is not None
        q = np.asarray(robot_q, float).reshape(4) if has_robot else self._no_q
        return crowd_step(np.asarray(state, float), self._goal_table, self._people_table, table, self._box_table,
                          q, self._object_points, self._kernel_params[has_robot])

    def step_reference(self, state: np.ndarray, t: float, others: PeopleState,
                       robot_q: np.ndarray | None) -> np.ndarray:
        """The state ``time_step`` later, in numpy from the terms of :mod:`~drake_social.people.social_force`.

        First each person whose centre is within ``goal_radius`` of their
        goal moves on to the next (or the first, with ``cycle``; after the
        last, they stop: speed set to 0, and from then on they stand). Then
        the forces at ``state`` (the crowd, the present ``others``, the
        boxes and the robot at ``robot_q``) give ``v' = cap(v + dt F)`` and
        ``x' = x + dt v'`` (semi-implicit Euler), ``cap`` scaling a speed
        above ``max_speed_factor * v0`` down to it. A person who stands
        (past their last goal) has no goal to walk to: their goal force is
        ``-v / tau`` and a speed below :data:`STANDING_SPEED` is set to 0, so
        they move only when pushed (by people, the walls or the robot). The
        heading turns to the velocity's direction when the speed exceeds
        :data:`HEADING_SPEED`, and is kept otherwise.

        Args:
            state: the crowd's state at time ``t``.
            t: seconds (unused: the model is time-invariant).
            others: the open-loop people at ``t``, who count as pedestrians
                the crowd reacts to.
            robot_q: the robot's configuration (4,), or None for no robot.
        """
        pos, vel, heading, goal = self.unpack(state)
        # Goals: move on from every goal reached.
        walking = goal < self._n_goals
        current = self._goal_table[self._rows, np.minimum(goal, self._n_goals - 1)]
        gap = current - pos
        reached = walking & (np.hypot(gap[:, 0], gap[:, 1]) <= self._goal_radius)
        goal = np.where(reached, goal + 1, goal)
        goal = np.where(reached & self._cycle & (goal >= self._n_goals), 0, goal)
        stopped = reached & (goal >= self._n_goals)
        vel[stopped] = 0.0
        walking = goal < self._n_goals
        current = self._goal_table[self._rows, np.minimum(goal, self._n_goals - 1)]
        desired = desired_velocities(pos, current, np.where(walking, self._speeds, 0.0))
        force = goal_force(vel, desired, self._tau)
        # People: the crowd (each without themselves) and the open-loop people present.
        if others is not None and others.count:
            seen = others.visible()
            opos = np.concatenate([pos, seen.positions])
            ovel = np.concatenate([vel, seen.velocities])
        else:
            opos, ovel = pos, vel
        force += pedestrian_force(pos, vel, opos, ovel, self_index=self._rows, **self._interaction)
        force += obstacle_force(pos, self._radii, *self._boxes, strength=self._a, range_=self._b)
        if robot_q is not None and self._geometry is not None:
            force += capsule_force(pos, self._radii, self._robot_capsules(robot_q), self._robot_radii,
                                   strength=self._a, range_=self._b)
        vel = cap_speed(vel + self._dt * force, self._max_speeds)
        standing = ~walking & (np.hypot(vel[:, 0], vel[:, 1]) < STANDING_SPEED)
        vel[standing] = 0.0
        pos = pos + self._dt * vel
        speed = np.hypot(vel[:, 0], vel[:, 1])
        heading = np.where(speed > HEADING_SPEED, np.arctan2(vel[:, 1], vel[:, 0]), heading)
        return np.concatenate([pos[:, 0], pos[:, 1], vel[:, 0], vel[:, 1], heading, goal.astype(float)])

    def people_state(self, state: np.ndarray, t: float) -> PeopleState:
        """The crowd's people in ``state``, reported at time ``t`` (seconds)."""
        # The state holds over a time step while the time moves on: the arrays
        # of the last state asked for are kept (read-only) and shared.
        key = np.asarray(state, float).tobytes()
        if self._last_people is None or self._last_people[0] != key:
            pos, vel, heading, _ = self.unpack(state)  # fresh copies: no need for the constructor's
            self._last_people = (key, PeopleState._trusted(0.0, pos, heading, vel, self._radii, self._names,
                                                           self._present))
        return self._last_people[1].at_time(t)

    # ---- helpers ---------------------------------------------------------

    def _robot_capsules(self, robot_q) -> np.ndarray:
        """(1 + S, 2, 2): the base disc (both ends at its centre), then link 1,
        link 2 and the object's segments (the capsules of
        :meth:`ArmGeometry.segments`, computed here on scalars: one
        configuration per step)."""
        x, y, psi1, psi2 = (float(v) for v in np.asarray(robot_q, float).reshape(4))
        g = self._geometry
        l1, l2 = g.link_lengths
        c1, s1, c2, s2 = math.cos(psi1), math.sin(psi1), math.cos(psi2), math.sin(psi2)
        c12, s12 = c1 * c2 - s1 * s2, s1 * c2 + c1 * s2
        ex, ey = x + l1 * c1, y + l1 * s1
        gx, gy = ex + l2 * c12, ey + l2 * s12
        pts = g.object_points
        verts = np.empty((len(pts), 2))
        verts[:, 0] = gx + c12 * pts[:, 0] - s12 * pts[:, 1]
        verts[:, 1] = gy + s12 * pts[:, 0] + c12 * pts[:, 1]
        out = np.empty((2 + len(pts), 2, 2))
        out[:3, 0] = [[x, y], [x, y], [ex, ey]]
        out[:3, 1] = [[x, y], [ex, ey], [gx, gy]]
        out[3:, 0] = verts[:-1]
        out[3:, 1] = verts[1:]
        return out


def crowd_model(scenario, *, compiled: bool = True) -> SocialForceCrowd | None:
    """The crowd of ``scenario`` (None when it has none).

    Preferred speeds: each person's ``desired_speed``, else drawn by
    :func:`draw_speeds` from ``numpy.random.default_rng(SeedSequence([scenario.random_seed,
    CROWD_SEED_TAG]))`` with ``crowd.speed_mean`` and ``crowd.speed_std``,
    for the people without one, in order. The obstacles and walls come from
    :func:`drake_social.world.world_model`, the robot from
    :class:`~drake_social.kinematics.ArmGeometry`. The scenario is assumed
    valid (:func:`crowd_problems` lists what is not). ``compiled``: as in
    :class:`SocialForceCrowd`.
    """
    crowd = scenario.crowd
    if crowd is None:
        return None
    people = crowd.people
    missing = [i for i, p in enumerate(people) if p.desired_speed is None]
    rng = np.random.default_rng(np.random.SeedSequence([int(scenario.random_seed), CROWD_SEED_TAG]))
    speeds = np.array([math.nan if p.desired_speed is None else float(p.desired_speed) for p in people])
    speeds[missing] = draw_speeds(len(missing), float(crowd.speed_mean), float(crowd.speed_std), rng)
    world = world_model(scenario)
    obs, walls = world.boxes, world.walls
    boxes = (np.concatenate([obs.centers, walls.centers]), np.concatenate([obs.halves, walls.halves]),
             np.concatenate([obs.cos, walls.cos]), np.concatenate([obs.sin, walls.sin]))
    return SocialForceCrowd(
        starts=[[p.x, p.y] for p in people], goals=[p.goals for p in people], cycle=[p.cycle for p in people],
        radii=[p.radius for p in people], speeds=speeds, names=[p.name for p in people], params=crowd,
        boxes=boxes, geometry=arm_geometry(scenario), compiled=compiled)
