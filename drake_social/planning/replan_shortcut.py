"""Shortcuts of a replan's path: fewer, longer motions where they stay safe and cost less.

The search's paths are raw RRT* paths (500 samples, no optimisation): they
zigzag, and the sequencer brings the robot to rest at every waypoint.
:func:`shortcut` walks the path greedily: from each kept waypoint it takes
the farthest of the next :data:`WINDOW` waypoints that one straight motion
reaches, accepted by the room's checker and clear of the predicted people at
its nominal times (the exact checks of the replanner's judge). The shortened
path is judged exactly and replaces the path only when it is safe and
cheaper under the objective: a shortcut never raises the cost nor comes
closer to a predicted person than the safety distance. Given the replan's
:class:`~drake_social.planning.replan_deadline.Deadline`, it checks it
before each waypoint's reach and before the exact judgement: once it has
passed, the path is returned as it was given (a shortened path is never
returned unjudged).
"""

from __future__ import annotations

import numpy as np

from drake_social.kinematics import nominal_durations
from drake_social.planning.replan_deadline import Deadline

__all__ = ["WINDOW", "shortcut"]

#: How many waypoints ahead a shortcut may reach (the farthest tried first).
WINDOW = 8


def shortcut(judge, path: np.ndarray, t0: float, evaluation, deadline: Deadline | None = None):
    """The path (N, 4) driven from ``t0``, shortened (see the module docstring).

    Args:
        judge: the replan's :class:`~drake_social.planning.replan_eval.PathJudge`.
        path: (N, 4) a safe path.
        t0: when its first waypoint is left, seconds.
        evaluation: ``judge.evaluate(path, t0)``.
        deadline: the replan's deadline (None: none).

    Returns:
        ``(path, evaluation)``: the shortened path and its exact evaluation
        when it is safe and cheaper, else the inputs (also when the
        deadline passed before the shortened path was judged).
    """
    deadline = Deadline() if deadline is None else deadline
    wp = np.asarray(path, float)
    n = len(wp)
    if n < 3:
        return path, evaluation
    keep, i, t = [0], 0, float(t0)
    ex_speed, arm_speed = judge.max_base_speed, judge.arm_max_velocity
    while i < n - 1:
        if deadline.passed():
            return path, evaluation
        ends = np.arange(min(n - 1, i + WINDOW), i, -1)  # farthest first; i + 1, the path's own motion, last
        starts = np.repeat(wp[i][None], len(ends), axis=0)
        durations = nominal_durations(starts, wp[ends], ex_speed, arm_speed)
        j, duration = i + 1, float(durations[-1])
        if len(ends) > 1:
            ok = np.asarray(judge.checker.are_motions_valid(starts[:-1], wp[ends[:-1]]), bool)
            for end, valid, d in zip(ends[:-1], ok, durations[:-1]):
                if valid and judge.people_safety.motion_clear(wp[i], wp[end], t, t + float(d)):
                    j, duration = int(end), float(d)
                    break
        t += duration
        keep.append(j)
        i = j
    if len(keep) == n:
        return path, evaluation
    if deadline.passed():
        return path, evaluation
    short = np.ascontiguousarray(wp[keep])
    ev = judge.evaluate(short, float(t0))
    if ev.safe and ev.cost < evaluation.cost:
        return short, ev
    return path, evaluation
