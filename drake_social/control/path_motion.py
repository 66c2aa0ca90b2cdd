"""Motions along a polyline: one jerk-limited profile of the distance travelled, mapped onto the path.

The synchronized reference (:class:`~drake_social.control.RuckigTrajectorySource`
with ``synchronization="phase"``) drives the robot along straight
configuration-space segments. A *run* is a chain of segments that go straight
on (the sequencer's waypoints between two rests, see
:func:`~drake_social.control.sequencer.next_rest`); the reference moves along
it as one 1-DoF Ruckig profile of the distance s travelled (a
:class:`PathProfile`), so the robot carries its speed through the waypoints
inside the run and comes to rest only at its end. The position is always
``P_k + (s - S_k) u_k`` on the segment k that s lies on, so every
configuration of the motion lies on a planned segment, whatever the
profile does: slowing for a speed limit, braking to a stop or resting
mid-run, each a new profile of s from the current ``(s, s', s'')``
(continuous position, velocity and acceleration, jerk within the limit).

* :class:`Polyline`: the run's points, cumulative lengths and unit directions.
* :func:`line_limits`: the limits of s on one straight segment from the
  DoFs' limits (each DoF's, the norm of a group such as the base's ``x, y``
  and the wheels' sum of absolute speeds).
* :func:`plan_profile`: the time-optimal profile of s from a state to the
  end of the run (at rest) under a speed cap, or the shortest stop (cap 0).
* :class:`PathProfile`: a profile on a polyline, evaluated like a
  ``ruckig.Trajectory`` (``duration``, ``at_time``).

Pure numpy and ruckig; no Drake.
"""

from __future__ import annotations

import bisect
import math
from typing import Callable, Sequence

import numpy as np
import ruckig

#: The smallest speed cap of s a profile keeps to (the DoFs' units per second); below it, a stop.
SMALLEST_CAP = 1e-6

__all__ = ["SMALLEST_CAP", "PathProfile", "Polyline", "line_limits", "plan_profile", "point_limits", "synchronized_limits"]


def synchronized_limits(options) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """The arguments of :func:`line_limits` for the synchronized reference of ``[x, y, psi1, psi2]``
    with a scenario's ``execution`` options: the per-DoF limits (the base's for x and y, bounding
    their norm), the group ``(0, 1)`` and the wheels' ``max_wheel_speed * wheel_radius``."""
    e = options
    return (np.array([e.max_base_speed, e.max_base_speed, *e.arm_max_velocity], float),
            np.array([e.max_base_acceleration, e.max_base_acceleration, *e.arm_max_acceleration], float),
            np.array([e.max_base_jerk, e.max_base_jerk, *e.arm_max_jerk], float),
            np.array([0, 1]), float(e.max_wheel_speed * e.wheel_radius))


class Polyline:
    """Straight segments through ``points`` (m + 1, n), m >= 1, zero-length steps dropped.

    Attributes:
        points: (m + 1, n) the corners, read-only; ``points[-1]`` is the
            last given point exactly.
        starts: (m + 1,) the distance along the path at each point (the
            Euclidean norm in the DoFs' units), ``starts[0] = 0``.
        units: (m, n) the unit direction of each segment.
        length: ``starts[-1]``.
    """

    __slots__ = ("points", "starts", "units", "length", "_points", "_units", "_starts")

    def __init__(self, points: np.ndarray):
        pts = np.array(points, float)
        keep = [0] + [i for i in range(1, len(pts)) if np.any(pts[i] != pts[i - 1])]
        if keep[-1] != len(pts) - 1:  # the last point is kept exactly (it is the target)
            keep[-1] = len(pts) - 1
        pts = pts[keep]
        if len(pts) < 2:
            raise ValueError("Polyline: needs two distinct points")
        d = np.diff(pts, axis=0)
        lengths = np.array([np.linalg.norm(dk) for dk in d])  # each as a vector's norm (the same rounding)
        units = np.array([dk / length for dk, length in zip(d, lengths)])
        starts = np.concatenate([[0.0], np.cumsum(lengths)])
        for a in (pts, units, starts):
            a.flags.writeable = False
        self.points, self.units, self.starts = pts, units, starts
        self.length = float(starts[-1])
        # Plain floats: at() runs at every step of a simulation.
        self._points = pts.tolist()
        self._units = units.tolist()
        self._starts = starts.tolist()

    def __copy__(self):
        return self

    def __deepcopy__(self, memo):
        return self

    def segment(self, s: float) -> int:
        """The segment k that s lies on (``starts[k] <= s``, the last one from its start on)."""
        return min(max(bisect.bisect_right(self._starts, s) - 1, 0), len(self._units) - 1)

    def at(self, s: float, sd: float = 0.0, sdd: float = 0.0) -> tuple[list[float], list[float], list[float]]:
        """Position, velocity and acceleration at distance s moving at s', s''.

        On the segment that s lies on (the first or the last one for an s
        beyond the path's ends, which profiles reach by rounding alone).
        """
        k = self.segment(s)
        ds = s - self._starts[k]
        u = self._units[k]
        return [p + ds * x for p, x in zip(self._points[k], u)], [sd * x for x in u], [sdd * x for x in u]


