"""The autonomy: the stack that drives the station.

:func:`make_autonomy` builds, as one Drake diagram named ``autonomy``, what
decides where the robot goes and how: a path source, the sequencer (*which*
target), the jerk-limited reference (*when* each joint gets there), the base
controller (*how* the base moves there) and, when people move, the safety
monitor. It reads the station's sensors and writes its driver commands, by
port name (:mod:`drake_social.sim.station`;
:func:`~drake_social.sim.diagram.build_diagram` wires the two).

Path sources (:data:`PathSource`): :class:`PlanAtInit` (the planner plans
at initialization, a :class:`~drake_social.control.PlannerSystem`),
:class:`Replan` (a :class:`~drake_social.control.ReplanningPlannerSystem`
replans while the robot moves), :class:`GivenWaypoints` (fixed waypoints)
and :class:`ExternalPath` (the path comes in through the input port
``path``, from a system of the script's own:
``docs/examples/custom_path.py``).

Ports::

    inputs   robot_state     8: [q, v] (the station's)
             people_state    PeopleState, Value[object] (the station's); only
                             when people move or with Replan
             path            (N, 4) waypoints, Value[object]; only with ExternalPath
    outputs  wheel_speeds    4: the base controller's wheel speeds, rad/s
             arm_command     6: the arm reference's psi1, psi2 positions,
                             velocities and accelerations
             target          4: the sequencer's current waypoint
             reference       4: what is being tracked: the reference position
                             (synchronized), or the target's xy with the arm's
                             reference (paper)
             reference_feedforward
                             4: the reference's mean velocity over the next control
                             period (synchronized execution only; the controller's
                             feed-forward)
             done, index     1 each: the sequencer's latched goal flag and target index
             planned_path    (N, 4) waypoints being followed, Value[object]
             stop            1: 1.0 while the safety monitor holds the robot (only when people move)
             waiting         1: 1.0 while the replanner finds no safe path (only with Replan)
             path_version    1: the replanner's path version (only with Replan)

Blocks (all named; ``[p]`` only with ``execution="paper"``, ``[s]`` only with
``"synchronized"``, ``[r]`` only with :class:`Replan`, ``[h]`` only when
people move)::

    planner or path ─waypoints─▶ sequencer ─target─▶ [s] reference (4-DoF Ruckig, phase sync)
    robot_state ─▶ robot_state_split ─q─▶ sequencer, base_position_split ─xy─▶ controller
    [s] reference ─state─▶ reference_state_split ─xy─▶ controller; ─arm p, v, a─▶ arm_command
    [p] sequencer ─target─▶ target_split ─xy─▶ controller; ─psi─▶ arm (2-DoF Ruckig) ─state─▶ arm_command
    [h] safety (SafetyMonitor) ◀─ q, people_state; stop ─hold─▶ sequencer, controller, reference / arm
    [r] q, people_state, sequencer.index, [s] reference.velocity ─▶ planner (ReplanningPlannerSystem)
        ─waypoints, version─▶ sequencer
    [r] planner.hold (waiting), [h] safety.stop ─▶ held (Adder) ─hold─▶ sequencer, [p] controller, arm
    [s] [r] planner.hold ─brake─▶ reference; [h] safety.stop ─hold─▶ reference

In ``synchronized`` execution each segment's reference is one
phase-synchronized Ruckig trajectory of all four coordinates, so it runs on
the straight configuration-space segment the planner checked and costed; the
base tracks it with feed-forward plus the P term, the arm follows it, and
the sequencer advances when the robot is within tolerance *and* the
reference has arrived. In ``paper`` execution (the paper's Section IV-C)
the P-controller drives the base to the target's (x, y) and a Ruckig
trajectory the arm to its (psi1, psi2), independently. The base controller's
feed-forward is the reference's mean velocity over the coming control
period, so that the station's sampled base (a zero-order hold) lands on the
reference.

With :class:`Replan` the planner plans at initialization, then every
``1 / planner.replan_rate`` seconds from the robot's configuration among the
predicted people; a new path comes with a new ``version``, on which the
sequencer heads for the new path's waypoint 1 (a new path starts with the
motion being driven, or is taken from rest: see
:class:`~drake_social.control.ReplanningPlannerSystem`). While no path is
safe the planner's ``hold`` is 1: the sequencer stays (the systems held read
``hold`` > 0.5: the sum of the two flags) and, in synchronized execution, the
reference brakes to rest on its path, jerk-limited (its ``brake`` input),
and goes on along it when the wait ends; only the safety monitor's stop
holds the reference at once. In the paper's execution the wait holds the
controller and the arm as a safety stop does. With standing people there is
no safety monitor and the planner's hold alone holds.

``[h]``: only when the people move (``execution.safety_distance`` >= 0; 0
stops on contact only). People who stand still are obstacles the planner
already kept clear of; a plan may pass them closer than the safety distance,
and a monitor would then hold the robot there for ever. While its ``stop``
is 1 the sequencer does not advance, the base controller commands zero wheel
speeds and the reference (or the arm's trajectory) is held where it is; when
clear a new jerk-limited segment from rest heads for the same target (see
:class:`~drake_social.control.SafetyMonitor` and the ``hold`` input of
:class:`~drake_social.control.RuckigTrajectorySource`). A controller of a
script's own, wired in place of the autonomy's ``wheel_speeds``, reads the
exported ``stop`` itself.
"""

