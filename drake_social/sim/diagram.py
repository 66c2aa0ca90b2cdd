"""The execution diagram: the station and its autonomy, wired by port name.

:func:`build_diagram` adds the station (:func:`~drake_social.sim.station.make_station`:
the robot and its world) and the autonomy
(:func:`~drake_social.sim.autonomy.make_autonomy`: path source, sequencer,
reference, controller, safety) to one builder, connects every input of each
to the output of the other with the same name, exports every other port and
logs the signals a run reads. Running it is
:func:`drake_social.sim.simulate` (in :mod:`drake_social.sim.run`)::

    station  ─robot_state, people_state─▶  autonomy
    autonomy ─wheel_speeds, arm_command─▶  station

The composed diagram's ports (by name): every output of the station, every
output of the autonomy but the two commands the station takes, and the
autonomy's ``path`` input with an :class:`~drake_social.sim.autonomy.ExternalPath`
(the tables of both are in their modules' docstrings and in
``docs/architecture.md``).

To replace a part, a script wires its own around the station instead
("wire your own"): ``docs/examples/custom_controller.py`` drives the station
with its own controller, ``docs/examples/custom_path.py`` feeds the autonomy
a path of its own.

Loggers (``VectorLogSink``, period ``execution.control_period``), in
:attr:`TransportDiagram.loggers`: ``q`` (configuration), ``v`` (its
velocity), ``wheel_speeds`` (applied), ``target`` (the sequencer's),
``reference`` (what is being tracked: the reference position, or the
target's xy with the arm trajectory), ``index`` (the target index), ``done``
(the sequencer's flag), with a crowd ``crowd_state`` (the people source's
discrete state, from which
:meth:`~drake_social.control.PeopleSource.people_log` rebuilds the people),
``stop`` (the safety monitor's flag; only when people move),
``speed_limit`` (the slow-down's limit, m/s, +inf when none; only with it),
and with replanning ``version`` (the path version) and ``waiting`` (the
planner's hold).
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np
from pydrake.geometry import Meshcat, SceneGraph
from pydrake.multibody.plant import MultibodyPlant, MultibodyPlantConfig
from pydrake.multibody.tree import ModelInstanceIndex
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import Demultiplexer, LogVectorOutput, VectorLogSink

from drake_social.arguments import require_instance
from drake_social.collision.validity import ValidityChecker
from drake_social.people import PeopleModel, people_model
from drake_social.scenario import Scenario
from drake_social.sim.autonomy import (Autonomy, GivenWaypoints, PathSource, autonomy_checked, check_path_source,
                                       path_source)
from drake_social.sim.checks import check_diagram_options, check_diagram_waypoints, resolve_replan
from drake_social.sim.ports import NamedPorts, connect_by_name, input_port_names, output_port_names
from drake_social.sim.station import Station, station_checked

__all__ = ["TransportDiagram", "build_checked", "build_diagram"]


@dc.dataclass
class TransportDiagram(NamedPorts):
    """A built execution diagram and the handles a run needs.

    Attributes:
        diagram: the Drake diagram: ``station``, ``autonomy`` and the loggers.
        station: the :class:`~drake_social.sim.station.Station` record.
        autonomy: the :class:`~drake_social.sim.autonomy.Autonomy` record.
        scenario: the scenario it was built from.
        mode, execution: see :data:`drake_social.scenario.SIM_MODES` and ``EXECUTIONS``.
        loggers: name -> VectorLogSink (see the module docstring).
    """

    diagram: Diagram
    station: Station
    autonomy: Autonomy
    scenario: Scenario
    mode: str
    execution: str
    loggers: dict[str, VectorLogSink]

    @property
    def plant(self) -> MultibodyPlant:
        """The station's plant."""
        return self.station.plant

    @property
    def scene_graph(self) -> SceneGraph:
        """The station's SceneGraph."""
        return self.station.scene_graph

    @property
    def robot(self) -> ModelInstanceIndex:
        """The robot's model instance."""
        return self.station.robot

    @property
    def meshcat(self) -> Meshcat | None:
        """The Meshcat the station's visualizer draws to, or None."""
        return self.station.meshcat

    @property
    def visualizer(self):
        """The station's ``MeshcatVisualizer``, or None."""
        return self.station.visualizer

    @property
    def waypoints(self) -> np.ndarray | None:
        """The given waypoints, or None when they are planned or come from outside."""
        return self.autonomy.waypoints

    @property
    def replanning(self) -> bool:
        """The autonomy's planner replans."""
        return self.autonomy.replanning

    def subsystem(self, name: str):
        """The subsystem called ``name`` in the diagram, the station or the
        autonomy (their names are unique across the three), for scripts.

        Raises:
            RuntimeError: no subsystem has that name.
        """
        for diagram in (self.diagram, self.station.diagram, self.autonomy.diagram):
            if diagram.HasSubsystemNamed(name):
                return diagram.GetSubsystemByName(name)
        raise RuntimeError(f"TransportDiagram.subsystem: no subsystem named {name!r} in the diagram, the station "
                           "or the autonomy")