def line_limits(u: np.ndarray, max_velocity: np.ndarray, max_acceleration: np.ndarray, max_jerk: np.ndarray,
                norm_dofs: np.ndarray | None = None, max_abs_sum: float | None = None) -> tuple[float, float, float]:
    """The velocity, acceleration and jerk limits of s on a segment of unit direction u.

    Each the tightest of the DoFs': ``max_i / |u_i|`` for a per-DoF limit,
    ``max / |u_g|`` for the norm of the group ``norm_dofs`` g (whose per-DoF
    values are equal) and ``max_abs_sum / sum_g |u_i|`` for the group's sum
    of absolute velocities.
    """
    scale = np.abs(u)
    free = np.ones(len(u), bool)
    limits = []
    for per_dof in (max_velocity, max_acceleration, max_jerk):
        bounds = []
        if norm_dofs is not None:
            free[norm_dofs] = False
            norm = float(np.linalg.norm(u[norm_dofs]))
            if norm > 0:
                bounds.append(float(np.min(per_dof[norm_dofs])) / norm)
        moving = free & (scale > 0)
        bounds.extend((per_dof[moving] / scale[moving]).tolist())
        limits.append(min(bounds))
    if max_abs_sum is not None:
        l1 = float(np.sum(scale[norm_dofs]))
        if l1 > 0:
            limits[0] = min(limits[0], max_abs_sum / l1)
    return limits[0], limits[1], limits[2]


def plan_profile(length: float, s: float, sd: float, sdd: float, vmax: float, amax: float, jmax: float):
    """The profile of s from ``(s, s', s'')`` to rest at ``length`` with ``|s'| <= vmax``.

    With ``vmax = 0``, the shortest jerk-limited stop from that state
    instead (Ruckig's velocity interface to ``s' = 0``), wherever it ends.
    A state beyond the cap is first braked to it (Ruckig's braking, within
    the acceleration and jerk limits).

    Returns:
        ``(ruckig.Trajectory(1), result)``; the trajectory is None when the
        state is already at rest at ``length`` (or at rest with ``vmax = 0``).

    Raises:
        RuntimeError: Ruckig fails (its message and input).
    """
    at_rest = sd == 0.0 and sdd == 0.0
    if at_rest and (s == length or vmax == 0.0):
        return None
    inp = ruckig.InputParameter(1)
    inp.current_position, inp.current_velocity, inp.current_acceleration = [s], [sd], [sdd]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [length], [0.0], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [vmax if vmax > 0 else 1.0], [amax], [jmax]
    if vmax == 0.0:
        inp.control_interface = ruckig.ControlInterface.Velocity
    trajectory = ruckig.Trajectory(1)
    try:
        result = ruckig.Ruckig(1).calculate(inp, trajectory)
    except ruckig.RuckigError as error:
        raise RuntimeError(f"Ruckig failed: {error}") from error
    if result != ruckig.Result.Working:
        raise RuntimeError(f"Ruckig failed with {result}; input:\n{inp}")
    return trajectory


