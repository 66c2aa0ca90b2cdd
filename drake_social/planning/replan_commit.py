"""Progress and commitment: what leaving the current route costs, and waiting for it to clear.

Two rules of the replanner (:mod:`.replan`, docs/replanning.md, "Progress
and commitment"), with the time term of the judge
(:class:`~.replan_eval.PathJudge`: ``planner.time_weight`` per second a path
takes):

* **leaving the route costs** (:func:`route_deviation`): a new path pays
  ``planner.switch_weight`` per metre of its base's mean distance from the
  current path's base polyline over its first :data:`SWITCH_WINDOW`-long
  stretch of time (the replan's prediction horizon), sampled every
  :data:`SWITCH_STEP` seconds. A path along the current route (shortened,
  or the same route) pays nearly nothing; one that turns to the other side
  of an obstacle or a person pays for how far it swings away. Routes of
  about equal cost then do not take turns as the prediction moves.
* **waiting may beat a detour** (:func:`pause_steps`): when the current path
  is not safe any more, the replanner judges it driven again after a pause
  of each of these steps (shares of the safety horizon left; the robot
  standing where it is until then, clear of everyone), and waits when the cheapest such pause, at
  ``planner.time_weight`` per second waited, costs less than the search's
  path with its switching cost. A person crossing the route then makes the
  robot wait a moment, not turn round.
"""

from __future__ import annotations

import numpy as np

from drake_social.kinematics import polyline_distance

__all__ = ["PAUSE_SHARES", "SWITCH_STEP", "pause_steps", "route_deviation"]

#: Seconds between the samples of a new path at which its distance from the current route is measured.
SWITCH_STEP = 0.25
#: The pauses tried, as shares of what is left of the safety horizon where the pause begins (of
#: ``planner.safety_horizon``, at most the prediction's length, from the prediction's start): the
#: resumed path is then still checked for safety over the last quarter of that at least (and again
#: at every replan).
PAUSE_SHARES = (0.25, 0.5, 0.75)


def pause_steps(safety_horizon: float) -> tuple[float, ...]:
    """The pauses (seconds, ascending) tried before the current path is driven again, given the
    seconds of the safety horizon left where the pause begins."""
    return tuple(share * float(safety_horizon) for share in PAUSE_SHARES)


def route_deviation(path: np.ndarray, times: np.ndarray, current: np.ndarray, window: float) -> float:
    """The mean distance (metres) of ``path``'s base from ``current``'s base polyline.

    Args:
        path: (N, 4) the new path, its waypoints reached at ``times`` (N,) seconds.
        current: (K, 4) the current path (K >= 1).
        window: seconds of the new path measured, from ``times[0]`` (> 0).

    Returns:
        The mean over the new path's base positions, linear in time between
        waypoints, every :data:`SWITCH_STEP` seconds from ``times[0]`` to the
        earlier of ``times[0] + window`` and its last waypoint (both ends
        included), of their distance from the current route; 0 for a single
        waypoint on it.
    """
    wp = np.asarray(path, float).reshape(-1, 4)
    tt = np.asarray(times, float).reshape(len(wp))
    end = min(float(tt[-1]), float(tt[0]) + float(window))
    at = np.append(np.arange(float(tt[0]), end, SWITCH_STEP), end)
    points = np.column_stack([np.interp(at, tt, wp[:, 0]), np.interp(at, tt, wp[:, 1])])
    route = np.asarray(current, float).reshape(-1, 4)[:, :2]
    return float(polyline_distance(points, route).mean())
