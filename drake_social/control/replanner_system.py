"""The replanning planner as a Drake system: a first plan, then a replan every 1 / ``planner.replan_rate`` s.

:class:`ReplanningPlannerSystem` sits beside :class:`~drake_social.control.PlannerSystem`
(which plans once). An initialization event plans from the robot's
configuration to the goal against the people predicted from their state at
t = 0 (the :class:`~drake_social.planning.replan.ReplanResult` of status
``"initial"``); a periodic unrestricted update every ``1 / replan_rate``
seconds (the first one period after the start) builds the prediction
(:func:`drake_social.people.predict`: ``planner.prediction`` over
``planner.replan_horizon``) and calls the replanner with the remainder of
the current path, ``[q] + path[index:]`` (``index`` the sequencer's current
target), as its candidate. While the robot drives (no wait in force) the
motion to that target is *committed* (``commit=True``): the replan starts
where the robot will come to rest at the target, so a new path keeps the
target and the reference never bends off the judged segments. A search
tree is grown at most every ``planner.replan_search_period`` seconds while
the path stays safe (``search``), and at every replan that finds it unsafe
or follows a wait. What a replan decides:

* ``"new"`` (``changed``): its waypoints, from the robot's configuration at
  the replan, become the path and ``version`` increments (the sequencer then
  heads for the new path's waypoint 1);
* ``"kept"``: the path and version stay (the sequencer goes on where it is);
* ``"wait"``: no path is safe: ``hold`` is 1 until a later replan finds one
  (the path and version stay, so the remainder is the next candidate).

* ``"evade"`` (``changed``): no path is safe and a person is predicted to
  come within the safety distance of the robot standing still: as ``"new"``,
  with a path that first steps the base aside.

``hold`` also ends on ``"kept"``, ``"new"`` and ``"evade"``.

A new path that does not start with the motion being driven (an ``"evade"``,
or a ``"new"`` one after a wait, made from the robot's configuration) is
taken only from rest: while the ``velocity`` input is not zero (above
:data:`MOVING_SPEED`) it becomes a ``"wait"`` ("braking on the path before a
new one"), the robot brakes along the segments it is on, and a later replan
makes the way from where it stopped. Every path is then driven from rest or
continues the motion being driven, and the robot keeps to the judged
segments (a reference turning from its velocity towards a new waypoint
would leave them by up to v^2 / (2 a)).

Everything of a run is in one abstract state, an immutable
:class:`ReplanState` (the path, version, hold, the latest result, the log of
every result, the path followed so far, what the deciding replans predicted): a second context, or a cloned one,
runs on its own, and Drake's copies of the state share it instead of copying
the log. The outputs read only that state (no direct feedthrough from ``q``,
``people_state`` or ``index``): closing the loop through the sequencer and
the robot creates no algebraic loop.

Ports:

* inputs ``q`` (4: ``[x, y, psi1, psi2]``, metres, radians), ``people_state``
  (abstract :class:`~drake_social.people.PeopleState`, e.g.
  :class:`~drake_social.control.PeopleSource`'s), ``index`` (1: the
  sequencer's ``index``; unconnected = 0), ``velocity`` (4: the velocity
  of the motion being driven, the synchronized reference's; unconnected =
  at rest);
* outputs ``waypoints`` (abstract (N, 4): the path to follow, from the
  configuration at the replan that chose it to the goal; ``[q]`` (1, 4) when
  no path was ever found), ``version`` (1: 0 for the first plan, +1 at each
  change), ``hold`` (1: 1.0 while waiting), ``result`` (the latest
  ReplanResult), ``replans`` (the tuple of every ReplanResult so far, the
  first plan's included).

What the robot predicted is kept for the replay and the figures: for each
replan that changed the path (status ``"initial"``, ``"new"``, ``"evade"``)
or began a wait (``"wait"`` after a replan that did not wait), a
:class:`~drake_social.people.predicted.PredictedPeople`: the prediction it
judged against at a few times (at most 10, about 0.5 s apart or more; under
the interactive prediction the people reacting to the robot driving the path
chosen, or standing while it waits), the
16 people nearest the paths chosen and replaced, and the person who made the
replaced path unsafe (:func:`~drake_social.control.replan_culprit.culprit`),
in ``ReplanState.predicted`` (:meth:`ReplanningPlannerSystem.predictions`).
A run keeps at most :data:`MAX_PREDICTED_REPLANS` of them (the first ones):
at most 1,000 x 16 people x 10 samples, about 3 MB. Keeping them changes no
decision: the replanner is called exactly as without.

The replanner is any object with ``plan(q_now, t_now, prediction, previous,
*, replan_index, deadline, commit, search) -> ReplanResult`` (the default:
:class:`~drake_social.planning.replan.Replanner` of the scenario's replanning
options, on the room without its people; the first plan has
``planner.iterations`` samples and no deadline).

Example::

    from pydrake.systems.analysis import Simulator
    from drake_social.sim import build_diagram

    built = build_diagram(scenario, replan=True)   # the autonomy's planner is a ReplanningPlannerSystem
    simulator = Simulator(built.diagram)
    simulator.AdvanceTo(5.0)
    planner = built.autonomy.planner
    print(len(planner.replans(planner.GetMyContextFromRoot(simulator.get_context()))))  # 51
"""

