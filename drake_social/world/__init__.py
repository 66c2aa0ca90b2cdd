"""Where the obstacles are: the room's bounds, walls and boxes as arrays.

The checkers, the plant, the figures and the replay read a
:class:`WorldGeometry` (:func:`world_model`) instead of the scenario's
``world.obstacles``; the derived quantities (the walls as boxes, corners,
half sizes, bounding radii) are computed once there.
"""

from drake_social.world.model import WALL_NAMES, Boxes, WorldGeometry, with_obstacles, world_model

__all__ = ["Boxes", "WALL_NAMES", "WorldGeometry", "with_obstacles", "world_model"]
