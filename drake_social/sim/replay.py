"""Meshcat recording of a run and its standalone HTML replay.

One :class:`~pydrake.geometry.Meshcat` per run, bound to localhost
(:func:`make_meshcat`). The plant's illustration geometry (robot, obstacles,
walls, people as cylinders) is drawn by a ``MeshcatVisualizer`` under
:data:`VISUALIZER_PREFIX` (:func:`add_visualizer`); what the plant does not
know is drawn by :func:`draw_overlays` under its own path
(:data:`OVERLAY_PREFIX`, never under the visualizer's prefix, which the
visualizer deletes at initialization):

* ``<prefix>/map``: the boxes of the scenario's occupancy-grid map as one
  mesh (:mod:`drake_social.sim.replay_map`; the plant gives them no
  illustration geometry);
* ``<prefix>/field``: the social-cost heat map as one textured quad (an OBJ,
  its MTL and a PNG, all in memory), emissive so that lights do not darken it;
* ``<prefix>/people/<i>``: an arrow along each person's facing ``theta``;
* ``<prefix>/path``: the planned base path as a flat ribbon (``SetLine``
  ignores its width in WebGL);
* ``<prefix>/plans/<k>`` and ``<prefix>/predicted/<k>``: with replanning,
  each plan and wait over its time, the people its replan predicted and why
  (:mod:`drake_social.sim.replay_plans`, :mod:`drake_social.sim.replay_predicted`);
* ``<prefix>/walkers/<i>``: when people walk (``draw_overlays(...,
  people=log)``), each walker's arrow and personal-space quad, animated in
  the recording (:mod:`drake_social.sim.replay_people`); the field and the
  arrows above then show the people who stand all along.

A run is recorded with :func:`start_recording` before
``Simulator.Initialize()`` and :func:`finish_recording` after the last
``AdvanceTo``; :func:`set_top_view` makes the first view a top-down map and
:func:`write_replay_html` writes ``Meshcat.StaticHtml()``, a page that opens
from disk and loads nothing from the network.
"""

from __future__ import annotations

import logging
import math
import os
import tempfile
from pathlib import Path
from typing import Sequence

import numpy as np
from pydrake.geometry import (
    Mesh,
    Meshcat,
    MeshcatParams,
    MeshcatVisualizer,
    MeshcatVisualizerParams,
    Rgba,
    Role,
    SceneGraph,
)
from pydrake.math import RigidTransform
from pydrake.systems.framework import DiagramBuilder

from drake_social.cost import SocialCost
from drake_social.people import PeopleLog, PeopleState, people_model
from drake_social.scenario import Scenario
from drake_social.world import world_model
from drake_social.sim.replay_meshes import (  # noqa: F401  (textured_quad, set_texture_properties: re-exported)
    ARROW_RGBA,
    FIELD_Z,
    OVERLAY_PREFIX,
    PATH_RGBA,
    PATH_WIDTH,
    PATH_Z,
    VISUALIZER_PREFIX,
    arrow_mesh,
    field_png,
    ribbon_mesh,
    set_texture_properties,
    textured_quad,
)
from drake_social.sim.replay_map import draw_map_mesh
from drake_social.sim.replay_pack import compact_page
from drake_social.sim.replay_people import animate_people, standing_mask, standing_people
from drake_social.sim.replay_plans import animate_plans, path_width
from drake_social.sim.replay_predicted import animate_predicted
from drake_social.viz.world import (  # noqa: F401  (FIELD_MAX_CELLS, field_resolution: re-exported)
    FIELD_MAX_CELLS,
    FIELD_MIN_RESOLUTION,
    VIEW_MARGIN,
    field_grid,
    field_resolution,
)

__all__ = [
    "FIELD_MAX_CELLS",
    "OVERLAY_PREFIX",
    "VISUALIZER_PREFIX",
    "add_visualizer",
    "animate_people",
    "animate_plans",
    "draw_overlays",
    "field_resolution",
    "finish_recording",
    "make_meshcat",
    "ribbon_mesh",
    "set_texture_properties",
    "set_top_view",
    "start_recording",
    "textured_quad",
    "top_view_frame",
    "write_replay_html",
]

_log = logging.getLogger(__name__)

def make_meshcat() -> Meshcat:
    """One Meshcat for one run, listening on localhost only (port chosen
    automatically among Drake's defaults)."""
    return Meshcat(MeshcatParams(host="localhost"))


