"""The execution diagram: planner, sequencer, controller, trajectory sources, robot.

:func:`build_diagram` wires the systems of :mod:`drake_social.control` into
one Drake diagram and names every subsystem, so that a script can fetch any of
them (``diagram.GetSubsystemByName("controller")``), and exports named ports
(a station, as in Drake's hardware_sim and the manipulation course's
``station.py``), so that a script can leave out the planner or the base
controller and wire its own. Running it is :func:`drake_social.sim.simulate`
(in :mod:`drake_social.sim.run`).

Blocks (all named; ``[p]`` only with ``execution="paper"``, ``[s]`` only with
``"synchronized"``, ``[k]`` only in ``mode="kinematic"``, ``[d]`` only in
``"dynamic"``)::

    planner ─waypoints─▶ sequencer ─target─▶ [s] reference (4-DoF Ruckig, phase sync)
                          ▲  │                    │ position, velocity
                          q  └─target─▶ [p] target_split ─xy─▶ controller
                          │            [p] arm (2-DoF Ruckig) ◀─psi─┘
                          │  controller ─wheel_speeds─▶ drive (mecanum forward kinematics)
    [k] base (Integrator of the drive's velocity) + arm position ─▶ configuration ─▶ to_pose ─▶ scene_graph
    [d] drive velocity ─▶ hold (ZOH) ─▶ desired_state ◀─ arm reference state (position, velocity, acceleration)
        desired_state, plant state ─▶ servo_* (commanded acceleration) ─▶ servo (inverse dynamics) ─▶ plant

    people (PeopleSource: the people model at the context's time; a crowd stepped with q) ─▶ people_state
    people_state ─▶ people_geometry (PeopleGeometry: moving bodies) ─▶ scene_graph   [only when people move]

People who stand still (a static people model) are anchored in the plant
where they stand, as in the planning checkers. People who move (scripted,
recorded or a crowd) are not in the plant: ``people_geometry`` registers
their bodies as its own SceneGraph source and moves them from
``people_state``, so ``query_object`` sees them where they are at the
context's time; an absent person is parked below the floor
(:data:`~drake_social.control.PARKED_DEPTH`). A crowd's ``people`` reads the
robot's configuration (its ``robot_q`` input) at its updates. In dynamic
mode the moving bodies are filtered out of collisions with every shape and
with each other: the plant must own every shape of a contact it is given
(Drake raises on a contact with a shape it did not register, drake issue
22164), and people are not obstacles the robot pushes; the pair query
``QueryObject.ComputeSignedDistancePairClosestPoints`` ignores filters and
still measures a person's distance in that mode.

    [h] safety (SafetyMonitor) ◀─ q, people_state; stop ─hold─▶ sequencer, controller, reference / arm

With ``replan`` (``simulate --replan``, ``planner.replan: true``) the
planner is a :class:`~drake_social.control.ReplanningPlannerSystem`::

    [r] q, people_state, sequencer.index ─▶ planner (ReplanningPlannerSystem) ─waypoints, version─▶ sequencer
    [r] planner.hold (waiting), [h] safety.stop ─▶ held (Adder) ─hold─▶ sequencer, controller, reference / arm

The planner plans at initialization, then every ``1 / planner.replan_rate``
seconds from the robot's configuration among the predicted people; a new
path comes with a new ``version``, on which the sequencer heads for the new
path's waypoint 1 and the jerk-limited reference turns towards it from its
current position, velocity and acceleration (no jump in either). While no
path is safe the planner's ``hold`` is 1 and the robot stops as on a safety
stop (the systems held read ``hold`` > 0.5: the sum of the two flags). With
standing people there is no safety monitor and the planner's hold alone
holds.

``[h]``: only when the people move (``execution.safety_distance`` >= 0; 0
stops on contact only). People who stand still are obstacles the planner
already kept clear of; a plan may pass them closer than the safety distance,
and a monitor would then hold the robot there for ever. While its ``stop`` is 1 the sequencer does not
advance, the base controller commands zero wheel speeds and the reference
(or the arm's trajectory) is held where it is; when clear a new jerk-limited
segment from rest heads for the same target (see
:class:`~drake_social.control.SafetyMonitor` and the ``hold`` input of
:class:`~drake_social.control.RuckigTrajectorySource`). A controller outside
the diagram (``controller=False``) reads the exported ``stop`` itself.

The planner is left out when ``waypoints`` are given, or with
``planner=False`` (the path then comes in through the input port ``path``);
the base controller with ``controller=False`` (the wheel speeds then come in
through the input port ``wheel_speeds``).

In ``synchronized`` execution each segment's reference is one phase-synchronized Ruckig
trajectory of all four coordinates, so it runs on the straight
configuration-space segment the planner checked and costed; the base tracks
it with feed-forward plus the P term, the arm follows it, and the sequencer
advances when the robot is within tolerance *and* the reference has arrived.
In ``paper`` execution (the paper's Section IV-C) the P-controller drives the
base to the target's (x, y) and a Ruckig trajectory the arm to its
(psi1, psi2), independently.

The base controller is sampled every ``execution.control_period`` (behind a
zero-order hold ``hold``), like the digital controller of a real base; in
``synchronized`` execution its feed-forward is the reference's mean velocity
over the coming period, so the sampled loop lands on the reference.

``kinematic`` mode: the base integrates the velocity its wheels produce (a
continuous ``Integrator``) and the arm follows its reference exactly; the
plant is not simulated (it stays outside the diagram and only turns
positions into SceneGraph poses, :attr:`TransportDiagram.plant`).
``dynamic`` mode: the ``MultibodyPlant`` is a discrete system
(:func:`scenario_plant_config`: ``execution.plant_time_step``, TAMSI) whose joint actuators are driven at
every plant step by a computed-torque servo in C++ blocks: the commanded
acceleration ``a = a_d + Kp (q_d - q) + Kd (v_d - v)`` (gain blocks
``servo_*``, the gains of :func:`servo_gains`), then Drake's
``InverseDynamics`` (``servo``) ``u = M(q) a + C(q, v) v`` of the plant.
The arm joints follow the reference's position, velocity and acceleration,
evaluated at the plant's rate like a servo drive's interpolation of its
trajectory: with the acceleration fed forward
and the inertia and coupling compensated, the error obeys ``e'' + Kd e' +
Kp e = 0`` (critically damped) in every configuration, so the arm lands on
the reference's end instead of passing it (a PD law on the joint error alone
leads a decelerating reference and can pass a joint limit at the goal). The
base joints are velocity servos on the drive's velocity (the digital base
controller's output, held for ``execution.control_period`` by ``hold``).

The station's ports (the diagram's exported ports, by name), so that a
script can wire another planner, controller or people model around it
(``builder.AddSystem(built.diagram)``, then ``GetInputPort`` /
``GetOutputPort`` by these names)::

    inputs   path            (N, 4) waypoints, Value[object]; only with planner=False and no waypoints
             wheel_speeds    4 wheel speeds, rad/s; only with controller=False
    outputs  robot_state     8: [q, v], q = [x, y, psi1, psi2] (m, rad), v its velocity (m/s, rad/s)
             target          4: the sequencer's current waypoint
             reference       4: what is being tracked (see the loggers below)
             reference_feedforward
                             4: the reference's mean velocity over the next control period
                             (synchronized execution only; the base controller's feed-forward)
             done, index     1 each: the sequencer's latched goal flag and target index
             planned_path    (N, 4) waypoints being followed, Value[object]
             wheel_speeds    4: the wheel speeds applied (held in kinematic mode), rad/s
             people_state    PeopleState at the context's time, Value[object]
             people_vector   6 P: per person [x, y, theta, vx, vy, radius]
                             (an absent person keeps a pose: see people_state's present)
             stop            1: 1.0 while the safety monitor holds the robot (only when people move)
             waiting         1: 1.0 while the replanner finds no safe path (only with replan)
             path_version    1: the replanner's path version (only with replan)
             query_object    SceneGraph's QueryObject (distances, collisions); a kinematic
                             diagram's SceneGraph has no boxes of world.map (see build_diagram):
                             measure against them with the planar checker

A base controller outside the diagram reads ``robot_state`` and
``reference`` (and ``reference_feedforward``) and writes ``wheel_speeds``;
``robot_state`` does not depend on ``wheel_speeds`` at the same instant
(the wheels act through the hold or the discrete plant), so such a loop
has no algebraic loop. ``docs/examples/custom_controller.py`` is one.

Loggers (``VectorLogSink``, period ``execution.control_period``), in
:attr:`TransportDiagram.loggers`: ``q`` (configuration), ``v`` (its
velocity), ``wheel_speeds``, ``target`` (the sequencer's), ``reference``
(what is being tracked: the reference position, or the target's xy with the
arm trajectory), ``index`` (the target index), ``done`` (the sequencer's flag),
with a crowd ``crowd_state`` (the people source's discrete state, from
which :meth:`~drake_social.control.PeopleSource.people_log` rebuilds the people),
``stop`` (the safety monitor's flag; only when people move), and with
replanning ``version`` (the path version) and ``waiting`` (the planner's hold).
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np
from pydrake.geometry import CollisionFilterDeclaration, GeometryId, GeometrySet, Meshcat, Role, SceneGraph
from pydrake.common.value import AbstractValue
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlant, MultibodyPlantConfig
from pydrake.multibody.tree import ModelInstanceIndex
from pydrake.systems.controllers import InverseDynamics
from pydrake.systems.framework import Diagram, DiagramBuilder, OutputPort
from pydrake.systems.primitives import (
    Adder,
    ConstantValueSource,
    ConstantVectorSource,
    Demultiplexer,
    Integrator,
    LogVectorOutput,
    MatrixGain,
    Multiplexer,
    PassThrough,
    VectorLogSink,
    ZeroOrderHold,
)
from pydrake.systems.rendering import MultibodyPositionToGeometryPose

from drake_social.arguments import require_checker, require_choice, require_instance, require_scenario
from drake_social.control import (
    HolonomicPController,
    MecanumDrive,
    PeopleGeometry,
    PeopleSource,
    PlannerSystem,
    ReplanningPlannerSystem,
    SafetyMonitor,
    WaypointSequencer,
    arm_source_from_options,
    reference_source_from_options,
)
from drake_social.scenario.geometry import arm_geometry, configuration_limits
from drake_social.model.plant import add_environment, add_robot
from drake_social.people import PeopleModel, people_model
from drake_social.collision.validity import ValidityChecker
from drake_social.scenario import (EXECUTIONS, SIM_MODES, SERVO_BANDWIDTH, SERVO_BASE_TIME_CONSTANT, Scenario,
                                    ScenarioError, plant_time_step_problem, replan_rate_problem, validate_scenario)
from drake_social.waypoints import check_waypoints
from drake_social.world import world_model

__all__ = ["MAX_DYNAMIC_MAP_BOXES", "DiagramArguments", "TransportDiagram", "build_diagram", "check_diagram_arguments", "check_diagram_options",
           "check_diagram_waypoints", "resolve_replan", "scenario_plant_config", "servo_gains"]


@dc.dataclass
class TransportDiagram:
    """A built execution diagram and the handles a run needs.

    Attributes:
        diagram: the Drake diagram (every subsystem named).
        plant: the scenario's MultibodyPlant (inside the diagram as ``plant``
            in dynamic mode; outside it, for poses only, in kinematic mode).
        scene_graph: the SceneGraph (``scene_graph``).
        robot: the robot's model instance.
        scenario: the scenario it was built from.
        mode, execution: see :data:`drake_social.scenario.SIM_MODES` and ``EXECUTIONS``.
        waypoints: the fixed waypoints, or None when ``planner`` plans them.
        meshcat: the Meshcat the visualizer draws to, or None.
        visualizer: the ``MeshcatVisualizer``, or None.
        loggers: name -> VectorLogSink (see the module docstring).
        planner_included, controller_included: whether the built-in planner
            and base controller are inside (see :func:`build_diagram`).
        replanning: the planner is a :class:`~drake_social.control.ReplanningPlannerSystem`.
    """

    diagram: Diagram
    plant: MultibodyPlant
    scene_graph: SceneGraph
    robot: ModelInstanceIndex
    scenario: Scenario
    mode: str
    execution: str
    waypoints: np.ndarray | None
    meshcat: Meshcat | None
    visualizer: object | None
    loggers: dict[str, VectorLogSink]
    planner_included: bool = True
    controller_included: bool = True
    replanning: bool = False

    def subsystem(self, name: str):
        """The subsystem called ``name`` (e.g. ``"sequencer"``)."""
        return self.diagram.GetSubsystemByName(name)

    def input_port_names(self) -> list[str]:
        """Names of the diagram's exported input ports (see :func:`build_diagram`)."""
        return [self.diagram.get_input_port(i).get_name() for i in range(self.diagram.num_input_ports())]

    def output_port_names(self) -> list[str]:
        """Names of the diagram's exported output ports (see :func:`build_diagram`)."""
        return [self.diagram.get_output_port(i).get_name() for i in range(self.diagram.num_output_ports())]


