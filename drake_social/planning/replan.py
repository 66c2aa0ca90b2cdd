"""Anytime replanning among walking people: one replan from where the robot is.

A :class:`Replanner` plans from the robot's configuration ``q_now`` at time
``t_now`` to the scenario's goal against a
:class:`~drake_social.people.prediction.Prediction` of the people
(docs/replanning.md has the design):

1. the **candidate** is the remainder of the path being driven (``previous``),
   judged exactly under the new prediction (:mod:`.replan_eval`): its
   time-indexed cost and whether it is still safe;
2. a **search** (the compiled RRT* in its timed mode, seeded with the
   candidate as a chain from the root) runs until ``budget`` seconds of wall
   clock or ``iterations`` samples, whichever comes first;
3. the search's best few goal connections (in ascending tree cost) are
   **judged exactly** (the tree's costs of rewired subtrees are approximate:
   their times moved);
4. the best safe search path (the cheapest with its cost of leaving the
   current route, :mod:`.replan_commit`) **replaces** the candidate only
   when it is cheaper by the margin with that cost (``cost_new + switch <
   (1 - margin) cost_candidate``), or the candidate is no longer safe and no
   short pause makes it safe for less; a safe candidate is kept otherwise;
   an unsafe one is waited for (a pause) or, when nothing is safe, the
   robot **waits**, with the reason in words. Every judged cost
   includes ``planner.time_weight`` per second of the path.

Every stage keeps to ``budget`` (:mod:`.replan_deadline`): the search
stops early enough to leave time for the judgement (and for a way out of a
person's path when one may be needed, :data:`EVADE_RESERVE`), and the
judgement, the shortcut and the evasion check the deadline between small
chunks, keeping the best answer judged by then.

Every random choice comes from ``numpy.random.default_rng([seed,
replan_index])``: a replan whose search stopped at the iteration cap is
reproducible bit for bit; one stopped by the wall clock (``deadline_hit``)
depends on the machine.

The replanner never builds a checker itself (planning sits below the
checkers in the import layers): the caller passes the room's checker,
``make_checker(without_people(scenario), "planar")``; the people are the
prediction's alone.
"""

from __future__ import annotations

import dataclasses as dc
import math
import time
from typing import NamedTuple

import numpy as np

from drake_social.arguments import real_array, require_checker, require_instance, require_int, require_number, \
    require_scenario
from drake_social.collision.validity import CompiledSceneChecker
from drake_social.cost.social import SocialCost
from drake_social.limits import MAX_ITERATIONS, MAX_REPLAN_BUDGET, MAX_REPLAN_ITERATIONS
from drake_social.people import people_model
from drake_social.people.interactive import InteractiveModel, InteractivePeople
from drake_social.people.model import PeopleState
from drake_social.people.prediction import Prediction
from drake_social.planning.algorithms import AlgorithmSpec, algorithm_spec, base_only_weights, make_objective
from drake_social.planning.replan_commit import pause_steps, route_deviation
from drake_social.planning.replan_deadline import Deadline
from drake_social.planning.replan_eval import VERIFY_PATHS, PathEvaluation, PathJudge
from drake_social.planning.replan_evade import LOOKAHEAD, escape, standing_clear
from drake_social.planning.replan_interactive import InteractiveJudge
from drake_social.planning.replan_search import SearchSetup, run_search, search_planner
from drake_social.planning.replan_shortcut import shortcut
from drake_social.planning.rrt_star import compiled
from drake_social.planning.space import ConfigurationSpace

__all__ = ["EVADE_RESERVE", "FINISH_RESERVE", "INTERACTIVE_VERIFY_RESERVE", "REPLAN_STATUSES", "ReplanResult",
           "Replanner", "VERIFY_PATHS", "VERIFY_RESERVE"]

#: Values of :attr:`ReplanResult.status`.
REPLAN_STATUSES = ("initial", "new", "kept", "wait", "evade")
#: The statuses that change the path to drive.
CHANGES = ("initial", "new", "evade")
#: Fraction of the budget kept for the exact judgement after the search.
VERIFY_RESERVE = 0.1
#: ... under the interactive prediction, where judging a path rolls the people out first
#: (:mod:`.replan_interactive`): measured on lobby_crowd.yaml, 10 % left p99 at 84 ms of an 80 ms budget.
INTERACTIVE_VERIFY_RESERVE = 0.3
#: ... and, when the current path is not safe and the robot standing still would not be either
#: (the replan may end in a way out, :mod:`.replan_evade`), the fraction kept for the evasion.
EVADE_RESERVE = 0.3
#: Fraction of the budget kept for the last chunk of work started before the deadline and the result:
#: the stages after the search stop at the budget less this.
FINISH_RESERVE = 0.05