def build_diagram(
    scenario: Scenario,
    *,
    mode: str | None = None,
    execution: str | None = None,
    waypoints: np.ndarray | None = None,
    checker: ValidityChecker | None = None,
    meshcat: Meshcat | None = None,
    path: PathSource | None = None,
    plant_config: MultibodyPlantConfig | None = None,
    people: PeopleModel | None = None,
    replan: bool | None = None,
    replanner=None,
) -> TransportDiagram:
    """Builds the diagram that plans (or takes) a path and executes it: the station and its autonomy.

    Args:
        scenario: a validated scenario (its ``execution`` section sets gains,
            limits, tolerances and periods).
        mode: ``"kinematic"`` or ``"dynamic"``; None = ``scenario.execution.mode``.
        execution: ``"synchronized"`` or ``"paper"``; None = ``scenario.execution.execution``.
        waypoints: (N, 4) configurations to follow from the scenario's start
            to its goal, checked first (:func:`~drake_social.waypoints.check_waypoints`);
            None = plan them at initialization (or replan, see ``replan``).
        checker: the planner's validity checker, which also checks given
            waypoints (None = the exact planar checker).
        meshcat: when given, a ``MeshcatVisualizer`` draws the scene to it at
            ``execution.replay_fps``.
        path: the autonomy's path source
            (:data:`~drake_social.sim.autonomy.PathSource`, e.g.
            :class:`~drake_social.sim.autonomy.ExternalPath`: the path comes
            in through the input port ``path``); None = the one that
            ``waypoints`` and ``replan`` say. Given, it is the only word on
            the path: ``waypoints``, ``replan`` and ``replanner`` stay None.
        plant_config: the dynamic mode's ``MultibodyPlantConfig``; None =
            :func:`~drake_social.sim.station.scenario_plant_config` (unused
            in kinematic mode, whose plant only places the shapes).
        people: the people model of the station's ``people`` source and the
            autonomy; None = :func:`~drake_social.people.people_model` of the scenario.
        replan: the planner replans periodically (a
            :class:`~drake_social.control.ReplanningPlannerSystem`, see
            :mod:`drake_social.sim.autonomy`); None = ``scenario.planner.replan``
            when the diagram plans (no ``waypoints``), else False.
        replanner: with replanning, the replanner of the first plan and
            the replans (an object with ``plan(...)``, see
            :class:`~drake_social.control.ReplanningPlannerSystem`); None =
            the scenario's :class:`~drake_social.planning.replan.Replanner`.

    Returns:
        The :class:`TransportDiagram`.

    Raises:
        TypeError: an argument of the wrong kind (named).
        ValueError: an unknown mode or execution; ``path`` with ``waypoints``,
            ``replan`` or ``replanner``; ``replan=True`` with ``waypoints``.
        ScenarioError: an invalid scenario (:func:`~drake_social.scenario.validate_scenario`:
            e.g. contradictory execution options), or ``waypoints`` that must not be executed
            (:func:`~drake_social.waypoints.check_waypoints`: shape, limits,
            start and goal, collisions).
    """
    who = "build_diagram"
    mode, execution = check_diagram_options(scenario, mode=mode, execution=execution, checker=checker,
                                            meshcat=meshcat, who=who)
    require_instance(plant_config, MultibodyPlantConfig, who, "plant_config",
                     "a pydrake.multibody.plant.MultibodyPlantConfig", optional=True)
    require_instance(people, PeopleModel, who, "people", "a drake_social.people.PeopleModel", optional=True)
    if path is None:
        replan = resolve_replan(scenario, replan, waypoints is not None, True, who)
        if waypoints is not None:
            waypoints = check_diagram_waypoints(scenario, waypoints, checker, who)
        path = path_source(waypoints, replan, replanner)
    else:
        also = [name for name, value in (("waypoints", waypoints), ("replan", replan), ("replanner", replanner))
                if value is not None]
        if also:
            raise ValueError(f"{who}: path: the path source says where the path comes from; leave out "
                             f"{', '.join(also)} (or leave out path)")
        path = check_path_source(scenario, path, checker, who)
    return build_checked(scenario, mode, execution, path, checker, meshcat, plant_config=plant_config, people=people)


