"""Drake: the robot model and the MultibodyPlant/SceneGraph of a scenario.

The checkers built on this model live in :mod:`drake_social.collision`.
"""

from drake_social.model.plant import ScenarioDiagram, build_robot_diagram
from drake_social.model.robot_model import robot_sdf

__all__ = ["ScenarioDiagram", "build_robot_diagram", "robot_sdf"]