from __future__ import annotations

import dataclasses as dc
from typing import NamedTuple, Union

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import Diagram, DiagramBuilder, InputPort, OutputPort
from pydrake.systems.primitives import Adder, ConstantValueSource, Demultiplexer, Multiplexer, PassThrough

from drake_social.arguments import require_instance
from drake_social.collision.validity import ValidityChecker
from drake_social.control import (
    HolonomicPController,
    PlannerSystem,
    ReplanningPlannerSystem,
    RuckigTrajectorySource,
    SafetyMonitor,
    SpeedLimit,
    WaypointSequencer,
    arm_source_from_options,
    reference_source_from_options,
)
from drake_social.scenario.geometry import arm_geometry, configuration_limits
from drake_social.people import PeopleModel, people_model
from drake_social.scenario import Scenario
from drake_social.sim.checks import check_diagram_options, check_diagram_waypoints, resolve_replan
from drake_social.sim.ports import NamedPorts

__all__ = ["Autonomy", "ExternalPath", "GivenWaypoints", "PATH_SOURCES", "PathSource", "PlanAtInit", "Replan",
           "autonomy_checked", "check_path_source", "make_autonomy", "path_source"]


@dc.dataclass(frozen=True)
class PlanAtInit:
    """The path is planned once, at initialization (a :class:`~drake_social.control.PlannerSystem`
    named ``planner``, with the checker given to :func:`make_autonomy`)."""


@dc.dataclass(frozen=True)
class Replan:
    """The path is replanned while the robot moves (a
    :class:`~drake_social.control.ReplanningPlannerSystem` named ``planner``).

    Attributes:
        replanner: the replanner of the first plan and the replans (an
            object with ``plan(...)``); None = the scenario's
            :class:`~drake_social.planning.replan.Replanner`.
    """

    replanner: object | None = None


@dc.dataclass(frozen=True, eq=False)
class GivenWaypoints:
    """The path is given: (N, 4) configurations from the scenario's start to
    its goal (checked by :func:`~drake_social.waypoints.check_waypoints` at
    the door); a constant source named ``path`` outputs them."""

    waypoints: np.ndarray


@dc.dataclass(frozen=True)
class ExternalPath:
    """The path comes in through the autonomy's input port ``path`` (an
    (N, 4) array in a ``Value[object]``), from a system outside it."""


#: Where the autonomy's path comes from: one of these four.
PathSource = Union[PlanAtInit, Replan, GivenWaypoints, ExternalPath]
PATH_SOURCES = (PlanAtInit, Replan, GivenWaypoints, ExternalPath)


