"""What the robot predicted, in the replay: the predicted people of the plan in force, and why it changed.

A replanning run keeps, for each replan that changed the path or began a
wait, a few samples of the people it predicted
(``SimulationResult.predicted``,
:class:`~drake_social.people.predicted.PredictedPeople`). For each distinct
plan or wait of the replay (:func:`~drake_social.sim.replay_plans.plan_spans`)
begun by such a replan, and visible exactly while that plan or wait is in
force (the same ``visible`` keyframes as its ribbon or ring):

* ``<prefix>/predicted/<k>/people``: one faded teal disc of the person's
  radius at each kept sample time where the person is predicted present
  (a disc at the place of the one before, within :data:`SAME_PLACE`, is
  not drawn again: a standing person is one disc), for every kept person
  but the culprit;
* ``<prefix>/predicted/<k>/culprit``: the same in orange, wider by
  :data:`CULPRIT_HALO`, for the person who made the replaced path unsafe (when the replan named one,
  :mod:`drake_social.control.replan_culprit`);
* ``<prefix>/predicted/<k>/why``: a label north of the robot, above the walls:
  the replan's time and category (:func:`~drake_social.planning.decisions.decision`),
  the culprit's name, and the replan's reason in words (at most
  :data:`LABEL_LINES` lines), as a textured quad; shown for the first
  :data:`LABEL_SECONDS` of the span (a wait's for all of it), so that it
  does not hide the room for long. The first plan has no label.

The real people are the plant's red cylinders and their heat-map quads; the
predicted discs lie flat just above the path ribbon, below the cylinders.
The labels lie above everything else (the top view is orthographic): each is
placed beside the robot, not over it.
The page grows with the plans drawn: on office_walkers (11 plans and waits
with their predictions) by 0.7 MB over the 4.3 MB without (a label is about
22 kB of base64, the discs of a span about 16 kB); a run with hundreds of
path changes adds tens of MB (at most :data:`~drake_social.control.replanner_system.MAX_PREDICTED_REPLANS`
spans have predictions).
"""

from __future__ import annotations

import io
import logging
import math
import textwrap
from typing import Sequence

import numpy as np
from matplotlib.figure import Figure
from pydrake.geometry import Meshcat, Rgba
from pydrake.math import RigidTransform

from drake_social.people.predicted import PredictedPeople
from drake_social.planning.decisions import DECISION_LABELS, decision
from drake_social.scenario import Scenario
from drake_social.sim.replay_meshes import ARROW_Z, OVERLAY_PREFIX, PATH_Z, set_texture_properties, textured_quad
from drake_social.sim.replay_plans import plan_spans, show_between

__all__ = ["CULPRIT_HALO", "CULPRIT_RGBA", "LABEL_LINES", "LABEL_SECONDS", "PREDICTED", "PREDICTED_RGBA", "SAME_PLACE",
           "animate_predicted", "disc_mesh", "label_lines", "predicted_discs"]

_log = logging.getLogger(__name__)

#: Name of the predictions' folder under the overlays' prefix.
PREDICTED = "predicted"
#: The predicted people: teal, faded (apart from the real people's red and the path's blue).
PREDICTED_RGBA = Rgba(0.0, 0.6, 0.55, 0.35)
#: The person who made the replaced path unsafe: orange, with a halo of
#: :data:`CULPRIT_HALO` metres beyond the body (seen around a standing person's cylinder).
CULPRIT_RGBA = Rgba(1.0, 0.5, 0.0, 0.75)
CULPRIT_HALO = 0.12
#: Metres within which a sample repeats the disc before it (not drawn again).
SAME_PLACE = 0.05
#: Seconds a label shows after its replan (a wait's: while it waits).
LABEL_SECONDS = 4.0
#: Lines of a label, at most (the reason is cut to fit).
LABEL_LINES = 5
_LABEL_CHARS = 72
_PREDICTED_Z = PATH_Z + 0.004
_LABEL_Z = ARROW_Z + 0.05  # above the walls, the people and the arrows (the top view is orthographic)
_DISC_SEGMENTS = 12


