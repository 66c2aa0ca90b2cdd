"""Walking people in the replay: an animated arrow and heat-map quad per walker.

The people's bodies are SceneGraph geometry on moving frames, animated by the
``MeshcatVisualizer`` like the robot. What the plant does not know, each
walker's facing arrow and personal space, is drawn here in the person's own
frame under ``<prefix>/walkers/<i>`` and moved by keyframes added to the
Meshcat recording (:func:`animate_people`):

* ``<prefix>/walkers/<i>``: the person's frame (x, y, yaw = theta), one
  transform keyframe per :data:`PEOPLE_REPLAY_FPS` (three.js interpolates
  linearly in between), plus keyframes where the person appears or leaves;
  ``visible`` is false while they are absent;
* ``.../arrow``: the facing arrow, as in the static overlays;
* ``.../agf``: Kirby's AGF of one person as a textured quad in the person's
  frame, in the static heat map's colour scale, transparent where the AGF is
  at or below the threshold. The quad is built once for the scenario's
  ``sigma_h``; with ``social.speed_scaling`` (sigma_h = max(2 v, 0.5), the
  side and rear sigmas keep their ratios to it) the AGF at speed v is the
  same picture scaled by ``sigma_h(v) / social.sigma_h`` in both axes, so the
  quad gets an animated ``scale`` keyframe with each pose: exact at the
  keyframes, no quantised sizes.

Overlapping walkers' quads are drawn on top of each other, not summed (the
static heat map sums the standing people).
"""

from __future__ import annotations

import io
import logging
import math

import numpy as np
from matplotlib.image import imsave
from pydrake.geometry import Meshcat, Rgba
from pydrake.math import RigidTransform, RotationMatrix

from drake_social.cost.agf import PersonalSpace, gaussian, speed_scaled_sigmas
from drake_social.people import PeopleLog, PeopleState
from drake_social.scenario import Scenario
from drake_social.sim.replay_meshes import (
    ARROW_RGBA,
    FIELD_Z,
    OVERLAY_PREFIX,
    PATH_Z,
    arrow_mesh,
    field_png,
    set_texture_properties,
    textured_quad,
)
from drake_social.viz.tracks import moving_people
from drake_social.viz.world import FIELD_MIN_RESOLUTION

__all__ = ["PEOPLE_REPLAY_FPS", "WALKERS", "animate_people", "personal_space_texture",
           "standing_mask", "standing_people", "walker_sigma_h"]

_log = logging.getLogger(__name__)

#: Keyframes per second of a walker's pose (at most the recording's rate). At
#: 1.5 m/s a walker moves 0.15 m between keyframes and three.js interpolates
#: linearly in between; 10 walkers over 2 minutes cost about 1 MB of page.
PEOPLE_REPLAY_FPS = 10.0
#: Name of the walkers' folder under the overlays' prefix.
WALKERS = "walkers"
#: Most texture cells along either side of a personal-space quad.
_MAX_TEXTURE_CELLS = 256
# three.js' MultiplyBlending and NearestFilter constants.
_THREE_MULTIPLY_BLENDING = 4.0
_THREE_NEAREST_FILTER = 1003.0


def standing_mask(people: PeopleLog) -> np.ndarray:
    """(P,) True for each person who stands still and is present all along."""
    return ~moving_people(people) & people.present[0]


def standing_people(people: PeopleLog) -> PeopleState:
    """The people who stand still and are present all along (:func:`standing_mask`),
    at the first sample, in the log's order."""
    keep = standing_mask(people)
    first = people.state(0)
    return PeopleState(t=first.t, positions=first.positions[keep], headings=first.headings[keep],
                       velocities=first.velocities[keep], radii=first.radii[keep],
                       names=tuple(n for n, k in zip(first.names, keep) if k))


