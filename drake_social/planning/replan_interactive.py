"""The replanner's judge under the interactive prediction: each path against the people it induces.

With ``planner.prediction: interactive`` (docs/replanning.md, "Interactive
prediction") a replan rolls out the people three ways
(:class:`~drake_social.people.interactive.InteractivePeople`, one compiled
rollout each):

* **the reference**: without the robot (what the people would do anyway);
* **the basis**: the robot drives the motion it is committed to (none when
  at rest) and then holds still. The search grows its tree against it, and
  the checks made outside the judgement (the shortcut's motions, standing
  clear, the way out of a person's path, the words of a wait) read it;
* **each judged path** (the current one, the search's best few, a shortened
  one): the robot drives the committed motion and then the path. The path's
  time-indexed cost and safety are those of :class:`~.replan_eval.PathJudge`
  against this induced prediction, its cost plus ``planner.courtesy_weight``
  times the people's effort, and it is **not safe** when it asks a person
  (:func:`~drake_social.people.interactive.demands`, against the reference)
  for a deceleration above ``planner.courtesy_deceleration`` or a deviation
  above ``planner.courtesy_deviation`` that the robot holding still (the
  basis) does not ask of them already: a robot already in someone's way is
  not frozen there by the bound, and a path that asks less of them than
  holding passes. The committed motion itself, whose cost a replan adds to
  that of the path from its end, is judged against the basis without the
  effort: the path after it counts the effort of the whole motion, once.

The replanner checks its deadline before each judged path, as for the other
predictions; a rollout costs about 0.4 ms for 10 people, 2.4 ms for 50 and
17 ms for 200 (docs/replanning.md has the measurement).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from drake_social.people.interactive import Demands, InteractivePeople, demands
from drake_social.people.prediction import Prediction
from drake_social.planning.replan_eval import PathEvaluation, PathJudge

__all__ = ["InteractiveJudge"]

#: Demands within this of the basis's count as no more than holding still asks (rounding).
_SAME = 1e-9


class InteractiveJudge(PathJudge):
    """Judges each path against the prediction it induces (see the module docstring).

    Args:
        make_judge: ``prediction -> PathJudge`` (the replanner's :meth:`~.replan.Replanner.judge`).
        people: the people now, packed for rollouts over the replan's horizon.
        prefix: (M, 4) the committed motion's waypoints (M = 1: none, the robot at rest there).
        t_now: when the committed motion starts, seconds.
        deceleration: ``planner.courtesy_deceleration``, m/s^2.
        deviation: ``planner.courtesy_deviation``, metres.
        weight: ``planner.courtesy_weight``.
    """

    def __init__(self, make_judge: Callable[[Prediction], PathJudge], people: InteractivePeople,
                 prefix: np.ndarray, t_now: float, deceleration: float, deviation: float, weight: float) -> None:
        self.make_judge = make_judge
        self.rollouts = people  #: the people now, packed for rollouts
        self.reference, self._reference_velocities = people.rollout(None)
        base = make_judge(self.reference)  # the limits that time a path
        self.prefix = np.ascontiguousarray(prefix, float).reshape(-1, 4)
        self.prefix_times = base.times(self.prefix, float(t_now))
        basis, velocities = people.driving(self.prefix, self.prefix_times)
        self.holding = demands(basis, velocities, self.reference, self._reference_velocities)
        self.deceleration = float(deceleration)
        self.deviation = float(deviation)
        self.weight = float(weight)
        judge = make_judge(basis)
        super().__init__(judge.objective, judge.social, judge.checker, basis, judge.safety, judge.max_base_speed,
                         judge.arm_max_velocity, safety_horizon=judge.safety_horizon, time_weight=judge.time_weight)

    def motion(self, waypoints: np.ndarray, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The robot's whole motion when it drives ``waypoints`` at ``times``: the committed motion first
        when the path starts where it ends, when it ends (or later: the robot stands there until then)."""
        if len(self.prefix) > 1 and np.array_equal(waypoints[0], self.prefix[-1]):
            pause = float(times[0]) - float(self.prefix_times[-1])
            if abs(pause) <= 1e-9:
                return np.vstack([self.prefix[:-1], waypoints]), np.concatenate([self.prefix_times[:-1], times])
            if pause > 0.0:
                return np.vstack([self.prefix, waypoints]), np.concatenate([self.prefix_times, times])
        return waypoints, times

    def induced(self, waypoints: np.ndarray, t0: float) -> tuple[Prediction, Demands]:
        """The people when the robot drives ``waypoints`` from ``t0``, and what that asks of them."""
        wp = np.ascontiguousarray(waypoints, float)
        prediction, velocities = self.rollouts.driving(*self.motion(wp, self.times(wp, t0)))
        return prediction, demands(prediction, velocities, self.reference, self._reference_velocities)

    def courtesy_words(self, asked: Demands) -> str:
        """Why ``asked`` is too much (the worst person, relative to the bound), empty when it is not."""
        names = self.rollouts.state.names
        worst, words = 1.0, ""
        for values, held, bound, say in (
                (asked.deceleration, self.holding.deceleration, self.deceleration,
                 lambda i, v: f"{names[i] or f'person {i}'} would have to brake at {v:.2f} m/s^2, more than "
                              f"planner.courtesy_deceleration {self.deceleration:g} m/s^2"),
                (asked.deviation, self.holding.deviation, self.deviation,
                 lambda i, v: f"{names[i] or f'person {i}'} would be moved {v:.2f} m off their way, more than "
                              f"planner.courtesy_deviation {self.deviation:g} m")):
            over = (values > bound) & (values > held + _SAME)
            if over.any():
                ratio = np.where(over, values / bound, 0.0)
                i = int(np.argmax(ratio))
                if ratio[i] > worst:
                    worst, words = float(ratio[i]), "courtesy: " + say(i, float(values[i]))
        return words

    def is_committed(self, waypoints: np.ndarray, t0: float) -> bool:
        """``waypoints`` driven from ``t0`` are the committed motion itself (the motion the basis drives)."""
        return (len(self.prefix) > 1 and waypoints.shape == self.prefix.shape and np.array_equal(waypoints, self.prefix)
                and abs(float(t0) - float(self.prefix_times[0])) <= 1e-9)

    def evaluate(self, waypoints: np.ndarray, t0: float) -> PathEvaluation:
        """The path's exact cost and safety against the people it induces, its courtesy and effort.

        The committed motion alone is judged against the basis (the people
        it induces) without the effort: every path from its end is judged
        with the committed motion before it, the effort of the whole motion
        in its cost, and a replan adds the two costs (so it counts the
        effort once). It asks nothing beyond what holding still asks."""
        wp = np.ascontiguousarray(waypoints, float)
        if len(wp) < 2 or self.is_committed(wp, t0):
            return super().evaluate(wp, t0)
        prediction, asked = self.induced(wp, t0)
        ev = self.make_judge(prediction).evaluate(wp, t0)
        return ev._replace(cost=ev.cost + self.weight * asked.effort, courtesy=self.courtesy_words(asked),
                           effort=asked.effort)