def add_visualizer(builder: DiagramBuilder, scene_graph: SceneGraph, meshcat: Meshcat, *, fps: float) -> MeshcatVisualizer:
    """Adds a MeshcatVisualizer of the illustration geometry to ``builder``.

    Args:
        builder: the diagram builder that holds ``scene_graph``.
        scene_graph: its query port feeds the visualizer.
        meshcat: see :func:`make_meshcat`.
        fps: frames per second (> 0); the publish period is ``1 / fps`` s.

    Returns:
        The visualizer, which draws under ``/drake/`` :data:`VISUALIZER_PREFIX`.
    """
    if not fps > 0:
        raise ValueError(f"fps must be > 0 frames per second, got {fps}")
    params = MeshcatVisualizerParams(role=Role.kIllustration, publish_period=1.0 / fps, prefix=VISUALIZER_PREFIX)
    return MeshcatVisualizer.AddToBuilder(builder, scene_graph, meshcat, params)


def start_recording(meshcat: Meshcat, fps: float) -> None:
    """Starts recording ``fps`` frames per second; call before
    ``Simulator.Initialize()`` so that the first frame is recorded.

    The browser view is not updated while recording (the run is watched in
    the replay), which also keeps a long run fast.
    """
    if not fps > 0:
        raise ValueError(f"fps must be > 0 frames per second, got {fps}")
    meshcat.StartRecording(frames_per_second=fps, set_visualizations_while_recording=False)


def finish_recording(meshcat: Meshcat) -> None:
    """Stops the recording and publishes it as the page's animation."""
    meshcat.StopRecording()
    meshcat.PublishRecording()


def _field_values(scenario: Scenario, people: PeopleState | None = None) -> np.ndarray:
    """The heat map ``G`` (ny, nx) of ``people`` (None: the scenario's at
    t = 0) on :func:`field_grid` of the world's bounds, row 0 = south."""
    bounds = scenario.world.bounds
    xs, ys = field_grid(bounds, field_resolution(bounds))
    return SocialCost.from_scenario(scenario, people=people).field(xs[None, :], ys[:, None])


def _field_png(scenario: Scenario) -> bytes:
    """The heat map as PNG bytes, row 0 at the top = north (y_max), coloured
    as :func:`drake_social.viz.world.draw_social_field` colours it."""
    return field_png(_field_values(scenario))


def _field_mesh(scenario: Scenario, png: bytes | None = None) -> Mesh:
    """One quad over ``world.bounds`` at z = 0 textured with the heat map
    ``png`` (None: :func:`_field_png` of the scenario's people)."""
    return textured_quad(tuple(scenario.world.bounds), _field_png(scenario) if png is None else png)