@dc.dataclass
class Autonomy(NamedPorts):
    """A built autonomy and the systems a run reads.

    Attributes:
        diagram: the Drake diagram named ``autonomy`` (every subsystem named;
            its ports: see the module docstring).
        path: the path source it was built with.
        execution: ``"synchronized"`` or ``"paper"``.
        sequencer: the :class:`~drake_social.control.WaypointSequencer` (``sequencer``).
        reference: the jerk-limited reference: the 4-DoF ``reference``
            (synchronized) or the arm's ``arm`` (paper).
        controller: the base controller (``controller``).
        planner: the :class:`~drake_social.control.PlannerSystem` or
            :class:`~drake_social.control.ReplanningPlannerSystem`
            (``planner``), or None (given waypoints, an external path).
        safety: the :class:`~drake_social.control.SafetyMonitor` (``safety``),
            or None (the people stand still).
        speed_limit: the :class:`~drake_social.control.SpeedLimit`
            (``speed_limit``), or None (the people stand still, the paper's
            execution, or ``execution.slow_down`` false).
    """

    diagram: Diagram
    path: PathSource
    execution: str
    sequencer: WaypointSequencer
    reference: RuckigTrajectorySource
    controller: HolonomicPController
    planner: PlannerSystem | ReplanningPlannerSystem | None = None
    safety: SafetyMonitor | None = None
    speed_limit: SpeedLimit | None = None

    @property
    def replanning(self) -> bool:
        """The planner replans (:class:`Replan`)."""
        return isinstance(self.planner, ReplanningPlannerSystem)

    @property
    def waypoints(self) -> np.ndarray | None:
        """The given waypoints (:class:`GivenWaypoints`), else None."""
        return self.path.waypoints if isinstance(self.path, GivenWaypoints) else None


def path_source(waypoints: np.ndarray | None, replan: bool, replanner=None) -> PathSource:
    """The path source of already checked arguments: the given waypoints, else
    the replanner (``replan``), else a plan at initialization."""
    if waypoints is not None:
        return GivenWaypoints(waypoints)
    return Replan(replanner) if replan else PlanAtInit()


def check_path_source(scenario: Scenario, path, checker: ValidityChecker | None, who: str) -> PathSource:
    """``path`` checked at the door of ``who``: None is the scenario's
    (:class:`Replan` with ``planner.replan``, else :class:`PlanAtInit`); given
    waypoints are checked with ``checker`` (the planar checker when None);
    :class:`Replan` keeps to the scenario's replanning rate rule.

    Raises:
        TypeError: ``path`` is none of :data:`PATH_SOURCES`.
        ValueError: a replanning rate above one replan per control period.
        ScenarioError: waypoints that must not be executed.
    """
    require_instance(path, PATH_SOURCES, who, "path",
                     "a PlanAtInit, Replan, GivenWaypoints or ExternalPath of drake_social.sim.autonomy", optional=True)
    if path is None:
        return path_source(None, resolve_replan(scenario, None, False, True, who))
    if isinstance(path, GivenWaypoints):
        return GivenWaypoints(check_diagram_waypoints(scenario, path.waypoints, checker, who))
    if isinstance(path, Replan):
        resolve_replan(scenario, True, False, True, who)
    return path


def make_autonomy(
    scenario: Scenario,
    *,
    execution: str | None = None,
    path: PathSource | None = None,
    checker: ValidityChecker | None = None,
    people: PeopleModel | None = None,
) -> Autonomy:
    """Builds the autonomy of a scenario: path source, sequencer, reference, controller, safety.

    Args:
        scenario: a validated scenario (its ``execution`` section sets gains,
            limits, tolerances and periods).
        execution: ``"synchronized"`` or ``"paper"``; None = ``scenario.execution.execution``.
        path: where the path comes from (:data:`PathSource`); None =
            :class:`Replan` when ``scenario.planner.replan``, else :class:`PlanAtInit`.
        checker: the planner's validity checker, which also checks given
            waypoints (None = the exact planar checker).
        people: the people model (whether they move decides the safety
            monitor; the replanner predicts them); None =
            :func:`~drake_social.people.people_model` of the scenario. Give
            the station's, so that both see the same people.

    Returns:
        The :class:`Autonomy`.

    Raises:
        TypeError: an argument of the wrong kind (named).
        ValueError: an unknown execution, a replanning rate above one
            replan per control period.
        ScenarioError: an invalid scenario, or given waypoints that must not
            be executed (:func:`~drake_social.waypoints.check_waypoints`).
    """
    _, execution = check_diagram_options(scenario, mode=None, execution=execution, checker=checker, meshcat=None,
                                         who="make_autonomy")
    require_instance(people, PeopleModel, "make_autonomy", "people", "a drake_social.people.PeopleModel",
                     optional=True)
    path = check_path_source(scenario, path, checker, "make_autonomy")
    return autonomy_checked(scenario, execution, path, people_model(scenario) if people is None else people,
                            checker=checker)


