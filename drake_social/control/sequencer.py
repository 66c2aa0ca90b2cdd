"""The waypoint sequencer: decides *which* configuration the robot heads for.

:class:`WaypointSequencer` holds the index of the current target waypoint in
discrete state and moves on to the next one only when the measured
configuration ``q = [x, y, psi1, psi2]`` (metres, radians) is within the
acceptance tolerances of the current target: the base position within
``base_tolerance`` (Euclidean distance, metres) and each arm joint within
``joint_tolerance`` (radians), as in the paper's Section IV-C. Optionally it
also waits for a trajectory source to report that its reference has arrived
(``reference_done``). At the last waypoint the same condition latches
``done = 1`` instead. While the optional input ``hold`` (the safety
monitor's stop; unconnected = never held) is above 0.5 it does not advance.

A replanner changes the path under it: with ``versioned=True`` the input ``version`` (1;
e.g. :class:`~drake_social.control.ReplanningPlannerSystem`'s) counts the
paths, and a version different from the last one seen means a new path
that starts at the robot's configuration: the index goes to ``min(1, N - 1)``
(the new path's first waypoint after that configuration) and ``done`` to 0.
The outputs answer for the new path at once (the version input is among
their prerequisites, so the target never shows the new path at the old
index); the update stores the new version. Without it (or unconnected), nothing of this runs.

With ``pass_through=True`` (the synchronized execution) the sequencer heads
only for the waypoints where the path turns: from the waypoint the robot
rests at (index i), the next target is :func:`next_rest` (i), the farthest
later waypoint v such that every waypoint between lies within
:data:`PASS_THROUGH_TOLERANCE` of the straight segment i -> v (in the
planner's weighted configuration distance ``||W dq||``) and in order along
it; the output ``via`` gives the waypoints between, which the reference
goes through without stopping. The planned waypoints need not be free of
such points (a given path, a raw path): they are gone through, not dropped.
After a new path version the target is its waypoint 1 (the motion the
replanner committed to), with nothing between.

The decision is taken in a periodic discrete update (also declared as a
forced update, so ``CalcForcedDiscreteVariableUpdate`` runs it); the outputs only read
the state (and the waypoints), so ``target``, ``done`` and ``index`` have no
direct feedthrough from ``q``: closing the loop through a controller and a
plant creates no algebraic loop.

Ports:

* inputs ``waypoints`` (abstract ``Value[object]``, an (N, 4) array, e.g.
  :class:`~drake_social.control.PlannerSystem`'s ``waypoints``; only when no
  fixed array is given), ``q`` (4), ``reference_done`` (1; only with
  ``wait_for_reference=True``), ``hold`` (1, optional), ``version`` (1, only with ``versioned=True``; optional);
* outputs ``target`` (4), ``done`` (1, 0.0 or 1.0), ``index`` (1), ``via``
  (abstract (m, 4): the waypoints between the rest and the target; only
  with ``pass_through=True``).

Example::

    import numpy as np
    from drake_social.control import WaypointSequencer

    waypoints = np.array([[0, 0, 0, 0], [1, 0, 0.5, 0], [1, 1, 0.5, 0.2]])
    dut = WaypointSequencer(waypoints, base_tolerance=0.05, joint_tolerance=0.05, period=0.01)
    context = dut.CreateDefaultContext()
    dut.GetInputPort("q").FixValue(context, [0.01, 0.0, 0.0, 0.0])
    update = dut.AllocateDiscreteVariables()
    dut.CalcForcedDiscreteVariableUpdate(context, update)
    context.SetDiscreteState(update)
    print(dut.GetOutputPort("target").Eval(context))  # [1. 0. 0.5 0.]
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import EventStatus, BasicVector, Context, DiscreteValues, LeafSystem

from drake_social.arguments import require_execution_options
from drake_social.scenario import ExecutionOptions

__all__ = ["PASS_THROUGH_TOLERANCE", "WaypointSequencer", "next_rest"]

# Layout of the single discrete state group (then the origin with pass_through).
_INDEX, _DONE, _VERSION = 0, 1, 2

#: Largest distance ``||W (q - s)||`` (metres and radians scaled by the
#: planner's ``planner.distance_weights`` W) of a waypoint from the straight
#: segment between the rest before it and a later waypoint, for the robot to
#: go through it without stopping (:func:`next_rest`). The optimiser's
#: collinear waypoints (equal parts of a subdivided motion) lie within a few
#: ulp of a room's coordinates of their neighbours' segment (3.6e-15 on
#: office_bar, whose nearest turning waypoint is 1.5e-3 off it): 1e-9 is a
#: million times their rounding. The reference runs on the planned segments
#: themselves whatever this is; the tolerance only bounds the turn it carries
#: speed through (``2 tolerance / l`` radians between segments of length l).
PASS_THROUGH_TOLERANCE = 1e-9


def next_rest(waypoints: np.ndarray, i: int, weights: np.ndarray | None = None,
              tolerance: float = PASS_THROUGH_TOLERANCE) -> int:
    """The next waypoint to come to rest at after waypoint i.

    The farthest v > i such that every waypoint strictly between i and v
    lies within ``tolerance`` of the straight segment i -> v (the distance
    ``||W (w - s)||`` to its nearest point s) and in order along it (their
    positions on it do not go back); i + 1 when the next waypoint turns, i at
    the last waypoint.

    Args:
        waypoints: (N, 4) the path.
        i: the index the robot rests at, 0 <= i < N.
        weights: (4,) the distance's per-coordinate scale W (the planner's
            ``planner.distance_weights``); None = all ones.
        tolerance: the largest distance, >= 0.
    """
    wp = np.asarray(waypoints, float)
    w = np.ones(wp.shape[1]) if weights is None else np.asarray(weights, float)
    if i >= len(wp) - 1:
        return i
    scaled = (wp[i:] - wp[i]) * w  # relative to the rest, scaled: rest at 0
    v = i + 1
    for j in range(2, len(scaled)):
        d = scaled[j]
        dd = float(d @ d)
        if dd == 0.0:
            break
        between = scaled[1:j]
        t = between @ d / dd
        off = np.linalg.norm(between - np.clip(t, 0.0, 1.0)[:, None] * d, axis=1)
        if not (np.all(off <= tolerance) and np.all(np.diff(np.concatenate([[0.0], t, [1.0]])) >= 0.0)):
            break
        v = i + j
    return v


def _checked_waypoints(waypoints, who: str) -> np.ndarray:
    """The waypoints as a finite (N, 4) float array, N >= 1, or a ValueError naming ``who``."""
    wp = np.asarray(waypoints, dtype=float)
    if wp.ndim != 2 or wp.shape[1] != 4:
        raise ValueError(f"{who}: waypoints must be an (N, 4) array of [x, y, psi1, psi2], got shape {wp.shape}")
    if len(wp) == 0:
        raise ValueError(f"{who}: no waypoints (an empty path, e.g. the planner found none); nothing to follow")
    if not np.all(np.isfinite(wp)):
        rows = sorted(set(np.nonzero(~np.isfinite(wp))[0].tolist()))
        raise ValueError(f"{who}: waypoints must be finite; rows {rows} hold NaN or inf")
    return wp


class WaypointSequencer(LeafSystem):
    """Steps through waypoints when the robot is within tolerance of the current one.

    Discrete state: one group, ``[index, done]`` (the target index, starting
    at 0, and the latched done flag, 0.0 or 1.0), with ``versioned=True``
    ``[index, done, version]`` (the last path version seen on the ``version``
    input, starting at 0).

    Args:
        waypoints: a fixed (N, 4) array of configurations ``[x, y, psi1,
            psi2]`` (metres, radians), N >= 1; None declares the abstract
            input port ``waypoints`` instead.
        base_tolerance: largest distance |q[:2] - target[:2]| to accept,
            metres (> 0).
        joint_tolerance: largest |q[i] - target[i]| for i = 2, 3 to accept,
            radians (> 0).
        period: period of the discrete update, seconds (> 0).
        wait_for_reference: also require ``reference_done[0] > 0.5`` (declares
            the input port ``reference_done``).
        versioned: declare the input port ``version`` (a replanner's path
            version; see the module docstring).
        pass_through: head only for the waypoints where the path turns
            (:func:`next_rest`) and declare the output ``via``.
        distance_weights: (4,) W of the pass-through tolerance's distance
            (the planner's ``planner.distance_weights``); None = all ones.

    Raises:
        ValueError: a fixed array that is empty, not (N, 4) or not finite;
            tolerances or period not positive.
        RuntimeError: (from an update or output) the ``waypoints`` input
            holds an empty or malformed array.
    """

    def __init__(
        self,
        waypoints: np.ndarray | None = None,
        *,
        base_tolerance: float,
        joint_tolerance: float,
        period: float,
        wait_for_reference: bool = False,
        versioned: bool = False,
        pass_through: bool = False,
        distance_weights=None,
    ):
        super().__init__()
        for name, value in (("base_tolerance", base_tolerance), ("joint_tolerance", joint_tolerance),
                            ("period", period)):
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"WaypointSequencer: {name} must be a finite number > 0, got {value!r}")
        self._base_tolerance = float(base_tolerance)
        self._joint_tolerance = float(joint_tolerance)
        self._fixed = None if waypoints is None else _checked_waypoints(waypoints, "WaypointSequencer")
        self._weights = None
        if distance_weights is not None:
            self._weights = np.array(distance_weights, float).reshape(-1)
            if self._weights.shape != (4,) or not np.all(np.isfinite(self._weights)) or np.any(self._weights < 0):
                raise ValueError(f"WaypointSequencer: distance_weights must be 4 finite numbers >= 0, "
                                 f"got {distance_weights!r}")
        self._pass_through = bool(pass_through)

        self._waypoints_port = None
        if self._fixed is None:
            self._waypoints_port = self.DeclareAbstractInputPort("waypoints", AbstractValue.Make(np.zeros((0, 4))))
        self._q_port = self.DeclareVectorInputPort("q", 4)
        self._reference_done_port = (
            self.DeclareVectorInputPort("reference_done", 1) if wait_for_reference else None
        )
        self._hold_port = self.DeclareVectorInputPort("hold", 1)
        self._version_port = self.DeclareVectorInputPort("version", 1) if versioned else None

        # [index, done] (+ version) (+ origin: the rest before the target), all start at 0
        size = 3 if versioned else 2
        self._origin = size if pass_through else None
        self._state_index = self.DeclareDiscreteState(size + (1 if pass_through else 0))
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._Advance)
        # The same decision on demand (CalcForcedDiscreteVariableUpdate), for tests and scripts.
        self.DeclareForcedDiscreteUpdateEvent(self._Advance)

        # Outputs read the state (and the waypoints and version), never q: no feedthrough from q.
        state = {self.discrete_state_ticket(self._state_index)}
        if self._version_port is not None:
            state.add(self.input_port_ticket(self._version_port.get_index()))
        target_prereqs = set(state)
        if self._waypoints_port is not None:
            target_prereqs.add(self.input_port_ticket(self._waypoints_port.get_index()))
        self.DeclareVectorOutputPort("target", 4, self._CalcTarget, prerequisites_of_calc=target_prereqs)
        self.DeclareVectorOutputPort("done", 1, self._CalcDone, prerequisites_of_calc=state)
        self.DeclareVectorOutputPort("index", 1, self._CalcIndex, prerequisites_of_calc=target_prereqs)
        if pass_through:
            self.DeclareAbstractOutputPort("via", lambda: AbstractValue.Make(np.zeros((0, 4))), self._CalcVia,
                                           prerequisites_of_calc=target_prereqs)

    @classmethod
    def from_options(
        cls, execution_options: ExecutionOptions, waypoints: np.ndarray | None = None,
        wait_for_reference: bool = False, versioned: bool = False, pass_through: bool = False,
        distance_weights=None,
    ) -> "WaypointSequencer":
        """A sequencer with the tolerances and period of a scenario's ``execution`` section."""
        require_execution_options(execution_options, "WaypointSequencer.from_options")
        return cls(
            waypoints,
            base_tolerance=execution_options.base_tolerance,
            joint_tolerance=execution_options.joint_tolerance,
            period=execution_options.control_period,
            wait_for_reference=wait_for_reference,
            versioned=versioned,
            pass_through=pass_through,
            distance_weights=distance_weights,
        )

    # ---- helpers ---------------------------------------------------------------

    def _Waypoints(self, context: Context) -> np.ndarray:
        if self._fixed is not None:
            return self._fixed
        value = self._waypoints_port.Eval(context)
        try:
            return _checked_waypoints(value, f"{self.get_name() or 'WaypointSequencer'}")
        except ValueError as error:
            raise RuntimeError(f"{error} (read from the input port 'waypoints')") from None

    def _NewVersion(self, context: Context) -> float | None:
        """The ``version`` input when it differs from the last one seen, else None."""
        if self._version_port is None or not self._version_port.HasValue(context):
            return None
        version = float(self._version_port.Eval(context)[0])
        return None if version == context.get_discrete_state(self._state_index).GetAtIndex(_VERSION) else version

    def _Index(self, context: Context, n_waypoints: int) -> int:
        # Clamped so that a shorter array on the input never indexes past its end.
        if self._NewVersion(context) is not None:
            return min(1, n_waypoints - 1)
        index = int(round(context.get_discrete_state(self._state_index).GetAtIndex(_INDEX)))
        return min(max(index, 0), n_waypoints - 1)

    def _Done(self, context: Context) -> float:
        if self._NewVersion(context) is not None:
            return 0.0
        return context.get_discrete_state(self._state_index).GetAtIndex(_DONE)

    # ---- event -----------------------------------------------------------------

    def _Advance(self, context: Context, discrete_state: DiscreteValues) -> None:
        version = self._NewVersion(context)
        out = discrete_state.get_mutable_vector(self._state_index)
        if version is not None:  # a new path from the robot's configuration: its waypoint 1 next
            out.SetAtIndex(_INDEX, min(1, len(self._Waypoints(context)) - 1))
            out.SetAtIndex(_DONE, 0.0)
            out.SetAtIndex(_VERSION, version)
            if self._origin is not None:
                out.SetAtIndex(self._origin, 0.0)
            return None
        xd = context.get_discrete_state(self._state_index).value()
        if xd[_DONE] > 0.5:
            return EventStatus.DidNothing()  # latched
        if self._hold_port.HasValue(context) and self._hold_port.Eval(context)[0] > 0.5:
            return EventStatus.DidNothing()  # held (the safety monitor's stop, a replanner's wait)
        waypoints = self._Waypoints(context)
        index = self._Index(context, len(waypoints))
        target = waypoints[index]
        q = np.asarray(self._q_port.Eval(context), float)
        arrived = (
            np.hypot(q[0] - target[0], q[1] - target[1]) <= self._base_tolerance
            and abs(q[2] - target[2]) <= self._joint_tolerance
            and abs(q[3] - target[3]) <= self._joint_tolerance
        )
        if arrived and self._reference_done_port is not None:
            arrived = self._reference_done_port.Eval(context)[0] > 0.5
        if not arrived:
            return EventStatus.DidNothing()  # nothing changed (the outputs still recompute each period)
        if index + 1 < len(waypoints):  # one step per update
            if self._origin is None:
                out.SetAtIndex(_INDEX, index + 1)
            else:
                out.SetAtIndex(_INDEX, next_rest(waypoints, index, self._weights))
                out.SetAtIndex(self._origin, index)
        else:
            out.SetAtIndex(_INDEX, index)
            out.SetAtIndex(_DONE, 1.0)

    # ---- outputs ---------------------------------------------------------------

    def _CalcTarget(self, context: Context, output: BasicVector) -> None:
        waypoints = self._Waypoints(context)
        output.SetFromVector(waypoints[self._Index(context, len(waypoints))])

    def _CalcDone(self, context: Context, output: BasicVector) -> None:
        output.SetAtIndex(0, self._Done(context))

    def _CalcVia(self, context: Context, output: AbstractValue) -> None:
        waypoints = self._Waypoints(context)
        index = self._Index(context, len(waypoints))
        origin = 0
        if self._NewVersion(context) is None:
            origin = int(round(context.get_discrete_state(self._state_index).GetAtIndex(self._origin)))
        output.set_value(waypoints[min(max(origin, 0), index) + 1:index].copy())

    def _CalcIndex(self, context: Context, output: BasicVector) -> None:
        if self._NewVersion(context) is not None:
            waypoints = self._Waypoints(context)
            output.SetAtIndex(0, float(self._Index(context, len(waypoints))))
            return
        output.SetAtIndex(0, context.get_discrete_state(self._state_index).GetAtIndex(_INDEX))