def draw_overlays(
    meshcat: Meshcat,
    scenario: Scenario,
    waypoints: np.ndarray | None = None,
    *,
    prefix: str = OVERLAY_PREFIX,
    people: PeopleLog | None = None,
    replans: Sequence | None = None,
    predicted: Sequence = (),
) -> None:
    """Draws the heat map, the people's facing arrows and the planned path.

    The people's bodies are the plant's illustration geometry already; this
    adds what the plant does not know. Without walking people everything is
    static (not animated), so it costs the same in a replay of any length.

    Args:
        meshcat: the run's Meshcat.
        scenario: gives the bounds, the people and the social cost.
        waypoints: (N, >= 2) planned configurations (only x, y are drawn);
            None or fewer than 2 distinct points: no path.
        prefix: absolute Meshcat path of the overlays; must not be the
            visualizer's (it is cleared at initialization).
        people: where the people were over the run (call after
            :func:`finish_recording`). When someone moves (``not
            people.static``) the static heat map and arrows show only the
            people who stand all along, and the walkers get an animated
            arrow and heat-map quad each (:func:`animate_people`, at
            ``scenario.execution.replay_fps``, the recording's rate); None or
            a static log: the scenario's people at t = 0, as always.
        replans: the run's replanning log (``SimulationResult.replans``, a
            sequence of ReplanResult; call after :func:`finish_recording`):
            when not empty, each distinct plan and wait is drawn, visible
            from its time until the next (:func:`animate_plans`, at
            ``scenario.execution.replay_fps``), and ``waypoints`` is not
            drawn; None or empty: the one path ``waypoints``.
        predicted: with ``replans``, what its deciding replans predicted
            (``SimulationResult.predicted``): the predicted people of each
            plan and wait, and why it began
            (:func:`~drake_social.sim.replay_predicted.animate_predicted`).
    """
    if not prefix.startswith("/"):
        raise ValueError(f"prefix must be an absolute Meshcat path (start with '/'), got {prefix!r}")
    meshcat.Delete(prefix)
    walking = people is not None and not people.static
    if walking:
        standing, labels = standing_people(people), np.flatnonzero(standing_mask(people))
        values = _field_values(scenario, standing)
        # One colour scale for the standing field and the walkers' quads
        # (whose AGF peaks at 1): the field's top, at least 1.
        vmax = max(float(values.max()), 1.0)
        field = _field_mesh(scenario, field_png(values, vmax))
    else:
        standing = people_model(scenario).state_at(0.0)
        labels = np.arange(standing.count)
        field = _field_mesh(scenario)
    draw_map_mesh(meshcat, world_model(scenario), f"{prefix}/map")
    meshcat.SetObject(f"{prefix}/field", field, Rgba(1, 1, 1, 1))
    meshcat.SetTransform(f"{prefix}/field", RigidTransform([0.0, 0.0, FIELD_Z]))
    set_texture_properties(meshcat, f"{prefix}/field")
    # Arrows are labelled by the person's index among all the people.
    for i, (x, y), theta, radius in zip(labels, standing.positions, standing.headings, standing.radii):
        vertices, faces = arrow_mesh(float(x), float(y), float(theta), float(radius))
        meshcat.SetTriangleMesh(f"{prefix}/people/{i}", vertices, faces, ARROW_RGBA)
    replanned = replans is not None and len(replans) > 0
    if waypoints is not None and not replanned:
        xy = np.asarray(waypoints, float).reshape(len(waypoints), -1)[:, :2]
        if len(np.unique(xy, axis=0)) >= 2:
            vertices, faces = ribbon_mesh(xy, path_width(scenario), PATH_Z)
            meshcat.SetTriangleMesh(f"{prefix}/path", vertices, faces, PATH_RGBA)
        else:
            _log.warning("path of %d waypoint(s) has fewer than 2 distinct points: not drawn", len(xy))
    if walking:
        animate_people(meshcat, scenario, people, float(scenario.execution.replay_fps), prefix=prefix, vmax=vmax)
    if replanned:
        animate_plans(meshcat, scenario, replans, float(scenario.execution.replay_fps), prefix=prefix)
        if len(predicted):
            animate_predicted(meshcat, scenario, replans, predicted, float(scenario.execution.replay_fps),
                              prefix=prefix)


def top_view_frame(scenario: Scenario, *, aspect: float | None = 16 / 9,
                   margin: float | None = None) -> tuple[float, float, float, float]:
    """The region the top view shows: centre x, y and half width, half height, metres.

    It holds the walls plus ``margin`` metres (None: the larger of
    :data:`~drake_social.viz.world.VIEW_MARGIN` and 3 % of the map's longer
    side, which keeps the viewer's controls bar off the north wall), widened
    or heightened to the width / height ``aspect`` of the window (None: not,
    the walls and margin alone).
    """
    if aspect is not None and not aspect > 0:
        raise ValueError(f"aspect must be > 0 (width / height), got {aspect}")
    x0, y0, x1, y1 = (float(v) for v in scenario.world.bounds)
    if margin is None:
        margin = max(VIEW_MARGIN, 0.03 * max(x1 - x0, y1 - y0))
    pad = float(scenario.world.wall_thickness) + margin
    width, height = x1 - x0 + 2 * pad, y1 - y0 + 2 * pad
    if aspect is None:
        return (x0 + x1) / 2, (y0 + y1) / 2, width / 2, height / 2
    half_h = max(height, width / aspect) / 2
    return (x0 + x1) / 2, (y0 + y1) / 2, half_h * aspect, half_h