@dc.dataclass(frozen=True, eq=False)
class ReplanResult:
    """What one replan decided.

    Attributes:
        t: the replan's time (``t_now``), seconds.
        waypoints: (N, 4) the path to drive from ``q_now`` (its first row) to
            the goal; ``[q_now]`` (1, 4) while waiting.
        cost: the exact time-indexed objective cost of ``waypoints``; inf
            when waiting, and for a way out of a person's path that is not
            safe itself ("evade", or "kept" to drive on: standing still was
            predicted worse).
        changed: the path to drive is a new one (status "new", "evade" or "initial");
            False when the candidate is kept and while waiting (the caller
            holds the robot; its last path stays the one to resume).
        status: "initial" (the first plan, ``replan_index`` 0), "new" (the
            search's path replaced the candidate), "kept" (the candidate
            stays), "wait" (the robot holds: nothing is safe, or a pause
            before the current path costs less than a new one,
            :mod:`.replan_commit`), "evade" (nothing safe, and a person is predicted to come within the safety
            distance of the robot standing still: the path steps the base
            aside first, :mod:`.replan_evade`, then comes back to the
            current path).
        reason: why, in words.
        plan_time: wall-clock seconds of the whole replan (judging, search,
            judging again).
        iterations: samples the search drew.
        deadline_hit: the wall-clock budget cut the replan: the search
            stopped before the iteration cap, or the judgement of its paths,
            their shortcut or the search for a way out (evasion) stopped
            before it was done, with the best answer judged by then (the
            result then depends on the machine's speed).
        candidate_cost: the candidate's exact cost when it is safe, inf when
            there is none or it is not safe.
        search_cost: the exact cost of the best safe search path judged, inf
            when none.
        replan_index: the replan's index (0: the initial plan).
        searched: the search tree was grown (False: the candidate was only
            judged and kept, or the robot waits on an unsafe committed motion).
    """

    t: float
    waypoints: np.ndarray
    cost: float
    changed: bool
    status: str
    reason: str
    plan_time: float
    iterations: int
    deadline_hit: bool
    candidate_cost: float
    search_cost: float
    replan_index: int
    searched: bool = False

    def __post_init__(self) -> None:
        if self.status not in REPLAN_STATUSES:
            raise ValueError(f"ReplanResult.status must be one of {', '.join(REPLAN_STATUSES)}, got {self.status!r}")
        wp = np.array(self.waypoints, float).reshape(-1, 4)
        wp.flags.writeable = False
        object.__setattr__(self, "waypoints", wp)

    def __eq__(self, other) -> bool:
        """Equal fields, the waypoints bit for bit (``plan_time`` too: it is
        wall-clock time, so two runs' results rarely compare equal)."""
        if not isinstance(other, ReplanResult):
            return NotImplemented
        return all(np.array_equal(getattr(self, f.name), getattr(other, f.name)) if f.name == "waypoints"
                   else getattr(self, f.name) == getattr(other, f.name) for f in dc.fields(self))

    __hash__ = None  # holds an array

    @property
    def waiting(self) -> bool:
        """Whether the robot is to hold position."""
        return self.status == "wait"

    def to_record(self) -> dict:
        """The log's row (``replans.csv``): t, plan_time, cost (None when
        infinite), changed, status, searched, iterations, deadline_hit, reason."""
        return {"t": float(self.t), "plan_time": float(self.plan_time),
                "cost": float(self.cost) if math.isfinite(self.cost) else None, "changed": bool(self.changed),
                "status": self.status, "searched": bool(self.searched), "iterations": int(self.iterations),
                "deadline_hit": bool(self.deadline_hit), "reason": self.reason}


