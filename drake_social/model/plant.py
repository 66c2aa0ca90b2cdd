"""A MultibodyPlant + SceneGraph of a scenario: the robot, its object and the room.

Everything is planar honestly: each collision shape is a vertical extrusion
over the same slab z in [0, COLLISION_HEIGHT] (cylinders for the base and the
people, boxes for obstacles and walls, box + end-cylinder stadia for the links
and the object; see :mod:`drake_social.model.robot_model`), so SceneGraph's
signed distances between shapes that are apart equal the 2-D distances.

The environment is anchored: its shapes are registered on the world body under
readable names (:func:`environment_names`), which the collision reports use.
The four walls stand outside the bounds, ``world.wall_thickness`` thick; the
south and north walls run past the corners so the room is closed.
"""

from __future__ import annotations

import dataclasses as dc
import re
from typing import Sequence

import numpy as np
from pydrake.geometry import Box as DrakeBox
from pydrake.geometry import Cylinder, SceneGraph
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex
from pydrake.planning import RobotDiagram, RobotDiagramBuilder

from drake_social.model.robot_model import COLLISION_HEIGHT, robot_sdf
from drake_social.people import PeopleState, people_model
from drake_social.scenario import Box, Scenario
from drake_social.scenario.map_rules import map_box_label
from drake_social.world import WALL_NAMES, world_model

__all__ = [
    "ACTUATED_JOINTS",
    "EnvironmentShape",
    "ScenarioDiagram",
    "add_environment",
    "add_robot",
    "ENVIRONMENT_PART",
    "PERSON_RGBA",
    "people_at_start",
    "person_geometry_names",
    "build_environment_geometry",
    "build_robot_diagram",
    "environment_discs",
    "environment_names",
    "environment_parts",
    "environment_shapes",
    "register_environment",
    "registration_order",
    "shape_label",
    "wall_boxes",
]

_FRICTION = CoulombFriction(static_friction=0.5, dynamic_friction=0.5)
#: RGBA of a person's body (the anchored one here, the moving one of
#: :class:`drake_social.control.people_geometry.PeopleGeometry`).
PERSON_RGBA = (0.85, 0.2, 0.2, 1.0)
_ENV_COLOURS = {"obstacle": (0.55, 0.45, 0.35, 1.0), "person": PERSON_RGBA, "wall": (0.6, 0.6, 0.6, 1.0)}


def wall_boxes(scenario: Scenario) -> dict[str, Box]:
    """The four boundary walls as boxes outside ``world.bounds``, by name.

    South and north walls span x in [x_min - t, x_max + t] to close the
    corners; west and east walls span y in [y_min, y_max]; t is
    ``world.wall_thickness`` (metres).
    """
    walls = world_model(scenario).walls
    return {name: Box(center=[float(v) for v in c], size=[float(v) for v in size], yaw=float(yaw))
            for name, c, size, yaw in zip(WALL_NAMES, walls.centers, walls.sizes, walls.yaws)}


def environment_names(scenario: Scenario) -> list[str]:
    """Names of the environment's collision shapes, as used in error messages.

    ``obstacle[i]`` for ``world.obstacles[i]``, ``map[j]`` for box j of the
    map (:class:`~drake_social.world.WorldGeometry`), ``person[i]`` (plus its name
    in quotes, when it has one) for each person present at t = 0
    (:func:`people_at_start`; i is the person's index among all the scenario's
    people, so a recorded id entering later leaves a gap), and ``wall_<side>``.
    """
    names = world_model(scenario).box_names
    indices, people = people_at_start(scenario)
    return names + person_geometry_names(people.names, indices) + list(WALL_NAMES)


def shape_label(scenario: Scenario, name: str) -> str:
    """How a report names the environment shape ``name``
    (:func:`environment_names`): the name, and for a box of the map,
    ``map[j]``, also where it is (its image rows and columns and its world
    coordinates, :func:`~drake_social.scenario.map_rules.map_box_label`),
    since no figure numbers the map's boxes."""
    match = re.fullmatch(r"map\[(\d+)\]", name)
    if match is None or scenario.world.map is None:
        return name
    return f"{name}, {map_box_label(scenario.world, int(match.group(1)))}"


def people_at_start(scenario: Scenario) -> tuple[np.ndarray, PeopleState]:
    """The people present at t = 0 (the room planning sees): their indices
    (K,) in the scenario's full people order
    (:func:`drake_social.people.people_model`) and their state (K people).
    A recorded id entering later, or one gone before, is no obstacle."""
    state = people_model(scenario).state_at(0.0)
    return np.flatnonzero(state.present), state.visible()


def person_geometry_names(names: Sequence[str], indices: Sequence[int] | None = None) -> list[str]:
    """The shape name of each person: ``person[i]`` plus the name in quotes when it has one.

    Args:
        names: the people's names ("" where unnamed).
        indices: each person's index i in the full people order; None = 0, 1, ...
    """
    indices = range(len(names)) if indices is None else [int(i) for i in indices]
    return [f"person[{i}] {name!r}" if name else f"person[{i}]" for i, name in zip(indices, names)]


