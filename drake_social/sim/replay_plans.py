"""Replanning in the replay: the current plan as it changes, and the waits.

A replanning run logs one :class:`~drake_social.planning.replan.ReplanResult`
per replan (``SimulationResult.replans``): its simulated time ``t``, its
``waypoints`` (from the robot's configuration at ``t``; ``[q_now]`` while
waiting), whether the path ``changed`` and its ``status`` (``"initial"``,
``"new"``, ``"kept"`` or ``"wait"``). Most replans keep the path; the replay
draws each *distinct* plan once (:func:`plan_spans`):

* ``<prefix>/plans/<k>``: the k-th plan's base path as a flat ribbon (as the
  plan-once replay draws its path), visible from the plan's time until the
  next plan or wait replaces it (two ``visible`` keyframes of the Meshcat
  recording, three for all but the first);
* ``<prefix>/plans/<k>`` of a wait: a magenta ring around the base where the
  robot holds, visible while it waits.

A plan whose base does not move (fewer than 2 distinct x, y: the arm alone)
has no ribbon; it still hides the plan before it. Spans that start in the
same recording frame as the next one are never on screen and are not drawn.
A 2-minute run with 100 plan changes adds about 0.3 MB to the page (a ribbon
of a few dozen waypoints is about 1-2 kB of base64).
"""

from __future__ import annotations

import dataclasses as dc
import logging
import math
from typing import Sequence

import numpy as np
from pydrake.geometry import Meshcat, Rgba

from drake_social.scenario import Scenario
from drake_social.sim.replay_meshes import OVERLAY_PREFIX, PATH_RGBA, PATH_WIDTH, PATH_Z, ribbon_mesh

__all__ = ["PLANS", "WAIT_RGBA", "PlanSpan", "animate_plans", "path_width", "plan_spans", "ring_mesh", "show_between"]

_log = logging.getLogger(__name__)

#: Name of the plans' folder under the overlays' prefix.
PLANS = "plans"
#: Colour of the ring drawn around the base while the robot waits (magenta:
#: apart from the heat map's reds and the arm's yellows).
WAIT_RGBA = Rgba(0.75, 0.0, 0.75, 1.0)
#: Statuses of a ReplanResult (drake_social.planning.replan).
_STATUSES = ("initial", "new", "kept", "wait", "evade")


@dc.dataclass(frozen=True)
class PlanSpan:
    """One distinct plan (or wait) of a replanning run.

    Attributes:
        start: simulated time the plan (or wait) began, seconds.
        end: when the next span began, seconds (None: the last, until the end).
        waypoints: (N, 4) the plan from the robot's configuration at ``start``
            ((1, 4) for a wait: where the robot holds).
        wait: True for a wait.
        replan: index of the ReplanResult that began it in the log.
    """

    start: float
    end: float | None
    waypoints: np.ndarray
    wait: bool
    replan: int


def plan_spans(replans: Sequence) -> list[PlanSpan]:
    """The distinct plans and waits of a replanning log, in time order.

    A replan begins a new span when it is the first, when it changed the path
    (``changed``), or when it enters or leaves a wait (``status == "wait"``
    against the span before); a replan that keeps the path does not.

    Args:
        replans: ReplanResult-like records (``t``, ``waypoints``,
            ``changed``, ``status``) in time order.

    Raises:
        ValueError: times not non-decreasing, an unknown status, or waypoints
            not (N, >= 2) with N >= 1.
    """
    starts: list[tuple[float, np.ndarray, bool, int]] = []
    last_t = -math.inf
    for i, r in enumerate(replans):
        t = float(r.t)
        if not (math.isfinite(t) and t >= last_t):
            raise ValueError(f"replans[{i}].t must be finite and non-decreasing, got {t} after {last_t}")
        last_t = t
        if r.status not in _STATUSES:
            raise ValueError(f"replans[{i}].status must be one of {', '.join(_STATUSES)}, got {r.status!r}")
        wp = np.asarray(r.waypoints, float)
        if wp.ndim != 2 or len(wp) < 1 or wp.shape[1] < 2:
            raise ValueError(f"replans[{i}].waypoints must be (N, >= 2) with N >= 1, got shape {wp.shape}")
        wait = r.status == "wait"
        if not starts or bool(r.changed) or wait != starts[-1][2]:
            starts.append((t, wp, wait, i))
    ends = [s[0] for s in starts[1:]] + [None]
    return [PlanSpan(start=t, end=end, waypoints=wp, wait=wait, replan=i)
            for (t, wp, wait, i), end in zip(starts, ends)]