class Replanner:
    """Plans from where the robot is, again and again, among predicted people.

    Args:
        scenario: a validated :class:`~drake_social.scenario.Scenario` (its
            goal, planner, social and execution sections); the objective
            adds ``planner.replan_length_weight`` to ``social.length_weight``
            (:attr:`scenario` is that copy).
        checker: the room's checker, without people:
            ``make_checker(without_people(scenario), "planar")`` (a checker
            with a compiled scene: the compiled search and the people's
            safety check read its planar scene). Every person, standing or
            walking, is the prediction's.
        algorithm: a name of :data:`~drake_social.planning.algorithms.ALGORITHM_SPECS`
            or a spec; None = ``scenario.planner.algorithm``.
        iterations: samples per replan at most (at most
            :data:`~drake_social.limits.MAX_REPLAN_ITERATIONS`); None = ``planner.replan_iterations``.
        budget: wall-clock seconds per replan (at most
            :data:`~drake_social.limits.MAX_REPLAN_BUDGET`); None = ``planner.replan_budget``.
        margin: the fraction by which a search path must be cheaper than the
            candidate to replace it, in [0, 1); None = ``planner.replan_margin``.
        safety: the smallest allowed surface distance from any part of the
            robot to a predicted person's body, metres (>= 0); None =
            ``execution.safety_distance``.
        seed: the seed of every replan's generator (with the replan's index);
            None = ``scenario.random_seed``.
        initial_iterations: samples of the initial plan (``replan_index`` 0,
            no deadline); None = ``planner.iterations``.
        lookahead: seconds ahead that the robot standing still must stay
            clear of predicted people, else it steps aside
            (:mod:`.replan_evade`; default
            :data:`~drake_social.planning.replan_evade.LOOKAHEAD`).

    Raises:
        TypeError: an argument of the wrong kind (a checker without a
            compiled scene included), named.
        ValueError: a value out of range, an unknown algorithm, or a checker
            built on a scenario with people in it.
    """

    def __init__(self, scenario, checker, algorithm: str | AlgorithmSpec | None = None, *,
                 iterations: int | None = None, budget: float | None = None, margin: float | None = None,
                 safety: float | None = None, seed: int | None = None, initial_iterations: int | None = None,
                 lookahead: float = LOOKAHEAD):
        who = "Replanner"
        require_scenario(scenario, who)
        require_checker(checker, who)
        if not isinstance(checker, CompiledSceneChecker):
            raise TypeError(f"{who}: checker must have a compiled scene (compiled_scene(), e.g. "
                            f"make_checker(without_people(scenario), 'planar')), got {type(checker).__name__}")
        room = getattr(checker, "scenario", None)
        if room is not None and people_model(room).count > 0:
            raise ValueError(f"{who}: checker must be built on the room without people "
                             "(make_checker(without_people(scenario), 'planar')): the replanner checks people "
                             "against their prediction, not as static discs")
        p = scenario.planner
        require_int(iterations, who, "iterations", minimum=1, maximum=MAX_REPLAN_ITERATIONS, optional=True)
        require_int(initial_iterations, who, "initial_iterations", minimum=1, maximum=MAX_ITERATIONS, optional=True)
        require_number(budget, who, "budget", positive=True, optional=True, unit="seconds")
        if budget is not None and budget > MAX_REPLAN_BUDGET:
            raise ValueError(f"{who}: budget must be in (0, {MAX_REPLAN_BUDGET:g}] seconds, got {budget}")
        require_number(margin, who, "margin", optional=True)
        require_number(safety, who, "safety", optional=True, unit="metres")
        require_int(seed, who, "seed", minimum=0, optional=True)
        require_number(lookahead, who, "lookahead", positive=True, unit="seconds")
        margin = p.replan_margin if margin is None else float(margin)
        if not 0.0 <= margin < 1.0:
            raise ValueError(f"{who}: margin must be in [0, 1), got {margin}")
        safety = scenario.execution.safety_distance if safety is None else float(safety)
        if not safety >= 0.0:
            raise ValueError(f"{who}: safety must be >= 0 metres, got {safety}")
        # The replanner's objective: the scenario's, with planner.replan_length_weight added to its length weight.
        social = scenario.social
        scenario = dc.replace(scenario, social=dc.replace(
            social, length_weight=float(social.length_weight) + float(p.replan_length_weight)))
        self.scenario = scenario
        self.checker = checker
        self.spec = algorithm_spec(p.algorithm if algorithm is None else algorithm, who)
        self.iterations = p.replan_iterations if iterations is None else int(iterations)
        self.initial_iterations = p.iterations if initial_iterations is None else int(initial_iterations)
        self.budget = p.replan_budget if budget is None else float(budget)
        self.margin = margin
        self.safety = safety
        #: seconds of a prediction over which paths must keep the safety distance (planner.safety_horizon)
        self.safety_horizon = float(scenario.planner.safety_horizon)
        #: cost per second a path takes, and per metre a new path swings from the current route (.replan_commit)
        self.time_weight = float(p.time_weight)
        self.switch_weight = float(p.switch_weight)
        self.horizon = float(p.replan_horizon)
        self.lookahead = float(lookahead)
        self.seed = scenario.random_seed if seed is None else int(seed)
        self.goal = np.asarray(scenario.goal, float)
        self.space = ConfigurationSpace.from_scenario(scenario)
        #: The static objective: its weights, length weight and distance weights (the search's is per prediction).
        self.objective = make_objective(scenario, self.spec)
        self._weights = None if self.spec.objective == "length" else (
            base_only_weights(self.objective.social.geometry.num_interest_points)
            if self.spec.weights == "base_only" else None)
        #: What every search reads: the RRT* (compiled, timed mode; its objective per prediction) and the rest.
        self.search = SearchSetup(search_planner(p, self.spec, self.space, checker, self.objective), self.goal,
                                  scenario.execution, safety, self.objective, float(scenario.social.length_weight),
                                  self.safety_horizon)
        #: The world of the interactive prediction's rollouts (None for the other predictions).
        self.interactive = InteractiveModel.from_scenario(scenario) if p.prediction == "interactive" else None
        supported, why = compiled.compiled_support(checker, self.objective, self.search.planner.options)
        if not supported:
            raise ValueError(f"{who}: the replanner's search runs the compiled tree loop only, and it cannot: {why}")

    # ---- judging -------------------------------------------------------------

    def social_for(self, prediction: Prediction) -> SocialCost | None:
        """The time-indexed social cost of this prediction (None for the length objective)."""
        if self.spec.objective == "length":
            return None
        return SocialCost.for_prediction(self.scenario, prediction, weights=self._weights)

    def judge(self, prediction: Prediction) -> PathJudge:
        """The exact judge of paths under ``prediction`` (:class:`~.replan_eval.PathJudge`)."""
        ex = self.scenario.execution
        return PathJudge(self.objective, self.social_for(prediction), self.checker, prediction, self.safety,
                         ex.max_base_speed, ex.arm_max_velocity, safety_horizon=self.safety_horizon,
                         time_weight=self.time_weight)

    def evaluate(self, waypoints: np.ndarray, t0: float, prediction: Prediction) -> PathEvaluation:
        """A path's exact nominal times, time-indexed cost and safety.

        Args:
            waypoints: (N, 4) configurations, N >= 1.
            t0: the time the first waypoint is left, seconds.
            prediction: the people.

        Returns:
            A :class:`~.replan_eval.PathEvaluation` (``times``, ``cost``,
            ``social``, ``length``, ``static_bad``, ``people_bad``, ``safe``).

        Raises:
            TypeError, ValueError: an argument of the wrong kind or shape, named.
        """
        who = "Replanner.evaluate"
        wp = real_array(waypoints, who, "waypoints", (None, 4), layout="rows [x, y, psi1, psi2]", rows=(1, None),
                        row_name="waypoint")
        require_number(t0, who, "t0", unit="seconds")
        require_instance(prediction, Prediction, who, "prediction", "a drake_social.people.Prediction")
        return self.judge(prediction).evaluate(wp, float(t0))

    # ---- one replan ------------------------------------------------------------

    def plan(self, q_now: np.ndarray, t_now: float, prediction: Prediction, previous: np.ndarray | None = None, *,
             replan_index: int, deadline: bool | None = None, commit: bool = False,
             search: bool = True, people: PeopleState | None = None) -> ReplanResult:
        """One replan from ``q_now`` at ``t_now`` (see the module docstring).

        Args:
            q_now: (4,) the robot's configuration now.
            t_now: the time now, seconds (the path's first waypoint is left then).
            prediction: the people over the horizon.
            previous: the remainder of the path being driven, from ``q_now``
                to the goal: ``[q_now] + old[index:]`` (N, 4); ``q_now`` is
                put in front when its first row differs, and a row equal to
                the one before it is dropped. None, or a single
                row (a wait), is no candidate. While waiting, pass the path
                waited on: it is kept again once it is safe.
            replan_index: 0 for the initial plan (``initial_iterations``
                samples, no deadline, status "initial"), then 1, 2, ...; it
                seeds the generator with the replanner's seed.
            deadline: hold the replan to ``budget`` seconds of wall clock:
                the search stops at the budget less :data:`VERIFY_RESERVE`
                of it (:data:`INTERACTIVE_VERIFY_RESERVE` under the
                interactive prediction), kept for judging the search's paths (less
                :data:`EVADE_RESERVE` too when the current path is not safe
                and standing still would not be either), and the work after
                it (judging, shortcut, evasion) stops at the budget less
                :data:`FINISH_RESERVE` with the best answer judged by then;
                None = for every replan but the initial one.
            commit: the robot is moving towards ``previous``'s second row
                and will reach it at rest (the sequencer's target): that
                motion is kept as it is and the replan is made from its end,
                at the time the robot gets there. Every path then starts
                with it, so a new path takes over where the reference comes
                to rest and the robot drives exactly the segments judged. When
                the committed motion is not safe any more, the robot waits
                (it holds where it is; the next replan starts from rest).
            search: grow the search tree; False only judges the candidate and
                keeps it when it is safe (the tree is grown anyway when it is
                not, or when there is none).
            people: the people now (at ``t_now``); required when
                ``planner.prediction`` is "interactive", read only then: each
                judged path is judged against the people it induces, rolled
                out over ``prediction``'s samples, and the search grows its
                tree against the people with the robot holding still after
                its committed motion (:mod:`.replan_interactive`).

        Returns:
            A :class:`ReplanResult`.

        Raises:
            TypeError, ValueError: an argument of the wrong kind, shape or
                value (``previous`` not ending at the goal), named.
        """
        t_start = time.perf_counter()
        who = "Replanner.plan"
        q = real_array(q_now, who, "q_now", (4,), layout="[x, y, psi1, psi2]")
        require_number(t_now, who, "t_now", unit="seconds")
        require_instance(prediction, Prediction, who, "prediction", "a drake_social.people.Prediction")
        require_int(replan_index, who, "replan_index", minimum=0)
        require_instance(deadline, bool, who, "deadline", "True or False", optional=True)
        require_instance(commit, bool, who, "commit", "True or False")
        require_instance(search, bool, who, "search", "True or False")
        t_now = float(t_now)
        initial = replan_index == 0
        use_deadline = (not initial) if deadline is None else deadline
        reserve = VERIFY_RESERVE if self.interactive is None else INTERACTIVE_VERIFY_RESERVE
        clock = Deadline(t_start + self.budget * (1.0 - FINISH_RESERVE),
                         t_start + self.budget * (1.0 - reserve)) if use_deadline else Deadline()
        candidate = self._candidate(q, previous, who)
        committed = commit and candidate is not None and len(candidate) >= 2 and not initial
        if self.interactive is not None:
            require_instance(people, PeopleState, who, "people", "a drake_social.people.PeopleState (the "
                             "interactive prediction rolls the people out from their state now)")
            judge = self.interactive_judge(people, t_now, prediction, candidate[:2] if committed else q[None])
            prediction = judge.prediction
        else:
            judge = self.judge(prediction)
        if committed:
            return self._plan_committed(q, t_now, prediction, candidate, judge, t_start, replan_index, clock, search)
        return self._plan_from(q, t_now, prediction, candidate, judge, t_start, replan_index, clock, search)

    def interactive_judge(self, people: PeopleState, t_now: float, prediction: Prediction,
                           prefix: np.ndarray) -> InteractiveJudge:
        """The judge of the interactive prediction (:class:`~.replan_interactive.InteractiveJudge`).

        Args:
            people: the people now.
            t_now: the time now, seconds.
            prediction: gives the samples (its ``dt`` and horizon); the people
                are rolled out from ``people``.
            prefix: (M, 4) the committed motion from the robot's configuration
                (M = 1: none).
        """
        p = self.scenario.planner
        state = people if people.t == t_now else people.at_time(t_now)
        packed = InteractivePeople(self.interactive, state, prediction.horizon - prediction.t0, prediction.dt)
        return InteractiveJudge(self.judge, packed, prefix, t_now, p.courtesy_deceleration, p.courtesy_deviation,
                                p.courtesy_weight)

    def _plan_committed(self, q: np.ndarray, t_now: float, prediction: Prediction, candidate: np.ndarray,
                        judge: PathJudge, t_start: float, replan_index: int, clock: Deadline,
                        search: bool) -> ReplanResult:
        """A replan from the end of the committed motion ``candidate[0] -> candidate[1]``."""
        head = judge.evaluate(candidate[:2], t_now)
        if not head.safe:
            held = ReplanResult(t_now, q[None], math.inf, False, "wait",
                                f"waiting: the motion being driven is not safe any more ({judge.unsafe_words(head)})",
                                time.perf_counter() - t_start, 0, False, math.inf, math.inf, int(replan_index))
            return self._hold_or_evade(held, q, t_now, judge, prediction, candidate, t_start, clock)
        rest = self._plan_from(candidate[1], float(head.times[1]), prediction, candidate[1:], judge, t_start,
                               replan_index, clock, search, head_cost=float(head.cost), robot=(q, t_now))
        if rest.waiting or rest.status == "evade":
            t_b = float(head.times[1])
            if rest.waiting and standing_clear(judge, candidate[1], t_b, min(prediction.horizon,
                                                                             t_b + self.lookahead)):
                # Nothing safe from the motion's end, but the robot may stand there: it drives on and waits there.
                return dc.replace(rest, t=t_now, waypoints=candidate, status="kept", cost=math.inf,
                                  reason=rest.reason.replace("waiting:", "driving on to the end of the motion "
                                                             "being driven, to wait there:", 1),
                                  plan_time=time.perf_counter() - t_start)
            why = rest.reason.replace("waiting:", "waiting: from the end of the motion being driven,", 1) \
                if rest.waiting else "waiting: standing at the end of the motion being driven would not be safe"
            held = dc.replace(rest, t=t_now, waypoints=q[None], status="wait", changed=False, cost=math.inf,
                              reason=why, plan_time=time.perf_counter() - t_start)
            return self._hold_or_evade(held, q, t_now, judge, prediction, candidate, t_start, clock)
        cost = head.cost
        return dc.replace(rest, t=t_now, waypoints=np.vstack([q[None], rest.waypoints]), cost=cost + rest.cost,
                          candidate_cost=cost + rest.candidate_cost, search_cost=cost + rest.search_cost,
                          plan_time=time.perf_counter() - t_start)

    def _plan_from(self, q: np.ndarray, t_now: float, prediction: Prediction, candidate: np.ndarray | None,
                   judge: PathJudge, t_start: float, replan_index: int, clock: Deadline,
                   grow: bool, head_cost: float = 0.0, robot: tuple | None = None) -> ReplanResult:
        """The replan from ``q`` at ``t_now`` (the module docstring's steps;
        ``grow`` False: no search while the candidate is safe). ``head_cost``:
        the cost of the committed motion before ``q``, part of both paths'
        costs in the margin's comparison and in the reason's words.
        ``robot``: ``(q, t)`` where a way out would start (None: ``q`` at
        ``t_now``), for the evasion's share of the budget."""
        initial = replan_index == 0

        def result(waypoints, cost, status, reason, iterations=0, deadline_hit=False, candidate_cost=math.inf,
                   search_cost=math.inf, searched=False) -> ReplanResult:
            return ReplanResult(t_now, waypoints, float(cost), status in CHANGES, status, reason,
                                time.perf_counter() - t_start, int(iterations), bool(deadline_hit),
                                float(candidate_cost), float(search_cost), int(replan_index), bool(searched))

        if np.array_equal(q, self.goal):
            return result(q[None], 0.0, "initial" if initial else "kept", "at the goal: nothing to plan",
                          candidate_cost=0.0 if candidate is not None else math.inf)
        cand = judge.evaluate(candidate, t_now) if candidate is not None else None
        cand_cost = cand.cost if cand is not None and cand.safe else math.inf
        if not grow and math.isfinite(cand_cost) and not initial:
            return result(candidate, cand_cost, "kept", f"the current path (cost {head_cost + cand_cost:.4g}) is "
                          "still safe: kept without a search", candidate_cost=cand_cost)
        stop = clock.search_stop
        if stop is not None and candidate is not None and not math.isfinite(cand_cost) and not initial:
            q_r, t_r = (q, t_now) if robot is None else robot
            if not standing_clear(judge, q_r, t_r, min(prediction.horizon, t_r + self.lookahead)):
                stop -= self.budget * EVADE_RESERVE  # the replan may end in a way out: time is kept for it
        iterations = self.initial_iterations if initial else self.iterations
        search = run_search(self.search, judge.social, q, t_now, prediction, candidate, iterations, stop,
                            np.random.default_rng([self.seed, int(replan_index)]))
        best, best_eval, best_switch = None, None, 0.0
        for judged, path in enumerate(search.paths):
            if clock.passed() or (judged >= VERIFY_PATHS and best is not None):
                break  # the first few, and more only while none is safe; all within the budget
            ev = judge.evaluate(path, t_now)
            if ev.safe:
                switch = self._switch(path, ev, candidate)
                if best_eval is None or ev.cost + switch < best_eval.cost + best_switch:
                    best, best_eval, best_switch = path, ev, switch
        if best is not None:
            short, short_eval = shortcut(judge, best, t_now, best_eval, clock)
            if short is not best:
                best, best_eval, best_switch = short, short_eval, self._switch(short, short_eval, candidate)
        search_cost = best_eval.cost if best_eval is not None else math.inf
        cand_safe = math.isfinite(cand_cost)
        pause = None if cand_safe or initial else self._pause(judge, q, t_now, prediction, candidate, clock)
        common = dict(iterations=search.iterations, deadline_hit=search.deadline_hit or clock.hit,
                      candidate_cost=cand_cost, search_cost=search_cost, searched=True)
        pause_cost = math.inf if pause is None else pause[1].cost + self.time_weight * pause[0]
        leave = search_cost + best_switch  # what taking the search's path costs, leaving the route included
        whole_search, whole_cand = head_cost + search_cost, head_cost + cand_cost  # the paths from the robot
        switch_words = f" and {best_switch:.4g} for leaving the current route" if best_switch > 0.0 else ""
        if best is not None and (leave < pause_cost if not cand_safe
                                 else head_cost + leave < (1.0 - self.margin) * whole_cand):
            if initial:
                why = f"the first plan: cost {search_cost:.4g} after {search.iterations} samples"
            elif candidate is None:
                why = f"no current path: the search's path costs {search_cost:.4g}"
            elif not cand_safe:
                why = f"the current path is not safe any more ({judge.unsafe_words(cand)}); " \
                      f"the search's path costs {whole_search:.4g}{switch_words}" + (
                          "" if pause is None else f", less than waiting {pause[0]:.2g} s for the current path "
                                                   f"({head_cost + pause_cost:.4g})")
            else:
                why = (f"the search's path costs {whole_search:.4g}{switch_words}, below (1 - {self.margin:g}) x "
                       f"{whole_cand:.4g} of the current path")
            return result(best, search_cost, "initial" if initial else "new", why, **common)
        if cand_safe:
            why = (f"the current path (cost {whole_cand:.4g}) stays: " +
                   (f"the search's best costs {whole_search:.4g}{switch_words}, not below (1 - {self.margin:g}) x "
                    f"{whole_cand:.4g}" if best is not None
                    else f"the search found no safe path ({search.message})"))
            return result(candidate, cand_cost, "initial" if initial else "kept", why, **common)
        if pause is not None:
            w = pause[0]
            why = (f"waiting: the current path is not safe now ({judge.unsafe_words(cand)}); after a pause of "
                   f"{w:.2g} s it is, and costs {head_cost + pause_cost:.4g} with the {self.time_weight:g} per "
                   "second waited" + (f", less than the search's path ({whole_search:.4g}{switch_words})"
                                      if best is not None else f" (the search found no safe path: {search.message})"))
            return result(q[None], math.inf, "wait", why, **common)
        held = result(q[None], math.inf, "wait", judge.wait_words(q, t_now, cand, search.message), **common)
        return held if initial else self._hold_or_evade(held, q, t_now, judge, prediction, candidate, t_start,
                                                        clock)

    def _switch(self, path: np.ndarray, evaluation: PathEvaluation, current: np.ndarray | None) -> float:
        """What taking ``path`` (judged as ``evaluation``) in place of the
        ``current`` path costs (:func:`~.replan_commit.route_deviation`
        times ``planner.switch_weight``; 0 without a current path)."""
        if current is None or self.switch_weight == 0.0:
            return 0.0
        return self.switch_weight * route_deviation(path, evaluation.times, current, self.horizon)

    def _pause(self, judge: PathJudge, q: np.ndarray, t_now: float, prediction: Prediction,
               candidate: np.ndarray | None, clock: Deadline) -> tuple[float, PathEvaluation] | None:
        """The shortest pause of :func:`~.replan_commit.pause_steps` after
        which ``candidate`` (from ``q``) is safe, the robot standing at ``q``
        clear of everyone until then, and its evaluation driven from then;
        None when there is none (or the deadline passed first). The pauses
        are shares of what is left at ``t_now`` of the seconds over which
        paths are checked (``planner.safety_horizon`` from the prediction's
        start, at most the prediction): after a pause at the end of a
        committed motion, or with a safety horizon longer than the
        prediction, the resumed path is still checked over a quarter of it."""
        if candidate is None or len(candidate) < 2:
            return None
        left = min(prediction.t0 + self.safety_horizon, prediction.horizon) - t_now
        if not left > 0.0:
            return None
        for w in pause_steps(left):
            if clock.passed() or not standing_clear(judge, q, t_now, t_now + w):
                return None
            ev = judge.evaluate(candidate, t_now + w)
            if ev.safe:
                return w, ev
        return None

    def _hold_or_evade(self, held: ReplanResult, q: np.ndarray, t_now: float, judge: PathJudge,
                       prediction: Prediction, candidate: np.ndarray | None, t_start: float,
                       clock: Deadline) -> ReplanResult:
        """``held`` (a wait at ``q``), or an escape (:mod:`.replan_evade`)
        when standing at ``q`` is not safe until the horizon and there is a
        path to come back to (``candidate``, from ``q`` to the goal): the new
        path is ``[q, escape end] + candidate``, status "evade". The search
        for a way out stops at ``clock``'s deadline with the best escape
        judged by then, or none (the robot holds); ``deadline_hit`` says so."""
        until = min(prediction.horizon, t_now + self.lookahead)
        if candidate is None or standing_clear(judge, q, t_now, until):
            return held
        current = candidate[1] if len(candidate) > 1 else None
        way = escape(judge, self.space, q, t_now, until, current, clock)
        cut = "; the search for a way out stopped at the deadline" if clock.hit else ""
        held = dc.replace(held, deadline_hit=held.deadline_hit or clock.hit)
        if way is None:
            return dc.replace(held, reason=held.reason + ("; no escape motion is clear either" if not cut else
                                                          cut + " with none found"),
                              plan_time=time.perf_counter() - t_start)
        how = ("(clear)" if way.clear else
               f"(the best effort: least clearance {way.clearance:.2f} m as predicted)") + cut
        if way.q is current:  # driving on is the way out: the path stays
            return dc.replace(held, waypoints=candidate, changed=False, status="kept",
                              reason=f"evading: standing here is not safe before t = {until:.2f} s "
                                     f"({held.reason}); driving on to the next waypoint is the way out {how}",
                              plan_time=time.perf_counter() - t_start)
        shift = way.q[:2] - q[:2]
        return dc.replace(held, waypoints=np.vstack([q[None], way.q[None], candidate]), changed=True, status="evade",
                          reason=f"evading: standing here is not safe before t = {until:.2f} s "
                                 f"({held.reason}); the base steps aside by [{shift[0]:.2f}, {shift[1]:.2f}] m {how}",
                          plan_time=time.perf_counter() - t_start)

    def _candidate(self, q: np.ndarray, previous, who: str) -> np.ndarray | None:
        """The candidate path from ``q`` (None without one)."""
        if previous is None:
            return None
        prev = real_array(previous, who, "previous", (None, 4), layout="rows [x, y, psi1, psi2]", rows=(1, None),
                          row_name="waypoint")
        if len(prev) == 1 and not np.array_equal(prev[0], self.goal):
            return None  # a wait: no path to keep
        if not np.array_equal(prev[-1], self.goal):
            raise ValueError(f"{who}: previous must end at the goal {self.goal.tolist()} (the remainder of the "
                             f"path being driven), its last row is {prev[-1].tolist()}")
        if not np.array_equal(prev[0], q):
            prev = np.vstack([q[None], prev])
        repeated = np.all(prev[1:] == prev[:-1], axis=1)  # a waypoint reached exactly: no zero-length motions
        return np.ascontiguousarray(prev[np.concatenate([[True], ~repeated])])