class PathProfile:
    """A motion along a :class:`Polyline`: a 1-DoF profile of s from t = 0, or rest at ``rest_s``.

    The part of ``ruckig.Trajectory`` that
    :class:`~drake_social.control.RuckigSegment` uses (``duration``,
    ``at_time``), plus ``end`` (the position where it comes to rest) and
    ``arrives`` (it comes to rest at the end of the path). Immutable.

    Attributes:
        path: the :class:`Polyline`.
        limits: ``(vmax, amax, jmax)`` of s on the whole path (its segments' tightest).
        cap: the largest speed of s this profile keeps to (<= ``limits[0]``; 0: a stop).
        trajectory: the ``ruckig.Trajectory(1)`` of s, or None (at rest at ``rest_s``).
    """

    __slots__ = ("path", "limits", "cap", "trajectory", "rest_s", "duration", "end_s", "end", "arrives")

    def __init__(self, path: Polyline, limits: tuple[float, float, float], cap: float, trajectory,
                 rest_s: float = 0.0):
        self.path, self.limits, self.cap, self.trajectory = path, limits, float(cap), trajectory
        self.rest_s = float(rest_s)
        if trajectory is None:
            self.duration, end = 0.0, self.rest_s
        else:
            self.duration = float(trajectory.duration)
            end = float(trajectory.at_time(self.duration)[0][0])
        # At rest where the profile ends: exactly the last point when it gets there.
        self.end_s = min(max(end, 0.0), path.length)
        if cap > 0.0 and trajectory is not None:
            self.end_s = path.length  # a profile with a positive cap ends at rest at the end
        self.arrives = self.end_s >= path.length
        self.end = list(path._points[-1]) if self.arrives else path.at(self.end_s)[0]

    def __copy__(self):
        return self

    def __deepcopy__(self, memo):
        return self

    @classmethod
    def plan(cls, path: Polyline, limits: tuple[float, float, float], cap: float, s: float = 0.0, sd: float = 0.0,
             sdd: float = 0.0) -> "PathProfile":
        """The profile along ``path`` from ``(s, s', s'')`` with ``|s'| <= cap`` (0: stop); see :func:`plan_profile`."""
        vmax, amax, jmax = limits
        cap = min(max(float(cap), 0.0), vmax)
        if cap < SMALLEST_CAP:  # a crawl that Ruckig cannot plan (it fails near 1e-12): a stop
            cap = 0.0
        return cls(path, limits, cap, plan_profile(path.length, s, sd, sdd, cap, amax, jmax), rest_s=s)

    def state(self, t: float) -> tuple[float, float, float]:
        """``(s, s', s'')`` at t (clamped to [0, duration]; at rest at the end after it).

        s stays on the path: a profile re-planned in its last braking may pass
        the end by Ruckig's precision (1e-9 of a unit) and come back; s is
        held at the end meanwhile, so the position never leaves the last segment.
        """
        if self.trajectory is None:
            return self.rest_s, 0.0, 0.0
        if t >= self.duration:
            return self.end_s, 0.0, 0.0
        (s,), (sd,), (sdd,) = self.trajectory.at_time(max(t, 0.0))
        if s > self.path.length:
            s = self.path.length
        return s, sd, sdd

    def at_time(self, t: float) -> tuple[list[float], list[float], list[float]]:
        """Position, velocity and acceleration at t (seconds from the profile's start)."""
        s, sd, sdd = self.state(t)
        return self.path.at(s, sd, sdd)

    def resting(self, t: float) -> "PathProfile":
        """At rest where this profile is at t, on the same path."""
        return PathProfile(self.path, self.limits, 0.0, None, rest_s=self.state(t)[0])


def point_limits(u: np.ndarray, limit_args: Sequence, factor: Callable[[np.ndarray], float]
                 ) -> tuple[float, float, float]:
    """The speed, deceleration and jerk limits of the robot's fastest point on a straight motion of
    unit direction u: ``factor(u)`` (its speed per unit of s') times :func:`line_limits`; the
    reference brakes it at least that hard."""
    k = float(factor(u))
    return tuple(k * x for x in line_limits(u, *limit_args))


def path_speed_factor(path: Polyline, factor: Callable[[np.ndarray], float] | None) -> float:
    """The largest ``factor(u_k)`` over the path's segments (1 without a factor): the speed of the
    fastest point of the robot per unit of s'."""
    if factor is None:
        return 1.0
    return max(float(factor(u)) for u in path.units)


def run_limits(path: Polyline, limit_args: Sequence) -> tuple[float, float, float]:
    """:func:`line_limits` of every segment of ``path``, the tightest of each."""
    per_segment = [line_limits(u, *limit_args) for u in path.units]
    return tuple(min(x[i] for x in per_segment) for i in range(3))


def speed_cap(limits: tuple[float, float, float], point_speed_limit: float, factor: float) -> float:
    """The cap of s' under a limit on the fastest point's speed (m/s): ``min(vmax, limit / factor)``."""
    if not math.isfinite(point_speed_limit):
        return limits[0]
    return min(limits[0], max(point_speed_limit, 0.0) / factor)
