"""Slowing down near people: a speed limit that falls with the distance to the nearest person.

:class:`SpeedLimit` reads the robot's configuration ``q = [x, y, psi1, psi2]``
and the people (a :class:`~drake_social.people.PeopleState`) and, every
``period`` seconds, outputs ``speed_limit``: the largest speed (m/s) any point
of the robot may move at. The synchronized reference
(:class:`~drake_social.control.RuckigTrajectorySource` with ``point_speed``)
caps its motion along the path with it, braking jerk-limited on the path
when it falls, down to rest when it is 0. It is speed and separation
monitoring (ISO/TS 15066): the robot keeps moving, slower, near people, and
stops before the safety distance; the safety monitor's stop stays behind it
as the last resort.

The law, for each present person i at surface distance ``d_i`` from the
robot's nearest part (base disc, links, object:
:func:`~drake_social.people.proximity_kernel.robot_distance`, the safety
monitor's distance) and closing at ``c_i`` >= 0 (how fast their own motion
shrinks ``d_i``, from their velocity), with the gap ``g_i = d_i - d_stop``
to the stop distance ``d_stop = safety_distance + stop_margin``:

* **stopping distance** (:func:`allowed_speed`): the largest v such that a
  robot moving at v can still stop within the gap while the person keeps
  closing: ``v (T + A/J) + D(v) + c_i (T + A/J + t(v)) <= g_i``, with
  ``D(v)`` and ``t(v)`` the distance and time of a jerk-limited stop from v
  (:func:`stopping_distance`, :func:`stopping_time`), A and J the
  deceleration and jerk the reference brakes the fastest point with at
  least (:func:`point_braking`), ``T = 2 period`` (the limit reaches the
  reference one period after the sample it is computed from, and the gap is
  sampled once a period) and ``A/J`` the time to turn a full acceleration
  into braking;
* **comfort ramp** (:func:`ramp_speed`): within ``slow_distance`` the limit
  falls linearly from ``max_base_speed`` there to ``slow_speed`` at
  ``d_stop``, as a person carrying a bar slows down near others.

The limit of the moment is the smallest of both over the people (+inf with
nobody near). Braking is Ruckig's, so every slow-down and stop is jerk- and
acceleration-limited. Hysteresis, against chatter:

* a **minimum hold**: the output is the smallest limit of the last
  ``release_time`` seconds (kept per sixteenth of it, so a low value holds
  between ``release_time`` and 1/16 more): it falls at once and rises only
  when the lower values are that old;
* a **release margin**: once the output is 0 (a stop), it stays 0 until that
  windowed limit reaches ``slow_speed``, so the robot does not creep off and
  stop again at the boundary.

Each stop (output 0) is recorded like the safety monitor's
(:class:`~drake_social.control.safety_monitor.Stop`: start, end, the person
that binds, the nearest part, its distance), in the state: read them from a
run's final context (:meth:`SpeedLimit.stops`).

Ports: inputs ``q`` (4) and ``people_state`` (abstract PeopleState); output
``speed_limit`` (1, m/s; +inf when nobody limits). The output reads the state
only (no direct feedthrough).
"""

from __future__ import annotations

import dataclasses as dc
import functools
import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, Context, EventStatus, LeafSystem, State

from drake_social.arguments import require_execution_options
from drake_social.control.path_motion import point_limits, synchronized_limits
from drake_social.control.safety_monitor import SAFETY_PARTS, Stop, robot_reach
from drake_social.kinematics import ArmGeometry, displacement_bound
from drake_social.people import PeopleState, proximity_kernel
from drake_social.people.proximity import part_distances, robot_distance_args
from drake_social.scenario import ExecutionOptions

__all__ = ["CREEP_SPEED", "HOLD_BUCKETS", "SpeedLimit", "SpeedLimitRecord", "allowed_speed", "ramp_speed", "stopping_distance", "stopping_time"]

#: Buckets of the minimum hold's window (see the module docstring).
HOLD_BUCKETS = 16

#: A limit below this is a stop, m/s: the stopping distance's reaction term
#: makes the limit fall in proportion to the gap near the stop distance, so
#: the robot would close the last millimetres ever more slowly, for ever; at
#: 1 mm/s it is within a fraction of a millimetre of it.
CREEP_SPEED = 1e-3

# Bisection steps of allowed_speed: the speed to 2^-60 of the top speed.
_BISECTIONS = 60