from __future__ import annotations

import dataclasses as dc
import logging
import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, Context, EventStatus, LeafSystem, State

from drake_social.arguments import require_instance, require_int, require_scenario
from drake_social.control.replan_culprit import culprit
from drake_social.people import PeopleModel, PeopleState, people_model, predict
from drake_social.kinematics import nominal_path_times
from drake_social.people.interactive import InteractiveModel, InteractivePeople
from drake_social.people.predicted import predicted_people
from drake_social.planning.decisions import decision
from drake_social.scenario import Scenario, replan_rate_problem

__all__ = ["KEPT_PREDICTIONS", "MAX_PREDICTED_REPLANS", "MOVING_SPEED", "ReplanState", "ReplanningPlannerSystem",
           "replanning_summary"]

_log = logging.getLogger(__name__)

#: Speed (m/s or rad/s, any coordinate of the ``velocity`` input) above which
#: the motion being driven is under way. A reference at rest, or held at the
#: end of a stop, outputs exactly 0.
MOVING_SPEED = 1e-9
#: The statuses whose prediction is kept (a wait only when the replan before did not wait).
KEPT_PREDICTIONS = ("initial", "new", "evade", "wait")
#: Predictions kept in a run, at most (the first ones; see the module docstring).
MAX_PREDICTED_REPLANS = 1000


def _braking_first(result, q: np.ndarray):
    """``result``, a new path that does not start with the motion being
    driven, turned into a wait while the robot moves: it brakes along the
    judged segments it is on, and a later replan, from rest, takes the way."""
    return dc.replace(result, waypoints=q[None], cost=math.inf, changed=False, status="wait",
                      reason=f"braking on the path before a new one ({result.status}: {result.reason})")


def _frozen(a) -> np.ndarray:
    a = np.array(a, float).reshape(-1, 4)
    a.flags.writeable = False
    return a


@dc.dataclass(frozen=True)
class ReplanState:
    """The replanning system's whole state in a context (immutable).

    Attributes:
        path: (N, 4) the path the sequencer follows (read-only), or None
            before the first plan; with no path ever found, ``[q]`` at the
            last replan.
        planned: whether ``path`` leads to the goal (a plan was found).
        version: 0 for the first plan, +1 at each change of the path.
        hold: waiting: no safe path at the last replan.
        result: the latest ReplanResult (None before the first plan).
        log: every ReplanResult in order (the first plan's first).
        followed: (M, 4) the path followed so far: the rows of each earlier
            path up to the target it was heading for when it was replaced,
            then the current path (its row ``offset`` is the current path's row 0).
        offset: the row of ``followed`` where the current path starts.
        judged: (K, 4) the segments driven on, as one polyline: as
            ``followed``, but each replaced path kept up to and including the
            target it was heading for (the robot may have passed the point
            where the next path starts on that segment: a jerk-limited stop
            runs a little past its rest and back), then the current path;
            the executed motion's deviation is measured from it.
        judged_offset: the row of ``judged`` where the current path starts.
        searched_at: the time of the last replan that grew a search tree
            (-inf before any).
        predicted: the :class:`~drake_social.people.predicted.PredictedPeople`
            of the replans that changed the path or began a wait, in order
            (at most :data:`MAX_PREDICTED_REPLANS`).
    """

    path: np.ndarray | None = None
    planned: bool = False
    version: int = 0
    hold: bool = False
    result: object = None
    log: tuple = ()
    followed: np.ndarray | None = None
    offset: int = 0
    judged: np.ndarray | None = None
    judged_offset: int = 0
    searched_at: float = -math.inf
    predicted: tuple = ()

    # Drake clones abstract state (Value[object] deep-copies): an immutable
    # state is shared instead, so the log is never copied.
    def __copy__(self):
        return self

    def __deepcopy__(self, memo):
        return self


