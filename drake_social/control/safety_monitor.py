"""The safety monitor: stops the robot while a person is too close.

:class:`SafetyMonitor` reads the robot's configuration ``q = [x, y, psi1,
psi2]`` and the people (a :class:`~drake_social.people.PeopleState`, as
:class:`~drake_social.control.PeopleSource` outputs it) and, in a periodic
update every ``period`` seconds, sets its ``stop`` flag when any part of the
robot (the base disc, the two link capsules, the object's capsules) is within
``safety_distance`` of a present person's body disc, surface to surface
(:func:`drake_social.people.proximity.part_distances`, the one home of that
distance; every period its compiled single-configuration form
:func:`~drake_social.people.proximity.robot_distance`, the same numbers), and clears it when every part is farther: a safety field, as on
real mobile robots. ``safety_distance = 0`` stops on contact (or overlap) only.
A stop is released only once every part has been clear for ``release_time``
seconds (a minimum hold, against stop-and-go at the boundary).

The flag is state, so ``stop`` has no direct feedthrough from ``q``: the
loop monitor -> controller -> robot -> monitor has no algebraic loop. The
decision is an unrestricted update, which Drake's Simulator applies before
the discrete updates of the same instant: the sampled base command (a
zero-order hold) and the sequencer read the new flag at once, while another
unrestricted update (a Ruckig reference) reads it one ``period`` later (see
:func:`braking_travel` for what the robot may travel meanwhile; in the
synchronized execution the base follows that reference, so that base and arm
stop together on the planned segment).

State (one abstract value, an immutable :class:`SafetyRecord`): the flag and
every stop so far (:class:`Stop`: start, end, nearest person, part,
distance), so a run's stops are read from its final context
(:meth:`SafetyMonitor.stops`) with the exact update times; a cloned context
keeps its own record.

Ports: inputs ``q`` (4) and ``people_state`` (abstract PeopleState); output
``stop`` (1: 1.0 while stopped, else 0.0).

Example::

    import numpy as np
    from drake_social.control import SafetyMonitor
    from drake_social.kinematics import ArmGeometry
    from drake_social.people import StaticPeople
    from drake_social.scenario import load_scenario
    from drake_social.scenario.geometry import arm_geometry

    scenario = load_scenario("scenarios/tiny.yaml")
    monitor = SafetyMonitor(arm_geometry(scenario), safety_distance=0.05, period=0.01)
    context = monitor.CreateDefaultContext()
    monitor.GetInputPort("q").FixValue(context, [1.0, 2.5, 0.0, 1.5708])
    people = StaticPeople([[1.0, 1.92, 0.0]], [0.2]).state_at(0.0)  # 0.03 m from the base disc
    monitor.GetInputPort("people_state").FixValue(context, people)
    scratch = context.Clone()
    monitor.CalcForcedUnrestrictedUpdate(context, scratch.get_mutable_state())
    context.SetAbstractState(0, scratch.get_abstract_state(0).get_value())
    print(monitor.GetOutputPort("stop").Eval(context))  # [1.]
"""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, Context, EventStatus, LeafSystem, State

from drake_social.kinematics import ArmGeometry
from drake_social.people import PeopleState
from drake_social.people import proximity_kernel
from drake_social.people.proximity import part_distances, robot_distance_args

__all__ = ["SAFETY_PARTS", "SafetyMonitor", "SafetyRecord", "Stop", "braking_travel", "robot_reach"]

#: The parts the monitor watches, in the order a tie is reported.
SAFETY_PARTS = ("base", "arm", "object")


@dc.dataclass(frozen=True)
class Stop:
    """One stop of the robot by the safety monitor.

    Attributes:
        start: time of the update that stopped the robot, seconds.
        end: time of the update that let it go, seconds, or None while stopped.
        person: the nearest person at the start: their name, or their index
            (from 0, as a string) when unnamed.
        part: the robot's part nearest to them: ``base``, ``arm`` or ``object``.
        distance: that part's surface distance to that person's body at the
            start, metres (<= the safety distance; negative is overlap).
    """

    start: float
    end: float | None
    person: str
    part: str
    distance: float

    def to_dict(self, end_time: float | None = None) -> dict:
        """``{start, end, duration, person, part, distance}``; a stop still on
        (end None) lasts until ``end_time`` when given (its end stays None)."""
        until = self.end if self.end is not None else end_time
        return {"start": self.start, "end": self.end,
                "duration": None if until is None else max(until - self.start, 0.0),
                "person": self.person, "part": self.part, "distance": self.distance}