def stopping_distance(v: float, decel: float, jerk: float) -> float:
    """Distance (m) of the shortest jerk-limited stop from speed v (m/s) at zero acceleration.

    With deceleration at most ``decel`` (m/s^2) and jerk at most ``jerk``
    (m/s^3): ``v^2 / (2 A) + v A / (2 J)`` when the stop reaches the full
    deceleration (``v >= A^2 / J``), else ``v sqrt(v / J)``.
    """
    if v <= 0.0:
        return 0.0
    if v >= decel * decel / jerk:
        return v * v / (2.0 * decel) + v * decel / (2.0 * jerk)
    return v * math.sqrt(v / jerk)


def stopping_time(v: float, decel: float, jerk: float) -> float:
    """Duration (s) of that stop: ``v / A + A / J``, or ``2 sqrt(v / J)`` below ``A^2 / J``."""
    if v <= 0.0:
        return 0.0
    if v >= decel * decel / jerk:
        return v / decel + decel / jerk
    return 2.0 * math.sqrt(v / jerk)


def _needed(v: float, closing: float, decel: float, jerk: float, reaction: float, approach: float = 1.0) -> float:
    """The gap (m) a robot at v needs to stop while a person closes at ``closing``."""
    lead = reaction + decel / jerk
    return approach * (v * lead + stopping_distance(v, decel, jerk)) + closing * (lead + stopping_time(v, decel, jerk))


def allowed_speed(gap: float, closing: float, *, decel: float, jerk: float, reaction: float, top: float,
                  approach: float = 1.0) -> float:
    """The largest speed in [0, top] (m/s) from which the robot still stops within ``gap`` (m).

    ``rho (v (T + A/J) + D(v)) + c (T + A/J + t(v)) <= gap`` (see the module
    docstring), with ``rho = approach`` (in [0, 1]: the share of the fastest
    point's travel that closes the gap), ``c = closing`` (m/s, >= 0), ``T =
    reaction`` (s), ``A = decel``, ``J = jerk``; 0 when even a robot at rest
    cannot keep the gap, ``top`` when ``top`` can. A robot whose motion does
    not close the gap (``approach = 0``) is limited by a closing person alone
    (it is to be at rest when they arrive), and not at all when nobody closes.
    """
    if approach <= 0.0 and closing <= 0.0 or _needed(top, closing, decel, jerk, reaction, approach) <= gap:
        return top
    if _needed(0.0, closing, decel, jerk, reaction, approach) >= gap:
        return 0.0
    lo, hi = 0.0, top
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        if _needed(mid, closing, decel, jerk, reaction, approach) <= gap:
            lo = mid
        else:
            hi = mid
    return lo


def ramp_speed(distance: float, *, stop_distance: float, slow_distance: float, slow_speed: float,
               full_speed: float) -> float:
    """The comfort ramp (m/s): +inf from ``slow_distance`` on, falling linearly to
    ``slow_speed`` at ``stop_distance`` from ``full_speed`` at ``slow_distance``;
    ``slow_speed`` below ``stop_distance``."""
    if distance >= slow_distance:
        return math.inf
    share = max(distance - stop_distance, 0.0) / (slow_distance - stop_distance)
    return slow_speed + (full_speed - slow_speed) * share


@dc.dataclass(frozen=True)
class SpeedLimitRecord:
    """The limiter's state (immutable, shared by copies).

    Attributes:
        limit: the output, m/s (+inf: none).
        buckets: ``(index, smallest limit)`` of the hold's window, oldest
            first: bucket k holds the samples of ``[k w, (k + 1) w)``, ``w =
            release_time / HOLD_BUCKETS``.
        stopped: the output is 0 (a stop), released only at ``slow_speed``.
        stops: every stop in order; the last one has ``end = None`` while stopped.
    """

    limit: float = math.inf
    buckets: tuple[tuple[int, float], ...] = ()
    stopped: bool = False
    stops: tuple[Stop, ...] = ()

    def __copy__(self):
        return self

    def __deepcopy__(self, memo):
        return self