def servo_gains(*, bandwidth: float = SERVO_BANDWIDTH,
                base_time_constant: float = SERVO_BASE_TIME_CONSTANT) -> tuple[np.ndarray, np.ndarray]:
    """Gains ``(Kp, Kd)`` of the dynamic mode's inverse-dynamics servo, in joint order.

    They act on accelerations (the inertia is compensated): the arm joints
    get a critically damped error of ``bandwidth`` rad/s, ``Kp = w^2``
    (1/s^2), ``Kd = 2 w`` (1/s); the base joints are velocity servos of time
    constant ``base_time_constant`` seconds, ``Kp = 0``, ``Kd = 1 / tau``.
    The discrete plant (TAMSI) applies the force explicitly, which is stable
    while ``Kd dt`` stays at most 1 (here ``2 w dt`` = 0.24 and ``dt /
    tau`` = 0.1 at the 2 ms step); validation holds a dynamic run's step to
    :data:`~drake_social.scenario.MAX_DYNAMIC_PLANT_TIME_STEP`.

    Returns:
        Two (4,) arrays for ``[base_x, base_y, psi1, psi2]``.
    """
    w, tau = float(bandwidth), float(base_time_constant)
    return np.array([0.0, 0.0, w * w, w * w]), np.array([1.0 / tau, 1.0 / tau, 2.0 * w, 2.0 * w])


