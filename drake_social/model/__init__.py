"""Drake: the robot model, the MultibodyPlant/SceneGraph of a scenario, and the
SceneGraphCollisionChecker adapter of the validity-checker protocol."""

from drake_social.model.checker import Contact, SceneGraphChecker, check_start_goal
from drake_social.model.plant import ScenarioDiagram, build_robot_diagram
from drake_social.model.robot_model import robot_sdf

__all__ = [
    "Contact",
    "ScenarioDiagram",
    "SceneGraphChecker",
    "build_robot_diagram",
    "check_start_goal",
    "robot_sdf",
]