def walker_sigma_h(scenario: Scenario, speeds: np.ndarray) -> np.ndarray:
    """Each walker's sigma_h, metres, at ``speeds`` (m/s): Kirby's
    ``max(2 v, 0.5)`` with ``social.speed_scaling``, else ``social.sigma_h``."""
    speeds = np.asarray(speeds, float)
    if scenario.social.speed_scaling:
        return speed_scaled_sigmas(speeds, 1.0, 1.0)[:, 0].reshape(speeds.shape)
    return np.full(speeds.shape, float(scenario.social.sigma_h))


def personal_space_texture(space: PersonalSpace, vmax: float) -> tuple[tuple[float, float, float, float],
                                                                        np.ndarray, bytes, bytes]:
    """The AGF of one person at the origin facing +x, as a texture.

    Args:
        space: variances and threshold.
        vmax: top of the colour scale (the static heat map's).

    Returns:
        ``(corners, values, png, alpha_png)``: the quad ``(u0, v0, u1, v1)``
        in the person's frame, metres, from the AGF's rear reach to its front
        reach and side to side; the thresholded AGF at the cell centres
        (nv, nu), row 0 = -v (right); the image in :data:`FIELD_CMAP` from 0
        to ``vmax``; its alpha image (white where the AGF is above the
        threshold, black elsewhere).
    """
    front, side, rear = space.reach("front"), space.reach("side"), space.reach("rear")
    if not math.isfinite(max(front, side, rear)):
        raise ValueError(f"the AGF's threshold must be > 0 for a bounded quad, got {space.threshold}")
    corners = (-rear, -side, front, side)
    cell = max(FIELD_MIN_RESOLUTION, max(front + rear, 2 * side) / _MAX_TEXTURE_CELLS)
    nu, nv = max(1, math.ceil((front + rear) / cell)), max(1, math.ceil(2 * side / cell))
    u = -rear + (np.arange(nu) + 0.5) * (front + rear) / nu
    v = -side + (np.arange(nv) + 0.5) * (2 * side) / nv
    raw = gaussian(u[None, :], v[:, None], 1.0, 0.0, space)
    above = raw > space.threshold
    values = np.where(above, raw, 0.0)
    alpha = io.BytesIO()
    imsave(alpha, above.astype(float), cmap="gray", vmin=0.0, vmax=1.0, origin="lower", format="png")
    return corners, values, field_png(values, vmax), alpha.getvalue()


def _multiply(meshcat: Meshcat, path: str) -> None:
    """Blends the quad at ``path`` by multiplying what is under it: over the
    white of zero cost it shows the colour map's own colours; where it
    overlaps the static field or another walker both stay visible, darker
    (more cost). The cut-out (alpha test on the alpha map, sampled nearest
    so that every kept texel is fully opaque) drops the transparent texels,
    which would otherwise multiply to black or leave the canvas partly
    transparent; no depth writes, so every overlapping quad blends whatever
    the drawing order."""
    for name, value in (("blending", _THREE_MULTIPLY_BLENDING), ("premultipliedAlpha", True), ("alphaTest", 0.5),
                        ("depthWrite", False), ("alphaMap.magFilter", _THREE_NEAREST_FILTER),
                        ("alphaMap.minFilter", _THREE_NEAREST_FILTER), ("alphaMap.needsUpdate", True),
                        ("needsUpdate", True)):
        meshcat.SetProperty(f"{path}/<object>", f"material.{name}", value)


def _frame_samples(people: PeopleLog, fps: float, step: int) -> tuple[np.ndarray, np.ndarray]:
    """The recording's frames over the log (k / fps from 0 to the last
    sample) and which of them get a pose keyframe: every ``step``-th and the last."""
    last = int(math.floor(float(people.times[-1]) * fps + 1e-9))
    frames = np.arange(max(last, 0) + 1)
    keys = np.zeros(len(frames), bool)
    keys[::step] = True
    keys[-1] = True
    return frames, keys