#: Most map boxes a dynamic run's SceneGraph holds: it keeps a filter state
#: for every pair of shapes (about 60 N^2 bytes, 240 MB at 2,000).
MAX_DYNAMIC_MAP_BOXES = 2_000


def _populate(plant: MultibodyPlant, scenario: Scenario, people: bool = True, *,
              map_boxes: bool = True) -> ModelInstanceIndex:
    robot = add_robot(plant, scenario)
    add_environment(plant, scenario, people=people, map_boxes=map_boxes)
    plant.Finalize()
    # The model's joints each have an actuator (Drake's SDFormat parser adds one
    # per joint of unlimited effort): the actuation input is [u_x, u_y, u_1, u_2].
    B = plant.MakeActuationMatrix()
    if plant.num_positions() != 4 or not np.array_equal(B, np.eye(4)):  # our own model: a bug if it fails
        raise RuntimeError(f"unexpected actuation matrix of the robot model:\n{B}")
    return robot


def build_diagram(
    scenario: Scenario,
    *,
    mode: str | None = None,
    execution: str | None = None,
    waypoints: np.ndarray | None = None,
    checker: ValidityChecker | None = None,
    meshcat: Meshcat | None = None,
    planner: bool = True,
    controller: bool = True,
    plant_config: MultibodyPlantConfig | None = None,
    people: PeopleModel | None = None,
    replan: bool | None = None,
    replanner=None,
) -> TransportDiagram:
    """Builds the diagram that plans (or takes) a path and executes it.

    The diagram is a station: its named ports (see the module docstring,
    :data:`INPUTS` and :data:`OUTPUTS`) let a script wire another planner,
    controller or people model around it without editing this builder.

    Args:
        scenario: a validated scenario (its ``execution`` section sets gains,
            limits, tolerances and periods).
        mode: ``"kinematic"`` or ``"dynamic"``; None = ``scenario.execution.mode``.
        execution: ``"synchronized"`` or ``"paper"``; None = ``scenario.execution.execution``.
        waypoints: (N, 4) configurations to follow from the scenario's start
            to its goal, checked first (:func:`~drake_social.waypoints.check_waypoints`);
            None = plan them with a ``planner`` (:class:`PlannerSystem`) at
            initialization.
        checker: the planner's validity checker, which also checks given
            waypoints (None = the exact planar checker).
        meshcat: when given, a ``MeshcatVisualizer`` draws the scene to it at
            ``execution.replay_fps``.
        planner: with no ``waypoints``, plan them with the built-in
            ``planner``; False leaves it out and exports the sequencer's
            input as the diagram's input port ``path`` (an (N, 4) array in a
            ``Value[object]``) for a planner outside the diagram.
        controller: include the built-in base controller; False leaves it
            out and exports the drive's input as the diagram's input port
            ``wheel_speeds`` (4, rad/s) for a controller outside the diagram.
        plant_config: the dynamic mode's ``MultibodyPlantConfig``; None =
            :func:`scenario_plant_config` (unused in kinematic mode, whose
            plant only places the shapes).
        people: the people model of the ``people`` source; None =
            :func:`~drake_social.people.people_model` of the scenario.
        replan: the planner replans periodically (a
            :class:`~drake_social.control.ReplanningPlannerSystem`, see the
            module docstring); None = ``scenario.planner.replan`` when the
            diagram plans (no ``waypoints``, ``planner`` True), else False.
            True needs the built-in planner.
        replanner: with replanning, the replanner of the first plan and
            the replans (an object with ``plan(...)``, see
            :class:`~drake_social.control.ReplanningPlannerSystem`); None =
            the scenario's :class:`~drake_social.planning.replan.Replanner`.

    Returns:
        The :class:`TransportDiagram`.

    Raises:
        TypeError: an argument of the wrong kind (named).
        ValueError: an unknown mode or execution.
        ScenarioError: an invalid scenario (:func:`~drake_social.scenario.validate_scenario`:
            e.g. contradictory execution options), or ``waypoints`` that must not be executed
            (:func:`~drake_social.waypoints.check_waypoints`: shape, limits,
            start and goal, collisions).
    """
    checked = check_diagram_arguments(scenario, mode=mode, execution=execution, waypoints=waypoints, checker=checker,
                                      meshcat=meshcat, who="build_diagram")
    require_instance(planner, (bool, np.bool_), "build_diagram", "planner", "True or False")
    require_instance(controller, (bool, np.bool_), "build_diagram", "controller", "True or False")
    require_instance(plant_config, MultibodyPlantConfig, "build_diagram", "plant_config",
                     "a pydrake.multibody.plant.MultibodyPlantConfig", optional=True)
    require_instance(people, PeopleModel, "build_diagram", "people",
                     "a drake_social.people.PeopleModel", optional=True)
    replan = resolve_replan(scenario, replan, waypoints is not None, bool(planner), "build_diagram")
    return build_checked(scenario, checked.mode, checked.execution, checked.waypoints, checker, meshcat,
                         planner=bool(planner), controller=bool(controller), plant_config=plant_config,
                         people=people, replan=replan, replanner=replanner)


