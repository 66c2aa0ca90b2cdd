"""The people as moving bodies in SceneGraph, so that Drake's queries see them.

:class:`PeopleGeometry` registers itself as a SceneGraph geometry source
(named ``people``) with one frame per person and, on it, the person's body:
a cylinder of the person's radius over the collision slab z in [0,
:data:`~drake_social.model.robot_model.COLLISION_HEIGHT`] (the shape the
plant anchors for a standing person, :func:`drake_social.model.plant.add_environment`),
with the proximity role (distance and collision queries) and the
illustration role (the replay), in the people's colour
(:data:`~drake_social.model.plant.PERSON_RGBA`). Geometry names are those of
:func:`~drake_social.model.plant.environment_names` (``person[i] 'name'``).

Its ``geometry_pose`` output (a ``FramePoseVector``) places each frame at
the person's ``[x, y]`` on the floor, turned by their heading, from the
``people_state`` input (a :class:`~drake_social.people.PeopleState`). A person
who is absent at that time (``present`` False: a recorded pedestrian before
entering or after leaving) is parked :data:`PARKED_DEPTH` metres below the
floor, out of reach of every query of the room and out of the top view.

Ports::

    input   people_state   Value[PeopleState]
    output  geometry_pose  Value[FramePoseVector], to scene_graph.get_source_pose_port(source_id)
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.geometry import (
    Cylinder,
    FramePoseVector,
    GeometryFrame,
    GeometryId,
    GeometryInstance,
    MakePhongIllustrationProperties,
    ProximityProperties,
    SceneGraph,
)
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.framework import Context, LeafSystem

from drake_social.model.plant import PERSON_RGBA, person_geometry_names
from drake_social.model.robot_model import COLLISION_HEIGHT
from drake_social.people import PeopleState

__all__ = ["PARKED_DEPTH", "PeopleGeometry"]

#: How far below the floor (metres) an absent person's body is parked: far
#: beyond any room (the walls and obstacles span z in [0, COLLISION_HEIGHT]).
PARKED_DEPTH = 1000.0


class PeopleGeometry(LeafSystem):
    """Moves the people's bodies in SceneGraph (see the module docstring).

    Args:
        scene_graph: the SceneGraph to register with (before its context exists).
        people: the people at any time (their count, radii and names are used).

    Raises:
        ValueError: a radius that is not finite and positive.
    """

    def __init__(self, scene_graph: SceneGraph, people: PeopleState):
        super().__init__()
        radii = np.asarray(people.radii, float)
        if not (np.isfinite(radii).all() and (radii > 0).all()):
            raise ValueError(f"PeopleGeometry: people's radii must be finite and > 0, got {radii}")
        self._source_id = scene_graph.RegisterSource("people")
        self._frames = []
        self._geometries: list[GeometryId] = []
        for name, radius in zip(person_geometry_names(people.names), radii):
            frame = scene_graph.RegisterFrame(self._source_id, GeometryFrame(name))
            body = GeometryInstance(RigidTransform([0.0, 0.0, COLLISION_HEIGHT / 2]),
                                    Cylinder(float(radius), COLLISION_HEIGHT), name)
            body.set_proximity_properties(ProximityProperties())
            body.set_illustration_properties(MakePhongIllustrationProperties(np.array(PERSON_RGBA)))
            self._geometries.append(scene_graph.RegisterGeometry(self._source_id, frame, body))
            self._frames.append(frame)
        self._count = len(self._frames)
        self._parked = RigidTransform([0.0, 0.0, -PARKED_DEPTH])
        self.DeclareAbstractInputPort("people_state", AbstractValue.Make(people))
        self.DeclareAbstractOutputPort("geometry_pose", lambda: AbstractValue.Make(FramePoseVector()),
                                       self._CalcPoses)

    @property
    def source_id(self):
        """The SceneGraph source id (connect ``geometry_pose`` to its pose port)."""
        return self._source_id

    @property
    def geometry_ids(self) -> list[GeometryId]:
        """Each person's body geometry, in the people's order."""
        return list(self._geometries)

    def _CalcPoses(self, context: Context, output: AbstractValue) -> None:
        state: PeopleState = self.get_input_port(0).Eval(context)
        if state.count != self._count:
            raise ValueError(f"PeopleGeometry: people_state has {state.count} people; {self._count} are registered")
        poses = output.get_mutable_value()
        poses.clear()
        for frame, (x, y), theta, present in zip(self._frames, state.positions, state.headings, state.present):
            X_WF = (RigidTransform(RotationMatrix.MakeZRotation(float(theta)), [float(x), float(y), 0.0])
                    if present else self._parked)
            poses.set_value(frame, X_WF)
