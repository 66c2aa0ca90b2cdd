"""The station: the robot and its world, as its drivers and sensors see them.

:func:`make_station` builds the simulated robot of a scenario and its world
as one Drake diagram named ``station``, as Drake's ``examples/hardware_sim``
and the manipulation course's ``MakeHardwareStation`` do: the plant or the
integrator, the drivers (the mecanum drive, the arm servo), the people and
their bodies, the SceneGraph and, with a Meshcat, the visualizer. It holds
no planner and no controller: its inputs are what the drivers take, its
outputs what the sensors give, and a script wires an autonomy to them by
name (:mod:`drake_social.sim.autonomy` is the package's;
:func:`~drake_social.sim.diagram.build_diagram` wires the two;
``docs/examples/custom_controller.py`` drives the station with its own
controller).

Ports::

    inputs   wheel_speeds   4 wheel speeds, rad/s (the base's command)
             arm_command    6: psi1, psi2 positions (rad), velocities (rad/s),
                            accelerations (rad/s^2), as a servo drive takes them
    outputs  robot_state    8: [q, v], q = [x, y, psi1, psi2] (m, rad), v its velocity (m/s, rad/s)
             wheel_speeds   4: the wheel speeds applied, rad/s (kinematic mode:
                            the command held for a control period)
             people_state   PeopleState at the context's time, Value[object]
             people_vector  6 P: per person [x, y, theta, vx, vy, radius]
                            (an absent person keeps a pose: see people_state's present)
             crowd_state    the crowd's discrete state (only with a crowd), from which
                            PeopleSource.people_log rebuilds the people after a run
             query_object   SceneGraph's QueryObject (distances, collisions); a kinematic
                            station's SceneGraph has no boxes of world.map: measure
                            against them with the planar checker

``robot_state`` does not depend on ``wheel_speeds`` at the same instant (the
wheels act through the hold or the discrete plant), so a controller that
reads it and commands the wheels closes no algebraic loop. In kinematic mode
it does depend on ``arm_command`` at the same instant (the arm is where it
is commanded): an arm command must not read ``robot_state`` directly.

Blocks (all named; ``[k]`` only in ``mode="kinematic"``, ``[d]`` only in
``"dynamic"``)::

    [k] wheel_speeds ─▶ hold (ZOH) ─▶ drive (mecanum forward kinematics) ─▶ base (Integrator)
        base, arm_command position ─▶ configuration ─▶ to_pose ─▶ scene_graph
    [d] wheel_speeds ─▶ drive ─▶ hold (ZOH) ─▶ desired_state ◀─ arm_command (position, velocity, acceleration)
        desired_state, plant state ─▶ servo_* (commanded acceleration) ─▶ servo (inverse dynamics) ─▶ plant
    people (PeopleSource: the people model at the context's time; a crowd stepped with q) ─▶ people_state
    people_state ─▶ people_geometry (PeopleGeometry: moving bodies) ─▶ scene_graph   [only when people move]

``kinematic`` mode: the base integrates the velocity its wheels produce (a
continuous ``Integrator``) and the arm is exactly where ``arm_command`` puts
it; the plant is not simulated (it stays outside the diagram and only turns
positions into SceneGraph poses, :attr:`Station.plant`). The wheel speeds
are held for ``execution.control_period`` (``hold``), as a digital base
controller's output.

``dynamic`` mode: the ``MultibodyPlant`` is a discrete system
(:func:`scenario_plant_config`: ``execution.plant_time_step``, TAMSI) whose
joint actuators are driven at every plant step by a computed-torque servo in
C++ blocks: the commanded acceleration ``a = a_d + Kp (q_d - q) + Kd (v_d -
v)`` (gain blocks ``servo_*``, the gains of :func:`servo_gains`), then
Drake's ``InverseDynamics`` (``servo``) ``u = M(q) a + C(q, v) v`` of the
plant. The arm joints follow ``arm_command``'s position, velocity and
acceleration, read at the plant's rate like a servo drive's interpolation
of its trajectory: with the acceleration fed forward and the inertia and
coupling compensated, the error obeys ``e'' + Kd e' + Kp e = 0`` (critically
damped) in every configuration, so the arm lands on the command's end
instead of passing it (a PD law on the joint error alone leads a
decelerating command and can pass a joint limit at the goal). The base
joints are velocity servos on the drive's velocity, held for
``execution.control_period`` by ``hold``.

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

Example::

    from drake_social.scenario import load_scenario
    from drake_social.sim.station import make_station

    station = make_station(load_scenario("scenarios/tiny.yaml"), mode="kinematic")
    print(station.input_port_names())   # ['wheel_speeds', 'arm_command']
"""