class ReplanningPlannerSystem(LeafSystem):
    """Plans at initialization, then replans periodically from the robot's configuration.

    Args:
        scenario: a validated scenario (goal, ``planner.replan_*`` options,
            ``planner.prediction``, safety distance, seed).
        replanner: the replanner of the first plan (``replan_index`` 0, no
            deadline) and the periodic replans (see the module docstring);
            None = :class:`~drake_social.planning.replan.Replanner` of the
            scenario on the room without its people (``planner.iterations``
            for the first plan, ``planner.replan_iterations``,
            ``replan_budget``, ``replan_margin``, ``execution.safety_distance``,
            ``random_seed``).
        people: the people model (the ``"perfect"`` prediction reads it);
            None = :func:`~drake_social.people.people_model` of the scenario.
        rate: replans per second, at most one per ``execution.control_period``;
            None = ``planner.replan_rate``.
        max_predicted: predictions kept in a run, at most (0 to
            :data:`MAX_PREDICTED_REPLANS`; see the module docstring).

    Raises:
        TypeError, ValueError: an argument of the wrong kind or value (named).

    Planning errors of the first plan (start or goal unusable) surface from
    ``Simulator.Initialize()`` (or ``ExecuteInitializationEvents``). An
    output evaluated before initialization raises a ``RuntimeError`` saying so.
    """

    def __init__(
        self,
        scenario: Scenario,
        replanner=None,
        *,
        people: PeopleModel | None = None,
        rate: float | None = None,
        max_predicted: int = MAX_PREDICTED_REPLANS,
    ):
        super().__init__()
        require_scenario(scenario, "ReplanningPlannerSystem")
        if replanner is not None and not callable(getattr(replanner, "plan", None)):
            raise TypeError(f"ReplanningPlannerSystem: replanner must have a plan(q_now, t_now, prediction, "
                            f"previous, *, replan_index, deadline, commit, search) method, "
                            f"got {type(replanner).__name__}")
        require_instance(people, PeopleModel, "ReplanningPlannerSystem", "people",
                         "a drake_social.people.PeopleModel", optional=True)
        rate = float(scenario.planner.replan_rate if rate is None else rate)
        if not (math.isfinite(rate) and rate > 0 and 1 / rate < math.inf):
            raise ValueError(f"ReplanningPlannerSystem: rate must be a finite number of replans per second > 0 "
                             f"(with a finite period), got {rate!r}")
        problem = replan_rate_problem(rate, scenario.execution)
        if problem:
            raise ValueError(f"ReplanningPlannerSystem: rate {problem}")
        if replanner is None:  # the scenario's, on the room alone (every person is the prediction's)
            from drake_social.collision.drake_checker import make_checker
            from drake_social.people import without_people
            from drake_social.planning.replan import Replanner

            replanner = Replanner(scenario, make_checker(without_people(scenario), "planar"))
        self._scenario = scenario
        self._replanner = replanner
        self._people = people_model(scenario) if people is None else people
        self._prediction = scenario.planner.prediction
        # The interactive prediction: the replanner rolls the people out per judged path from their state now.
        self._interactive = InteractiveModel.from_scenario(scenario) if self._prediction == "interactive" else None
        self._horizon = float(scenario.planner.replan_horizon)
        self._period = 1.0 / rate
        self._search_period = float(scenario.planner.replan_search_period)
        require_int(max_predicted, "ReplanningPlannerSystem", "max_predicted", minimum=0,
                    maximum=MAX_PREDICTED_REPLANS)
        self._max_predicted = int(max_predicted)

        self._q_port = self.DeclareVectorInputPort("q", 4)
        self._people_port = self.DeclareAbstractInputPort(
            "people_state", AbstractValue.Make(PeopleState(0.0, np.zeros((0, 2)), np.zeros(0), np.zeros((0, 2)),
                                                           np.zeros(0), ())))
        self._index_port = self.DeclareVectorInputPort("index", 1)
        self._velocity_port = self.DeclareVectorInputPort("velocity", 4)
        self._state_index = self.DeclareAbstractState(AbstractValue.Make(ReplanState()))
        self.DeclareInitializationUnrestrictedUpdateEvent(self._FirstPlan)
        self.DeclarePeriodicUnrestrictedUpdateEvent(self._period, self._period, self._Replan)
        # The same replan on demand (CalcForcedUnrestrictedUpdate), for tests and scripts.
        self.DeclareForcedUnrestrictedUpdateEvent(self._Replan)

        state = {self.abstract_state_ticket(self._state_index)}
        self.DeclareAbstractOutputPort("waypoints", lambda: AbstractValue.Make(np.zeros((0, 4))),
                                       self._CalcWaypoints, prerequisites_of_calc=state)
        self.DeclareVectorOutputPort("version", 1, self._CalcVersion, prerequisites_of_calc=state)
        self.DeclareVectorOutputPort("hold", 1, self._CalcHold, prerequisites_of_calc=state)
        self.DeclareAbstractOutputPort("result", lambda: AbstractValue.Make(None), self._CalcResult,
                                       prerequisites_of_calc=state)
        self.DeclareAbstractOutputPort("replans", lambda: AbstractValue.Make(()), self._CalcReplans,
                                       prerequisites_of_calc=state)

    @property
    def rate(self) -> float:
        """Replans per second."""
        return 1.0 / self._period

    @property
    def period(self) -> float:
        """Seconds between replans."""
        return self._period

    # ---- the state -------------------------------------------------------------

    def state(self, context: Context) -> ReplanState:
        """The :class:`ReplanState` in ``context`` (this system's context)."""
        return context.get_abstract_state(self._state_index).get_value()

    def replans(self, context: Context) -> tuple:
        """Every ReplanResult so far in ``context``, the first plan's first."""
        return self.state(context).log

    def predictions(self, context: Context) -> tuple:
        """What the deciding replans predicted so far in ``context`` (see :class:`ReplanState`)."""
        return self.state(context).predicted

    def followed(self, context: Context) -> np.ndarray:
        """(M, 4) the path followed so far (see :class:`ReplanState`)."""
        return self._planned(context).followed

    def judged(self, context: Context) -> np.ndarray:
        """(K, 4) the segments driven on (see :class:`ReplanState`)."""
        return self._planned(context).judged

    def _planned(self, context: Context) -> ReplanState:
        state = self.state(context)
        if state.path is None:
            raise RuntimeError(
                f"{self.get_name() or 'ReplanningPlannerSystem'}: the first path is planned at initialization; call "
                "Simulator.Initialize() or system.ExecuteInitializationEvents(context) before evaluating its outputs")
        return state

    # ---- events ----------------------------------------------------------------

    def _inputs(self, context: Context):
        q = np.array(self._q_port.Eval(context), float)
        people = self._people_port.Eval(context)
        t = context.get_time()
        now = people.at_time(t) if people.t != t else people
        prediction = predict(self._prediction, self._people, now, self._horizon, interactive=self._interactive)
        return q, t, prediction, now

    def _people_now(self, now: PeopleState) -> dict:
        """The replanner's ``people`` argument: the people now under the interactive prediction, else none."""
        return {} if self._interactive is None else {"people": now}

    def _moving(self, context: Context) -> bool:
        """Whether the motion being driven is under way: the ``velocity`` input
        (the reference's) is not zero; unconnected: at rest."""
        if not self._velocity_port.HasValue(context):
            return False
        return bool(np.any(np.abs(self._velocity_port.Eval(context)) > MOVING_SPEED))

    def _FirstPlan(self, context: Context, state: State) -> None:
        q, t, prediction, now = self._inputs(context)
        result = self._replanner.plan(q, t, prediction, None, replan_index=0, deadline=False, **self._people_now(now))
        if result.status != "wait" and result.status != "initial":
            result = dc.replace(result, status="initial")
        waiting = result.status == "wait"
        path = _frozen(result.waypoints)
        new = ReplanState(path=path, planned=not waiting, version=0, hold=waiting, result=result, log=(result,),
                          followed=path, offset=0, judged=path, judged_offset=0, searched_at=t,
                          predicted=self._kept((), result, 0, prediction, q, None, False, now))
        _log.info("first plan at t = %.2f s: %s", t, _describe(result))
        state.get_mutable_abstract_state(self._state_index).set_value(new)

    def _Replan(self, context: Context, state: State):
        old = self.state(context)
        if old.path is None:  # not initialized (a forced update before the first plan)
            raise RuntimeError(f"{self.get_name() or 'ReplanningPlannerSystem'}: replan before the first plan; "
                               "run the initialization events first")
        q, t, prediction, now = self._inputs(context)
        index = 0
        if self._index_port.HasValue(context):
            index = min(max(int(round(self._index_port.Eval(context)[0])), 0), len(old.path) - 1)
        previous = np.vstack([q[None], old.path[index:]]) if old.planned else None
        # Moving along the path (not held): the motion to the sequencer's target is committed.
        # A search while the path stays safe every replan_search_period s, and always after a wait.
        search = old.hold or t - old.searched_at >= self._search_period - 1e-9
        committed = old.planned and not old.hold
        result = self._replanner.plan(q, t, prediction, previous, replan_index=len(old.log), deadline=True,
                                      commit=committed, search=search, **self._people_now(now))
        if result.changed and (result.status == "evade" or not committed) and self._moving(context):
            result = _braking_first(result, q)
        log = old.log + (result,)
        if result.status == "wait":
            new = dc.replace(old, hold=True, result=result, log=log)
            if not old.planned:  # nothing to follow yet: stay where the robot is
                path = _frozen(result.waypoints)
                new = dc.replace(new, path=path, followed=path, judged=path)
        elif result.changed or not old.planned:
            path = _frozen(result.waypoints)
            cut = old.offset + index if old.planned else 0
            followed = np.vstack([old.followed[:cut], path]) if cut else path
            followed.flags.writeable = False
            kept = old.judged[:old.judged_offset + index + 1] if old.planned else path[:0]
            if len(kept) and np.array_equal(kept[-1], path[0]):
                kept = kept[:-1]  # the new path starts at the target: one row
            judged = np.vstack([kept, path]) if len(kept) else path
            judged.flags.writeable = False
            new = ReplanState(path=path, planned=True, version=old.version + 1, hold=False, result=result, log=log,
                              followed=followed, offset=cut, judged=judged, judged_offset=len(kept),
                              searched_at=old.searched_at)
        else:
            new = dc.replace(old, hold=False, result=result, log=log)
        if getattr(result, "searched", True):
            new = dc.replace(new, searched_at=t)
        new = dc.replace(new, predicted=self._kept(old.predicted, result, len(old.log), prediction, q, previous,
                                                   old.hold, now))
        if new.hold != old.hold or new.version != old.version:
            _log.debug("replan %d at t = %.2f s: %s", len(old.log), t, _describe(result))
        state.get_mutable_abstract_state(self._state_index).set_value(new)
        return EventStatus.Succeeded()

    def _kept(self, kept: tuple, result, index: int, prediction, q: np.ndarray, replaced: np.ndarray | None,
              waiting: bool, now: PeopleState) -> tuple:
        """``kept`` with the prediction of replan ``index`` added when it
        changed the path or began a wait (``waiting``: the replan before
        waited), within :data:`MAX_PREDICTED_REPLANS`. Under the interactive
        prediction, the people (from ``now``) reacting to the robot driving the
        path chosen, the culprit from the people reacting to the replaced path
        (:meth:`_driving`)."""
        status = result.status
        if status not in KEPT_PREDICTIONS or (status == "wait" and waiting) or len(kept) >= self._max_predicted:
            return kept
        checker = getattr(self._replanner, "checker", None)
        scene = checker.compiled_scene() if callable(getattr(checker, "compiled_scene", None)) else None
        ex = self._scenario.execution
        chosen_path = np.asarray(result.waypoints, float).reshape(-1, 4)
        shown, judged, standing = prediction, prediction, None
        if self._interactive is not None:
            shown = self._driving(now, prediction, chosen_path)
            if scene is not None and decision(result) not in ("initial", "cheaper"):  # else no culprit is sought
                standing = shown if len(chosen_path) == 1 else self._driving(now, prediction, q[None])
                judged = standing if replaced is None else self._driving(now, prediction, replaced)
        who = culprit(result, judged, replaced, q, scene, ex.max_base_speed, ex.arm_max_velocity, standing=standing,
                      safety_horizon=float(self._scenario.planner.safety_horizon))
        chosen = chosen_path[:, :2]
        near = chosen if replaced is None else np.vstack([replaced[::-1, :2], chosen])
        if len(kept) + 1 == self._max_predicted:
            _log.info("kept the predictions of %d replans: no more are kept this run", self._max_predicted)
        return kept + (predicted_people(shown, index, near=near, culprit=who),)

    def _driving(self, now: PeopleState, prediction, waypoints: np.ndarray):
        """The people of ``now`` over ``prediction``'s samples reacting to the
        robot driving ``waypoints`` (N, 4) from ``now.t`` at the execution
        limits and then holding still (the interactive prediction's rollout, as
        the replanner judges a path; (1, 4): the robot standing)."""
        ex = self._scenario.execution
        wp = np.asarray(waypoints, float).reshape(-1, 4)
        people = InteractivePeople(self._interactive, now, prediction.horizon - prediction.t0, prediction.dt)
        return people.driving(wp, nominal_path_times(wp, ex.max_base_speed, ex.arm_max_velocity, float(now.t)))[0]

    # ---- outputs ---------------------------------------------------------------

    def _CalcWaypoints(self, context: Context, output: AbstractValue) -> None:
        output.set_value(self._planned(context).path)

    def _CalcVersion(self, context: Context, output: BasicVector) -> None:
        output.SetAtIndex(0, float(self._planned(context).version))

    def _CalcHold(self, context: Context, output: BasicVector) -> None:
        output.SetAtIndex(0, 1.0 if self._planned(context).hold else 0.0)

    def _CalcResult(self, context: Context, output: AbstractValue) -> None:
        output.set_value(self._planned(context).result)

    def _CalcReplans(self, context: Context, output: AbstractValue) -> None:
        output.set_value(self.state(context).log)


