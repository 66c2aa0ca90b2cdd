"""Stepping aside: where the robot goes when it must not stand still.

A replan that finds no safe path would hold the robot where it is. When a
predicted person is coming within the safety distance of the robot *standing
there* before the prediction's horizon (a walker who does not see it, say),
holding is not safe either (within :data:`LOOKAHEAD` seconds: the callers
pass ``min(horizon, t_now + LOOKAHEAD)`` as the horizon). :func:`escape` then looks for a short base motion
out of the way: the base moved by :data:`ESCAPE_DISTANCES` metres in each of
:data:`ESCAPE_DIRECTIONS` directions, the arm as it is, each accepted by the
room's checker and driven at the nominal speeds.

1. **Clear escapes** first: the motion keeps clear of every predicted person
   (the exact, sound check of the replanner's paths) and the robot standing
   at its end stays clear until the horizon. The shortest is taken, and of
   those the one whose end is farthest from the people at the horizon.
2. Without one (a person already close, or coming too fast), the **best
   effort**: the escape whose least clearance over the motion and the wait
   at its end until the horizon (sampled every :data:`SAMPLE_STEP` seconds)
   is the largest, when it beats standing still by :data:`BETTER_BY`
   metres. It is not certified: it is the way out that keeps the robot
   farthest from the people as predicted.

The motion the robot is driving (``current``: the next waypoint of its
path) is a candidate too, and is preferred: clear, it is taken at once; as
a best effort, while its least clearance is within :data:`BETTER_BY` of the
best one's (so that an escape under way is not swapped every replan for
one barely better). None of either: the robot holds (and says why).

The search is anytime: given the replan's
:class:`~drake_social.planning.replan_deadline.Deadline`, it checks it
before each candidate it judges (and before each distance's candidates are
checked against the room) and, once the deadline has passed, stops with the
best escape judged so far by the rules above, or none (the robot holds).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from drake_social.planning.replan_deadline import Deadline

__all__ = ["BETTER_BY", "ESCAPE_DIRECTIONS", "ESCAPE_DISTANCES", "LOOKAHEAD", "SAMPLE_STEP", "Escape", "escape",
           "standing_clear"]

#: Directions of the base's escape motions (evenly spaced from +x).
ESCAPE_DIRECTIONS = 16
#: Lengths of the base's escape motions, metres, tried shortest first.
ESCAPE_DISTANCES = (0.4, 0.8, 1.2, 1.6)
#: Seconds between the clearance samples of a best-effort escape.
SAMPLE_STEP = 0.2
#: Metres by which a best-effort escape's least clearance must beat standing still.
BETTER_BY = 0.05
#: Seconds ahead that standing still must stay clear (at most the prediction's horizon): a
#: person predicted to reach the robot later may still turn, stop or step aside.
LOOKAHEAD = 2.0


class Escape(NamedTuple):
    """An escape motion."""

    q: np.ndarray  #: (4,) where the escape ends (the arm unchanged)
    t_end: float  #: when the robot gets there at the nominal speeds, seconds
    clearance: float  #: clear: at its end at the horizon; best effort: least over the motion and the wait (metres)
    clear: bool  #: certified clear (step 1) or a best effort (step 2)


def standing_clear(judge, q: np.ndarray, t_from: float, t_to: float) -> bool:
    """Whether the robot standing at ``q`` from ``t_from`` to ``t_to``
    keeps more than the judge's safety distance from every predicted person."""
    return bool(judge.people_safety.motion_clear(q, q, float(t_from), max(float(t_from), float(t_to))))


def _candidates(judge, space, q: np.ndarray, deadline: Deadline) -> list[tuple[np.ndarray, float]]:
    """Every escape end the room allows, with its distance, shortest first
    (the distances reached before the deadline passed)."""
    angles = 2.0 * math.pi * np.arange(ESCAPE_DIRECTIONS) / ESCAPE_DIRECTIONS
    unit = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    out = []
    for d in ESCAPE_DISTANCES:
        if deadline.passed():
            break
        ends = np.repeat(q[None], ESCAPE_DIRECTIONS, axis=0)
        ends[:, :2] += d * unit
        inside = np.asarray(space.contains(ends), bool).reshape(-1)
        if not inside.any():
            continue
        valid = np.asarray(judge.checker.are_motions_valid(np.repeat(q[None], int(inside.sum()), axis=0),
                                                           ends[inside]), bool)
        out += [(end, d) for end in ends[inside][valid]]
    return out


