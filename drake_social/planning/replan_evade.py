"""Stepping aside: where the robot goes when it must not stand still.

A replan that finds no safe path would hold the robot where it is. When a
predicted person is coming within the safety distance of the robot *standing
there* before the prediction's horizon (a walker who does not see it, say),
holding is not safe either. :func:`escape` then looks for a short base motion
out of the way: the base moved by :data:`ESCAPE_DISTANCES` metres in each of
:data:`ESCAPE_DIRECTIONS` directions, the arm as it is. An escape is usable
when the room's checker accepts the motion, the motion driven at the
nominal speeds keeps clear of every predicted person, and the robot standing
at its end stays clear until the horizon. The shortest usable escape is
taken, and of those the one whose end is farthest from the people at the
horizon; none usable: the robot holds (and says why).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["ESCAPE_DIRECTIONS", "ESCAPE_DISTANCES", "Escape", "escape", "standing_clear"]

#: Directions of the base's escape motions (evenly spaced from +x).
ESCAPE_DIRECTIONS = 16
#: Lengths of the base's escape motions, metres, tried shortest first.
ESCAPE_DISTANCES = (0.4, 0.8, 1.2, 1.6)


class Escape(NamedTuple):
    """A usable escape motion."""

    q: np.ndarray  #: (4,) where the escape ends (the arm unchanged)
    t_end: float  #: when the robot gets there at the nominal speeds, seconds
    clearance: float  #: its clearance to the people at the horizon, metres (inf: nobody considered)


def standing_clear(judge, q: np.ndarray, t_from: float, t_to: float) -> bool:
    """Whether the robot standing at ``q`` from ``t_from`` to ``t_to``
    keeps more than the judge's safety distance from every predicted person."""
    return bool(judge.people_safety.motion_clear(q, q, float(t_from), max(float(t_from), float(t_to))))


def escape(judge, space, q: np.ndarray, t_now: float, t_horizon: float) -> Escape | None:
    """The escape from ``q`` at ``t_now`` (see the module docstring), or None.

    Args:
        judge: the replan's :class:`~drake_social.planning.replan_eval.PathJudge`
            (its room checker, people safety and nominal timing).
        space: the configuration space (escapes end inside its bounds).
        q: (4,) the robot's configuration.
        t_now: the time now, seconds.
        t_horizon: the prediction's last time, seconds.
    """
    q = np.asarray(q, float)
    angles = 2.0 * math.pi * np.arange(ESCAPE_DIRECTIONS) / ESCAPE_DIRECTIONS
    unit = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    for d in ESCAPE_DISTANCES:
        ends = np.repeat(q[None], ESCAPE_DIRECTIONS, axis=0)
        ends[:, :2] += d * unit
        inside = np.asarray(space.contains(ends), bool).reshape(-1)
        valid = np.zeros(ESCAPE_DIRECTIONS, bool)
        if inside.any():
            starts = np.repeat(q[None], int(inside.sum()), axis=0)
            valid[inside] = np.asarray(judge.checker.are_motions_valid(starts, ends[inside]), bool)
        best = None
        for k in np.flatnonzero(valid):
            times = judge.times(np.stack([q, ends[k]]), t_now)
            t_end = float(times[1])
            if not judge.people_safety.motion_clear(q, ends[k], float(t_now), t_end):
                continue
            if not standing_clear(judge, ends[k], t_end, t_horizon):
                continue
            clearance = float(judge.people_safety.clearance(ends[k], max(t_end, t_horizon)))
            if best is None or clearance > best.clearance:
                best = Escape(ends[k].copy(), t_end, clearance)
        if best is not None:
            return best
    return None
