"""SDFormat text of the planar mobile manipulator and its object, from a scenario.

The robot's dimensions live in the scenario, so the model text is generated
here, in one function (:func:`robot_sdf`), rather than kept as a second source
of truth. ``models/mobile_manipulator.sdf`` (at the top of the repository;
``drake_social/models`` links to it, so that it is package data, installed with
the package: :func:`models_dir`) is this function's output for the default
:class:`~drake_social.scenario.Scenario`; a test keeps them equal.

The model (all lengths metres, angles radians):

* ``base_x`` (prismatic along world x) moves the massless ``carriage``;
  ``base_y`` (prismatic along world y) moves ``base``, a disc that never
  rotates. Their limits are the room bounds.
* ``psi1`` (revolute about z at the base centre) turns ``link1``; its zero is
  the world x axis because the base does not rotate, so ``psi1`` is the
  absolute link angle of :mod:`drake_social.kinematics`.
* ``psi2`` (revolute about z at the tip of link 1) turns ``link2``.
* the frame ``gripper`` (G) sits at the tip of link 2, x along the link; the
  ``object`` body is welded to it (``gripper_weld``) so the object's
  polyline is expressed in G, exactly as in ``ArmGeometry``.
* frames ``link1_tip`` and ``object_point_<k>`` mark the interest points.

Collision geometry is planar by construction: every shape is a vertical
extrusion over z in [0, :data:`COLLISION_HEIGHT`], the same slab as the
environment's (see :mod:`drake_social.model.plant`), so SceneGraph's 3-D
distances equal the 2-D distances. A 2-D capsule (link, object segment) is a
*stadium*: a box of the segment's length and the capsule's width plus one
cylinder at each end (a 3-D capsule would not be an extrusion). Visual
geometry shows the same footprints as thin layers at increasing heights (base,
link 1, link 2, object), to show that the arm carries the object above the
base.

Self-collisions: every robot-robot pair (base, links, object) is filtered
with a ``drake:collision_filter_group``. In reality the links and the object
move in planes above the base, and adjacent stadia overlap at the joints by
construction, so no robot-robot contact is meaningful in this planar model.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from drake_social.scenario import Scenario
from drake_social.scenario.geometry import object_interest_points, object_polyline

__all__ = [
    "BODY_COLOURS",
    "COLLISION_HEIGHT",
    "MODEL_NAME",
    "ROBOT_BODIES",
    "default_model_path",
    "models_dir",
    "robot_sdf",
]

#: Height of the collision slab z in [0, COLLISION_HEIGHT] shared by every
#: collision shape of the robot and the environment, metres.
COLLISION_HEIGHT = 1.0

#: Name of the SDFormat model (and of its model instance in the plant).
MODEL_NAME = "mobile_manipulator"

#: The robot bodies that carry collision geometry, in kinematic order.
ROBOT_BODIES = ("base", "link1", "link2", "object")

# Visual layers: (z of the bottom, thickness), metres. Only for display.
_VISUAL_LAYERS = {"base": (0.0, 0.30), "link1": (0.32, 0.05), "link2": (0.38, 0.05), "object": (0.44, 0.04)}
#: Each robot body's display colour, "r g b a" (the visual geometry's diffuse colour).
BODY_COLOURS = {
    "base": "0.10 0.15 0.45 1",
    "link1": "0.95 0.75 0.10 1",
    "link2": "0.95 0.45 0.10 1",
    "object": "0.45 0.75 0.95 1",
}
# Masses, kilograms (only the simulation uses them).
_MASSES = {"base": 20.0, "link1": 1.0, "link2": 1.0, "object": 0.5}


def models_dir() -> Path:
    """The package's ``models/`` folder (``package://drake_social``: its
    ``package.xml``): in a checkout a link to the repository's ``models/``,
    in an installed package a copy of it (package data), so an installed
    package finds it without the repository."""
    return Path(__file__).resolve().parents[1] / "models"


def default_model_path() -> Path:
    """The checked-in model file generated for the default scenario."""
    return models_dir() / "mobile_manipulator.sdf"


def _num(v: float) -> str:
    # repr round-trips doubles exactly, so Drake sees the scenario's numbers.
    return repr(float(v))


def _pose(x: float = 0.0, y: float = 0.0, z: float = 0.0, yaw: float = 0.0) -> str:
    return " ".join(_num(v) for v in (x, y, z, 0.0, 0.0, yaw))


def _stadium(tag: str, name: str, points: np.ndarray, radius: float, z0: float, height: float, extra: str) -> list[str]:
    """A 2-D capsule chain extruded over [z0, z0 + height]: boxes + end cylinders.

    ``points`` (M, 2) is a polyline in the body frame; each segment becomes a
    box of its length and width 2 * radius, each vertex a cylinder, so their
    union is the Minkowski sum of the polyline and a disc, extruded.
    """
    zc = z0 + height / 2
    out = []
    for k, p in enumerate(points):
        out.append(
            f'      <{tag} name="{name}_disc{k}"><pose>{_pose(p[0], p[1], zc)}</pose>'
            f"<geometry><cylinder><radius>{_num(radius)}</radius><length>{_num(height)}</length>"
            f"</cylinder></geometry>{extra}</{tag}>"
        )
    for k in range(len(points) - 1):
        a, b = points[k], points[k + 1]
        length = float(np.hypot(*(b - a)))
        if length == 0.0:  # a repeated vertex: its disc already covers it
            continue
        mid = (a + b) / 2
        yaw = math.atan2(b[1] - a[1], b[0] - a[0])
        out.append(
            f'      <{tag} name="{name}_box{k}"><pose>{_pose(mid[0], mid[1], zc, yaw)}</pose>'
            f"<geometry><box><size>{_num(length)} {_num(2 * radius)} {_num(height)}</size></box>"
            f"</geometry>{extra}</{tag}>"
        )
    return out


def _inertial(mass: float, points: np.ndarray, radius: float) -> str:
    """A solid upright cylinder's inertia, centred on the footprint's vertices.

    Its radius is the footprint's extent from the vertex centroid and its
    height the collision slab's: a plausible, valid inertia for the
    simulation (collision checking ignores it).
    """
    c = points.mean(axis=0)
    extent = float(np.max(np.hypot(*(points - c).T))) + radius
    izz = 0.5 * mass * extent**2
    ixx = mass * (3 * extent**2 + COLLISION_HEIGHT**2) / 12
    return (
        f"      <inertial><pose>{_pose(c[0], c[1], COLLISION_HEIGHT / 2)}</pose><mass>{_num(mass)}</mass>"
        f"<inertia><ixx>{_num(ixx)}</ixx><iyy>{_num(ixx)}</iyy><izz>{_num(izz)}</izz>"
        "<ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial>"
    )


def _link(name: str, parent: str, x: float, points: np.ndarray, radius: float) -> list[str]:
    """A body at (x, 0) in frame ``parent`` whose footprint is a stadium chain."""
    z0, thickness = _VISUAL_LAYERS[name]
    colour = f"<material><diffuse>{BODY_COLOURS[name]}</diffuse></material>"
    return [
        f'    <link name="{name}">',
        f'      <pose relative_to="{parent}">{_pose(x)}</pose>',
        _inertial(_MASSES[name], points, radius),
        *_stadium("collision", name, points, radius, 0.0, COLLISION_HEIGHT, ""),
        *_stadium("visual", name, points, radius, z0, thickness, colour),
        "    </link>",
    ]


def _joint(name: str, kind: str, parent: str, child: str, axis: str, lower: float, upper: float) -> str:
    return (
        f'    <joint name="{name}" type="{kind}"><parent>{parent}</parent><child>{child}</child>'
        f"<axis><xyz>{axis}</xyz><limit><lower>{_num(lower)}</lower><upper>{_num(upper)}</upper></limit>"
        "</axis></joint>"
    )


def robot_sdf(scenario: Scenario) -> str:
    """The SDFormat 1.9 text of the robot and its welded object.

    Args:
        scenario: supplies ``robot`` (base radius, link lengths and width,
            joint limits), ``object`` (polyline, thickness, interest points)
            and ``world.bounds`` (limits of the prismatic base joints).

    Returns:
        A complete ``<sdf>`` document with one model named :data:`MODEL_NAME`
        whose bodies are :data:`ROBOT_BODIES` (plus the massless ``carriage``)
        and whose joints are ``base_x``, ``base_y``, ``psi1``, ``psi2`` (in this
        position order) and the weld ``gripper_weld``.
    """
    r, o = scenario.robot, scenario.object
    l1, l2 = (float(v) for v in r.link_lengths)
    link_radius = float(r.link_width) / 2
    x_min, y_min, x_max, y_max = (float(v) for v in scenario.world.bounds)
    obj_points = object_polyline(o)
    obj_interest = object_interest_points(o)
    origin = np.zeros((1, 2))

    lines = [
        '<?xml version="1.0"?>',
        "<!-- Generated by drake_social.model.robot_model.robot_sdf(); do not edit by hand. -->",
        '<sdf xmlns:drake="http://drake.mit.edu" version="1.9">',
        f'  <model name="{MODEL_NAME}">',
        '    <link name="carriage"><inertial><mass>0</mass><inertia><ixx>0</ixx><iyy>0</iyy><izz>0</izz>'
        "<ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial></link>",
        *_link("base", "carriage", 0.0, origin, float(r.base_radius)),
        *_link("link1", "base", 0.0, np.array([[0.0, 0.0], [l1, 0.0]]), link_radius),
        *_link("link2", "link1", l1, np.array([[0.0, 0.0], [l2, 0.0]]), link_radius),
        f'    <frame name="link1_tip" attached_to="link1"><pose>{_pose(l1)}</pose></frame>',
        f'    <frame name="gripper" attached_to="link2"><pose>{_pose(l2)}</pose></frame>',
        *_link("object", "gripper", 0.0, obj_points, float(o.thickness) / 2),
        *(
            f'    <frame name="object_point_{k + 1}" attached_to="object"><pose>{_pose(p[0], p[1])}</pose></frame>'
            for k, p in enumerate(obj_interest)
        ),
        _joint("base_x", "prismatic", "world", "carriage", "1 0 0", x_min, x_max),
        _joint("base_y", "prismatic", "carriage", "base", "0 1 0", y_min, y_max),
        _joint("psi1", "revolute", "base", "link1", "0 0 1", r.joint_lower[0], r.joint_upper[0]),
        _joint("psi2", "revolute", "link1", "link2", "0 0 1", r.joint_lower[1], r.joint_upper[1]),
        '    <joint name="gripper_weld" type="fixed"><parent>link2</parent><child>object</child></joint>',
        '    <drake:collision_filter_group name="robot">',
        *(f"      <drake:member>{b}</drake:member>" for b in ROBOT_BODIES),
        "      <drake:ignored_collision_filter_group>robot</drake:ignored_collision_filter_group>",
        "    </drake:collision_filter_group>",
        "  </model>",
        "</sdf>",
        "",
    ]
    return "\n".join(lines)