def resolve_replan(scenario: Scenario, replan, given_path: bool, planner: bool, who: str) -> bool:
    """Whether a run replans: ``replan``, or with None ``scenario.planner.replan`` when it plans.

    Raises:
        TypeError: ``replan`` is not None, True or False.
        ValueError: ``replan=True`` with given waypoints or without the
            built-in planner, or for a scenario whose ``planner.replan_rate``
            is more than one replan per control period.
    """
    require_instance(replan, (bool, np.bool_), who, "replan", "True, False or None", optional=True)
    if replan is None:
        return bool(scenario.planner.replan) and planner and not given_path
    if replan and given_path:
        raise ValueError(f"{who}: replan=True replans the path; with given waypoints nothing is planned "
                         "(leave out the waypoints, or replan)")
    if replan and not planner:
        raise ValueError(f"{who}: replan=True needs the built-in planner (planner=True)")
    problem = replan_rate_problem(scenario.planner.replan_rate, scenario.execution) if replan else None
    if problem:
        raise ValueError(f"{who}: replan=True: the scenario's planner.replan_rate {problem}")
    return bool(replan)


@dc.dataclass(frozen=True)
class DiagramArguments:
    """:func:`check_diagram_arguments`' verdict: the mode and execution in
    force and the checked waypoints (None: planned)."""

    mode: str
    execution: str
    waypoints: np.ndarray | None