def animate_people(meshcat: Meshcat, scenario: Scenario, people: PeopleLog, fps: float, *,
                   prefix: str = OVERLAY_PREFIX, vmax: float = 1.0,
                   rate: float = PEOPLE_REPLAY_FPS) -> int:
    """Adds the walkers' arrows and heat-map quads to the run's recording.

    Call after :func:`~drake_social.sim.replay.finish_recording` (the
    recording is published again with the people's keyframes) and after
    :func:`~drake_social.sim.replay.draw_overlays`, which deletes ``prefix``
    (``draw_overlays(..., people=people)`` calls this itself).

    Args:
        meshcat: the run's Meshcat.
        scenario: gives the AGF's variances, threshold and speed scaling.
        people: where the people were over the run; only the movers
            (:func:`drake_social.viz.tracks.moving_people`) are animated.
        fps: frames per second of the recording (its frame k is at k / fps s).
        prefix: the overlays' absolute Meshcat path.
        vmax: top of the colour scale, that of the static heat map.
        rate: pose keyframes per second (<= fps: every round(fps / rate)-th
            recording frame); three.js interpolates linearly in between.

    Returns:
        The number of animated people.
    """
    if not fps > 0:
        raise ValueError(f"fps must be > 0 frames per second, got {fps}")
    if not rate > 0:
        raise ValueError(f"rate must be > 0 keyframes per second, got {rate}")
    if not (math.isfinite(vmax) and vmax > 0):
        raise ValueError(f"vmax must be a finite colour-scale top > 0, got {vmax}")
    walkers = np.flatnonzero(moving_people(people))
    if len(walkers) == 0:
        return 0
    space = PersonalSpace.from_options(scenario.social)
    corners, _, png, alpha = personal_space_texture(space, vmax)
    step = max(1, int(round(fps / min(rate, fps))))
    frames, keys = _frame_samples(people, fps, step)
    states = [people.state_at(float(k) / fps) for k in frames]
    present = np.array([s.present for s in states])  # (F, P)
    # A pose keyframe where anyone appears or leaves, and the frame before.
    change = np.flatnonzero((present[1:] != present[:-1]).any(axis=1)) + 1
    keys[change] = True
    keys[change - 1] = True
    recording = meshcat.get_mutable_recording()
    scaled = bool(scenario.social.speed_scaling)
    for n, i in enumerate(walkers):
        node = f"{prefix}/{WALKERS}/{i}"
        vertices, faces = arrow_mesh(0.0, 0.0, 0.0, float(people.radii[i]))
        meshcat.SetTriangleMesh(f"{node}/arrow", vertices, faces, ARROW_RGBA)
        meshcat.SetObject(f"{node}/agf", textured_quad(corners, png, alpha_png=alpha, name="agf"), Rgba(1, 1, 1, 1))
        # Above the static heat map, below the path; one level per walker
        # keeps overlapping quads from flickering.
        z = FIELD_Z + (PATH_Z - FIELD_Z) * (1 + n % 16) / 18
        meshcat.SetTransform(f"{node}/agf", RigidTransform([0.0, 0.0, z]))
        set_texture_properties(meshcat, f"{node}/agf", alpha=True)
        _multiply(meshcat, f"{node}/agf")
        shown = None
        for k in frames:
            state = states[k]
            if present[k, i] != shown:
                shown = bool(present[k, i])
                recording.SetProperty(int(k), node, "visible", shown)
            if not keys[k]:
                continue
            (x, y), theta = state.positions[i], float(state.headings[i])
            recording.SetTransform(int(k), node, RigidTransform(RotationMatrix.MakeZRotation(theta), [x, y, 0.0]))
            if scaled:
                s = float(walker_sigma_h(scenario, state.speeds()[i])) / space.sigma_h
                recording.SetProperty(int(k), f"{node}/agf", "scale", [s, s, 1.0])
    meshcat.PublishRecording()
    _log.info("animated %d walking people over %d frames (a pose every %d frame(s))", len(walkers), len(frames), step)
    return len(walkers)
