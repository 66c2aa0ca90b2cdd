"""The exact planar validity checker, built from the SceneGraph's collision geometry.

:class:`PlanarChecker` reads every proximity shape of the scenario's
RobotDiagram from its ``SceneGraphInspector`` (shape, frame, pose) and turns
it into the footprints of :mod:`drake_social.collision.planar_kernel`: the
robot's cylinders and stadia (box + end cylinders) become discs and capsules
in their body frames, the anchored boxes and cylinders (obstacles, walls,
people) rotated boxes and discs in the world. The SceneGraph stays the one
model of the geometry: nothing is read again from the scenario's YAML except
the limits and the resolution.

Bodies are moved by the plant's kinematics reduced to the plane: the poses
``X_PC`` of link 1 in the base, link 2 in link 1 and the object in link 2 are
read from the plant at q = 0, and ``X_WC(q) = X_WP(q) X_PC R_z(q_joint)``
(``psi1`` turns link 1, ``psi2`` link 2, the object is welded); a test checks
these poses against ``MultibodyPlant.EvalBodyPoseInWorld``.

Distances are exact in closed form (see the kernel), so configuration checks
need no tolerance and motion checks are sound by conservative advancement
(:func:`~drake_social.collision.planar_kernel.motion_valid`) with the lever
arms of the displacement bound measured on the same shapes.
"""

from __future__ import annotations

import math
from typing import Iterable

import numpy as np
from pydrake.geometry import Box as DrakeBox
from pydrake.geometry import Cylinder, Role, SceneGraph
from pydrake.multibody.plant import MultibodyPlant

from drake_social.model.plant import (
    ScenarioDiagram,
    build_environment_geometry,
    build_robot_diagram,
    environment_shapes,
    registration_order,
    shape_label,
)
from drake_social.collision import planar_kernel as kernel
from drake_social.collision.broadphase import build_grid
from drake_social.collision.geometric import CheckerBase
from drake_social.collision.validity import Contact, PlanarScene
from drake_social.scenario import Scenario

__all__ = ["PlanarChecker"]

# The planar chain: body, parent, joint (position index, -1 = weld).
_CHAIN = (("base", None, -1), ("link1", "base", 2), ("link2", "link1", 3), ("object", "link2", -1))
_TOL = 1e-9  # metres: what counts as "the same" when matching shapes and checking planarity
#: Shapes per SceneGraph when reading a room in parts (at most
#: ENVIRONMENT_PART): registering a proximity shape costs about 0.4 us per shape already
#: in its SceneGraph on top of a fixed ~0.14 ms, and a part costs little
#: else, so parts of 64 keep 10,000 boxes at about 1.4 s.
READ_PART = 64


def _planar(X, what: str) -> tuple[float, float, float, float, float]:
    """``(x, y, cos, sin, z)`` of a RigidTransform that only turns about z."""
    R = X.rotation().matrix()
    if abs(R[2, 2] - 1.0) > _TOL:
        raise ValueError(f"{what}: not a vertical extrusion (rotation {R.tolist()})")
    p = X.translation()
    return float(p[0]), float(p[1]), float(R[0, 0]), float(R[1, 0]), float(p[2])


