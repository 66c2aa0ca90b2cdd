"""Run records from a planner's result (the planner's fields and the path's
measures) and from a simulated execution (the metrics over time).

``plan`` (``result.json``), ``bench`` (``bench.json``) and the studies
(``results.json``, ``results.csv``) build their records with
:func:`run_record`, so that every quantity has one name in all of them: the
schema, with the meaning and unit of each field, is
:data:`drake_social.io.records.RUN_FIELDS`. ``simulate`` (``sim.json``) and
the studies' executed runs add
:func:`drake_social.evaluation.metrics.execution_metrics`, named as
:data:`drake_social.io.records.NAV_FIELDS` names them.
"""

from __future__ import annotations

import numpy as np

from drake_social.cost.social import SocialCost
from drake_social.io.records import PATH_FIELDS
from drake_social.kinematics import config_distance
from drake_social.planning.algorithms import base_only_weights
from drake_social.planning.objective import SocialObjective
from drake_social.scenario.geometry import arm_geometry

__all__ = ["path_costs", "run_record"]


def path_costs(scenario, waypoints: np.ndarray, planner_weights: np.ndarray | None = None) -> dict[str, float]:
    """The path's measures of a run record (``drake_social.io.records.PATH_FIELDS``).

    Args:
        scenario: the planned scenario (people, robot, object).
        waypoints: (N, 4), start to goal; straight motions between them.
        planner_weights: the interest-point weights the planner used (for
            ``F_planner``); None = the scenario's ``social.weights``.

    Returns:
        ``F_multi``, ``F_base``, ``F_planner`` (social integrals with weight 1
        everywhere, base-only weights and the planner's weights),
        ``path_length`` (configuration space, plain norm) and ``base_length`` (metres).
    """
    wp = np.asarray(waypoints, float).reshape(-1, 4)
    n = arm_geometry(scenario).num_interest_points
    multi = SocialCost.from_scenario(scenario, np.ones(n))
    a, b = wp[:-1], wp[1:]

    def integral(cost: SocialCost) -> float:
        return float(cost.motion_cost(a, b).sum()) if len(a) else 0.0

    return {
        "F_multi": integral(multi),
        "F_base": integral(multi.with_weights(base_only_weights(n))),
        "F_planner": integral(SocialCost.from_scenario(scenario, planner_weights)),
        "path_length": float(config_distance(a, b).sum()),
        "base_length": float(np.hypot(*(b - a)[:, :2].T).sum()),
    }


def run_record(scenario, result, objective=None, *, history: bool = False) -> dict:
    """A planning run's record: the planner's fields and the path's measures,
    named as ``drake_social.io.records.RUN_FIELDS`` names them (``plan``,
    ``bench`` and the studies all build theirs here).

    Args:
        scenario: the planned scenario.
        result: the planner's :class:`~drake_social.planning.result.PlannerResult`.
        objective: the planner's objective (its social weights give
            ``F_planner``); None = the scenario's ``social.weights``.
        history: keep ``cost_history`` (K values: ``plan`` keeps it, the
            many runs of ``bench`` and the studies do not).

    Returns:
        :meth:`PlannerResult.to_record` with :func:`path_costs` before the
        waypoints (each None when no path was found).
    """
    record = result.to_record()
    if not history:
        del record["cost_history"]
    weights = objective.social.weights if isinstance(objective, SocialObjective) else None
    costs = path_costs(scenario, result.waypoints, weights) if result.success else dict.fromkeys(PATH_FIELDS)
    waypoints = record.pop("waypoints")
    tail = {"cost_history": record.pop("cost_history")} if history else {}
    return {**record, **costs, "waypoints": waypoints, **tail}