def build_checked(
    scenario: Scenario, mode: str, execution: str, path: PathSource, checker: ValidityChecker | None,
    meshcat: Meshcat | None, *, plant_config: MultibodyPlantConfig | None = None, people: PeopleModel | None = None,
) -> TransportDiagram:
    """:func:`build_diagram` with its arguments already checked (the scenario
    validated; ``mode`` and ``execution`` the ones in force; ``path``
    checked: :func:`~drake_social.sim.autonomy.check_path_source`, or
    :func:`~drake_social.sim.autonomy.path_source` of checked waypoints).
    For drake_social's own callers that checked them once."""
    people = people_model(scenario) if people is None else people  # the station's and the autonomy's
    start = path.waypoints[0].copy() if isinstance(path, GivenWaypoints) else np.asarray(scenario.start, float)
    station = station_checked(scenario, mode, people, start=start, meshcat=meshcat, plant_config=plant_config)
    autonomy = autonomy_checked(scenario, execution, path, people, checker=checker)

    builder = DiagramBuilder()
    builder.AddSystem(station.diagram)
    builder.AddSystem(autonomy.diagram)
    commands = connect_by_name(builder, autonomy.diagram, station.diagram)
    sensors = connect_by_name(builder, station.diagram, autonomy.diagram)
    for system, taken in ((station.diagram, ()), (autonomy.diagram, commands)):
        for name in output_port_names(system):
            if name not in taken:
                builder.ExportOutput(system.GetOutputPort(name), name)
    for system, fed in ((station.diagram, commands), (autonomy.diagram, sensors)):
        for name in input_port_names(system):
            if name not in fed:
                builder.ExportInput(system.GetInputPort(name), name)
    loggers = _loggers(builder, station.diagram, autonomy.diagram, float(scenario.execution.control_period))
    diagram = builder.Build()
    diagram.set_name(f"transport_{mode}_{execution}")
    return TransportDiagram(diagram=diagram, station=station, autonomy=autonomy, scenario=scenario, mode=mode,
                            execution=execution, loggers=loggers)


#: Logger name -> the autonomy's output it logs (when the autonomy has it).
_AUTONOMY_LOGS = {"target": "target", "reference": "reference", "index": "index", "done": "done", "stop": "stop",
                  "version": "path_version", "waiting": "waiting", "speed_limit": "speed_limit"}


def _loggers(builder: DiagramBuilder, station: Diagram, autonomy: Diagram, period: float) -> dict[str, VectorLogSink]:
    """The run's loggers (see the module docstring), each named ``<name>_log``."""
    state = builder.AddNamedSystem("logged_state", Demultiplexer([4, 4]))
    builder.Connect(station.GetOutputPort("robot_state"), state.get_input_port())
    ports = {"q": state.get_output_port(0), "v": state.get_output_port(1),
             "wheel_speeds": station.GetOutputPort("wheel_speeds")}
    present = set(output_port_names(autonomy))
    ports.update({name: autonomy.GetOutputPort(port) for name, port in _AUTONOMY_LOGS.items() if port in present})
    if station.HasOutputPort("crowd_state"):
        ports["crowd_state"] = station.GetOutputPort("crowd_state")
    loggers = {}
    for name in ("q", "v", "wheel_speeds", "target", "reference", "index", "done", "crowd_state", "stop", "version",
                 "waiting", "speed_limit"):
        if name in ports:
            logger = LogVectorOutput(ports[name], builder, publish_period=period)
            logger.set_name(f"{name}_log")
            loggers[name] = logger
    return loggers