def _least_clearance(judge, q: np.ndarray, end: np.ndarray, t_now: float, t_end: float, t_horizon: float) -> float:
    """The least sampled clearance driving q -> end from t_now to t_end, then standing at end until t_horizon."""
    n_move = max(2, int(math.ceil((t_end - t_now) / SAMPLE_STEP)) + 1)
    u = np.linspace(0.0, 1.0, n_move)
    qs = [q + u[:, None] * (end - q)]
    ts = [t_now + u * (t_end - t_now)]
    if t_horizon > t_end:
        n_wait = max(2, int(math.ceil((t_horizon - t_end) / SAMPLE_STEP)) + 1)
        ts.append(np.linspace(t_end, t_horizon, n_wait))
        qs.append(np.repeat(end[None], n_wait, axis=0))
    return float(judge.people_safety.clearances(np.concatenate(qs), np.concatenate(ts)).min())


def escape(judge, space, q: np.ndarray, t_now: float, t_horizon: float,
           current: np.ndarray | None = None, deadline: Deadline | None = None) -> Escape | None:
    """The escape from ``q`` at ``t_now`` (see the module docstring), or None.

    Args:
        judge: the replan's :class:`~drake_social.planning.replan_eval.PathJudge`
            (its room checker, people safety and nominal timing).
        space: the configuration space (escapes end inside its bounds).
        q: (4,) the robot's configuration.
        t_now: the time now, seconds.
        t_horizon: the prediction's last time, seconds.
        current: (4,) the end of the motion being driven, or None (the
            returned escape's ``q`` is then this very array when chosen;
            left out when it is ``q`` or the room's checker rejects the motion).
        deadline: the replan's :class:`~.replan_deadline.Deadline` (None:
            none), checked before each candidate is judged: once it has
            passed, the best escape judged so far by the rules above (a
            clear one, else the best effort among those whose clearance was
            computed), or None (the robot holds); ``deadline.hit`` then
            says so.
    """
    deadline = Deadline() if deadline is None else deadline
    q = np.asarray(q, float)
    if deadline.passed():
        return None
    if current is not None and (np.array_equal(current, q)
                                or not bool(judge.checker.are_motions_valid(q[None], current[None])[0])):
        current = None  # no motion, or one the room does not allow
    if current is not None:
        t_cur = float(judge.times(np.stack([q, current]), t_now)[1])
        if (judge.people_safety.motion_clear(q, current, float(t_now), t_cur)
                and standing_clear(judge, current, t_cur, t_horizon)):
            return Escape(current, t_cur, float(judge.people_safety.clearance(current, max(t_cur, t_horizon))), True)
    ends = _candidates(judge, space, q, deadline)
    timed = []  # the candidates timed so far: all of them unless the deadline cut the clear ones
    best = None
    for end, d in ends:  # 1. clear escapes, the shortest first
        if best is not None and d > best[1]:
            break
        if deadline.passed():
            break
        t_end = float(judge.times(np.stack([q, end]), t_now)[1])
        timed.append((end, d, t_end))
        if not (judge.people_safety.motion_clear(q, end, float(t_now), t_end)
                and standing_clear(judge, end, t_end, t_horizon)):
            continue
        clearance = float(judge.people_safety.clearance(end, max(t_end, t_horizon)))
        if best is None or clearance > best[0].clearance:
            best = (Escape(end.copy(), t_end, clearance, True), d)
    if best is not None:
        return best[0]
    if deadline.passed():
        return None
    standing = _least_clearance(judge, q, q, t_now, t_now, t_horizon)  # 2. the best effort
    driving_on = None  # (t_end, least clearance) of driving on, judged first
    if current is not None and not deadline.passed():
        t_cur = float(judge.times(np.stack([q, current]), t_now)[1])
        driving_on = (t_cur, _least_clearance(judge, q, current, t_now, t_cur, t_horizon))
    effort = None
    for end, d, t_end in timed:
        if deadline.passed():
            break
        least = _least_clearance(judge, q, end, t_now, t_end, t_horizon)
        if least > standing + BETTER_BY and (effort is None or least > effort.clearance):
            effort = Escape(end.copy(), t_end, least, False)
    if driving_on is not None:
        t_cur, least = driving_on
        if least > standing + BETTER_BY and (effort is None or least >= effort.clearance - BETTER_BY):
            return Escape(current, t_cur, least, False)
    return effort