class SpeedLimit(LeafSystem):
    """Outputs the largest speed of the robot's fastest point near people (see the module docstring).

    Args:
        geometry: the robot and its object (``drake_social.scenario.geometry.arm_geometry``).
        options: the scenario's ``execution`` section: ``safety_distance``,
            ``stop_margin``, ``slow_distance``, ``slow_speed``,
            ``release_time``, ``control_period`` (the update's period) and
            the limits of the synchronized reference
            (:func:`~drake_social.control.path_motion.synchronized_limits`).

    Raises:
        TypeError: ``geometry`` is not an ArmGeometry, ``options`` not ExecutionOptions.
    """

    def __init__(self, geometry: ArmGeometry, options: ExecutionOptions):
        super().__init__()
        if not isinstance(geometry, ArmGeometry):
            raise TypeError(f"SpeedLimit: geometry must be a drake_social.kinematics.ArmGeometry, "
                            f"got {type(geometry).__name__}")
        require_execution_options(options, "SpeedLimit")
        self._geometry = geometry
        self._args = robot_distance_args(geometry)
        self._reach = robot_reach(geometry)
        self._period = float(options.control_period)
        self._stop = float(options.safety_distance) + float(options.stop_margin)
        self._slow_distance = float(options.slow_distance)
        self._slow_speed = float(options.slow_speed)
        self._full_speed = float(options.max_base_speed)
        self._release = float(options.release_time)
        self._bucket = self._release / HOLD_BUCKETS
        self._reaction = 2.0 * self._period
        self._limit_args = synchronized_limits(options)
        lever = np.asarray(geometry.lever(include_body=True), float)
        self._point_speed = functools.partial(displacement_bound, lever=lever)
        self._q_port = self.DeclareVectorInputPort("q", 4)
        self._target_port = self.DeclareVectorInputPort("target", 4)
        self._people_port = self.DeclareAbstractInputPort(
            "people_state", AbstractValue.Make(PeopleState(0.0, np.zeros((0, 2)), np.zeros(0), np.zeros((0, 2)),
                                                           np.zeros(0), ())))
        self._record_index = self.DeclareAbstractState(AbstractValue.Make(SpeedLimitRecord()))
        self.DeclarePeriodicUnrestrictedUpdateEvent(self._period, 0.0, self._Decide)
        self.DeclareForcedUnrestrictedUpdateEvent(self._Decide)
        self.DeclareVectorOutputPort("speed_limit", 1, self._CalcLimit,
                                     prerequisites_of_calc={self.abstract_state_ticket(self._record_index)})

    @property
    def stop_distance(self) -> float:
        """``safety_distance + stop_margin``: where the limit plans the robot's rest, metres."""
        return self._stop

    def record(self, context: Context) -> SpeedLimitRecord:
        """The limiter's state in ``context`` (this system's context)."""
        return context.get_abstract_state(self._record_index).get_value()

    def stops(self, context: Context) -> tuple[Stop, ...]:
        """Every stop (output 0) so far in ``context``, in order."""
        return self.record(context).stops

    def law(self, distance: float, closing: float, approach: float, braking: tuple[float, float, float]) -> float:
        """The limit (m/s) for one person at surface distance ``distance`` (m) closing at ``closing``
        (m/s), the robot's motion closing the gap at ``approach`` (in [0, 1]) times the fastest
        point's speed, which moves at most at ``braking = (top speed, deceleration, jerk)``
        (:func:`~drake_social.control.path_motion.point_limits` of the motion); +inf when it
        does not limit the motion."""
        top, decel, jerk = braking
        stopping = allowed_speed(distance - self._stop, max(closing, 0.0), decel=decel, jerk=jerk,
                                 reaction=self._reaction, top=top, approach=approach)
        ramp = ramp_speed(distance, stop_distance=self._stop, slow_distance=self._slow_distance,
                          slow_speed=self._slow_speed, full_speed=self._full_speed)
        limit = min(stopping, ramp / approach if approach > 0.0 else math.inf)
        if limit < CREEP_SPEED:
            return 0.0
        return math.inf if limit >= top else limit

    def limit_of(self, q, people: PeopleState, target=None) -> tuple[float, int]:
        """The limit of the moment (m/s, +inf: none) and the person that binds it (-1: nobody).

        Args:
            q: (4,) the robot's configuration.
            people: the people.
            target: (4,) where the robot heads along a straight motion (the
                sequencer's target), which decides how much of its motion
                closes the gap to each person; None or ``q``: it does not move.
        """
        q = np.array(q, float).reshape(4)
        step = np.zeros(4) if target is None else np.asarray(target, float).reshape(4) - q
        length = float(np.linalg.norm(step))
        if length == 0.0:  # the robot does not move: nothing to limit
            return math.inf, -1
        u = step / length
        braking = point_limits(u, self._limit_args, self._point_speed)
        top, decel, jerk = braking
        # A cheap lower bound of each distance first: most people are too far to matter. Beyond
        # the horizon neither the ramp nor the stopping distance limits (the gap a robot at the
        # top speed needs grows linearly with the closing speed, at most the person's speed).
        speeds = np.hypot(people.velocities[:, 0], people.velocities[:, 1])
        lower = np.hypot(people.positions[:, 0] - q[0], people.positions[:, 1] - q[1]) - people.radii - self._reach
        still = _needed(top, 0.0, decel, jerk, self._reaction)
        per_closing = _needed(top, 1.0, decel, jerk, self._reaction) - still
        horizon = np.maximum(self._slow_distance, self._stop + still + speeds * per_closing)
        # The approach is measured along the motion over a point's travel in a stop from the lower of
        # the ramp's full speed and the motion's top speed (reaction included), at half and at all of it.
        k = float(self._point_speed(u))
        span = min(length, _needed(min(self._full_speed, top), 0.0, decel, jerk, self._reaction) / k)
        ahead = [(q + u * (span * f), k * span * f) for f in (0.5, 1.0)]
        best, who = math.inf, -1
        for i in np.flatnonzero(people.present & (lower < horizon)):
            centre, radius = people.positions[i], float(people.radii[i])
            d = self._distance(q, centre, radius)
            closing = 0.0
            if speeds[i] > 0.0:  # how fast their own motion shrinks the distance
                moved = self._distance(q, centre + people.velocities[i] * self._period, radius)
                closing = max((d - moved) / self._period, 0.0)
            # The share of the fastest point's travel along the motion that closes the gap.
            approach = max([(d - self._distance(qa, centre, radius)) / travel for qa, travel in ahead], default=0.0)
            limit = self.law(d, closing, min(max(approach, 0.0), 1.0), braking)
            if limit < best:
                best, who = limit, int(i)
        return best, who

    def _distance(self, q: np.ndarray, centre, radius: float) -> float:
        return float(proximity_kernel.robot_distance(q, np.cos(q[2:]), np.sin(q[2:]), *self._args,
                                                     np.asarray(centre, float).reshape(1, 2), np.array([radius]),
                                                     np.ones(1, bool)))

    def _Decide(self, context: Context, state: State) -> None:
        record = self.record(context)
        t = context.get_time()
        people = self._people_port.Eval(context)
        q = self._q_port.Eval(context)
        target = self._target_port.Eval(context) if self._target_port.HasValue(context) else None
        limit, who = self.limit_of(q, people, target)
        buckets, windowed = self._Window(record.buckets, t, limit)
        stopped, stops = record.stopped, record.stops
        if stopped and windowed >= self._slow_speed:  # released: the margin reached, held long enough
            stopped = False
            stops = stops[:-1] + (dc.replace(stops[-1], end=t),)
        elif not stopped and windowed <= 0.0:
            stopped = True
            stops = stops + (self._Stop(t, q, people, who),)
        out = 0.0 if stopped else windowed
        new = SpeedLimitRecord(limit=out, buckets=buckets, stopped=stopped, stops=stops)
        if new == record:
            return EventStatus.DidNothing()
        state.get_mutable_abstract_state(self._record_index).set_value(new)
        return None

    def _Window(self, buckets: tuple, t: float, limit: float) -> tuple[tuple, float]:
        """The hold's buckets with the limit of time t, and their smallest limit."""
        if self._bucket <= 0.0:
            return (), limit
        k = int(math.floor(t / self._bucket + 1e-9))
        oldest = k - HOLD_BUCKETS  # bucket j is over when (j + 1) w <= t - release_time
        kept = [(j, v) for j, v in buckets if j >= oldest]
        if math.isfinite(limit):
            if kept and kept[-1][0] == k:
                kept[-1] = (k, min(kept[-1][1], limit))
            else:
                kept.append((k, limit))
        return tuple(kept), min((v for _, v in kept), default=math.inf)

    def _Stop(self, t: float, q, people: PeopleState, who: int) -> Stop:
        """The record of a stop starting at t, bound by person ``who``."""
        if who < 0:  # a stop held over from the window: nobody binds now
            return Stop(t, None, "", "", math.inf)
        d = part_distances(self._geometry, np.asarray(q, float).reshape(1, 4), people.positions[who:who + 1],
                           people.radii[who:who + 1])
        part = min(SAFETY_PARTS, key=lambda name: float(d[name][0]))
        return Stop(t, None, people.names[who] or str(who), part, float(d[part][0]))

    def _CalcLimit(self, context: Context, output: BasicVector) -> None:
        output.SetAtIndex(0, self.record(context).limit)
