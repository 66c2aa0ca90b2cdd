"""The planner as a Drake system: plan once at initialization, output the path.

:class:`PlannerSystem` runs :func:`drake_social.planning.algorithms.plan` in an
initialization event (``Simulator.Initialize()`` or
``system.ExecuteInitializationEvents(context)``) and stores the
:class:`~drake_social.planning.result.PlannerResult` in abstract state. Its
output ports only read that state, and each declares the abstract state as
its sole prerequisite, so Drake's cache computes every output once: neither
evaluating a port again nor advancing time re-plans or recomputes anything.

Output ports (all abstract, ``Value[object]``):

* ``waypoints``: the (N, 4) array of configurations ``[x, y, psi1, psi2]``
  (metres, radians) from start to exactly the goal; (0, 4) when no path.
* ``path``: a :class:`pydrake.trajectories.PiecewisePolynomial` first-order
  hold through the waypoints, parametrised by the cumulative configuration
  distance ``s`` along the path (the axis of the paper's Fig. 6/8, with the
  scenario's ``planner.distance_weights``); ``s = 0`` at the start and
  ``end_time()`` is the path length. Zero-length segments are dropped. An
  empty trajectory (no segments) when no path was found.
* ``result``: the whole :class:`PlannerResult` (costs, counters, anytime curve).
"""

from __future__ import annotations

import logging

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import Context, LeafSystem, State
from pydrake.trajectories import PiecewisePolynomial

from drake_social.arguments import require_checker, require_choice, require_int, require_scenario
from drake_social.kinematics import cumulative_distance
from drake_social.planning.result import PlannerResult
from drake_social.collision.validity import ValidityChecker
from drake_social.planning.algorithms import plan
from drake_social.scenario import ALGORITHMS, MAX_ITERATIONS, Scenario

__all__ = ["PlannerSystem", "path_parameter", "waypoint_trajectory"]

_log = logging.getLogger(__name__)


def path_parameter(waypoints: np.ndarray, distance_weights=None) -> np.ndarray:
    """Cumulative configuration distance (N,) at each waypoint, starting at 0.

    Args:
        waypoints: (N, 4) configurations.
        distance_weights: per-coordinate scale of the norm (None = plain).
    """
    return cumulative_distance(waypoints, distance_weights)


def waypoint_trajectory(waypoints: np.ndarray, distance_weights=None) -> PiecewisePolynomial:
    """A first-order hold through ``waypoints`` over cumulative configuration distance.

    Repeated waypoints (zero-length segments) are dropped, since breakpoints
    must increase strictly. No waypoint gives an empty trajectory (no
    segments); a single distinct configuration gives a constant trajectory
    (Drake's, defined on (-inf, inf)).

    Args:
        waypoints: (N, 4) configurations.
        distance_weights: per-coordinate scale of the norm (None = plain).
    """
    wp = np.asarray(waypoints, float).reshape(-1, 4)
    if len(wp) == 0:
        return PiecewisePolynomial()
    s = path_parameter(wp, distance_weights)
    keep = np.concatenate([[True], np.diff(s) > 0])
    if keep.sum() < 2:
        return PiecewisePolynomial(wp[0].reshape(4, 1))
    return PiecewisePolynomial.FirstOrderHold(s[keep], wp[keep].T)


class PlannerSystem(LeafSystem):
    """Plans a scenario once, at initialization, and outputs the path.

    Args:
        scenario: a validated scenario (start, goal, planner options, seed).
        checker: the validity checker; None = the exact planar checker built
            from the scenario's SceneGraph (:class:`~drake_social.collision.planar_checker.PlanarChecker`).
        algorithm: one of ``scenario.ALGORITHMS``; None = ``scenario.planner.algorithm``.
        iterations: K; None = ``scenario.planner.iterations``.
        seed: the planner's seed; None = ``scenario.random_seed``.

    Raises:
        TypeError, ValueError: an argument of the wrong kind or value (named).

    The planning itself (which may take seconds) happens in the
    initialization event, never in an output calculation. An output
    evaluated before initialization raises a ``RuntimeError`` saying so.
    Planning errors (start or goal in collision) surface from
    ``Simulator.Initialize()`` as
    :class:`~drake_social.planning.result.PlanningInputError`.
    """

    def __init__(
        self,
        scenario: Scenario,
        checker: ValidityChecker | None = None,
        algorithm: str | None = None,
        iterations: int | None = None,
        seed: int | None = None,
    ):
        super().__init__()
        require_scenario(scenario, "PlannerSystem")
        require_checker(checker, "PlannerSystem", optional=True)
        require_choice(algorithm, "PlannerSystem", "algorithm", ALGORITHMS, optional=True)
        require_int(iterations, "PlannerSystem", "iterations", minimum=1, maximum=MAX_ITERATIONS, optional=True)
        require_int(seed, "PlannerSystem", "seed", minimum=0, optional=True)
        if checker is None:
            from drake_social.collision.drake_checker import make_checker

            checker = make_checker(scenario, "planar")
        self._scenario = scenario
        self._checker = checker
        self._algorithm = algorithm
        self._iterations = iterations
        self._seed = seed
        self._distance_weights = scenario.planner.distance_weights

        # None until the initialization event has planned.
        self._result_index = self.DeclareAbstractState(AbstractValue.Make(None))
        self.DeclareInitializationUnrestrictedUpdateEvent(self._Plan)
        planned = {self.abstract_state_ticket(self._result_index)}
        self.DeclareAbstractOutputPort(
            "waypoints", lambda: AbstractValue.Make(np.zeros((0, 4))), self._CalcWaypoints,
            prerequisites_of_calc=planned,
        )
        self.DeclareAbstractOutputPort(
            "path", lambda: AbstractValue.Make(PiecewisePolynomial()), self._CalcPath,
            prerequisites_of_calc=planned,
        )
        self.DeclareAbstractOutputPort(
            "result", lambda: AbstractValue.Make(None), self._CalcResult, prerequisites_of_calc=planned,
        )

    # ---- event ---------------------------------------------------------------

    def _Plan(self, context: Context, state: State) -> None:
        result = plan(
            self._scenario, self._checker, algorithm=self._algorithm, iterations=self._iterations, seed=self._seed
        )
        _log.info("%s", result.summary())
        state.get_mutable_abstract_state(self._result_index).set_value(result)

    # ---- outputs ---------------------------------------------------------------

    def _planned(self, context: Context) -> PlannerResult:
        result = context.get_abstract_state(self._result_index).get_value()
        if result is None:
            raise RuntimeError(
                f"{self.get_name()}: the path is planned at initialization; call Simulator.Initialize() "
                "or system.ExecuteInitializationEvents(context) before evaluating its outputs"
            )
        return result

    def _CalcWaypoints(self, context: Context, output: AbstractValue) -> None:
        output.set_value(np.array(self._planned(context).waypoints, float).reshape(-1, 4))

    def _CalcPath(self, context: Context, output: AbstractValue) -> None:
        output.set_value(waypoint_trajectory(self._planned(context).waypoints, self._distance_weights))

    def _CalcResult(self, context: Context, output: AbstractValue) -> None:
        output.set_value(self._planned(context))