class _Tracking(NamedTuple):
    """The reference's ports inside the autonomy's builder."""

    source: RuckigTrajectorySource  # the 4-DoF reference or the arm's
    reference: OutputPort  # 4: what is being tracked
    arm_command: OutputPort  # 6: the arm's positions, velocities, accelerations
    feedforward: OutputPort | None  # 4: the reference's mean velocity (synchronized)


def autonomy_checked(scenario: Scenario, execution: str, path: PathSource, people: PeopleModel, *,
                     checker: ValidityChecker | None = None) -> Autonomy:
    """:func:`make_autonomy` with its arguments already checked (the scenario
    validated, ``execution`` the one in force, ``path`` checked by
    :func:`check_path_source`). For drake_social's own builders."""
    opts = scenario.execution
    synchronized = execution == "synchronized"
    builder = DiagramBuilder()
    state = builder.AddNamedSystem("robot_state_split", Demultiplexer([4, 4]))
    builder.ExportInput(state.get_input_port(), "robot_state")
    q = state.get_output_port(0)
    sequencer, planner, path_port = _path(builder, scenario, path, people, checker, synchronized, q)
    controller = builder.AddNamedSystem("controller", HolonomicPController.from_options(opts, feedforward=synchronized))
    position = builder.AddNamedSystem("base_position_split", Demultiplexer([2, 2]))
    builder.Connect(q, position.get_input_port())
    builder.Connect(position.get_output_port(0), controller.GetInputPort("base_position"))
    # The references keep to the limits of a valid configuration: the room
    # bounds for the base and the joint limits (the checkers' and the model's).
    start = path.waypoints[0].copy() if isinstance(path, GivenWaypoints) else np.asarray(scenario.start, float)
    track = (_synchronized if synchronized else _paper)(builder, scenario, start, sequencer, controller)

    people_inputs: list[InputPort] = []
    safety = limiter = None
    if not people.static:  # hold the robot while a walking person is within the safety distance
        safety = builder.AddNamedSystem("safety", SafetyMonitor(
            arm_geometry(scenario), safety_distance=float(opts.safety_distance),
            period=float(opts.control_period), release_time=float(opts.release_time)))
        builder.Connect(q, safety.GetInputPort("q"))
        people_inputs.append(safety.GetInputPort("people_state"))
        if synchronized and opts.slow_down:  # and slow down before that, on the path
            limiter = builder.AddNamedSystem("speed_limit", SpeedLimit(arm_geometry(scenario), opts))
            builder.Connect(q, limiter.GetInputPort("q"))
            builder.Connect(sequencer.GetOutputPort("target"), limiter.GetInputPort("target"))
            builder.Connect(limiter.GetOutputPort("speed_limit"), track.source.GetInputPort("speed_limit"))
            people_inputs.append(limiter.GetInputPort("people_state"))
    if isinstance(planner, ReplanningPlannerSystem):  # it reads the robot and the people
        builder.Connect(q, planner.GetInputPort("q"))
        if synchronized:  # and takes a new path only from rest (the paper's execution leaves the segments anyway)
            builder.Connect(track.source.GetOutputPort("velocity"), planner.GetInputPort("velocity"))
        people_inputs.append(planner.GetInputPort("people_state"))
    for k, port in enumerate(people_inputs):  # one exported input feeds them all
        if k == 0:
            builder.ExportInput(port, "people_state")
        else:
            builder.ConnectInput("people_state", port)
    # Synchronized, the base follows the held reference (base and arm stop together, on the path).
    _hold(builder, safety, planner, (sequencer, track.source) if synchronized else (sequencer, controller, track.source),
          brake=track.source if synchronized else None)

    outputs = {
        "wheel_speeds": controller.GetOutputPort("wheel_speeds"),
        "arm_command": track.arm_command,
        "target": sequencer.GetOutputPort("target"),
        "reference": track.reference,
        "done": sequencer.GetOutputPort("done"),
        "index": sequencer.GetOutputPort("index"),
        "planned_path": path_port,
    }
    if track.feedforward is not None:
        outputs["reference_feedforward"] = track.feedforward
    if safety is not None:
        outputs["stop"] = safety.GetOutputPort("stop")
    if limiter is not None:
        outputs["speed_limit"] = limiter.GetOutputPort("speed_limit")
    if isinstance(planner, ReplanningPlannerSystem):
        outputs["waiting"] = planner.GetOutputPort("hold")
        outputs["path_version"] = planner.GetOutputPort("version")
    for name, port in outputs.items():
        builder.ExportOutput(port, name)
    diagram = builder.Build()
    diagram.set_name("autonomy")
    return Autonomy(diagram=diagram, path=path, execution=execution, sequencer=sequencer, reference=track.source,
                    controller=controller, planner=planner, safety=safety, speed_limit=limiter)


