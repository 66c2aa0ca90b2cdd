"""The slow-down in the replay: the robot's base coloured by what the people make it do.

:func:`animate_slow_down` adds to a run's Meshcat recording the colour of the
robot's base disc over time: its own colour (navy) while nothing limits its
speed, amber while the slow-down's speed limit is in force, red while it is
held at rest for a person (the slow-down's stop or the safety monitor's). It
animates the disc's ``material.color`` (a three.js vector track; a keyframe at
each change and one at the frame before, so that the colour switches instead
of blending), so the page shows the speed limit at work wherever the replay
is played or paused. A run whose speed was never limited nor stopped is left
as it is.
"""

from __future__ import annotations

import logging

import numpy as np
from pydrake.geometry import Meshcat

from drake_social.model.robot_model import BODY_COLOURS, MODEL_NAME
from drake_social.sim.replay_meshes import VISUALIZER_PREFIX

__all__ = ["BASE_NODE", "SLOW_DOWN_COLOURS", "animate_slow_down", "slow_down_states"]

_log = logging.getLogger(__name__)

#: The Meshcat node of the base disc's visual geometry (drawn by the run's MeshcatVisualizer).
BASE_NODE = f"/drake/{VISUALIZER_PREFIX}/{MODEL_NAME}/base/{MODEL_NAME}/base_disc0"

#: The base's colour (r, g, b) in each state of :func:`slow_down_states`: free, limited, held.
SLOW_DOWN_COLOURS = (tuple(float(c) for c in BODY_COLOURS["base"].split()[:3]), (0.95, 0.6, 0.05), (0.85, 0.1, 0.1))


def slow_down_states(run) -> np.ndarray:
    """(T,) per log sample of ``run`` (a :class:`~drake_social.sim.results.SimulationResult`):
    2 while a stop holds the robot for a person (the slow-down's or the safety monitor's),
    1 while the slow-down's speed limit is in force, else 0."""
    times = np.asarray(run.times, float)
    states = np.zeros(len(times), int)
    limit = np.asarray(getattr(run, "speed_limit", np.zeros(0)), float)
    if len(limit) == len(times):
        states[np.isfinite(limit)] = 1
    for flag in (getattr(run, "stopped", None), getattr(run, "slow_stopped", None)):
        if flag is not None and len(flag) == len(times):
            states[np.asarray(flag, bool)] = 2
    return states


def animate_slow_down(meshcat: Meshcat, run, fps: float) -> int:
    """Colours the base over the recording by :func:`slow_down_states`; returns the keyframes added.

    Args:
        meshcat: the run's Meshcat, its recording finished (its frames at ``fps``).
        run: the run's result.
        fps: the recording's frames per second.
    """
    if not fps > 0:
        raise ValueError(f"fps must be > 0 frames per second, got {fps}")
    states = slow_down_states(run)
    if not states.any():
        return 0
    if not meshcat.HasPath(BASE_NODE):
        _log.warning("the replay has no %s: the slow-down is not coloured", BASE_NODE)
        return 0
    times = np.asarray(run.times, float)
    frames = np.arange(int(np.floor(times[-1] * fps)) + 1)
    shown = states[np.clip(np.searchsorted(times, frames / fps + 1e-9, side="right") - 1, 0, len(times) - 1)]
    recording = meshcat.get_mutable_recording()
    node = f"{BASE_NODE}/<object>"
    keys = 0
    changes = np.flatnonzero(shown[1:] != shown[:-1]) + 1
    for k in [0, *changes.tolist()]:
        if k > 0:  # hold the old colour up to the frame before
            recording.SetProperty(int(k - 1), node, "material.color", list(SLOW_DOWN_COLOURS[shown[k - 1]]))
            keys += 1
        recording.SetProperty(int(k), node, "material.color", list(SLOW_DOWN_COLOURS[shown[k]]))
        keys += 1
    meshcat.PublishRecording()
    _log.info("coloured the base by the slow-down: %d changes over %d frames", len(changes), len(frames))
    return keys