#: Most environment shapes in one diagram built for reading shapes or for a
#: second opinion (:func:`environment_parts`): SceneGraph's pair filter then
#: costs at most about 60 * (ENVIRONMENT_PART + robot shapes)^2 bytes (a few MB).
ENVIRONMENT_PART = 256


def registration_order(scenario: Scenario) -> list[int]:
    """Indices into :func:`environment_names` in the order :func:`add_environment`
    registers the shapes: obstacles, walls, then people."""
    n_obstacles, n_people = len(world_model(scenario).boxes), len(people_at_start(scenario)[0])
    n = n_obstacles + n_people + len(WALL_NAMES)
    return [*range(n_obstacles), *range(n_obstacles + n_people, n), *range(n_obstacles, n_obstacles + n_people)]


def environment_parts(indices: Sequence[int], size: int | None = None) -> list[list[int]]:
    """``indices`` in consecutive parts of at most ``size`` (>= 1; None =
    :data:`ENVIRONMENT_PART`); one empty part when there are none."""
    indices = [int(i) for i in indices]
    size = ENVIRONMENT_PART if size is None else size
    if size < 1:
        raise ValueError(f"size must be >= 1, got {size}")
    return [indices[k : k + size] for k in range(0, len(indices), size)] or [[]]


@dc.dataclass(frozen=True)
class EnvironmentShape:
    """One anchored shape of the room, as it is registered on the world body.

    Attributes:
        name: its name (:func:`environment_names`).
        kind: ``obstacle``, ``map`` (a box of the scenario's map), ``person`` or ``wall``.
        X_WG: its pose in the world.
        shape: a Drake Box (obstacles, walls) or Cylinder (people).
    """

    name: str
    kind: str
    X_WG: RigidTransform
    shape: DrakeBox | Cylinder


def environment_shapes(scenario: Scenario, only: Sequence[int] | None = None) -> list[EnvironmentShape]:
    """The environment's shapes ``only`` (indices into :func:`environment_names`,
    in that order; None = all, in the order of :func:`environment_names`:
    obstacles, the people present at t = 0, walls)."""
    names = environment_names(scenario)
    world, people = world_model(scenario), people_at_start(scenario)[1]
    n_obstacles, n_people = len(world.boxes), people.count
    first_map = n_obstacles - world.map_box_count

    def shape(i: int) -> EnvironmentShape:
        if n_obstacles <= i < n_obstacles + n_people:
            k = i - n_obstacles
            return EnvironmentShape(names[i], "person", RigidTransform([*people.positions[k], COLLISION_HEIGHT / 2]),
                                    Cylinder(people.radii[k], COLLISION_HEIGHT))
        if i < n_obstacles:
            boxes, k, kind = world.boxes, i, "obstacle" if i < first_map else "map"
        else:
            boxes, k, kind = world.walls, i - n_obstacles - n_people, "wall"
        X_WG = RigidTransform(RotationMatrix.MakeZRotation(float(boxes.yaws[k])),
                              [*boxes.centers[k], COLLISION_HEIGHT / 2])
        size = boxes.sizes[k]
        return EnvironmentShape(names[i], kind, X_WG, DrakeBox(size[0], size[1], COLLISION_HEIGHT))

    return [shape(int(i)) for i in (range(len(names)) if only is None else only)]


def register_environment(plant: MultibodyPlant, shapes: Sequence[EnvironmentShape], *, visual: bool = True) -> None:
    """Anchors ``shapes`` to the world body of ``plant`` (before
    ``plant.Finalize()``) as collision geometry, and as visual geometry
    unless ``visual`` is False (a checker reading the room needs only the
    collision shapes; each registration costs about 0.1 ms in Drake) or the
    shape is a box of the map (the replay draws the map as one mesh,
    :mod:`drake_social.sim.replay_map`)."""
    world = plant.world_body()
    for g in shapes:
        plant.RegisterCollisionGeometry(world, g.X_WG, g.shape, g.name, _FRICTION)
        if visual and g.kind != "map":
            plant.RegisterVisualGeometry(world, g.X_WG, g.shape, g.name, np.array(_ENV_COLOURS[g.kind]))


def environment_discs(scenario: Scenario) -> np.ndarray:
    """(N, 3) ``[x, y, rho]`` of the environment's shapes in the order of
    :func:`environment_names`: each shape lies within ``rho`` metres of
    ``(x, y)`` (a box's half diagonal, a person's radius)."""
    world, people = world_model(scenario), people_at_start(scenario)[1]
    return np.concatenate([
        np.column_stack([world.boxes.centers, world.boxes.radii]),
        np.column_stack([people.positions, people.radii]),
        np.column_stack([world.walls.centers, world.walls.radii]),
    ]).reshape(-1, 3)


