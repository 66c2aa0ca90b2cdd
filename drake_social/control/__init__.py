"""Drake systems for planning and path following.

* :class:`PlannerSystem` plans once at initialization and outputs the path;
  :class:`ReplanningPlannerSystem` plans then replans periodically among
  walking people.
* :class:`WaypointSequencer` decides which waypoint is the current target.
* :class:`HolonomicPController` drives the mecanum base towards it;
  :class:`MecanumDrive` turns wheel speeds into the base velocity.
* :class:`RuckigTrajectorySource` gives jerk-limited references (the arm's,
  or the synchronized whole-configuration reference).
* :class:`PeopleSource` outputs where the people are at the context's time
  (and steps a crowd fed back the robot); :class:`PeopleGeometry` moves their
  bodies in SceneGraph.
* :class:`SafetyMonitor` stops the robot while a person is too close;
  :class:`SpeedLimit` slows it down near people before that.
"""

from drake_social.control.holonomic import (
    HolonomicPController,
    MecanumDrive,
    base_velocity,
    mecanum_matrix,
    saturate_norm,
    wheel_limited_speed,
    wheel_speeds,
)
from drake_social.control.people_geometry import PARKED_DEPTH, PeopleGeometry
from drake_social.control.people_source import PEOPLE_VECTOR_FIELDS, PeopleSource, people_vector
from drake_social.control.planner_system import PlannerSystem, path_parameter, waypoint_trajectory
from drake_social.control.replanner_system import ReplanningPlannerSystem, ReplanState, replanning_summary
from drake_social.control.ruckig_source import (
    RuckigSegment,
    RuckigTrajectorySource,
    arm_source_from_options,
    reference_source_from_options,
)
from drake_social.control.safety_monitor import SafetyMonitor, Stop, braking_travel
from drake_social.control.sequencer import WaypointSequencer
from drake_social.control.speed_limit import SpeedLimit

__all__ = [
    "HolonomicPController",
    "MecanumDrive",
    "PARKED_DEPTH",
    "PEOPLE_VECTOR_FIELDS",
    "PeopleGeometry",
    "PeopleSource",
    "PlannerSystem",
    "ReplanState",
    "ReplanningPlannerSystem",
    "RuckigSegment",
    "RuckigTrajectorySource",
    "SafetyMonitor",
    "SpeedLimit",
    "Stop",
    "WaypointSequencer",
    "arm_source_from_options",
    "base_velocity",
    "braking_travel",
    "mecanum_matrix",
    "path_parameter",
    "people_vector",
    "reference_source_from_options",
    "replanning_summary",
    "saturate_norm",
    "waypoint_trajectory",
    "wheel_limited_speed",
    "wheel_speeds",
]
