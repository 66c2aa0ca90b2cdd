"""Jerk-limited reference trajectories from Ruckig: *when* each joint gets there.

:class:`RuckigTrajectorySource` turns a piecewise-constant target (n DoFs)
into a smooth reference that never exceeds the velocity, acceleration and
jerk limits. Whenever its periodic update sees a target different from the
one it is heading for, it computes a new time-optimal segment with the
offline ``Ruckig(n).calculate`` from the reference's current position,
velocity and acceleration, so the reference never jumps. Between updates the
outputs only evaluate the stored segment at the context time.

State: one abstract value, an immutable :class:`RuckigSegment` (start time
t0, the ``ruckig.Trajectory`` or None when at rest, the rest position, the
target it heads for). Outputs depend on the state and the time only (no
direct feedthrough from ``target``); the position, velocity and acceleration
of one instant come from one cache entry of the context, so the system keeps
nothing of a run on ``self`` (a cloned context, or a second context of the
same system, runs on its own).

Ports: inputs ``target`` (n; while it has no value, the reference stays
where it is) and ``hold`` (1, optional: unconnected = never held); outputs ``position``, ``velocity``,
``acceleration`` (n each), ``state`` (3n: the three in one evaluation, for
a consumer that reads them at every step of a fast plant) and ``finished``
(1: 1.0 once ``t - t0 >= duration``, never while held).

The hold (a safety stop): an update that reads ``hold`` > 0.5 replaces the
segment by a *held* rest segment at the reference's current position (the
reference stops there: position continuous, velocity and acceleration to 0)
and keeps it while ``hold`` stays on, whatever the target. The first update
after the hold is released plans a new segment from rest at that position to
the current target, as from any rest: with ``synchronization="phase"`` on the
straight segment to the target, so the synchronized reference goes on along
the straight segment it was on. With ``hold`` unconnected or 0 nothing of
this runs and the reference is exactly the one without the port.

Ruckig is only ever given a current and a target state, never intermediate
positions: the community version would otherwise call a remote web service.
Nor does it take position limits (a feature of Ruckig Pro); with
``position_limits`` the source itself keeps the reference within them: it
checks each new segment's position extrema and, when a segment would leave
the limits, heads for the new target only once at rest (a rest-to-rest
segment between two positions within the limits stays within them).

Factories: :func:`arm_source_from_options` (the two arm joints) and
:func:`reference_source_from_options` (the synchronized 4-DoF reference
``[x, y, psi1, psi2]``, phase-synchronized so that each segment from rest is
a motion on the straight segment, with the base speed limit on the *norm* of ``[vx, vy]``
and the wheels' limit on ``|vx| + |vy|``).

Example::

    import numpy as np
    from pydrake.systems.analysis import Simulator
    from drake_social.control import RuckigTrajectorySource

    dut = RuckigTrajectorySource(initial_position=[0.0, 0.0], max_velocity=[1.0, 1.0],
                                 max_acceleration=[2.0, 2.0], max_jerk=[10.0, 10.0], period=0.01)
    simulator = Simulator(dut)
    dut.GetInputPort("target").FixValue(simulator.get_mutable_context(), [1.0, -0.5])
    simulator.AdvanceTo(3.0)
    context = simulator.get_context()
    print(dut.GetOutputPort("position").Eval(context))  # [ 1.  -0.5]
    print(dut.GetOutputPort("finished").Eval(context))  # [1.]
"""

from __future__ import annotations

import functools
import math
from typing import Callable, Sequence

import numpy as np
import ruckig
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import EventStatus, BasicVector, Context, LeafSystem, State, ValueProducer

from drake_social.arguments import real_array, require_execution_options
from drake_social.control.path_motion import (PathProfile, Polyline, path_speed_factor, run_limits, speed_cap,
                                              synchronized_limits)
from drake_social.kinematics import displacement_bound
from drake_social.scenario import ExecutionOptions

__all__ = [
    "RuckigSegment",
    "RuckigTrajectorySource",
    "arm_source_from_options",
    "reference_source_from_options",
]

_SYNCHRONIZATIONS = {
    "time": ruckig.Synchronization.Time,
    "phase": ruckig.Synchronization.Phase,
    "time_if_necessary": ruckig.Synchronization.TimeIfNecessary,
    "none": ruckig.Synchronization.No,
}

# Smallest share of a norm-limited group's limits that a DoF gets, so that a
# DoF that does not move still has a valid (positive) limit.
_SHARE_FLOOR = 1e-6