def add_environment(plant: MultibodyPlant, scenario: Scenario, only: Sequence[int] | None = None, *,
                    people: bool = True, map_boxes: bool = True) -> list[str]:
    """Anchors the obstacles, people and walls of ``scenario`` to the world.

    Must be called before ``plant.Finalize()``.

    Args:
        only: indices into :func:`environment_names` of the shapes to add
            (each keeps its name); None = all.
        people: anchor the people present at t = 0 where they are then (the
            default: the planning checkers' room); False leaves them out (the simulation
            diagram of walking people moves them in SceneGraph itself,
            :class:`drake_social.control.people_geometry.PeopleGeometry`).
        map_boxes: anchor the boxes of the scenario's map (the default);
            False leaves them out (the kinematic simulation diagram, whose
            SceneGraph would otherwise keep a filter state for every pair of
            its thousands of shapes; see :func:`build_robot_diagram`).

    Returns:
        The registered shape names, in the order of :func:`environment_names`.
    """
    world = world_model(scenario)
    n_obstacles, n_people = len(world.boxes), len(people_at_start(scenario)[0])
    wanted = set(range(len(environment_names(scenario)))) if only is None else {int(i) for i in only}
    if not people:
        wanted -= set(range(n_obstacles, n_obstacles + n_people))
    if not map_boxes:
        wanted -= set(range(n_obstacles - world.map_box_count, n_obstacles))
    # Registration order: obstacles, walls, then people (:func:`registration_order`).
    register_environment(plant, environment_shapes(scenario, [i for i in registration_order(scenario) if i in wanted]))
    names = environment_names(scenario)
    return [names[i] for i in sorted(wanted)]


def build_environment_geometry(shapes: Sequence[EnvironmentShape]) -> tuple[MultibodyPlant, SceneGraph]:
    """A SceneGraph holding only ``shapes``, anchored as collision geometry
    through a MultibodyPlant (not finalized: nothing moves), for reading a
    large room in parts: no robot, no visual geometry. Returns the plant and
    its SceneGraph (keep both alive while reading)."""
    scene_graph = SceneGraph()
    plant = MultibodyPlant(0.0)
    plant.RegisterAsSourceForSceneGraph(scene_graph)
    register_environment(plant, shapes, visual=False)
    return plant, scene_graph


def add_robot(plant: MultibodyPlant, scenario: Scenario, parser: Parser | None = None) -> ModelInstanceIndex:
    """Adds the robot and its welded object (:func:`robot_sdf`) to ``plant``.

    Must be called before ``plant.Finalize()``. Its positions are
    ``[x, y, psi1, psi2]`` when it is the plant's only model with joints.
    """
    parser = parser or Parser(plant)
    (instance,) = parser.AddModelsFromString(robot_sdf(scenario), "sdf")
    return instance


#: The robot's joints in the order of the plant's positions and actuators
#: (Drake's SDFormat parser gives each joint of unlimited effort an actuator).
ACTUATED_JOINTS = ("base_x", "base_y", "psi1", "psi2")


@dc.dataclass(frozen=True)
class ScenarioDiagram:
    """A finalized RobotDiagram of a scenario.

    Attributes:
        diagram: the RobotDiagram (plant + scene graph).
        robot: the model instance of the robot and its object.
        environment: names of the anchored shapes (see
            :func:`environment_names`).
    """

    diagram: RobotDiagram
    robot: ModelInstanceIndex
    environment: list[str]


def build_robot_diagram(scenario: Scenario, *, time_step: float = 0.0,
                        environment: Sequence[int] | None = None) -> ScenarioDiagram:
    """Builds the robot, its object and the room into a RobotDiagram.

    Args:
        scenario: the scenario.
        time_step: the plant's time step, seconds; 0 (the default) makes a
            continuous plant, which serves kinematics and collision queries.
        environment: indices into :func:`environment_names` of the shapes to
            build (a part of the room); None = all. SceneGraph keeps a filter
            state for every pair of collision shapes, and every context
            copies it: about 60 N^2 bytes for N shapes (250 MB per copy at
            2,000 boxes), so large rooms are built in parts
            (:data:`ENVIRONMENT_PART`).

    The plant's positions are ``[x, y, psi1, psi2]``.
    """
    builder = RobotDiagramBuilder(time_step=float(time_step))
    robot = add_robot(builder.plant(), scenario, builder.parser())
    names = add_environment(builder.plant(), scenario, environment)
    builder.plant().Finalize()
    diagram = builder.Build()
    plant = diagram.plant()
    order = [plant.GetJointByName(n, robot).position_start() for n in ("base_x", "base_y", "psi1", "psi2")]
    if order != [0, 1, 2, 3] or plant.num_positions() != 4:  # our own model: a bug if it fails
        raise RuntimeError(f"unexpected position order {order} of {plant.num_positions()} positions")
    return ScenarioDiagram(diagram=diagram, robot=robot, environment=names)
