"""The occupancy-grid map in a replay: its boxes as one merged mesh.

The plant registers a map's boxes as collision geometry only
(:func:`drake_social.model.plant.add_environment`), so the visualizer does
not draw thousands of separate objects; :func:`draw_map_mesh` draws them
here instead as a single triangle mesh, extruded over the collision slab,
which a replay stores once (about 0.3 kB per box) whatever its length.
"""

from __future__ import annotations

import numpy as np
from pydrake.geometry import Meshcat, Rgba

from drake_social.model.robot_model import COLLISION_HEIGHT
from drake_social.world import WorldGeometry

__all__ = ["MAP_RGBA", "boxes_mesh", "draw_map_mesh"]

#: Colour of the map's boxes in the replay (the obstacles' brown, darker).
MAP_RGBA = Rgba(0.42, 0.36, 0.30, 1.0)

# Per box: the top (two triangles) and the four sides (two each), over the
# corners 0-3 at the bottom and 4-7 at the top, counter-clockwise seen from outside.
_TOP = [[4, 5, 6], [4, 6, 7]]
_SIDES = [[k, (k + 1) % 4, 4 + (k + 1) % 4] for k in range(4)] + [[k, 4 + (k + 1) % 4, 4 + k] for k in range(4)]
_FACES = np.array(_TOP + _SIDES, dtype=np.int32)  # (10, 3)


def boxes_mesh(corners: np.ndarray, height: float) -> tuple[np.ndarray, np.ndarray]:
    """Boxes with footprints ``corners`` (K, 4, 2, counter-clockwise),
    extruded from z = 0 to ``height``, as one mesh without bottoms.

    Returns:
        vertices (3, 8K) and faces (3, 10K) int32, as
        ``Meshcat.SetTriangleMesh`` takes them.
    """
    corners = np.asarray(corners, float).reshape(-1, 4, 2)
    k = len(corners)
    vertices = np.empty((k, 8, 3))
    vertices[:, :4, :2] = corners
    vertices[:, 4:, :2] = corners
    vertices[:, :4, 2] = 0.0
    vertices[:, 4:, 2] = float(height)
    faces = _FACES[None] + 8 * np.arange(k, dtype=np.int32)[:, None, None]
    return np.asfortranarray(vertices.reshape(-1, 3).T), np.asfortranarray(faces.reshape(-1, 3).T)


def draw_map_mesh(meshcat: Meshcat, world: WorldGeometry, path: str) -> int:
    """Draws the map's boxes of ``world`` at ``path`` as one mesh (nothing
    without a map, or a map without boxes).

    Returns:
        The number of boxes drawn.
    """
    k = world.map_box_count
    if world.map is None or k == 0:
        return 0
    vertices, faces = boxes_mesh(world.boxes.corners[len(world.boxes) - k:], COLLISION_HEIGHT)
    meshcat.SetTriangleMesh(path, vertices, faces, MAP_RGBA)
    return k