def _path(builder: DiagramBuilder, scenario: Scenario, path: PathSource, people: PeopleModel,
          checker: ValidityChecker | None, synchronized: bool, q: OutputPort):
    """The sequencer, the planner (or None) and the port of the path followed."""
    opts = scenario.execution
    if isinstance(path, GivenWaypoints):
        sequencer = builder.AddNamedSystem("sequencer", WaypointSequencer.from_options(
            opts, waypoints=path.waypoints, wait_for_reference=synchronized, pass_through=synchronized,
            distance_weights=scenario.planner.distance_weights))
        builder.Connect(q, sequencer.GetInputPort("q"))
        source = builder.AddNamedSystem("path", ConstantValueSource(AbstractValue.Make(path.waypoints.copy())))
        return sequencer, None, source.get_output_port()
    replan = isinstance(path, Replan)
    sequencer = builder.AddNamedSystem("sequencer", WaypointSequencer.from_options(
        opts, wait_for_reference=synchronized, versioned=replan, pass_through=synchronized,
        distance_weights=scenario.planner.distance_weights))
    builder.Connect(q, sequencer.GetInputPort("q"))
    planner = None
    if replan:  # the room's planar checker of the replanner, not the one with the people at t = 0
        planner = builder.AddNamedSystem("planner", ReplanningPlannerSystem(scenario, path.replanner, people=people))
        builder.Connect(planner.GetOutputPort("version"), sequencer.GetInputPort("version"))
        builder.Connect(sequencer.GetOutputPort("index"), planner.GetInputPort("index"))
        path_port = planner.GetOutputPort("waypoints")
    elif isinstance(path, PlanAtInit):
        planner = builder.AddNamedSystem("planner", PlannerSystem(scenario, checker))
        path_port = planner.GetOutputPort("waypoints")
    else:  # a system outside the autonomy gives the path
        path_in = builder.AddNamedSystem("path", PassThrough(AbstractValue.Make(np.zeros((0, 4)))))
        builder.ExportInput(path_in.get_input_port(), "path")
        path_port = path_in.get_output_port()
    builder.Connect(path_port, sequencer.GetInputPort("waypoints"))
    return sequencer, planner, path_port