def _describe(result) -> str:
    cost = "inf" if not math.isfinite(result.cost) else f"{result.cost:.4g}"
    return (f"{result.status}, cost {cost}, {result.iterations} samples in {result.plan_time * 1e3:.1f} ms"
            + (" (deadline)" if result.deadline_hit else "") + (f": {result.reason}" if result.reason else ""))


def replanning_summary(replans, rate: float, budget: float) -> dict:
    """The summary of a run's replans (``sim.json``'s ``replanning``).

    Args:
        replans: the ReplanResults in order (the first plan's first).
        rate: replans per second (``planner.replan_rate``).
        budget: seconds of one replan (``planner.replan_budget``).

    Returns:
        ``count`` (the periodic replans, the first plan excluded),
        ``changed`` (of them, those that changed the path), ``waits`` (of
        them, those that found no safe path and held the robot),
        ``evasions`` (of them, those that stepped the robot aside),
        ``searches`` (of them, those that grew a search tree),
        ``search_time_median`` (seconds of those; None without any), ``plan_time_median``,
        ``plan_time_p95``, ``plan_time_p99``, ``plan_time_max`` (seconds of
        computation of those replans: the median, the 95th and 99th
        percentiles, numpy's linear interpolation, and the largest; None
        without any), ``deadline_hits`` (those the budget cut: their search,
        judging, shortcut or evasion stopped at the deadline), ``rate``,
        ``budget``, and ``first_plan_time`` (seconds of the first plan; None
        without it).
    """
    replans = tuple(replans)
    first = [r for r in replans if r.status == "initial" or r.replan_index == 0]
    periodic = [r for r in replans if not (r.status == "initial" or r.replan_index == 0)]
    times = np.array([r.plan_time for r in periodic], float)
    searched = np.array([r.plan_time for r in periodic if getattr(r, "searched", True)], float)

    def stat(value):
        return float(value) if len(times) else None

    return {
        "count": len(periodic),
        "changed": sum(1 for r in periodic if r.changed),
        "waits": sum(1 for r in periodic if r.status == "wait"),
        "evasions": sum(1 for r in periodic if r.status == "evade"),
        "searches": len(searched),
        "search_time_median": float(np.median(searched)) if len(searched) else None,
        "plan_time_median": stat(np.median(times) if len(times) else None),
        "plan_time_p95": stat(np.percentile(times, 95) if len(times) else None),
        "plan_time_p99": stat(np.percentile(times, 99) if len(times) else None),
        "plan_time_max": stat(times.max() if len(times) else None),
        "deadline_hits": sum(1 for r in periodic if r.deadline_hit),
        "rate": float(rate),
        "budget": float(budget),
        "first_plan_time": float(first[0].plan_time) if first else None,
    }