def path_width(scenario: Scenario) -> float:
    """Width of a path ribbon, metres: :data:`PATH_WIDTH`, at least a few
    pixels in the top view of the whole room."""
    x0, y0, x1, y1 = (float(v) for v in scenario.world.bounds)
    return max(PATH_WIDTH, max(x1 - x0, y1 - y0) / 250)


def ring_mesh(x: float, y: float, inner: float, outer: float, z: float,
              segments: int = 32) -> tuple[np.ndarray, np.ndarray]:
    """A flat annulus about (x, y) at height ``z``: vertices (3, 2 segments)
    and faces (3, 2 segments) int32, as ``Meshcat.SetTriangleMesh`` takes them."""
    if not 0 <= inner < outer:
        raise ValueError(f"ring radii must satisfy 0 <= inner < outer, got {inner}, {outer}")
    a = 2 * math.pi * np.arange(segments) / segments
    vertices = np.empty((3, 2 * segments))
    vertices[0, 0::2], vertices[1, 0::2] = x + inner * np.cos(a), y + inner * np.sin(a)
    vertices[0, 1::2], vertices[1, 1::2] = x + outer * np.cos(a), y + outer * np.sin(a)
    vertices[2] = z
    k = np.arange(segments)
    i0, o0, i1, o1 = 2 * k, 2 * k + 1, (2 * k + 2) % (2 * segments), (2 * k + 3) % (2 * segments)
    faces = np.concatenate([np.stack([i0, o0, o1]), np.stack([i0, o1, i1])], axis=1)
    return np.asfortranarray(vertices), np.asfortranarray(faces.astype(np.int32))


def _mesh(scenario: Scenario, span: PlanSpan) -> tuple[np.ndarray, np.ndarray, Rgba] | None:
    """The span's ribbon or wait ring, or None (a plan whose base stands still)."""
    xy = span.waypoints[:, :2]
    if span.wait:
        radius = float(scenario.robot.base_radius)
        width = path_width(scenario)
        return (*ring_mesh(float(xy[0, 0]), float(xy[0, 1]), radius + width, radius + 3 * width, PATH_Z), WAIT_RGBA)
    if len(np.unique(xy, axis=0)) < 2:
        return None
    return (*ribbon_mesh(xy, path_width(scenario), PATH_Z), PATH_RGBA)


def show_between(meshcat: Meshcat, node: str, first: int, last: int | None) -> None:
    """``node`` visible in the recording from frame ``first`` until frame
    ``last`` (None: the end). The static state (the page before the
    animation plays) shows it only when it begins at frame 0."""
    recording = meshcat.get_mutable_recording()
    meshcat.SetProperty(node, "visible", first == 0)
    if first > 0:
        recording.SetProperty(0, node, "visible", False)
    recording.SetProperty(first, node, "visible", True)
    if last is not None:
        recording.SetProperty(last, node, "visible", False)


def animate_plans(meshcat: Meshcat, scenario: Scenario, replans: Sequence, fps: float, *,
                  prefix: str = OVERLAY_PREFIX) -> int:
    """Draws each distinct plan and wait of ``replans`` (:func:`plan_spans`),
    visible in the recording from its time until the next one.

    Call after :func:`~drake_social.sim.replay.finish_recording` (the
    recording is published again with the keyframes);
    ``draw_overlays(..., replans=...)`` calls this itself.

    Args:
        meshcat: the run's Meshcat.
        scenario: gives the room's size (ribbon width) and the base radius.
        replans: the run's ReplanResult log (``SimulationResult.replans``).
        fps: frames per second of the recording (its frame k is at k / fps s).
        prefix: the overlays' absolute Meshcat path.

    Returns:
        The number of plans and waits drawn (nodes under ``<prefix>/plans``).
    """
    if not fps > 0:
        raise ValueError(f"fps must be > 0 frames per second, got {fps}")
    spans = plan_spans(replans)
    frames = [int(round(s.start * fps)) for s in spans]
    drawn = 0
    for k, span in enumerate(spans):
        first, last = frames[k], frames[k + 1] if k + 1 < len(spans) else None
        if last is not None and last <= first:
            continue  # replaced within the frame: never on screen
        mesh = _mesh(scenario, span)
        if mesh is None:
            continue
        node = f"{prefix}/{PLANS}/{k}"
        meshcat.SetTriangleMesh(node, *mesh)
        show_between(meshcat, node, first, last)
        drawn += 1
    meshcat.PublishRecording()
    _log.info("drew %d plan(s) and wait(s) of %d replans (%d spans)", drawn, len(replans), len(spans))
    return drawn