def _synchronized(builder: DiagramBuilder, scenario: Scenario, start: np.ndarray, sequencer: WaypointSequencer,
                  controller: HolonomicPController) -> _Tracking:
    """One 4-DoF reference: the controller tracks its xy with its feed-forward, the arm its psi."""
    reference = builder.AddNamedSystem("reference", reference_source_from_options(
        scenario.execution, start, configuration_limits(scenario),
        lever=arm_geometry(scenario).lever(include_body=True)))
    builder.Connect(sequencer.GetOutputPort("target"), reference.GetInputPort("target"))
    builder.Connect(sequencer.GetOutputPort("via"), reference.GetInputPort("via"))
    builder.Connect(reference.GetOutputPort("finished"), sequencer.GetInputPort("reference_done"))
    # [xy, arm] x (position, velocity, acceleration) in one evaluation (a servo's, every plant step).
    state = builder.AddNamedSystem("reference_state_split", Demultiplexer([2] * 6))
    builder.Connect(reference.GetOutputPort("state"), state.get_input_port())
    builder.Connect(state.get_output_port(0), controller.GetInputPort("base_target"))
    feedforward = builder.AddNamedSystem("reference_feedforward_split", Demultiplexer([2, 2]))
    builder.Connect(reference.GetOutputPort("mean_velocity"), feedforward.get_input_port())
    builder.Connect(feedforward.get_output_port(0), controller.GetInputPort("base_velocity_ff"))
    arm = builder.AddNamedSystem("arm_command", Multiplexer([2, 2, 2]))
    for k in range(3):
        builder.Connect(state.get_output_port(2 * k + 1), arm.get_input_port(k))
    return _Tracking(reference, reference.GetOutputPort("position"), arm.get_output_port(),
                     reference.GetOutputPort("mean_velocity"))


def _paper(builder: DiagramBuilder, scenario: Scenario, start: np.ndarray, sequencer: WaypointSequencer,
           controller: HolonomicPController) -> _Tracking:
    """The target split: the controller drives the base to its xy, a 2-DoF reference the arm to its psi."""
    lower, upper = configuration_limits(scenario)
    split = builder.AddNamedSystem("target_split", Demultiplexer([2, 2]))
    builder.Connect(sequencer.GetOutputPort("target"), split.get_input_port())
    arm = builder.AddNamedSystem("arm", arm_source_from_options(scenario.execution, start[2:],
                                                                (lower[2:], upper[2:])))
    builder.Connect(split.get_output_port(1), arm.GetInputPort("target"))
    builder.Connect(split.get_output_port(0), controller.GetInputPort("base_target"))
    tracked = builder.AddNamedSystem("reference_config", Multiplexer([2, 2]))
    builder.Connect(split.get_output_port(0), tracked.get_input_port(0))
    builder.Connect(arm.GetOutputPort("position"), tracked.get_input_port(1))
    return _Tracking(arm, tracked.get_output_port(0), arm.GetOutputPort("state"), None)


def _hold(builder: DiagramBuilder, safety: SafetyMonitor | None, planner, held: tuple,
          brake: RuckigTrajectorySource | None = None) -> None:
    """The safety stop and the replanner's wait hold the sequencer, the
    controller and the reference: each flag alone, or their sum (> 0.5: either).
    With ``brake`` (the synchronized reference) the replanner's wait brakes it
    on its path (its ``brake`` input) instead, and only the safety stop holds it."""
    ports = [safety.GetOutputPort("stop")] if safety is not None else []
    if isinstance(planner, ReplanningPlannerSystem):
        if brake is not None:
            builder.Connect(planner.GetOutputPort("hold"), brake.GetInputPort("brake"))
            if safety is not None:
                builder.Connect(safety.GetOutputPort("stop"), brake.GetInputPort("hold"))
            held = tuple(system for system in held if system is not brake)
        ports.append(planner.GetOutputPort("hold"))
    if not ports:
        return
    hold = ports[0]
    if len(ports) == 2:
        either = builder.AddNamedSystem("held", Adder(2, 1))
        for k, port in enumerate(ports):
            builder.Connect(port, either.get_input_port(k))
        hold = either.get_output_port()
    for system in held:
        builder.Connect(hold, system.GetInputPort("hold"))