@dc.dataclass(frozen=True)
class SafetyRecord:
    """The monitor's state: the flag and the stops so far (immutable, shared by copies).

    Attributes:
        stopped: the robot is held.
        stops: every stop in order; the last one has ``end = None`` while stopped.
        clear_since: while stopped, the time of the first of the samples in a
            row that found every part clear (None: the last one did not).
    """

    stopped: bool = False
    stops: tuple[Stop, ...] = ()
    clear_since: float | None = None

    def __copy__(self):
        return self

    def __deepcopy__(self, memo):
        return self


def robot_reach(geometry: ArmGeometry) -> float:
    """Largest distance of any point of the robot (base disc, link and object
    capsules) from the base centre, metres, in every configuration."""
    l1, l2 = geometry.link_lengths
    obj = float(np.max(np.linalg.norm(geometry.object_points, axis=1))) + geometry.object_radius
    return max(geometry.base_radius, l1 + l2 + max(geometry.link_radius, obj))


def braking_travel(geometry: ArmGeometry, *, max_base_speed: float, arm_max_velocity, period: float,
                   execution: str = "synchronized") -> float:
    """How far a point of the robot may move towards a person after the last clear sample, metres.

    The monitor decides every ``period``: at the last clear sample t_{k-1}
    every part is farther than the safety distance; the robot moves freely
    until the next sample t_k, where the monitor sees it within. The Ruckig
    references read the flag of t_k one period later and hold at t_{k+1}.
    In ``synchronized`` execution the base follows the held reference, so
    base and arm stop together at t_{k+1}, on the planned segment: a body
    point moves at most ``2 period (v_base + v_arm)``. In ``paper``
    execution the base's sampled command reads the flag at t_k (zero from
    then on) while the arm moves one more period: ``period (v_base + 2
    v_arm)``. Here ``v_arm = w1 (l1 + l2 + e) + w2 (l2 + e)`` (``e`` the
    object's reach beyond the gripper, its farthest point plus the capsule
    radius, and ``w1``, ``w2`` the joint speed limits). So in ``kinematic``
    mode the robot never brings a part closer than ``safety_distance`` minus
    this (and minus what the person walks meanwhile) to a person; a person
    who walks on into the held robot comes closer by their own motion. In
    ``dynamic`` mode the servo's lag adds to it.

    Args:
        geometry: the robot and its object.
        max_base_speed: base speed limit, m/s.
        arm_max_velocity: (2,) joint speed limits, rad/s.
        period: the monitor's (and the controller's) period, seconds.
        execution: ``"synchronized"`` or ``"paper"``.
    """
    l1, l2 = geometry.link_lengths
    e = max(geometry.link_radius,
            float(np.max(np.linalg.norm(geometry.object_points, axis=1))) + geometry.object_radius)
    w1, w2 = (float(w) for w in arm_max_velocity)
    arm = w1 * (l1 + l2 + e) + w2 * (l2 + e)
    if execution == "paper":
        return period * (max_base_speed + 2.0 * arm)
    if execution != "synchronized":
        raise ValueError(f"braking_travel: execution must be 'synchronized' or 'paper', got {execution!r}")
    return 2.0 * period * (max_base_speed + arm)


