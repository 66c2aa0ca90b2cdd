"""Drake systems for planning and path following.

* :class:`PlannerSystem` plans once at initialization and outputs the path.
* :class:`WaypointSequencer` decides which waypoint is the current target.
"""

from drake_social.control.planner_system import PlannerSystem, path_parameter, waypoint_trajectory
from drake_social.control.sequencer import WaypointSequencer

__all__ = ["PlannerSystem", "WaypointSequencer", "path_parameter", "waypoint_trajectory"]