from __future__ import annotations

import dataclasses as dc
from typing import NamedTuple

import numpy as np
from pydrake.geometry import CollisionFilterDeclaration, GeometryId, GeometrySet, Meshcat, Role, SceneGraph
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlant, MultibodyPlantConfig
from pydrake.multibody.tree import ModelInstanceIndex
from pydrake.systems.controllers import InverseDynamics
from pydrake.systems.framework import Diagram, DiagramBuilder, OutputPort
from pydrake.systems.primitives import (
    Adder,
    ConstantVectorSource,
    Demultiplexer,
    Integrator,
    MatrixGain,
    Multiplexer,
    PassThrough,
    ZeroOrderHold,
)
from pydrake.systems.rendering import MultibodyPositionToGeometryPose

from drake_social.arguments import real_array, require_instance
from drake_social.control import MecanumDrive, PeopleGeometry, PeopleSource
from drake_social.scenario.geometry import configuration_limits
from drake_social.model.plant import add_environment, add_robot
from drake_social.people import PeopleModel, people_model
from drake_social.scenario import (SERVO_BANDWIDTH, SERVO_BASE_TIME_CONSTANT, ExecutionOptions, Scenario,
                                    ScenarioError)
from drake_social.sim.checks import check_diagram_options
from drake_social.sim.ports import NamedPorts
from drake_social.world import world_model

__all__ = ["MAX_DYNAMIC_MAP_BOXES", "Station", "make_station", "scenario_plant_config", "servo_gains",
           "station_checked"]

#: Most map boxes a dynamic run's SceneGraph holds: it keeps a filter state
#: for every pair of shapes (about 60 N^2 bytes, 240 MB at 2,000).
MAX_DYNAMIC_MAP_BOXES = 2_000