# Ruckig's position extrema and at_time() are exact up to rounding; a segment
# whose extrema pass a position limit by at most this much (in the DoF's
# units, relative to max(1, |limit|)) is within it, and its outputs are
# clipped to the limits, which removes only that rounding.
_LIMIT_ROUNDING = 1e-12

# A speed limit that rises re-plans a motion along a path only when the cap
# of its speed rises by more than this share (a lower one re-plans at once):
# a limit that changes every period near a person does not re-plan the
# profile every period for a gain of nothing.
_CAP_RAISE = 1e-3


class RuckigSegment:
    """One reference segment: immutable, so copies may share it.

    ``ruckig.Trajectory`` cannot be deep-copied; Drake clones abstract state
    (contexts, ``AbstractValue.Clone``), so ``copy``/``deepcopy`` return the
    object itself. Nothing ever mutates a segment after construction.

    Attributes:
        t0: start time of the segment, seconds.
        trajectory: the ``ruckig.Trajectory`` from t0, or None when at rest.
        rest: (n,) position held when ``trajectory`` is None.
        target: (n,) target this segment heads for, or None when no target
            has been seen yet (any target then starts a segment).
        held: a rest segment of the hold (see the module docstring): the
            next update without the hold starts a segment to the target.
        clip: (lower, upper) position limits (lists of floats) the segment's
            extrema respect up to rounding; positions are clipped to them, or None.
    """

    __slots__ = ("t0", "trajectory", "rest", "target", "target_list", "clip", "held")

    def __init__(self, t0: float, trajectory, rest: np.ndarray, target: np.ndarray | None,
                 clip: tuple[np.ndarray, np.ndarray] | None = None, held: bool = False):
        object.__setattr__(self, "t0", float(t0))
        object.__setattr__(self, "trajectory", trajectory)
        rest = np.array(rest, float)
        rest.flags.writeable = False
        object.__setattr__(self, "rest", rest)
        if target is not None:
            target = np.array(target, float)
            target.flags.writeable = False
        object.__setattr__(self, "target", target)
        object.__setattr__(self, "target_list", None if target is None else target.tolist())
        object.__setattr__(self, "clip", clip)
        object.__setattr__(self, "held", bool(held))

    def __setattr__(self, name, value):
        raise AttributeError("RuckigSegment is immutable")

    def __copy__(self):
        return self

    def __deepcopy__(self, memo):
        return self

    @property
    def duration(self) -> float:
        """Duration of the motion, seconds (0 when at rest)."""
        return 0.0 if self.trajectory is None else float(self.trajectory.duration)

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position, velocity, acceleration at time t.

        Before t0 the start state; from t0 + duration on, exactly at rest at the target.
        """
        if self.trajectory is None:
            zero = np.zeros_like(self.rest)
            return self.rest.copy(), zero, zero.copy()
        duration = self.trajectory.duration
        if t - self.t0 >= duration:
            # Exactly at rest at the target (at_time(duration) leaves ~1e-16
            # residues, which would make the next rest-to-rest segment
            # non-collinear and Ruckig fall back from phase to time sync);
            # a motion along a path at rest where it ends (a stop mid-run).
            end = getattr(self.trajectory, "end", None)
            zero = np.zeros_like(self.rest)
            return (self.target.copy() if end is None else np.array(end, float)), zero, zero.copy()
        # at_time extrapolates for t < t0: clamp.
        p, v, a = self.trajectory.at_time(max(t - self.t0, 0.0))
        if self.clip is not None:  # rounding only: see _LIMIT_ROUNDING (plain floats: this runs every step)
            p = [lo if x < lo else hi if x > hi else x for x, lo, hi in zip(p, *self.clip)]
        return np.array(p, float), np.array(v, float), np.array(a, float)


def _limit_vector(name: str, value, n: int) -> np.ndarray:
    v = np.array(value, float).reshape(-1)
    if v.shape != (n,) or not np.all(np.isfinite(v)) or not np.all(v > 0):
        raise ValueError(
            f"RuckigTrajectorySource: {name} must hold {n} finite numbers > 0 (one per DoF), got {value!r}"
        )
    return v


def _direction_share(*vectors: np.ndarray) -> np.ndarray:
    """Per-DoF share of a norm limit: the elementwise max of |u_i| / |u| over the non-zero vectors, floored."""
    share = np.full(len(vectors[0]), _SHARE_FLOOR)
    scale = max(1.0, *(float(np.max(np.abs(u))) for u in vectors))
    for u in vectors:
        norm = np.linalg.norm(u)
        if norm > 1e-12 * scale:
            share = np.maximum(share, np.abs(u) / norm)
    return share


class RuckigTrajectorySource(LeafSystem):
    """A jerk-limited reference that heads for its ``target`` input.

    Args:
        initial_position: (n,) rest position before any target (and in a
            default context), in the DoFs' units (metres or radians).
        max_velocity: (n,) velocity limits, units/s (> 0).
        max_acceleration: (n,) acceleration limits, units/s^2 (> 0).
        max_jerk: (n,) jerk limits, units/s^3 (> 0).
        period: period of the update that reads the target, seconds (> 0).
        synchronization: "time", "phase", "time_if_necessary", "none" or a
            ``ruckig.Synchronization``. With "phase", a segment from rest is
            the time-optimal motion *on the straight segment* (a 1-DoF
            Ruckig profile of the distance along it, each limit the tightest
            the DoFs allow); Ruckig's own n-DoF phase synchronization falls
            back to time synchronization, off the segment, when the DoFs'
            profiles differ in shape.
        xy_norm_dofs: indices of DoFs (e.g. ``(0, 1)`` for the base x, y)
            whose limits bound the *norm* of their velocity, acceleration and
            jerk instead of each component (on a straight segment from rest:
            exactly). When a target changes mid-motion, their limits are
            scaled by ``|d_i| / |d|`` (d the displacement of those DoFs), each
            share at least the share of the current velocity and
            acceleration, so the current state stays within the per-DoF
            limits (that transition is not on a straight line and its norm
            may exceed the limit by up to sqrt(2)).
        xy_max_abs_sum: when given (units/s, > 0; needs ``xy_norm_dofs``),
            also bounds the *sum* of the group's absolute velocities: the
            group's speed limit on a segment of direction d is
            ``min(max_velocity, xy_max_abs_sum |d| / sum_i |d_i|)``
            (mecanum wheels at ``max_wheel_speed`` reach exactly
            ``|vx| + |vy| = max_wheel_speed * wheel_radius``).
        position_limits: when given, ``(lower, upper)`` (n each, lower <
            upper): the reference stays within them. A target outside them
            is an error; a new segment whose position extrema (Ruckig's
            ``position_extrema``) would leave them is not started while the
            reference moves (the current segment, within the limits,
            finishes first), and from rest it is the straight segment
            (between two points of the box, within it). Positions are
            clipped to the limits, which removes only rounding (see
            ``_LIMIT_ROUNDING``).
        preview: when given (seconds, > 0), an extra output port
            ``mean_velocity`` = ``(position(t + preview) - position(t)) /
            preview`` along the current segment: the feed-forward that makes
            a controller sampled every ``preview`` seconds (behind a
            zero-order hold) land exactly on the reference at the next sample.
        via: declare the abstract input port ``via`` ((m, n) positions, m >=
            0; unconnected = none): with ``synchronization="phase"`` a
            segment from rest runs along the polyline from the rest position
            through them to the target (a :class:`~drake_social.control.path_motion.PathProfile`:
            one profile of the distance travelled, so the speed is carried
            through them), on its straight segments exactly.
        point_speed: a function of a unit direction u (n,) giving the speed
            of the robot's fastest point per unit of speed along u (e.g.
            :func:`~drake_social.kinematics.displacement_bound` with the arm's
            levers); declares the input port ``speed_limit`` (1: the largest
            speed of that point, m/s; unconnected or +inf = none), which caps
            the speed of a motion along a path: a lower limit re-plans the
            profile from the current state at once (jerk-limited braking on
            the path), a higher one when it rises by more than
            ``_CAP_RAISE``; a limit of 0 brakes to rest on the path. It also
            declares the input ``brake`` (1; unconnected = never): above 0.5
            the limit is 0, so the motion brakes to rest on its path,
            jerk-limited (a replanner's wait, where ``hold`` is the safety
            stop's instant one), and goes on along it when released.

    Raises:
        ValueError: limits not positive or of the wrong length, unknown
            synchronization, bad ``xy_norm_dofs``, ``xy_max_abs_sum`` or
            ``position_limits``.
        RuntimeError: (from an update) Ruckig cannot compute a segment, or
            the target lies outside ``position_limits``.
    """

    def __init__(
        self,
        *,
        initial_position: Sequence[float],
        max_velocity: Sequence[float],
        max_acceleration: Sequence[float],
        max_jerk: Sequence[float],
        period: float,
        synchronization: str | ruckig.Synchronization = "time",
        xy_norm_dofs: Sequence[int] | None = None,
        xy_max_abs_sum: float | None = None,
        position_limits: tuple[Sequence[float], Sequence[float]] | None = None,
        preview: float | None = None,
        via: bool = False,
        point_speed: Callable[[np.ndarray], float] | None = None,
    ):
        super().__init__()
        initial = np.array(initial_position, float).reshape(-1)
        n = len(initial)
        if n == 0 or not np.all(np.isfinite(initial)):
            raise ValueError(f"RuckigTrajectorySource: initial_position must be finite, n >= 1; got {initial_position!r}")
        self._n = n
        self._initial = initial
        self._max_velocity = _limit_vector("max_velocity", max_velocity, n)
        self._max_acceleration = _limit_vector("max_acceleration", max_acceleration, n)
        self._max_jerk = _limit_vector("max_jerk", max_jerk, n)
        if not (np.isfinite(period) and period > 0):
            raise ValueError(f"RuckigTrajectorySource: period must be a finite number > 0, got {period!r}")
        if isinstance(synchronization, str):
            if synchronization not in _SYNCHRONIZATIONS:
                raise ValueError(
                    f"RuckigTrajectorySource: synchronization must be one of {sorted(_SYNCHRONIZATIONS)}, "
                    f"got {synchronization!r}"
                )
            synchronization = _SYNCHRONIZATIONS[synchronization]
        self._synchronization = synchronization
        self._norm_dofs = None
        if xy_norm_dofs is not None:
            dofs = [int(i) for i in xy_norm_dofs]
            if len(dofs) < 2 or len(set(dofs)) != len(dofs) or not all(0 <= i < n for i in dofs):
                raise ValueError(
                    f"RuckigTrajectorySource: xy_norm_dofs must be >= 2 distinct DoF indices in [0, {n}), "
                    f"got {xy_norm_dofs!r}"
                )
            self._norm_dofs = np.array(dofs)
        self._max_abs_sum = None
        if xy_max_abs_sum is not None:
            if self._norm_dofs is None or not (np.isfinite(xy_max_abs_sum) and xy_max_abs_sum > 0):
                raise ValueError(
                    f"RuckigTrajectorySource: xy_max_abs_sum must be a finite number > 0 and needs xy_norm_dofs, "
                    f"got {xy_max_abs_sum!r}"
                )
            self._max_abs_sum = float(xy_max_abs_sum)
        self._position_limits = None
        if position_limits is not None:
            try:
                lower, upper = (np.array(v, float).reshape(-1) for v in position_limits)
            except (TypeError, ValueError):
                lower = upper = np.zeros(0)
            if (lower.shape != (n,) or upper.shape != (n,) or not np.all(np.isfinite(lower))
                    or not np.all(np.isfinite(upper)) or not np.all(lower < upper)):
                raise ValueError(
                    f"RuckigTrajectorySource: position_limits must be (lower, upper) of {n} finite numbers each "
                    f"with lower < upper, got {position_limits!r}"
                )
            if not np.all((initial >= lower) & (initial <= upper)):
                raise ValueError(f"RuckigTrajectorySource: initial_position {initial.tolist()} is outside "
                                 f"position_limits [{lower.tolist()}, {upper.tolist()}]")
            lower.flags.writeable = False
            upper.flags.writeable = False
            self._position_limits = (lower, upper)
            self._limit_lists = (lower.tolist(), upper.tolist())

        self._target_port = self.DeclareVectorInputPort("target", n)
        self._hold_port = self.DeclareVectorInputPort("hold", 1)
        self._via_port = self.DeclareAbstractInputPort("via", AbstractValue.Make(np.zeros((0, n)))) if via else None
        if point_speed is not None and not callable(point_speed):
            raise ValueError(f"RuckigTrajectorySource: point_speed must be a function of a direction, got "
                             f"{point_speed!r}")
        self._point_speed = point_speed
        self._speed_port = self.DeclareVectorInputPort("speed_limit", 1) if point_speed is not None else None
        self._brake_port = self.DeclareVectorInputPort("brake", 1) if point_speed is not None else None
        self._segment_index = self.DeclareAbstractState(AbstractValue.Make(self._RestSegment(0.0, initial)))
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._Retarget)
        # The same update on demand (CalcForcedUnrestrictedUpdate), for tests and scripts.
        self.DeclareForcedUnrestrictedUpdateEvent(self._Retarget)

        prereqs = {self.abstract_state_ticket(self._segment_index), self.time_ticket()}
        # (p, v, a) at the context's time: the position, velocity and
        # acceleration ports of one instant share one at_time() call.
        self._at_cache = self.DeclareCacheEntry(
            "reference (position, velocity, acceleration) at the context's time",
            ValueProducer(allocate=lambda: AbstractValue.Make((initial, initial, initial)), calc=self._CalcAt),
            prerequisites_of_calc=prereqs)
        self.DeclareVectorOutputPort("position", n, self._CalcPosition, prerequisites_of_calc=prereqs)
        self.DeclareVectorOutputPort("velocity", n, self._CalcVelocity, prerequisites_of_calc=prereqs)
        self.DeclareVectorOutputPort("acceleration", n, self._CalcAcceleration, prerequisites_of_calc=prereqs)
        self.DeclareVectorOutputPort("state", 3 * n, self._CalcState, prerequisites_of_calc=prereqs)
        self.DeclareVectorOutputPort("finished", 1, self._CalcFinished, prerequisites_of_calc=prereqs)
        self._preview = None
        if preview is not None:
            if not (np.isfinite(preview) and preview > 0):
                raise ValueError(f"RuckigTrajectorySource: preview must be a finite number > 0, got {preview!r}")
            self._preview = float(preview)
            self.DeclareVectorOutputPort("mean_velocity", n, self._CalcMeanVelocity, prerequisites_of_calc=prereqs)

    @staticmethod
    def _RestSegment(t0: float, position) -> RuckigSegment:
        return RuckigSegment(t0, None, position, None)

    def SetInitialPosition(self, context: Context, q: Sequence[float]) -> None:
        """Puts the reference at rest at ``q`` (n,) in ``context``; the next update heads for the target."""
        q = np.array(q, float).reshape(-1)
        if q.shape != (self._n,) or not np.all(np.isfinite(q)):
            raise ValueError(f"{self.get_name()}: SetInitialPosition needs {self._n} finite numbers, got {q!r}")
        limits = self._position_limits
        if limits is not None and not np.all((q >= limits[0]) & (q <= limits[1])):
            raise ValueError(f"{self.get_name()}: SetInitialPosition: {q.tolist()} is outside the position limits "
                             f"[{limits[0].tolist()}, {limits[1].tolist()}]")
        context.get_mutable_abstract_state(self._segment_index).set_value(self._RestSegment(context.get_time(), q))

    # ---- event -----------------------------------------------------------------

    def _Segment(self, context: Context) -> RuckigSegment:
        return context.get_abstract_state(self._segment_index).get_value()

    def _Limits(self, d: np.ndarray, v: np.ndarray, a: np.ndarray):
        vmax, amax, jmax = self._max_velocity.copy(), self._max_acceleration.copy(), self._max_jerk.copy()
        if self._norm_dofs is not None:
            g = self._norm_dofs
            share = _direction_share(d[g], v[g], a[g])
            if self._max_abs_sum is not None:
                # Along the segment v_i = s share_i, so sum |v_i| <= xy_max_abs_sum
                # when the group's speed s <= xy_max_abs_sum / sum(share).
                vmax[g] = np.minimum(vmax[g], self._max_abs_sum / share.sum())
            vmax[g] *= share
            amax[g] *= share
            jmax[g] *= share
        return vmax, amax, jmax

    def _Retarget(self, context: Context, state: State) -> None:
        if self._hold_port.HasValue(context) and self._hold_port.Eval(context)[0] > 0.5:
            return self._Hold(context, state)
        if not self._target_port.HasValue(context):
            return EventStatus.DidNothing()  # no target yet (unconnected, unfixed): stay as is
        segment = self._Segment(context)
        target = self._target_port.Eval(context)
        if segment.target is not None and target.tolist() == segment.target_list:
            if not segment.held:
                return self._Recap(context, state, segment)  # the common case, every period: keep it cheap
            if isinstance(segment.trajectory, PathProfile):  # released: on along the same path
                return self._Replan(context, state, segment)
        target = np.asarray(target, float)
        if not np.all(np.isfinite(target)):
            raise RuntimeError(f"{self.get_name()}: the target input must be finite, got {target}")
        t = context.get_time()
        p, v, a = segment.at(t)
        limits = self._position_limits
        if limits is not None and not np.all((target >= limits[0]) & (target <= limits[1])):
            raise RuntimeError(f"{self.get_name()}: the target {target.tolist()} at t = {t} s is outside the "
                               f"position limits [{limits[0].tolist()}, {limits[1].tolist()}]")
        at_rest = not (np.any(v) or np.any(a))
        if at_rest and self._synchronization == ruckig.Synchronization.Phase:
            trajectory = self._Path(context, p, self._Via(context, t), target)
        else:
            trajectory = self._Calculate(t, p, v, a, target, self._synchronization)
            if limits is not None and not self._WithinLimits(trajectory):
                if not at_rest:
                    # The current segment stays within the limits and ends at rest;
                    # the next update after that starts a rest-to-rest segment.
                    return EventStatus.DidNothing()
                trajectory = self._Path(context, p, np.zeros((0, self._n)), target)  # in the box: within it
        if trajectory is None:  # already there
            state.get_mutable_abstract_state(self._segment_index).set_value(RuckigSegment(t, None, target, target))
            return None
        state.get_mutable_abstract_state(self._segment_index).set_value(
            RuckigSegment(t, trajectory, p, target, clip=None if limits is None else self._limit_lists))

    def _Hold(self, context: Context, state: State) -> None:
        """Stops the reference where it is (once; then keeps it while held).

        A motion along a path stops on it and keeps the path, so the release
        goes on along it (:meth:`_Replan`)."""
        segment = self._Segment(context)
        if segment.held:
            return EventStatus.DidNothing()
        t = context.get_time()
        p = segment.at(t)[0]
        if isinstance(segment.trajectory, PathProfile):
            held = RuckigSegment(t, segment.trajectory.resting(t - segment.t0), p, segment.target,
                                 clip=segment.clip, held=True)
        else:
            held = RuckigSegment(t, None, p, segment.target, held=True)
        state.get_mutable_abstract_state(self._segment_index).set_value(held)
        return None

    def _Cap(self, context: Context) -> float:
        """The ``speed_limit`` input, m/s of the fastest point (+inf: none, or
        unconnected); 0 while the ``brake`` input is above 0.5."""
        if self._brake_port is not None and self._brake_port.HasValue(context) and \
                self._brake_port.Eval(context)[0] > 0.5:
            return 0.0
        if self._speed_port is None or not self._speed_port.HasValue(context):
            return math.inf
        value = float(self._speed_port.Eval(context)[0])
        if math.isnan(value):
            raise RuntimeError(f"{self.get_name()}: the speed_limit input is NaN at t = {context.get_time()} s")
        return value

    def _Recap(self, context: Context, state: State, segment: RuckigSegment):
        """Re-plans a motion along a path whose speed cap the ``speed_limit`` input changed."""
        profile = segment.trajectory
        if self._speed_port is None or not isinstance(profile, PathProfile):
            return EventStatus.DidNothing()
        cap = speed_cap(profile.limits, self._Cap(context), path_speed_factor(profile.path, self._point_speed))
        if cap < profile.cap:  # lower: at once, unless at rest at the end
            arrived = context.get_time() - segment.t0 >= profile.duration and profile.arrives
            if arrived:
                return EventStatus.DidNothing()
        elif not (cap > 0.0 == profile.cap or cap > profile.cap * (1.0 + _CAP_RAISE)):
            return EventStatus.DidNothing()  # the same, or not risen enough to matter
        return self._Replan(context, state, segment, cap)

    def _Replan(self, context: Context, state: State, segment: RuckigSegment, cap: float | None = None):
        """A new profile along the segment's path from its state at the context's time."""
        profile = segment.trajectory
        t = context.get_time()
        if cap is None:
            cap = speed_cap(profile.limits, self._Cap(context), path_speed_factor(profile.path, self._point_speed))
        s, sd, sdd = profile.state(t - segment.t0)
        try:
            new = PathProfile.plan(profile.path, profile.limits, cap, s, sd, sdd)
        except RuntimeError as error:
            raise RuntimeError(f"{self.get_name()}: at t = {t} s: {error}") from error
        state.get_mutable_abstract_state(self._segment_index).set_value(
            RuckigSegment(t, new, segment.at(t)[0], segment.target, clip=segment.clip))
        return None

    def _Via(self, context: Context, t: float) -> np.ndarray:
        """The ``via`` input as an (m, n) array (none when undeclared or unconnected)."""
        if self._via_port is None or not self._via_port.HasValue(context):
            return np.zeros((0, self._n))
        via = np.asarray(self._via_port.Eval(context), float).reshape(-1, self._n)
        if not np.all(np.isfinite(via)):
            raise RuntimeError(f"{self.get_name()}: the via input must be finite, got {via.tolist()} at t = {t} s")
        limits = self._position_limits
        if limits is not None and not np.all((via >= limits[0]) & (via <= limits[1])):
            raise RuntimeError(f"{self.get_name()}: a via position {via.tolist()} at t = {t} s is outside the "
                               f"position limits [{limits[0].tolist()}, {limits[1].tolist()}]")
        return via

    def _Path(self, context: Context, p: np.ndarray, via: np.ndarray, target: np.ndarray) -> PathProfile | None:
        """The time-optimal motion from rest at p through ``via`` to rest at the target (None if p == target).

        One 1-DoF Ruckig profile of the distance s along the polyline (a
        :class:`~drake_social.control.path_motion.PathProfile`), with each
        limit the tightest of the DoFs' on every segment
        (:func:`~drake_social.control.path_motion.line_limits`) and the
        speed capped by the ``speed_limit`` input. Unlike an n-DoF phase
        synchronization, which Ruckig silently turns into a time
        synchronization off the segment when the DoFs' profiles differ in
        shape, it exists for every pair of limits.
        """
        t = context.get_time()
        points = np.vstack([p[None], via, target[None]])
        if not np.any(points != p):
            return None
        path = Polyline(points)
        limits = run_limits(path, (self._max_velocity, self._max_acceleration, self._max_jerk, self._norm_dofs,
                                   self._max_abs_sum))
        cap = speed_cap(limits, self._Cap(context), path_speed_factor(path, self._point_speed))
        try:
            return PathProfile.plan(path, limits, cap)
        except RuntimeError as error:
            raise RuntimeError(f"{self.get_name()}: at t = {t} s: {error}") from error

    def _Calculate(self, t: float, p: np.ndarray, v: np.ndarray, a: np.ndarray, target: np.ndarray,
                   synchronization: ruckig.Synchronization):
        vmax, amax, jmax = self._Limits(target - p, v, a)
        inp = ruckig.InputParameter(self._n)
        inp.current_position = p.tolist()
        inp.current_velocity = v.tolist()
        inp.current_acceleration = a.tolist()
        inp.target_position = target.tolist()
        inp.target_velocity = [0.0] * self._n
        inp.target_acceleration = [0.0] * self._n
        inp.max_velocity = vmax.tolist()
        inp.max_acceleration = amax.tolist()
        inp.max_jerk = jmax.tolist()
        inp.synchronization = synchronization
        # Never set inp.intermediate_positions (see the module docstring).
        trajectory = ruckig.Trajectory(self._n)
        try:
            # A fresh calculator each time: offline calculate() only, nothing kept on self.
            result = ruckig.Ruckig(self._n).calculate(inp, trajectory)
        except ruckig.RuckigError as error:
            raise RuntimeError(f"{self.get_name()}: Ruckig failed at t = {t} s: {error}") from error
        if result != ruckig.Result.Working:
            raise RuntimeError(f"{self.get_name()}: Ruckig failed at t = {t} s with {result}; input:\n{inp}")
        return trajectory

    def _WithinLimits(self, trajectory) -> bool:
        lower, upper = self._position_limits
        extrema = trajectory.position_extrema
        low = np.array([e.min for e in extrema])
        high = np.array([e.max for e in extrema])
        slack_low = _LIMIT_ROUNDING * np.maximum(1.0, np.abs(lower))
        slack_high = _LIMIT_ROUNDING * np.maximum(1.0, np.abs(upper))
        return bool(np.all(low >= lower - slack_low) and np.all(high <= upper + slack_high))

    # ---- outputs ---------------------------------------------------------------

    def _CalcAt(self, context: Context, value: AbstractValue) -> None:
        value.set_value(self._Segment(context).at(context.get_time()))

    def _At(self, context: Context) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self._at_cache.Eval(context)

    def _CalcPosition(self, context: Context, output: BasicVector) -> None:
        output.SetFromVector(self._At(context)[0])

    def _CalcVelocity(self, context: Context, output: BasicVector) -> None:
        output.SetFromVector(self._At(context)[1])

    def _CalcAcceleration(self, context: Context, output: BasicVector) -> None:
        output.SetFromVector(self._At(context)[2])

    def _CalcState(self, context: Context, output: BasicVector) -> None:
        p, v, a = self._At(context)
        output.SetFromVector(np.concatenate([p, v, a]))

    def _CalcMeanVelocity(self, context: Context, output: BasicVector) -> None:
        segment, t = self._Segment(context), context.get_time()
        ahead = segment.at(t + self._preview)[0]
        output.SetFromVector((ahead - self._At(context)[0]) / self._preview)

    def _CalcFinished(self, context: Context, output: BasicVector) -> None:
        segment = self._Segment(context)
        finished = (not segment.held and context.get_time() - segment.t0 >= segment.duration
                    and getattr(segment.trajectory, "arrives", True))
        output.SetAtIndex(0, 1.0 if finished else 0.0)


def arm_source_from_options(
    execution_options: ExecutionOptions, initial_arm: Sequence[float],
    position_limits: tuple[Sequence[float], Sequence[float]] | None = None,
) -> RuckigTrajectorySource:
    """The arm's reference (2 DoFs ``[psi1, psi2]``, radians) with the scenario's arm limits.

    Args:
        execution_options: a scenario's ``execution`` section.
        initial_arm: (2,) initial joint angles, radians.
        position_limits: (lower, upper) joint limits the reference keeps
            to (``robot.joint_lower``, ``robot.joint_upper``), radians, or None.
    """
    require_execution_options(execution_options, "arm_source_from_options")
    return RuckigTrajectorySource(
        position_limits=position_limits,
        initial_position=real_array(initial_arm, "arm_source_from_options", "initial_arm", (2,), layout="[psi1, psi2]"),
        max_velocity=execution_options.arm_max_velocity,
        max_acceleration=execution_options.arm_max_acceleration,
        max_jerk=execution_options.arm_max_jerk,
        period=execution_options.control_period,
    )


def reference_source_from_options(
    execution_options: ExecutionOptions, initial_q: Sequence[float],
    position_limits: tuple[Sequence[float], Sequence[float]] | None = None,
    lever: Sequence[float] | None = None,
) -> RuckigTrajectorySource:
    """The synchronized reference of the whole configuration ``[x, y, psi1, psi2]``.

    Phase-synchronized, so base and arm start and arrive together and (from
    rest) move proportionally: the base on the straight segment. The base
    limits bound the norm of ``[vx, vy]`` (and of the acceleration and jerk)
    through ``xy_norm_dofs=(0, 1)``, and the wheels' limit bounds ``|vx| +
    |vy|`` by ``max_wheel_speed * wheel_radius`` (``xy_max_abs_sum``), so the
    base's speed on a segment is at most
    :func:`~drake_social.control.holonomic.wheel_limited_speed` and the
    wheels are never asked for more than they give. Its ``mean_velocity``
    previews one ``control_period``, the feed-forward of the sampled base
    controller. From rest it runs through the ``via`` input's positions
    (the sequencer's waypoints where the path goes straight on) to the
    target, carrying its speed through them.

    Args:
        execution_options: a scenario's ``execution`` section.
        initial_q: (4,) initial configuration (metres, radians).
        position_limits: (lower, upper) limits of ``[x, y, psi1, psi2]`` the
            reference keeps to (the room bounds and the joint limits), or None.
        lever: the levers ``(c_s, c_g)`` of the robot's points
            (``ArmGeometry.lever(include_body=True)``, metres): when given,
            the input ``speed_limit`` caps the speed of the fastest point,
            ``|v_xy| + c_s |psi1'| + c_g |psi1' + psi2'|``
            (:func:`~drake_social.kinematics.displacement_bound`).
    """
    require_execution_options(execution_options, "reference_source_from_options")
    e = execution_options
    max_velocity, max_acceleration, max_jerk, _, abs_sum = synchronized_limits(e)
    return RuckigTrajectorySource(
        xy_max_abs_sum=abs_sum,
        position_limits=position_limits,
        initial_position=real_array(initial_q, "reference_source_from_options", "initial_q", (4,), layout="[x, y, psi1, psi2]"),
        max_velocity=max_velocity,
        max_acceleration=max_acceleration,
        max_jerk=max_jerk,
        period=e.control_period,
        synchronization="phase",
        xy_norm_dofs=(0, 1),
        preview=e.control_period,
        via=True,
        point_speed=None if lever is None else functools.partial(displacement_bound, lever=np.asarray(lever, float)),
    )