def set_top_view(meshcat: Meshcat, scenario: Scenario, *, aspect: float = 16 / 9,
                 margin: float | None = None) -> tuple[float, float]:
    """Makes the first view a top-down map of the whole room, north up.

    An orthographic camera frames :func:`top_view_frame` for a window of
    width / height ``aspect``. Meshcat itself keeps the frame's height and
    west edge when the window has another aspect (a narrower window would
    crop the east side); pass the returned extents to
    :func:`write_replay_html` (``fit``) and the page refits the whole room,
    centred, to any window size. Lights are set for a map (ambient plus a
    light straight above, no side lights); the floor grid and axes are
    hidden and the background is white.

    Returns:
        The half width and half height (metres, about the camera's axis) of
        the walls and the margin: what must stay in view.
    """
    cx, cy, half_w, half_h = top_view_frame(scenario, aspect=aspect, margin=margin)
    camera = Meshcat.OrthographicCamera()
    camera.left, camera.right, camera.top, camera.bottom = -half_w, half_w, half_h, -half_h
    span = 2 * max(half_w, half_h)
    camera.near, camera.far = 0.01, 4 * span + 20
    camera.zoom = 1.0
    meshcat.SetCamera(camera)
    elevation = 2 * span + 10
    # Straight down is degenerate for a z-up camera; a tilt of 1e-4 rad to the
    # south puts north at the top of the screen.
    meshcat.SetCameraPose([cx, cy - 1e-4 * elevation, elevation], [cx, cy, 0.0])
    meshcat.SetProperty("/Grid", "visible", False)
    meshcat.SetProperty("/Axes", "visible", False)
    meshcat.SetProperty("/Background/<object>", "top_color", [1.0, 1.0, 1.0])
    meshcat.SetProperty("/Background/<object>", "bottom_color", [1.0, 1.0, 1.0])
    for light in ("PointLightNegativeX", "PointLightPositiveX"):
        meshcat.SetProperty(f"/Lights/{light}", "visible", False)
    meshcat.SetProperty("/Lights/AmbientLight/<object>", "intensity", 1.6)
    meshcat.SetProperty("/Lights/FillLight/<object>", "intensity", 1.6)
    # The fill light is directional (towards the origin): put it straight above.
    meshcat.SetProperty("/Lights/FillLight/<object>", "position", [0.0, 0.0, elevation])
    return top_view_frame(scenario, aspect=None, margin=margin)[2:]


#: Appended to a replay page by write_replay_html(fit=...): it wraps the
#: viewer's ``set_camera`` and ``set_3d_pane_size`` (meshcat calls the latter
#: on load and on every resize, keeping an orthographic frame's height and
#: west edge) so that, after each, an orthographic camera frames the region
#: ``FIT`` (half width, half height about the camera's axis) centred in the
#: window, as large as it fits. The user's zoom and pan are kept (they are the
#: camera's zoom and the controls' target, not its frame).
_FIT_SCRIPT = """
<script>
(function () {
  const FIT = [__HALF_W__, __HALF_H__];
  if (typeof viewer === "undefined") return;
  function fit() {
    const camera = viewer.camera;
    if (!camera || camera.type !== "OrthographicCamera") return;
    const w = viewer.dom_element.offsetWidth, h = viewer.dom_element.offsetHeight;
    if (!(w > 0 && h > 0)) return;
    const aspect = w / h;
    const half_h = Math.max(FIT[1], FIT[0] / aspect), half_w = half_h * aspect;
    camera.left = -half_w; camera.right = half_w; camera.top = half_h; camera.bottom = -half_h;
    camera.updateProjectionMatrix();
    viewer.set_dirty();
  }
  for (const name of ["set_camera", "set_3d_pane_size"]) {
    const own = viewer[name].bind(viewer);
    viewer[name] = function (...args) { const out = own(...args); fit(); return out; };
  }
  fit();
})();
</script>
"""


def write_replay_html(meshcat: Meshcat, path: str | os.PathLike, *, fit: tuple[float, float] | None = None,
                      compact: bool = True) -> int:
    """Writes the standalone replay page ``meshcat.StaticHtml()`` to ``path``.

    With ``fit`` (half width, half height in metres, as
    :func:`set_top_view` returns them) the page keeps that region, centred,
    in view at any window size (:data:`_FIT_SCRIPT`, appended to the page;
    it acts on orthographic cameras only, so a perspective camera loaded
    into the viewer is left alone). With ``compact`` the recording's numbers
    are written as float32, as the page holds them anyway
    (:func:`drake_social.sim.replay_pack.compact_page`): the same replay in
    about 40 % fewer animation bytes. The file is written to a temporary file in the
    same folder and renamed into place, so a reader never sees half a page.

    Returns:
        The size of the page, bytes.
    """
    path = Path(path)
    text = meshcat.StaticHtml()
    if compact:
        text = compact_page(text)
    if fit is not None:
        half_w, half_h = (float(v) for v in fit)
        if not (math.isfinite(half_w) and math.isfinite(half_h) and half_w > 0 and half_h > 0):
            raise ValueError(f"fit must be two finite half extents > 0 (metres), got {fit}")
        script = _FIT_SCRIPT.replace("__HALF_W__", repr(half_w)).replace("__HALF_H__", repr(half_h))
        end = text.rfind("</body>")
        if end < 0:  # a page of another shape: the script still runs at its end
            _log.warning("Meshcat's StaticHtml() has no </body>: the fit script is appended at the end")
            end = len(text)
        text = text[:end] + script + text[end:]
    data = text.encode("utf-8")
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    _log.info("wrote %s (%.1f kB)", path, len(data) / 1e3)
    return len(data)

