"""The overlays' shared pieces: Meshcat paths, heights, colours and meshes.

Used by :mod:`drake_social.sim.replay` (the static overlays) and
:mod:`drake_social.sim.replay_people` (the walkers), so both draw the same
arrows and heat-map colours at the same heights.
"""

from __future__ import annotations

import io
import math

import numpy as np
from matplotlib.image import imsave
from pydrake.common import MemoryFile
from pydrake.geometry import InMemoryMesh, Mesh, Meshcat, Rgba

from drake_social.model.robot_model import COLLISION_HEIGHT
from drake_social.viz.world import FIELD_CMAP

__all__ = [
    "ARROW_RGBA",
    "ARROW_Z",
    "FIELD_Z",
    "OVERLAY_PREFIX",
    "PATH_RGBA",
    "PATH_WIDTH",
    "PATH_Z",
    "THREE_CLAMP_TO_EDGE",
    "VISUALIZER_PREFIX",
    "arrow_mesh",
    "field_png",
    "set_texture_properties",
    "ribbon_mesh",
    "textured_quad",
]

#: Meshcat path of the overlays drawn by :func:`draw_overlays`.
OVERLAY_PREFIX = "/drake_social"
#: Prefix of the MeshcatVisualizer (relative, so under ``/drake``): a body B of
#: model M is drawn at ``/drake/illustration/M/B``.
VISUALIZER_PREFIX = "illustration"

#: Heights above the floor, metres: the heat map just above z = 0 (the floor
# grid is hidden), the path above it, the facing arrows on top of the people's
# cylinders (which are COLLISION_HEIGHT tall).
FIELD_Z = 0.002
PATH_Z = 0.02
ARROW_Z = COLLISION_HEIGHT + 0.01
PATH_WIDTH = 0.08
# three.js' ClampToEdgeWrapping constant.
THREE_CLAMP_TO_EDGE = 1001.0
PATH_RGBA = Rgba(0.05, 0.45, 0.85, 1.0)
ARROW_RGBA = Rgba(0.05, 0.05, 0.05, 1.0)


def field_png(values: np.ndarray, vmax: float | None = None) -> bytes:
    """``values`` (ny, nx), row 0 = south, as PNG bytes (row 0 at the top =
    north) in :data:`FIELD_CMAP` from 0 to ``vmax`` (None: the values'
    maximum, 1 when that is not > 0), as the figures colour the heat map."""
    top = float(values.max()) if vmax is None else float(vmax)
    if not top > 0:  # an empty room: all white, as in the figure
        top = 1.0
    buffer = io.BytesIO()
    imsave(buffer, values, cmap=FIELD_CMAP, vmin=0.0, vmax=top, origin="lower", format="png")
    return buffer.getvalue()


def textured_quad(corners: tuple[float, float, float, float], png: bytes, *, alpha_png: bytes | None = None,
                  name: str = "field") -> Mesh:
    """A quad ``x0, y0, x1, y1`` (metres, in its frame) at z = 0 showing ``png``.

    The material's diffuse and specular colours are black and its emissive
    map is the image, so the pixels show their colours whatever the lights
    are. With ``alpha_png`` (grey levels: white opaque, black transparent;
    three.js reads its green channel) the material is transparent where the
    alpha image is black.
    """
    x0, y0, x1, y1 = (float(v) for v in corners)
    obj = "\n".join([
        f"mtllib {name}.mtl",
        f"v {x0!r} {y0!r} 0", f"v {x1!r} {y0!r} 0", f"v {x1!r} {y1!r} 0", f"v {x0!r} {y1!r} 0",
        "vt 0 0", "vt 1 0", "vt 1 1", "vt 0 1",
        "vn 0 0 1",
        f"usemtl {name}",
        "f 1/1/1 2/2/1 3/3/1", "f 1/1/1 3/3/1 4/4/1",
        "",
    ])
    mtl = f"newmtl {name}\nKa 0 0 0\nKd 0 0 0\nKs 0 0 0\nKe 1 1 1\nmap_Ke {name}.png\n"
    if alpha_png is not None:
        mtl += f"map_d {name}_alpha.png\n"
    files = {f"{name}.mtl": MemoryFile(mtl, ".mtl", f"{name}.mtl"), f"{name}.png": MemoryFile(png, ".png", f"{name}.png")}
    if alpha_png is not None:
        files[f"{name}_alpha.png"] = MemoryFile(alpha_png, ".png", f"{name}_alpha.png")
    return Mesh(InMemoryMesh(mesh_file=MemoryFile(obj, ".obj", f"social_{name}.obj"), supporting_files=files))