def disc_mesh(centres: np.ndarray, radii: np.ndarray, z: float,
              segments: int = _DISC_SEGMENTS) -> tuple[np.ndarray, np.ndarray]:
    """Flat discs (a fan each) at height ``z``: vertices (3, D (segments + 1))
    and faces (3, D segments) int32, as ``Meshcat.SetTriangleMesh`` takes them."""
    c = np.asarray(centres, float).reshape(-1, 2)
    r = np.asarray(radii, float).reshape(len(c))
    a = 2 * math.pi * np.arange(segments) / segments
    rim = c[:, None, :] + r[:, None, None] * np.stack([np.cos(a), np.sin(a)], axis=1)[None]  # (D, S, 2)
    xy = np.concatenate([c[:, None, :], rim], axis=1).reshape(-1, 2)
    vertices = np.vstack([xy.T, np.full(len(xy), z)])
    base = (segments + 1) * np.arange(len(c))[:, None]
    k = np.arange(segments)[None]
    faces = np.stack([np.broadcast_to(base, (len(c), segments)), base + 1 + k, base + 1 + (k + 1) % segments])
    return np.asfortranarray(vertices), np.asfortranarray(faces.reshape(3, -1).astype(np.int32))


def predicted_discs(predicted: PredictedPeople, person: int) -> tuple[np.ndarray, np.ndarray]:
    """The discs drawn for kept person ``person``: centres (D, 2) and the
    sample times (D,) (present samples, repeats within :data:`SAME_PLACE` dropped)."""
    centres, times = [], []
    for j in np.flatnonzero(predicted.present[:, person]):
        xy = predicted.positions[j, person]
        if centres and math.hypot(*(xy - centres[-1])) <= SAME_PLACE:
            continue
        centres.append(xy)
        times.append(predicted.times[j])
    return np.array(centres, float).reshape(-1, 2), np.array(times, float)


def label_lines(result, predicted: PredictedPeople | None) -> list[str]:
    """The lines of a replan's label: its time and category, the culprit
    (orange), and the reason wrapped (at most :data:`LABEL_LINES` lines)."""
    kind = decision(result)
    lines = [f"t = {float(result.t):.1f} s: {DECISION_LABELS[kind]}"]
    if predicted is not None and predicted.culprit >= 0:
        lines.append(f"because of {predicted.culprit_name!r} (orange: where the robot predicted them)")
    reason = textwrap.wrap(str(getattr(result, "reason", "")), _LABEL_CHARS)
    room = LABEL_LINES - len(lines)
    if len(reason) > room:
        reason = reason[:room]
        reason[-1] = reason[-1][:_LABEL_CHARS - 3] + "..."
    return lines + reason


def _label_png(lines: Sequence[str], colour: tuple) -> tuple[bytes, float]:
    """The label as PNG bytes and its width / height."""
    width, height = 6.4, 0.24 * len(lines) + 0.12
    fig = Figure(figsize=(width, height), dpi=100)
    fig.patch.set_facecolor((1.0, 1.0, 1.0))
    fig.patch.set_edgecolor(colour)
    fig.patch.set_linewidth(4.0)
    fig.text(0.012, 1 - 0.06 / height, lines[0], fontsize=11, fontweight="bold", color=colour, va="top")
    for i, line in enumerate(lines[1:], start=1):
        fig.text(0.012, 1 - (0.06 + 0.24 * i) / height, line, fontsize=9.5, color=(0.1, 0.1, 0.1), va="top")
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100, facecolor=fig.get_facecolor(), edgecolor=colour)
    return buffer.getvalue(), width / height


_KIND_COLOURS = {"unsafe": (0.85, 0.35, 0.0), "cheaper": (0.05, 0.45, 0.85), "evade": (0.6, 0.1, 0.6),
                 "wait": (0.75, 0.0, 0.75), "initial": (0.2, 0.2, 0.2), "kept": (0.2, 0.2, 0.2)}