@dc.dataclass
class Station(NamedPorts):
    """A built station and the handles a script needs.

    Attributes:
        diagram: the Drake diagram named ``station`` (every subsystem named;
            its ports: see the module docstring).
        plant: the scenario's MultibodyPlant (inside the diagram as ``plant``
            in dynamic mode; outside it, for poses only, in kinematic mode).
        scene_graph: the SceneGraph (``scene_graph``).
        robot: the robot's model instance.
        people: the ``people`` source (its ``model``, its ``people_log``).
        mode: ``"kinematic"`` or ``"dynamic"``.
        start: (4,) the configuration the robot starts at.
        meshcat: the Meshcat the visualizer draws to, or None.
        visualizer: the ``MeshcatVisualizer``, or None.
    """

    diagram: Diagram
    plant: MultibodyPlant
    scene_graph: SceneGraph
    robot: ModelInstanceIndex
    people: PeopleSource
    mode: str
    start: np.ndarray
    meshcat: Meshcat | None = None
    visualizer: object | None = None


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
    ``make_station(plant_config=...)`` (or ``build_diagram``'s), at about
    three times the cost of a step.
    """
    return MultibodyPlantConfig(time_step=float(scenario.execution.plant_time_step),
                                discrete_contact_approximation=scenario.execution.contact_approximation)


def make_station(
    scenario: Scenario,
    *,
    mode: str | None = None,
    start=None,
    people: PeopleModel | None = None,
    meshcat: Meshcat | None = None,
    plant_config: MultibodyPlantConfig | None = None,
) -> Station:
    """Builds the station of a scenario: the robot and its world, driven through named ports.

    Args:
        scenario: a validated scenario.
        mode: ``"kinematic"`` or ``"dynamic"``; None = ``scenario.execution.mode``.
        start: (4,) the configuration ``[x, y, psi1, psi2]`` (metres,
            radians) the robot starts at, within the room and the joint
            limits; None = ``scenario.start``.
        people: the people model of the ``people`` source; None =
            :func:`~drake_social.people.people_model` of the scenario.
        meshcat: when given, a ``MeshcatVisualizer`` draws the scene to it at
            ``execution.replay_fps``.
        plant_config: the dynamic mode's ``MultibodyPlantConfig``; None =
            :func:`scenario_plant_config` (unused in kinematic mode).

    Returns:
        The :class:`Station`.

    Raises:
        TypeError: an argument of the wrong kind (named).
        ValueError: an unknown mode, a start that is not 4 finite numbers
            within the configuration limits.
        ScenarioError: an invalid scenario, or a map too large for a dynamic run.
    """
    mode, _ = check_diagram_options(scenario, mode=mode, execution=None, checker=None, meshcat=meshcat,
                                    who="make_station")
    require_instance(plant_config, MultibodyPlantConfig, "make_station", "plant_config",
                     "a pydrake.multibody.plant.MultibodyPlantConfig", optional=True)
    require_instance(people, PeopleModel, "make_station", "people", "a drake_social.people.PeopleModel",
                     optional=True)
    if start is None:
        start = np.asarray(scenario.start, float)
    else:
        start = real_array(start, "make_station", "start", (4,), layout="[x, y, psi1, psi2]")
        lower, upper = configuration_limits(scenario)
        if not np.all((start >= lower) & (start <= upper)):
            raise ValueError(f"make_station: start: must lie within the room and the joint limits "
                             f"[{lower.tolist()}, {upper.tolist()}], got {start.tolist()}")
    return station_checked(scenario, mode, people_model(scenario) if people is None else people, start=start,
                           meshcat=meshcat, plant_config=plant_config)


class _Robot(NamedTuple):
    """The robot's sensor ports inside the station's builder."""

    q: OutputPort  # 4: the configuration
    state: OutputPort  # 8: [q, v]
    wheel_speeds: OutputPort  # 4: the wheel speeds applied


def station_checked(scenario: Scenario, mode: str, people: PeopleModel, *, start: np.ndarray,
                    meshcat: Meshcat | None = None, plant_config: MultibodyPlantConfig | None = None) -> Station:
    """:func:`make_station` with its arguments already checked (the scenario
    validated, ``mode`` the one in force, ``people`` the model, ``start``
    (4,) within the limits). For drake_social's own builders."""
    builder = DiagramBuilder()
    start = np.asarray(start, float)
    config = plant_config if plant_config is not None else scenario_plant_config(scenario)
    plant, scene_graph, robot = _plant(builder, scenario, mode, people.static, start, config)
    if mode == "dynamic":
        sensors = _dynamic_robot(builder, plant, robot, scenario.execution)
    else:
        sensors = _kinematic_robot(builder, plant, scene_graph, scenario.execution, start)
    source = _people(builder, scene_graph, people, sensors.q, mode)

    outputs = {
        "robot_state": sensors.state,
        "wheel_speeds": sensors.wheel_speeds,
        "people_state": source.GetOutputPort("people_state"),
        "people_vector": source.GetOutputPort("people_vector"),
        "query_object": scene_graph.get_query_output_port(),
    }
    if source.crowd is not None:  # the people are rebuilt from it after a run (PeopleSource.people_log)
        outputs["crowd_state"] = source.GetOutputPort("crowd_state")
    for name, port in outputs.items():
        builder.ExportOutput(port, name)

    visualizer = None
    if meshcat is not None:
        from drake_social.sim.replay import add_visualizer

        visualizer = add_visualizer(builder, scene_graph, meshcat, fps=float(scenario.execution.replay_fps))
    diagram = builder.Build()
    diagram.set_name("station")
    return Station(diagram=diagram, plant=plant, scene_graph=scene_graph, robot=robot, people=source, mode=mode,
                   start=start, meshcat=meshcat, visualizer=visualizer)


def _plant(builder: DiagramBuilder, scenario: Scenario, mode: str, people_static: bool, start: np.ndarray,
           config: MultibodyPlantConfig) -> tuple[MultibodyPlant, SceneGraph, ModelInstanceIndex]:
    """The plant and the SceneGraph; static people are anchored in the plant, moving ones move in SceneGraph."""
    if mode == "dynamic":
        count = world_model(scenario).map_box_count
        if count > MAX_DYNAMIC_MAP_BOXES:
            raise ScenarioError(
                f"world.map: {count:,} boxes are too many for a dynamic run (execution.mode dynamic), whose "
                f"SceneGraph keeps a filter state for every pair of shapes; at most {MAX_DYNAMIC_MAP_BOXES:,}: "
                f"run it kinematic, or coarsen or clean the map")
        plant, scene_graph = AddMultibodyPlant(config, builder)
        robot = _populate(plant, scenario, people_static)
        plant.SetDefaultPositions(robot, start)
    else:
        # The kinematic plant only places the shapes: the map's boxes (the
        # replay draws them as one mesh; the analysis checks the executed
        # trajectory against them) are left out of its SceneGraph.
        scene_graph = builder.AddNamedSystem("scene_graph", SceneGraph())
        plant = MultibodyPlant(time_step=0.0)
        plant.RegisterAsSourceForSceneGraph(scene_graph)
        robot = _populate(plant, scenario, people_static, map_boxes=False)
    return plant, scene_graph, robot


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


def _kinematic_robot(builder: DiagramBuilder, plant: MultibodyPlant, scene_graph: SceneGraph,
                     opts: ExecutionOptions, start: np.ndarray) -> _Robot:
    """The base integrates the velocity of the held wheel speeds; the arm is where it is commanded."""
    drive = builder.AddNamedSystem("drive", MecanumDrive(float(opts.wheel_radius)))
    hold = builder.AddNamedSystem("hold", ZeroOrderHold(float(opts.control_period), 4))
    builder.ExportInput(hold.get_input_port(), "wheel_speeds")
    builder.Connect(hold.get_output_port(), drive.GetInputPort("wheel_speeds"))
    arm = builder.AddNamedSystem("arm_command_split", Demultiplexer([2, 2, 2]))
    builder.ExportInput(arm.get_input_port(), "arm_command")
    base = builder.AddNamedSystem("base", Integrator(2))
    base.set_default_integral_value(start[:2])
    builder.Connect(drive.GetOutputPort("base_velocity"), base.get_input_port())
    configuration = builder.AddNamedSystem("configuration", Multiplexer([2, 2]))
    builder.Connect(base.get_output_port(), configuration.get_input_port(0))
    builder.Connect(arm.get_output_port(0), configuration.get_input_port(1))
    velocity = builder.AddNamedSystem("velocity", Multiplexer([2, 2]))
    builder.Connect(drive.GetOutputPort("base_velocity"), velocity.get_input_port(0))
    builder.Connect(arm.get_output_port(1), velocity.get_input_port(1))
    to_pose = builder.AddNamedSystem("to_pose", MultibodyPositionToGeometryPose(plant))
    builder.Connect(configuration.get_output_port(), to_pose.get_input_port())
    builder.Connect(to_pose.get_output_port(), scene_graph.get_source_pose_port(plant.get_source_id()))
    state = builder.AddNamedSystem("robot_state", Multiplexer([4, 4]))
    builder.Connect(configuration.get_output_port(), state.get_input_port(0))
    builder.Connect(velocity.get_output_port(), state.get_input_port(1))
    return _Robot(configuration.get_output_port(), state.get_output_port(), hold.get_output_port())


def _dynamic_robot(builder: DiagramBuilder, plant: MultibodyPlant, robot: ModelInstanceIndex,
                   opts: ExecutionOptions) -> _Robot:
    """The plant under the computed-torque servo (see the module docstring)."""
    command = builder.AddNamedSystem("wheel_speeds", PassThrough(4))
    builder.ExportInput(command.get_input_port(), "wheel_speeds")
    drive = builder.AddNamedSystem("drive", MecanumDrive(float(opts.wheel_radius)))
    builder.Connect(command.get_output_port(), drive.GetInputPort("wheel_speeds"))
    state = builder.AddNamedSystem("state_split", Demultiplexer([4, 4]))
    builder.Connect(plant.get_state_output_port(robot), state.get_input_port())
    q_split = builder.AddNamedSystem("q_split", Demultiplexer([2, 2]))
    builder.Connect(state.get_output_port(0), q_split.get_input_port())
    # The digital base controller's velocity, held for a control period.
    hold = builder.AddNamedSystem("hold", ZeroOrderHold(float(opts.control_period), 2))
    builder.Connect(drive.GetOutputPort("base_velocity"), hold.get_input_port())
    arm = builder.AddNamedSystem("arm_command_split", Demultiplexer([2, 2, 2]))
    builder.ExportInput(arm.get_input_port(), "arm_command")
    # Desired state [q_d, v_d] and acceleration in joint order; the base's
    # q_d is unused (velocity servo, Kp = 0) and its acceleration is 0.
    desired = builder.AddNamedSystem("desired_state", Multiplexer([2, 2, 2, 2]))
    builder.Connect(q_split.get_output_port(0), desired.get_input_port(0))
    builder.Connect(arm.get_output_port(0), desired.get_input_port(1))
    builder.Connect(hold.get_output_port(), desired.get_input_port(2))
    builder.Connect(arm.get_output_port(1), desired.get_input_port(3))
    base_acceleration = builder.AddNamedSystem("base_acceleration", ConstantVectorSource(np.zeros(2)))
    acceleration = builder.AddNamedSystem("desired_acceleration", Multiplexer([2, 2]))
    builder.Connect(base_acceleration.get_output_port(), acceleration.get_input_port(0))
    builder.Connect(arm.get_output_port(2), acceleration.get_input_port(1))
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
    return _Robot(state.get_output_port(0), plant.get_state_output_port(robot), command.get_output_port())


def _people(builder: DiagramBuilder, scene_graph: SceneGraph, model: PeopleModel, q: OutputPort,
            mode: str) -> PeopleSource:
    """The people source; a crowd reads the robot's ``q``; moving people get bodies in SceneGraph."""
    source = builder.AddNamedSystem("people", PeopleSource(model))
    if source.crowd is not None:
        builder.Connect(q, source.GetInputPort("robot_q"))
    if not model.static:
        bodies = builder.AddNamedSystem("people_geometry", PeopleGeometry(scene_graph, model.state_at(0.0)))
        builder.Connect(source.GetOutputPort("people_state"), bodies.get_input_port())
        builder.Connect(bodies.GetOutputPort("geometry_pose"), scene_graph.get_source_pose_port(bodies.source_id))
        if mode == "dynamic":
            _filter_people(scene_graph, bodies.geometry_ids)
    return source


def _filter_people(scene_graph: SceneGraph, people: list[GeometryId]) -> None:
    """Excludes the moving people's bodies from collisions with every other
    shape and with each other (dynamic mode: see the module docstring)."""
    inspector = scene_graph.model_inspector()
    theirs = GeometrySet(people)
    others = GeometrySet([g for g in inspector.GetAllGeometryIds(Role.kProximity) if g not in set(people)])
    declaration = CollisionFilterDeclaration().ExcludeWithin(theirs).ExcludeBetween(theirs, others)
    scene_graph.collision_filter_manager().Apply(declaration)