def set_texture_properties(meshcat: Meshcat, path: str, *, alpha: bool = False) -> None:
    """Shows a :func:`textured_quad` at ``path`` in the colour map's own
    colours: Meshcat tone-maps every material (ACES), which turns white into
    grey; three.js' MTL loader repeats textures, and clamped, the linear
    filter at one edge does not pick up the opposite edge's colours."""
    meshcat.SetProperty(f"{path}/<object>", "material.toneMapped", False)
    for texture in ("emissiveMap", "alphaMap") if alpha else ("emissiveMap",):
        for wrap in ("wrapS", "wrapT"):
            meshcat.SetProperty(f"{path}/<object>", f"material.{texture}.{wrap}", THREE_CLAMP_TO_EDGE)
    meshcat.SetProperty(f"{path}/<object>", "material.needsUpdate", True)


def arrow_mesh(x: float, y: float, theta: float, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """A flat arrow from a person's centre along ``theta``, its head beyond
    the body's edge (as in the matplotlib scene figure)."""
    length = radius + max(0.45, 1.6 * radius)
    shaft, head_w, head_l = 0.06, 0.26, 0.22
    local = np.array([
        [0.0, -shaft / 2], [length - head_l, -shaft / 2], [length - head_l, shaft / 2], [0.0, shaft / 2],
        [length - head_l, -head_w / 2], [length, 0.0], [length - head_l, head_w / 2],
    ])
    c, s = math.cos(theta), math.sin(theta)
    xy = local @ np.array([[c, s], [-s, c]]) + [x, y]
    vertices = np.vstack([xy.T, np.full(len(xy), ARROW_Z)])
    faces = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6]], dtype=np.int32).T
    return np.asfortranarray(vertices), np.asfortranarray(faces)


def ribbon_mesh(points: np.ndarray, width: float, z: float) -> tuple[np.ndarray, np.ndarray]:
    """A flat strip of ``width`` metres along a 2-D polyline, at height ``z``.

    Joints are mitred (the miter is capped at 3 half-widths so that a sharp
    turn does not spike). Repeated points are dropped.

    Args:
        points: (N, 2) polyline, metres, N >= 2 distinct points.
        width: strip width, metres (> 0).
        z: height of the strip, metres.

    Returns:
        vertices (3, 2N) and faces (3, 2(N-1)) int32, as
        ``Meshcat.SetTriangleMesh`` takes them.
    """
    p = np.asarray(points, float)[:, :2]
    keep = np.r_[True, np.any(np.diff(p, axis=0) != 0, axis=1)]
    p = p[keep]
    if len(p) < 2:
        raise ValueError(f"a ribbon needs at least 2 distinct points, got {len(p)}")
    seg = np.diff(p, axis=0)
    seg /= np.linalg.norm(seg, axis=1, keepdims=True)
    normals = np.stack([-seg[:, 1], seg[:, 0]], axis=1)
    # Per vertex: the mean of the adjacent segment normals, scaled to keep the
    # strip's width along both segments (1 / cos of the half turn).
    n = np.vstack([normals[:1], normals[:-1] + normals[1:], normals[-1:]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    adjacent = np.vstack([normals[:1], normals])
    cos_half = np.clip(np.sum(n * adjacent, axis=1), 1.0 / 3.0, 1.0)
    offset = n * (width / 2 / cos_half)[:, None]
    left, right = p + offset, p - offset
    vertices = np.empty((3, 2 * len(p)))
    vertices[:2, 0::2], vertices[:2, 1::2] = left.T, right.T
    vertices[2] = z
    k = np.arange(len(p) - 1)
    faces = np.concatenate([np.stack([2 * k, 2 * k + 1, 2 * k + 2]), np.stack([2 * k + 1, 2 * k + 3, 2 * k + 2])], axis=1)
    return np.asfortranarray(vertices), np.asfortranarray(faces.astype(np.int32))