class PlanarChecker(CheckerBase):
    """Exact configuration and sound motion validity of a scenario (compiled).

    Args:
        scenario, resolution: see :class:`CheckerBase`; the resolution only
            serves Drake's second opinion
            (:func:`~drake_social.collision.drake_checker.verify_path`).
        model: a built :func:`build_robot_diagram` of ``scenario``, read
            whole; None = the room is built and read in parts of
            :data:`READ_PART` shapes (at most
            :data:`~drake_social.model.plant.ENVIRONMENT_PART`), the robot
            with the first (the memory of one SceneGraph grows with the
            square of its shapes).

    Attributes:
        model: the given :class:`ScenarioDiagram`, or the first part's
            (the robot and the first shapes of the room).
        bodies: (B, 6) the planar chain, body names :attr:`body_names`.
        robot: (S, 6) the robot's capsules in their body frames.
        env: (K, 8) the environment's boxes and discs, names :attr:`env_names`.
        grid: the broadphase over env (:func:`~drake_social.collision.broadphase.build_grid`).
        levers: (S, 2) lever arms ``(c_shoulder, c_gripper)`` of each capsule, metres
            (:meth:`_levers`); motion checks advance each capsule by its own bound.
        lever: (2,) the largest of them (and the elbow's distance from the
            shoulder): the whole robot's bound, as :meth:`ArmGeometry.lever`.
        slab: ``(z_min, z_max)`` shared by every shape, metres.
    """

    def __init__(self, scenario: Scenario, resolution: float | None = None, model: ScenarioDiagram | None = None):
        super().__init__(scenario, resolution)
        self.scenario = scenario
        if model is not None:
            self.model = model
            self._read_geometry()
        else:
            # The room is read in parts, each from its own small SceneGraph
            # (SceneGraph's memory, and the time to register a proximity shape,
            # grow with the shapes already in it): the robot and the first
            # READ_PART shapes from a RobotDiagram, the rest from SceneGraphs
            # of READ_PART shapes each, collision geometry only.
            order = registration_order(scenario)
            self.model = build_robot_diagram(scenario, environment=order[:READ_PART])
            rest = environment_shapes(scenario, order[READ_PART:])
            self._read_geometry(build_environment_geometry(rest[k : k + READ_PART])
                                for k in range(0, len(rest), READ_PART))
        # numba initialises itself and loads cached machine code at the first
        # compiled call of a process (about 0.5 s): here, with the model,
        # rather than inside the first plan's timing.
        self.is_valid(0.5 * (self.lower + self.upper))

    # ---- reading the SceneGraph ---------------------------------------------

    def _read_geometry(self, more_environment: Iterable[tuple[MultibodyPlant, SceneGraph]] = ()) -> None:
        """Reads the chain, the robot's shapes and the environment's from
        :attr:`model`, and further environment shapes from the diagrams of
        ``more_environment`` (``(plant, scene_graph)`` pairs of
        :func:`build_environment_geometry`, built and dropped one at a time)."""
        diagram = self.model.diagram
        plant = diagram.plant()
        context = diagram.CreateDefaultContext()
        plant_context = plant.GetMyContextFromRoot(context)
        plant.SetPositions(plant_context, self.model.robot, np.zeros(4))

        self.body_names = [name for name, _, _ in _CHAIN]
        index = {name: i for i, name in enumerate(self.body_names)}
        X_W = {name: plant.EvalBodyPoseInWorld(plant_context, plant.GetBodyByName(name, self.model.robot))
               for name in self.body_names}
        bodies = []
        for name, parent, joint in _CHAIN:
            X = X_W[name] if parent is None else X_W[parent].inverse() @ X_W[name]
            x, y, c, s, _ = _planar(X, f"body {name} at q = 0")
            bodies.append([-1 if parent is None else index[parent], x, y, c, s, joint])
        self.bodies = np.array(bodies, float)

        # Shapes per body: (name, kind, x, y, c, s, a, b) with a, b = half sizes or (radius, 0).
        shapes: dict[str, list] = {}
        z_ranges = set()

        def read(plant: MultibodyPlant, scene_graph: SceneGraph, world_only: bool) -> None:
            inspector = scene_graph.model_inspector()
            world = inspector.world_frame_id()
            for g in inspector.GetAllGeometryIds(Role.kProximity):
                frame = inspector.GetFrameId(g)
                if frame == world:
                    key = "world"
                elif world_only:
                    continue
                else:
                    key = plant.GetBodyFromFrameId(frame).name()
                name = inspector.GetName(g)
                shape = inspector.GetShape(g)
                x, y, c, s, z = _planar(inspector.GetPoseInFrame(g), name)
                if isinstance(shape, DrakeBox):
                    entry = (name, kernel.BOX, x, y, c, s, shape.width() / 2, shape.depth() / 2)
                    height = shape.height()
                elif isinstance(shape, Cylinder):
                    entry = (name, kernel.DISC, x, y, c, s, shape.radius(), 0.0)
                    height = shape.length()
                else:
                    raise ValueError(f"{name}: unsupported collision shape {type(shape).__name__} (Box, Cylinder only)")
                z_ranges.add((round(z - height / 2, 9), round(z + height / 2, 9)))
                shapes.setdefault(key, []).append(entry)

        read(diagram.plant(), diagram.scene_graph(), world_only=False)
        for plant_, scene_graph in more_environment:
            read(plant_, scene_graph, world_only=True)
        if len(z_ranges) > 1:
            raise ValueError(f"collision shapes span different z slabs {sorted(z_ranges)}: not planar")
        self.slab = next(iter(z_ranges), (0.0, 0.0))

        unknown = set(shapes) - {"world", *self.body_names}
        if unknown:
            raise ValueError(f"collision geometry on bodies {sorted(unknown)} outside the chain {self.body_names}")
        robot, self.capsule_names = [], []
        for name in self.body_names:
            for label, row in _capsules(shapes.get(name, [])):
                robot.append([index[name], *row])
                self.capsule_names.append((name, label))
        self.robot = np.array(robot, float).reshape(-1, 6)

        env, self.env_names = [], []
        for name, kind, x, y, c, s, a, b in shapes.get("world", []):
            rho = math.hypot(a, b) if kind == kernel.BOX else a
            env.append([kind, x, y, c, s, a, b, rho])
            self.env_names.append(name)
        self.env = np.array(env, float).reshape(-1, 8)
        self.grid = build_grid(self.env)
        self.levers = self._levers()
        self.lever = np.array([max(self.levers[:, 0].max(initial=0.0), float(np.hypot(*self.bodies[2, 1:3]))),
                               self.levers[:, 1].max(initial=0.0)])

    def _levers(self) -> np.ndarray:
        """(S, 2) per capsule ``(c_shoulder, c_gripper)``: every point of a
        base capsule moves with the base only (0, 0); every point of a link-1
        capsule lies within c_shoulder of the shoulder (c_gripper 0); for a
        link-2 or object capsule c_shoulder is the elbow's distance from the
        shoulder and every point lies within c_gripper of the elbow (see
        :meth:`ArmGeometry.lever`)."""

        def reach(row: np.ndarray, offset: np.ndarray) -> float:
            return max(float(np.hypot(*(offset[:2] + _rotate(offset[2:], p)))) for p in (row[1:3], row[3:5])) + row[5]

        b = self.bodies
        ident = np.array([0.0, 0.0, 1.0, 0.0])
        elbow = float(np.hypot(*b[2, 1:3]))  # link 2's origin (the elbow) in link 1
        object_in_link2 = b[3, 1:5]  # welded
        out = np.zeros((len(self.robot), 2))
        for j, row in enumerate(self.robot):
            body = int(row[0])
            if body == 1:
                out[j] = reach(row, ident), 0.0
            elif body in (2, 3):
                out[j] = elbow, reach(row, ident if body == 2 else object_in_link2)
        return out

    # ---- kinematics -----------------------------------------------------------

    def body_poses(self, q: np.ndarray) -> np.ndarray:
        """World poses (B, 3) ``[x, y, yaw]`` of :attr:`body_names` at q (4,)."""
        p = kernel.body_poses(np.asarray(q, float), self.bodies)
        return np.column_stack([p[:, 0], p[:, 1], np.arctan2(p[:, 3], p[:, 2])])

    def capsules(self, q: np.ndarray) -> np.ndarray:
        """World capsules (S, 5) ``[ax, ay, bx, by, r]`` at q (4,), named by :attr:`capsule_names`."""
        return kernel.world_capsules(np.asarray(q, float), self.bodies, self.robot)

    # ---- ValidityChecker ------------------------------------------------------

    def clearance(self, q: np.ndarray) -> float:
        """Least signed distance (metres) from the robot to the environment.

        Exact when positive; when negative, only its sign is meaningful.
        Ignores the limits (see :meth:`in_limits`).
        """
        return float(kernel.clearance(np.asarray(q, float), self.bodies, self.robot, self.env, self.grid))

    def clearances(self, qs: np.ndarray) -> np.ndarray:
        """:meth:`clearance` of configurations (N, 4) -> (N,)."""
        qs = np.ascontiguousarray(qs, float).reshape(-1, 4)
        return kernel.clearances(qs, self.bodies, self.robot, self.env, self.grid)

    def is_valid(self, q: np.ndarray) -> bool:
        """One configuration (4,): within the limits, clearance > 0."""
        q = np.asarray(q, float).reshape(1, 4)
        return bool(kernel.valid(q, self.lower, self.upper, self.bodies, self.robot, self.env, self.grid)[0])

    def are_valid(self, qs: np.ndarray) -> np.ndarray:
        """Many configurations (N, 4) -> (N,) bool."""
        qs = np.ascontiguousarray(qs, float).reshape(-1, 4)
        return kernel.valid(qs, self.lower, self.upper, self.bodies, self.robot, self.env, self.grid)

    def is_motion_valid(self, q_a: np.ndarray, q_b: np.ndarray) -> bool:
        """The straight motion from q_a to q_b (4,), ends included; sound
        (conservative advancement, :func:`planar_kernel.motion_valid`)."""
        return bool(kernel.motion_valid(np.asarray(q_a, float), np.asarray(q_b, float), self.lower, self.upper,
                                        self.bodies, self.robot, self.env, self.grid, self.levers))

    @property
    def motion_check(self) -> str:
        """How a straight motion is checked, in words: continuously (each
        capsule advanced by its motion bound; no resolution)."""
        return "checked continuously"

    def are_motions_valid(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """Many motions (E, 4), (E, 4) -> (E,) bool."""
        q_a = np.ascontiguousarray(q_a, float).reshape(-1, 4)
        q_b = np.ascontiguousarray(q_b, float).reshape(-1, 4)
        return kernel.motions_valid(q_a, q_b, self.lower, self.upper, self.bodies, self.robot, self.env, self.grid,
                                    self.levers)

    def compiled_scene(self) -> PlanarScene:
        """The scene as the kernel's arrays (the validity protocol's
        :class:`~drake_social.collision.validity.CompiledSceneChecker` capability)."""
        f = np.ascontiguousarray
        return PlanarScene(f(self.lower, float), f(self.upper, float), f(self.bodies, float), f(self.robot, float),
                           f(self.env, float), f(self.levers, float), self.grid)

    # ---- reports and the second opinion ----------------------------------------

    def contacts(self, q: np.ndarray) -> list[Contact]:
        """The (robot body, environment shape) pairs at signed distance <= 0,
        deepest first, from the exact planar distances (see
        :meth:`~drake_social.collision.drake_checker.SceneGraphChecker.contacts` for Drake's)."""
        d = kernel.pair_distances(np.asarray(q, float), self.bodies, self.robot, self.env)
        deepest: dict[tuple[str, str], float] = {}
        for j, k in zip(*np.nonzero(d <= 0.0)):
            key = (self.capsule_names[j][0], self.env_names[k])
            deepest[key] = min(float(d[j, k]), deepest.get(key, math.inf))
        return sorted((Contact(a, shape_label(self.scenario, b), v) for (a, b), v in deepest.items()),
                      key=lambda c: c.distance)


def _rotate(cs: np.ndarray, p: np.ndarray) -> np.ndarray:
    c, s = cs
    return np.array([c * p[0] - s * p[1], s * p[0] + c * p[1]])


def _capsules(shapes: list) -> list[tuple[str, list[float]]]:
    """A body's boxes and cylinders as capsules ``(label, [ax, ay, bx, by, r])``.

    A box of width 2r with a cylinder of radius r centred on each end of one
    of its axes is a stadium: one capsule along that axis. The axis is the one
    whose two ends carry such cylinders, whichever side of the box is longer:
    a segment shorter than its capsule's width (a short bar or object segment,
    a link wider than long) is a box longer across than along. Every other
    cylinder is a disc (a capsule of length 0). Any other box is refused.
    """
    discs = [s for s in shapes if s[1] == kernel.DISC]
    used: set[int] = set()
    out = []

    def end_discs(x: float, y: float, half: float, r: float, ux: float, uy: float) -> list[int] | None:
        ends = []
        for sign in (-1.0, 1.0):
            ex, ey = x + sign * half * ux, y + sign * half * uy
            # The nearest cylinder of the radius: a box shorter than _TOL has both within _TOL of each end.
            match = [(math.hypot(d[2] - ex, d[3] - ey), i) for i, d in enumerate(discs) if abs(d[6] - r) <= _TOL]
            if not match or min(match)[0] > _TOL:
                return None
            ends.append(min(match)[1])
        return ends

    for name, kind, x, y, c, s, hx, hy in shapes:
        if kind != kernel.BOX:
            continue
        # The box's own x axis (half length hx, radius hy) first, then its y axis.
        r = hy
        ends = end_discs(x, y, hx, hy, c, s)
        if ends is None:
            r = hx
            ends = end_discs(x, y, hy, hx, -s, c)
        if ends is None:
            raise ValueError(f"{name}: a robot box that is not a stadium (a box with a cylinder of radius "
                             f"half its width on each end); only discs and stadia are supported")
        used.update(ends)
        (_, _, ax, ay, *_), (_, _, bx, by, *_) = discs[ends[0]], discs[ends[1]]
        out.append((name, [ax, ay, bx, by, r]))  # the discs' centres: exact, unlike the box's rotated ends
    for i, (name, _, x, y, _, _, r, _) in enumerate(discs):
        if i not in used:
            out.append((name, [x, y, x, y, r]))
    return out