def check_diagram_options(
    scenario: Scenario,
    *,
    mode: str | None,
    execution: str | None,
    checker: ValidityChecker | None,
    meshcat: Meshcat | None,
    who: str,
) -> tuple[str, str]:
    """The cheap part of :func:`check_diagram_arguments`: everything but the
    waypoints (the scenario is validated too).

    Returns:
        The mode and execution in force.

    Raises:
        TypeError: as :func:`build_diagram`.
        ValueError: as :func:`build_diagram`.
        ScenarioError: as :func:`build_diagram`.
    """
    require_scenario(scenario, who)
    require_choice(mode, who, "mode", SIM_MODES, optional=True)
    require_choice(execution, who, "execution", EXECUTIONS, optional=True)
    require_checker(checker, who, optional=True)
    require_instance(meshcat, Meshcat, who, "meshcat", "a pydrake.geometry.Meshcat", optional=True)
    # also one changed in code after loading; this checks the Drake settings
    # too (contact approximation, integration scheme, accuracy, realtime rate)
    validate_scenario(scenario, source=f"{who}: scenario")
    mode = mode or scenario.execution.mode
    problem = plant_time_step_problem(scenario.execution, mode)  # the scenario's mode was checked above
    if problem:
        raise ScenarioError(f"{who}: scenario: {problem[0]}: {problem[1]}")
    return mode, execution or scenario.execution.execution


def check_diagram_waypoints(scenario: Scenario, waypoints, checker: ValidityChecker | None, who: str) -> np.ndarray:
    """The waypoints to execute checked by :func:`~drake_social.waypoints.check_waypoints`
    with ``checker``, or the exact planar checker when it is None (the
    planner's default: the checker of the run)."""
    if checker is None:
        from drake_social.collision.drake_checker import make_checker

        checker = make_checker(scenario, "planar")
    return check_waypoints(scenario, waypoints, checker, source=f"{who}: waypoints")


def check_diagram_arguments(
    scenario: Scenario,
    *,
    mode: str | None,
    execution: str | None,
    waypoints: np.ndarray | None,
    checker: ValidityChecker | None,
    meshcat: Meshcat | None,
    who: str,
) -> DiagramArguments:
    """Checks :func:`build_diagram`'s arguments: the cheap ones first
    (:func:`check_diagram_options`), then the waypoints
    (:func:`check_diagram_waypoints`).

    Args:
        who: the public function, named in the errors.

    Raises:
        TypeError: as :func:`build_diagram`.
        ValueError: as :func:`build_diagram`.
        ScenarioError: as :func:`build_diagram`.
    """
    mode, execution = check_diagram_options(scenario, mode=mode, execution=execution, checker=checker,
                                            meshcat=meshcat, who=who)
    if waypoints is not None:
        waypoints = check_diagram_waypoints(scenario, waypoints, checker, who)
    return DiagramArguments(mode, execution, waypoints)


def _filter_people(scene_graph: SceneGraph, people: list[GeometryId]) -> None:
    """Excludes the moving people's bodies from collisions with every other
    shape and with each other (dynamic mode: see the module docstring)."""
    inspector = scene_graph.model_inspector()
    theirs = GeometrySet(people)
    others = GeometrySet([g for g in inspector.GetAllGeometryIds(Role.kProximity) if g not in set(people)])
    declaration = CollisionFilterDeclaration().ExcludeWithin(theirs).ExcludeBetween(theirs, others)
    scene_graph.collision_filter_manager().Apply(declaration)


def scenario_plant_config(scenario: Scenario) -> MultibodyPlantConfig:
    """The dynamic mode's ``MultibodyPlantConfig`` of a scenario.

    ``time_step`` is ``execution.plant_time_step`` (seconds) and
    ``discrete_contact_approximation`` is ``execution.contact_approximation``,
    by default TAMSI: a step of this plant costs ~60 us
    against ~200 us with the SAP solvers (measured on office_bar), which
    Drake's built-in joint PD controllers would need; the servo is therefore
    made of C++ blocks (``servo_*``, ``servo``) on the plant's actuation
    input. The other fields are Drake's defaults.

    Drake 1.51 marks TAMSI deprecated (removal announced for 2026-09-01; it
    logs one warning per process): a script can pass another approximation
    (``"lagged"``, ``"similar"``) in the scenario or through
    ``build_diagram(plant_config=...)``, at about three times the cost of a step.
    """
    return MultibodyPlantConfig(time_step=float(scenario.execution.plant_time_step),
                                discrete_contact_approximation=scenario.execution.contact_approximation)