class SafetyMonitor(LeafSystem):
    """Sets ``stop`` while a part of the robot is within ``safety_distance`` of a person.

    A stop is released by the first sample that has found every part clear
    for ``release_time`` seconds (every sample from one at least that long
    ago clear): a person lingering at the boundary does not make the robot
    stop and go every period. 0 releases at the first clear sample.

    Args:
        geometry: the robot and its object (``drake_social.scenario.geometry.arm_geometry``).
        safety_distance: metres (>= 0; 0 = stop on contact only).
        period: seconds between decisions (> 0; the control period).
        release_time: seconds clear before a release (>= 0; the scenario's
            ``execution.release_time``).

    Raises:
        TypeError: ``geometry`` is not an ArmGeometry.
        ValueError: ``safety_distance`` or ``period`` out of range.
    """

    def __init__(self, geometry: ArmGeometry, *, safety_distance: float, period: float, release_time: float = 0.0):
        super().__init__()
        if not isinstance(geometry, ArmGeometry):
            raise TypeError(f"SafetyMonitor: geometry must be a drake_social.kinematics.ArmGeometry, "
                            f"got {type(geometry).__name__}")
        if not (isinstance(safety_distance, (int, float)) and math.isfinite(safety_distance)
                and safety_distance >= 0):
            raise ValueError(f"SafetyMonitor: safety_distance must be a finite number of metres >= 0, "
                             f"got {safety_distance!r}")
        if not (isinstance(period, (int, float)) and math.isfinite(period) and period > 0):
            raise ValueError(f"SafetyMonitor: period must be a finite number of seconds > 0, got {period!r}")
        if not (isinstance(release_time, (int, float)) and math.isfinite(release_time) and release_time >= 0):
            raise ValueError(f"SafetyMonitor: release_time must be a finite number of seconds >= 0, "
                             f"got {release_time!r}")
        self._release = float(release_time)
        self._geometry = geometry
        self._safety = float(safety_distance)
        self._robot_args = robot_distance_args(geometry)
        self._q_port = self.DeclareVectorInputPort("q", 4)
        self._people_port = self.DeclareAbstractInputPort(
            "people_state", AbstractValue.Make(PeopleState(0.0, np.zeros((0, 2)), np.zeros(0), np.zeros((0, 2)),
                                                           np.zeros(0), ())))
        self._record_index = self.DeclareAbstractState(AbstractValue.Make(SafetyRecord()))
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._Decide)
        # The same decision on demand (CalcForcedUnrestrictedUpdate), for tests and scripts.
        self.DeclareForcedUnrestrictedUpdateEvent(self._Decide)
        self.DeclareVectorOutputPort("stop", 1, self._CalcStop,
                                     prerequisites_of_calc={self.abstract_state_ticket(self._record_index)})

    @property
    def safety_distance(self) -> float:
        """The distance that stops the robot, metres."""
        return self._safety

    def record(self, context: Context) -> SafetyRecord:
        """The flag and the stops in ``context`` (this system's context)."""
        return context.get_abstract_state(self._record_index).get_value()

    def stops(self, context: Context) -> tuple[Stop, ...]:
        """Every stop so far in ``context``, in order."""
        return self.record(context).stops

    def nearest(self, q, people: PeopleState) -> tuple[float, int, str]:
        """The smallest surface distance of a watched part to a present person:
        ``(distance in metres, person index, part)``; ``(inf, -1, "")`` with nobody present."""
        q = np.asarray(q, float).reshape(1, 4)
        best = (math.inf, -1, "")
        for i in np.flatnonzero(people.present):
            d = part_distances(self._geometry, q, people.positions[i:i + 1], people.radii[i:i + 1])
            for part in SAFETY_PARTS:
                if float(d[part][0]) < best[0]:
                    best = (float(d[part][0]), int(i), part)
        return best

    def too_close(self, q, people: PeopleState) -> bool:
        """Whether a watched part is within the safety distance of a present person."""
        # The compiled robot_distance (this runs every control period), its
        # arguments packed once; numpy's cosines, as the reference's kinematics;
        # q a fresh array (one compiled signature whatever the caller passes).
        q = np.array(q, float).reshape(4)
        d = proximity_kernel.robot_distance(q, np.cos(q[2:]), np.sin(q[2:]), *self._robot_args, people.positions,
                                            people.radii, people.present)
        return bool(d <= self._safety)

    def _Decide(self, context: Context, state: State) -> None:
        record = self.record(context)
        q = self._q_port.Eval(context)
        people = self._people_port.Eval(context)
        close = self.too_close(q, people)
        t = context.get_time()
        if close and record.stopped:
            if record.clear_since is None:
                return EventStatus.DidNothing()
            record = dc.replace(record, clear_since=None)  # not clear for long enough
        elif not close and not record.stopped:
            return EventStatus.DidNothing()
        elif close:
            distance, index, part = self.nearest(q, people)
            name = people.names[index] or str(index)
            record = SafetyRecord(True, record.stops + (Stop(t, None, name, part, distance),))
        else:  # stopped and clear: released once clear for release_time (1e-9 s: periods summed apart)
            since = t if record.clear_since is None else record.clear_since
            if t - since < self._release - 1e-9:
                if record.clear_since is not None:
                    return EventStatus.DidNothing()
                record = dc.replace(record, clear_since=since)
            else:
                last = dc.replace(record.stops[-1], end=t)
                record = SafetyRecord(False, record.stops[:-1] + (last,))
        state.get_mutable_abstract_state(self._record_index).set_value(record)
        return None

    def _CalcStop(self, context: Context, output: BasicVector) -> None:
        output.SetAtIndex(0, 1.0 if self.record(context).stopped else 0.0)
