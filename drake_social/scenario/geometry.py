"""The robot's and its object's dimensions read from a scenario.

:mod:`drake_social.kinematics` is the chain alone (pure numpy, batched over
``q``) and names no schema type; this module is where the schema meets it:
:func:`arm_geometry` builds a :class:`~drake_social.kinematics.ArmGeometry`
from a scenario's robot and object, :func:`configuration_limits` the box a
valid configuration lies in.
"""

from __future__ import annotations

import numpy as np

from drake_social.io.textfile import shorten
from drake_social.kinematics import ArmGeometry
from drake_social.scenario.schema import Bar, LShape, Polyline, Scenario

__all__ = ["arm_geometry", "configuration_limits", "object_interest_points", "object_polyline"]


def object_polyline(obj: Bar | LShape | Polyline) -> np.ndarray:
    """The object's vertices in the gripper frame, shape (M, 2), metres
    (each object type of the schema knows its own: ``obj.polyline()``)."""
    return obj.polyline()


def object_interest_points(obj: Bar | LShape | Polyline) -> np.ndarray:
    """The object's interest points in the gripper frame, shape (P, 2).

    Defaults: the two ends of a bar, the three vertices of an L, the first and
    last vertex of a polyline.
    """
    if obj.interest_points is not None:
        return np.asarray(obj.interest_points, dtype=float).reshape(-1, 2)
    return obj.default_interest_points()


def arm_geometry(scenario: Scenario) -> ArmGeometry:
    """The dimensions of ``scenario``'s robot and object.

    Raises:
        TypeError: ``scenario`` is not a scenario (has no robot and object).
    """
    try:
        r, o = scenario.robot, scenario.object
    except AttributeError:
        raise TypeError(f"arm_geometry: scenario must be a drake_social.scenario.Scenario, got "
                        f"{type(scenario).__name__} {shorten(repr(scenario))}") from None
    return ArmGeometry(
        base_radius=float(r.base_radius),
        link_lengths=(float(r.link_lengths[0]), float(r.link_lengths[1])),
        link_radius=float(r.link_width) / 2,
        object_points=object_polyline(o),
        object_radius=float(o.thickness) / 2,
        object_interest=object_interest_points(o),
    )


def configuration_limits(scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper), each (4,), of a valid ``q = [x, y, psi1, psi2]``: the
    room's ``world.bounds`` for the base position, ``robot.joint_lower`` /
    ``robot.joint_upper`` for the joints (metres, radians)."""
    x_min, y_min, x_max, y_max = (float(v) for v in scenario.world.bounds)
    r = scenario.robot
    return np.array([x_min, y_min, *r.joint_lower], float), np.array([x_max, y_max, *r.joint_upper], float)