def build_checked(
    scenario: Scenario, mode: str, execution: str, waypoints: np.ndarray | None, checker: ValidityChecker | None,
    meshcat: Meshcat | None, *, planner: bool = True, controller: bool = True,
    plant_config: MultibodyPlantConfig | None = None, people: PeopleModel | None = None, replan: bool = False,
    replanner=None,
) -> TransportDiagram:
    """:func:`build_diagram` with its arguments already checked
    (:func:`check_diagram_arguments`; ``mode`` and ``execution`` the ones in
    force). For drake_social's own callers that checked them once."""
    config = plant_config if plant_config is not None else scenario_plant_config(scenario)
    opts = scenario.execution
    start = np.asarray(scenario.start, float)
    if waypoints is not None:
        start = waypoints[0].copy()
    synchronized = execution == "synchronized"
    period = float(opts.control_period)
    # The references keep to the limits of a valid configuration: the room
    # bounds for the base and the joint limits (the checkers' and the model's).
    lower, upper = configuration_limits(scenario)

    builder = DiagramBuilder()
    scenario_people = people_model(scenario) if people is None else people  # static people are anchored in the plant, moving ones move in SceneGraph
    if mode == "dynamic":
        count = world_model(scenario).map_box_count
        if count > MAX_DYNAMIC_MAP_BOXES:
            raise ScenarioError(
                f"world.map: {count:,} boxes are too many for a dynamic run (execution.mode dynamic), whose "
                f"SceneGraph keeps a filter state for every pair of shapes; at most {MAX_DYNAMIC_MAP_BOXES:,}: "
                f"run it kinematic, or coarsen or clean the map")
        plant, scene_graph = AddMultibodyPlant(config, builder)
        robot = _populate(plant, scenario, scenario_people.static)
        plant.SetDefaultPositions(robot, start)
    else:
        # The kinematic plant only places the shapes: the map's boxes (the
        # replay draws them as one mesh; the analysis checks the executed
        # trajectory against them) are left out of its SceneGraph.
        scene_graph = builder.AddNamedSystem("scene_graph", SceneGraph())
        plant = MultibodyPlant(time_step=0.0)
        plant.RegisterAsSourceForSceneGraph(scene_graph)
        robot = _populate(plant, scenario, scenario_people.static, map_boxes=False)

    # ---- which target ---------------------------------------------------------
    replanning: ReplanningPlannerSystem | None = None
    if waypoints is None:
        sequencer = builder.AddNamedSystem(
            "sequencer", WaypointSequencer.from_options(opts, wait_for_reference=synchronized, versioned=replan))
        if replan:  # the room's planar checker of the replanner, not the one with the people at t = 0
            replanning = builder.AddNamedSystem("planner", ReplanningPlannerSystem(scenario, replanner,
                                                                                   people=scenario_people))
            path_port = replanning.GetOutputPort("waypoints")
            builder.Connect(replanning.GetOutputPort("version"), sequencer.GetInputPort("version"))
            builder.Connect(sequencer.GetOutputPort("index"), replanning.GetInputPort("index"))
        elif planner:
            path_port = builder.AddNamedSystem("planner", PlannerSystem(scenario, checker)).GetOutputPort("waypoints")
        else:  # a planner outside the diagram gives the path
            path_in = builder.AddNamedSystem("path", PassThrough(AbstractValue.Make(np.zeros((0, 4)))))
            builder.ExportInput(path_in.get_input_port(), "path")
            path_port = path_in.get_output_port()
        builder.Connect(path_port, sequencer.GetInputPort("waypoints"))
    else:
        sequencer = builder.AddNamedSystem(
            "sequencer", WaypointSequencer.from_options(opts, waypoints=waypoints, wait_for_reference=synchronized))
        path_port = builder.AddNamedSystem(
            "path", ConstantValueSource(AbstractValue.Make(waypoints.copy()))).get_output_port()

    # ---- how to get there -----------------------------------------------------
    if controller:
        base_controller = builder.AddNamedSystem(
            "controller", HolonomicPController.from_options(opts, feedforward=synchronized))
        command = base_controller.GetOutputPort("wheel_speeds")
    else:  # a controller outside the diagram commands the wheels
        base_controller = None
        command_in = builder.AddNamedSystem("wheel_speeds", PassThrough(4))
        builder.ExportInput(command_in.get_input_port(), "wheel_speeds")
        command = command_in.get_output_port()
    drive = builder.AddNamedSystem("drive", MecanumDrive(float(opts.wheel_radius)))
    if mode == "kinematic":
        # The controller is sampled every control period (a digital controller):
        # the base integrates the velocity of the held wheel speeds.
        hold = builder.AddNamedSystem("hold", ZeroOrderHold(period, 4))
        builder.Connect(command, hold.get_input_port())
        builder.Connect(hold.get_output_port(), drive.GetInputPort("wheel_speeds"))
        wheel_port = hold.get_output_port()
    else:
        builder.Connect(command, drive.GetInputPort("wheel_speeds"))
        wheel_port = command
    feedforward: OutputPort | None = None
    if synchronized:
        reference = builder.AddNamedSystem("reference", reference_source_from_options(opts, start, (lower, upper)))
        builder.Connect(sequencer.GetOutputPort("target"), reference.GetInputPort("target"))
        builder.Connect(reference.GetOutputPort("finished"), sequencer.GetInputPort("reference_done"))
        ref_pos = builder.AddNamedSystem("reference_position_split", Demultiplexer([2, 2]))
        ref_vel = builder.AddNamedSystem("reference_velocity_split", Demultiplexer([2, 2]))
        builder.Connect(reference.GetOutputPort("position"), ref_pos.get_input_port())
        builder.Connect(reference.GetOutputPort("velocity"), ref_vel.get_input_port())
        ref_ff = builder.AddNamedSystem("reference_feedforward_split", Demultiplexer([2, 2]))
        builder.Connect(reference.GetOutputPort("mean_velocity"), ref_ff.get_input_port())
        if base_controller is not None:
            builder.Connect(ref_pos.get_output_port(0), base_controller.GetInputPort("base_target"))
            builder.Connect(ref_ff.get_output_port(0), base_controller.GetInputPort("base_velocity_ff"))
        feedforward = reference.GetOutputPort("mean_velocity")
        arm_position: OutputPort = ref_pos.get_output_port(1)
        arm_velocity: OutputPort = ref_vel.get_output_port(1)
        # [xy, arm] x (position, velocity, acceleration) in one evaluation (the servo's, every plant step).
        ref_state = builder.AddNamedSystem("reference_state_split", Demultiplexer([2] * 6))
        builder.Connect(reference.GetOutputPort("state"), ref_state.get_input_port())
        arm_state = [ref_state.get_output_port(k) for k in (1, 3, 5)]
        reference_out: OutputPort = reference.GetOutputPort("position")
    else:
        split = builder.AddNamedSystem("target_split", Demultiplexer([2, 2]))
        builder.Connect(sequencer.GetOutputPort("target"), split.get_input_port())
        arm = builder.AddNamedSystem("arm", arm_source_from_options(opts, start[2:], (lower[2:], upper[2:])))
        builder.Connect(split.get_output_port(1), arm.GetInputPort("target"))
        if base_controller is not None:
            builder.Connect(split.get_output_port(0), base_controller.GetInputPort("base_target"))
        arm_position = arm.GetOutputPort("position")
        arm_velocity = arm.GetOutputPort("velocity")
        arm_split = builder.AddNamedSystem("arm_state_split", Demultiplexer([2, 2, 2]))
        builder.Connect(arm.GetOutputPort("state"), arm_split.get_input_port())
        arm_state = [arm_split.get_output_port(k) for k in range(3)]
        tracked = builder.AddNamedSystem("reference_config", Multiplexer([2, 2]))
        builder.Connect(split.get_output_port(0), tracked.get_input_port(0))
        builder.Connect(arm_position, tracked.get_input_port(1))
        reference_out = tracked.get_output_port(0)

    # ---- the robot ------------------------------------------------------------
    if mode == "dynamic":
        state = builder.AddNamedSystem("state_split", Demultiplexer([4, 4]))
        builder.Connect(plant.get_state_output_port(robot), state.get_input_port())
        q_port, v_port = state.get_output_port(0), state.get_output_port(1)
        state_port: OutputPort = plant.get_state_output_port(robot)
        q_split = builder.AddNamedSystem("q_split", Demultiplexer([2, 2]))
        builder.Connect(q_port, q_split.get_input_port())
        # The digital base controller's velocity, held for a control period.
        hold = builder.AddNamedSystem("hold", ZeroOrderHold(period, 2))
        builder.Connect(drive.GetOutputPort("base_velocity"), hold.get_input_port())
        # Desired state [q_d, v_d] and acceleration in joint order; the base's
        # q_d is unused (velocity servo, Kp = 0) and its acceleration is 0.
        desired = builder.AddNamedSystem("desired_state", Multiplexer([2, 2, 2, 2]))
        builder.Connect(q_split.get_output_port(0), desired.get_input_port(0))
        builder.Connect(arm_state[0], desired.get_input_port(1))
        builder.Connect(hold.get_output_port(), desired.get_input_port(2))
        builder.Connect(arm_state[1], desired.get_input_port(3))
        base_acceleration = builder.AddNamedSystem("base_acceleration", ConstantVectorSource(np.zeros(2)))
        acceleration = builder.AddNamedSystem("desired_acceleration", Multiplexer([2, 2]))
        builder.Connect(base_acceleration.get_output_port(), acceleration.get_input_port(0))
        builder.Connect(arm_state[2], acceleration.get_input_port(1))
        # The commanded acceleration a_d + K (x_d - x), K = [diag(Kp) diag(Kd)],
        # in stateless C++ blocks (Drake's InverseDynamicsController adds a
        # PID integrator: continuous state, which makes the simulator take
        # variable sub-steps between the plant's, 3x the evaluations), then
        # u = M(q) a + C(q, v) v of the plant itself (the room is welded to
        # the world: the plant's velocities are the robot's).
        kp, kd = servo_gains()
        K = np.hstack([np.diag(kp), np.diag(kd)])
        gain_desired = builder.AddNamedSystem("servo_desired", MatrixGain(K))
        gain_state = builder.AddNamedSystem("servo_state", MatrixGain(-K))
        commanded = builder.AddNamedSystem("servo_acceleration", Adder(3, 4))
        builder.Connect(desired.get_output_port(), gain_desired.get_input_port())
        builder.Connect(plant.get_state_output_port(robot), gain_state.get_input_port())
        builder.Connect(gain_desired.get_output_port(), commanded.get_input_port(0))
        builder.Connect(gain_state.get_output_port(), commanded.get_input_port(1))
        builder.Connect(acceleration.get_output_port(), commanded.get_input_port(2))
        servo = builder.AddNamedSystem("servo", InverseDynamics(plant))
        builder.Connect(plant.get_state_output_port(robot), servo.get_input_port_estimated_state())
        builder.Connect(commanded.get_output_port(), servo.get_input_port_desired_acceleration())
        # The actuation input is [u_x, u_y, u_1, u_2] (see _populate).
        builder.Connect(servo.get_output_port_generalized_force(), plant.get_actuation_input_port(robot))
    else:
        base = builder.AddNamedSystem("base", Integrator(2))
        base.set_default_integral_value(start[:2])
        builder.Connect(drive.GetOutputPort("base_velocity"), base.get_input_port())
        configuration = builder.AddNamedSystem("configuration", Multiplexer([2, 2]))
        builder.Connect(base.get_output_port(), configuration.get_input_port(0))
        builder.Connect(arm_position, configuration.get_input_port(1))
        velocity = builder.AddNamedSystem("velocity", Multiplexer([2, 2]))
        builder.Connect(drive.GetOutputPort("base_velocity"), velocity.get_input_port(0))
        builder.Connect(arm_velocity, velocity.get_input_port(1))
        to_pose = builder.AddNamedSystem("to_pose", MultibodyPositionToGeometryPose(plant))
        builder.Connect(configuration.get_output_port(), to_pose.get_input_port())
        builder.Connect(to_pose.get_output_port(), scene_graph.get_source_pose_port(plant.get_source_id()))
        q_port, v_port = configuration.get_output_port(), velocity.get_output_port()
        q_split = builder.AddNamedSystem("q_split", Demultiplexer([2, 2]))
        builder.Connect(q_port, q_split.get_input_port())
        robot_state = builder.AddNamedSystem("robot_state", Multiplexer([4, 4]))
        builder.Connect(q_port, robot_state.get_input_port(0))
        builder.Connect(v_port, robot_state.get_input_port(1))
        state_port = robot_state.get_output_port()
    builder.Connect(q_port, sequencer.GetInputPort("q"))
    if base_controller is not None:
        builder.Connect(q_split.get_output_port(0), base_controller.GetInputPort("base_position"))
    people = builder.AddNamedSystem("people", PeopleSource(scenario_people))
    if people.crowd is not None:
        builder.Connect(q_port, people.GetInputPort("robot_q"))
    if not scenario_people.static:
        bodies = builder.AddNamedSystem("people_geometry", PeopleGeometry(scene_graph, scenario_people.state_at(0.0)))
        builder.Connect(people.GetOutputPort("people_state"), bodies.get_input_port())
        builder.Connect(bodies.GetOutputPort("geometry_pose"), scene_graph.get_source_pose_port(bodies.source_id))
        if mode == "dynamic":
            _filter_people(scene_graph, bodies.geometry_ids)

    # ---- safety: hold the robot while a walking person is within the safety distance ----
    # Only when people move: a standing person is an obstacle of the plan, which may pass them
    # within the safety distance; a monitor would hold the robot there for ever.
    stop_port: OutputPort | None = None
    if not scenario_people.static:
        monitor = builder.AddNamedSystem("safety", SafetyMonitor(
            arm_geometry(scenario), safety_distance=float(opts.safety_distance), period=period))
        builder.Connect(q_port, monitor.GetInputPort("q"))
        builder.Connect(people.GetOutputPort("people_state"), monitor.GetInputPort("people_state"))
        stop_port = monitor.GetOutputPort("stop")
    hold_port = stop_port
    if replanning is not None:  # the replanner reads the robot and the people; its wait holds the robot too
        builder.Connect(q_port, replanning.GetInputPort("q"))
        builder.Connect(people.GetOutputPort("people_state"), replanning.GetInputPort("people_state"))
        hold_port = replanning.GetOutputPort("hold")
        if stop_port is not None:  # either flag holds: the held systems read their sum > 0.5
            either = builder.AddNamedSystem("held", Adder(2, 1))
            builder.Connect(stop_port, either.get_input_port(0))
            builder.Connect(replanning.GetOutputPort("hold"), either.get_input_port(1))
            hold_port = either.get_output_port()
    if hold_port is not None:
        for held in (sequencer, base_controller, reference if synchronized else arm):
            if held is not None:
                builder.Connect(hold_port, held.GetInputPort("hold"))

    # ---- the station's ports --------------------------------------------------
    exported = {
        "robot_state": state_port,
        "target": sequencer.GetOutputPort("target"),
        "reference": reference_out,
        "done": sequencer.GetOutputPort("done"),
        "index": sequencer.GetOutputPort("index"),
        "planned_path": path_port,
        "wheel_speeds": wheel_port,
        "people_state": people.GetOutputPort("people_state"),
        "people_vector": people.GetOutputPort("people_vector"),
        "query_object": scene_graph.get_query_output_port(),
    }
    if feedforward is not None:
        exported["reference_feedforward"] = feedforward
    if stop_port is not None:
        exported["stop"] = stop_port
    if replanning is not None:
        exported["waiting"] = replanning.GetOutputPort("hold")
        exported["path_version"] = replanning.GetOutputPort("version")
    for name, port in exported.items():
        builder.ExportOutput(port, name)

    # ---- records --------------------------------------------------------------
    ports = {
        "q": q_port,
        "v": v_port,
        "wheel_speeds": wheel_port,
        "target": sequencer.GetOutputPort("target"),
        "reference": reference_out,
        "index": sequencer.GetOutputPort("index"),
        "done": sequencer.GetOutputPort("done"),
    }
    if people.crowd is not None:  # the people are rebuilt from it after the run (PeopleSource.people_log)
        ports["crowd_state"] = people.GetOutputPort("crowd_state")
    if stop_port is not None:
        ports["stop"] = stop_port
    if replanning is not None:
        ports["version"] = replanning.GetOutputPort("version")
        ports["waiting"] = replanning.GetOutputPort("hold")
    loggers = {}
    for name, port in ports.items():
        logger = LogVectorOutput(port, builder, publish_period=period)
        logger.set_name(f"{name}_log")
        loggers[name] = logger

    visualizer = None
    if meshcat is not None:
        from drake_social.sim.replay import add_visualizer

        visualizer = add_visualizer(builder, scene_graph, meshcat, fps=float(opts.replay_fps))

    diagram = builder.Build()
    diagram.set_name(f"transport_{mode}_{execution}")
    return TransportDiagram(
        diagram=diagram, plant=plant, scene_graph=scene_graph, robot=robot, scenario=scenario, mode=mode,
        execution=execution, waypoints=waypoints, meshcat=meshcat, visualizer=visualizer, loggers=loggers,
        planner_included=waypoints is None and planner, controller_included=controller,
        replanning=replanning is not None,
    )
