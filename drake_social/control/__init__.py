"""Drake systems for planning and path following.

* :class:`PlannerSystem` plans once at initialization and outputs the path.
"""

from drake_social.control.planner_system import PlannerSystem, path_parameter, waypoint_trajectory

__all__ = ["PlannerSystem", "path_parameter", "waypoint_trajectory"]
