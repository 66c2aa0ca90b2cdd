"""Matplotlib figures, composable: each ``draw_*`` function draws on a given axes.

* :func:`draw_world` walls, obstacles, people with facing arrows;
* :func:`draw_social_field` the social-cost heat map with its colour bar;
* :func:`draw_robot` base, links, object and interest points at one q;
* :func:`show_figure` / :func:`write_show` the scene picture of ``drake-social show``.
"""

from drake_social.viz.robot import RobotStyle, capsule_outline, draw_robot
from drake_social.viz.show import draw_start_goal, scene_figure, show_figure, write_show
from drake_social.viz.world import box_corners, draw_social_field, draw_world, field_grid

__all__ = [
    "RobotStyle",
    "box_corners",
    "capsule_outline",
    "draw_robot",
    "draw_social_field",
    "draw_start_goal",
    "draw_world",
    "field_grid",
    "scene_figure",
    "show_figure",
    "write_show",
]