def _label_place(scenario: Scenario, xy: np.ndarray, aspect: float) -> tuple[float, float, float, float]:
    """The label's quad: north of the robot at ``xy``, inside the room."""
    x0, y0, x1, y1 = (float(v) for v in scenario.world.bounds)
    width = min(0.45 * (x1 - x0), 9.0)
    height = width / aspect
    gap = 1.5 * float(scenario.robot.base_radius)
    left = min(max(float(xy[0]) - width / 2, x0), x1 - width)
    bottom = float(xy[1]) + gap
    if bottom + height > y1:  # no room north of the robot: south of it
        bottom = float(xy[1]) - gap - height
    bottom = min(max(bottom, y0), y1 - height)
    return left, bottom, left + width, bottom + height


def animate_predicted(meshcat: Meshcat, scenario: Scenario, replans: Sequence, predicted: Sequence, fps: float, *,
                      prefix: str = OVERLAY_PREFIX) -> int:
    """Draws the predicted people of each plan and wait begun by a replan
    with a kept prediction, and its label (see the module docstring).

    Call after :func:`~drake_social.sim.replay.finish_recording` (the
    recording is published again); ``draw_overlays(..., replans=...,
    predicted=...)`` calls this itself.

    Args:
        meshcat: the run's Meshcat.
        scenario: the room (the labels' size and place) and the robot's radius.
        replans: the run's ReplanResult log (``SimulationResult.replans``).
        predicted: its kept predictions (``SimulationResult.predicted``).
        fps: frames per second of the recording.
        prefix: the overlays' absolute Meshcat path.

    Returns:
        The number of spans drawn with their predictions (folders under ``<prefix>/predicted``).
    """
    if not fps > 0:
        raise ValueError(f"fps must be > 0 frames per second, got {fps}")
    by_replan = {int(p.replan): p for p in predicted}
    spans = plan_spans(replans)
    frames = [int(round(s.start * fps)) for s in spans]
    drawn = 0
    for k, span in enumerate(spans):
        p = by_replan.get(span.replan)
        first, last = frames[k], frames[k + 1] if k + 1 < len(spans) else None
        if p is None or (last is not None and last <= first):
            continue
        node = f"{prefix}/{PREDICTED}/{k}"
        for name, people, rgba in (("people", [i for i in range(len(p.names)) if i != p.culprit], PREDICTED_RGBA),
                                   ("culprit", [p.culprit] if p.culprit >= 0 else [], CULPRIT_RGBA)):
            halo = CULPRIT_HALO if name == "culprit" else 0.0
            discs = [(predicted_discs(p, i)[0], p.radii[i] + halo) for i in people]
            centres = np.vstack([c for c, _ in discs] + [np.zeros((0, 2))])
            if len(centres) == 0:
                continue
            radii = np.concatenate([np.full(len(c), r) for c, r in discs])
            meshcat.SetTriangleMesh(f"{node}/{name}", *disc_mesh(centres, radii, _PREDICTED_Z), rgba)
        show_between(meshcat, node, first, last)
        result = replans[span.replan]
        kind = decision(result)
        if kind != "initial":
            png, aspect = _label_png(label_lines(result, p), _KIND_COLOURS[kind])
            corners = _label_place(scenario, np.asarray(result.waypoints, float)[0, :2], aspect)
            label = f"{node}/why"
            meshcat.SetObject(label, textured_quad(corners, png, name=f"why{k}"), Rgba(1, 1, 1, 1))
            meshcat.SetTransform(label, RigidTransform([0.0, 0.0, _LABEL_Z]))
            set_texture_properties(meshcat, label)
            stop = last if span.wait else int(round((span.start + LABEL_SECONDS) * fps))
            if last is not None:
                stop = min(stop, last)
            recording = meshcat.get_mutable_recording()
            recording.SetProperty(first, label, "visible", True)
            if stop is not None and stop > first:
                recording.SetProperty(stop, label, "visible", False)
        drawn += 1
    meshcat.PublishRecording()
    _log.info("drew the predicted people of %d plan(s) and wait(s) (%d predictions kept)", drawn, len(predicted))
    return drawn
