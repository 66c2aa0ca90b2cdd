"""The run record: one schema for a planning run, wherever it is recorded.

``plan`` writes one record as ``result.json``; ``bench`` keeps one per seeded
run in ``bench.json``; a study keeps one per task in ``results.json`` and
``results.csv``. All three name every quantity as :data:`RUN_FIELDS` does:
the planner's part comes from
:meth:`drake_social.planning.result.PlannerResult.to_record`, the path's
measures from :func:`drake_social.experiments.records.path_costs`, and each
producer adds the fields of its context (:data:`CONTEXT_FIELDS`). A producer
may leave a field out (``bench`` keeps no ``cost_history``), never rename it.

JSON is written strict (:func:`~drake_social.io.json_numbers.finite_or_none`): NaN and infinities become ``null``,
as does every value of a failed run that has no meaning (its cost, its
lengths).

Example::

    from drake_social.io.records import RUN_FIELDS, json_lines

    record = {"scenario": "scenarios/tiny.yaml", **result.to_record(), **path_costs(scenario, result.waypoints)}
    Path("result.json").write_text(json_lines(record))
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Mapping

from drake_social.io.json_numbers import finite_or_none

__all__ = ["CONTEXT_FIELDS", "PATH_FIELDS", "PLANNER_FIELDS", "RUN_FIELDS", "SHARED_FIELDS", "json_lines",
           "write_json"]

#: The fields a planner's result gives (:meth:`PlannerResult.to_record`), in order, with their meaning and unit.
PLANNER_FIELDS: dict[str, str] = {
    "algorithm": "the planner, one of scenario.ALGORITHMS (or ompl_rrt_star[<objective>] in bench)",
    "success": "whether a path from the start to exactly the goal was found (bool)",
    "message": "a one-line summary; why it failed when it did",
    "seed": "the seed of the planner's random generator (numpy.random.default_rng(seed))",
    "planning_time": "seconds of the search alone (the solve loop: no checker construction, no kernel "
                     "compilation, no optimisation of the path afterwards; bench: the median of its repeats)",
    "optimize_time": "seconds spent optimising the path after the search (0 when planner.optimize is false)",
    "cost": "the returned path's objective (the algorithm's own: length for rrt_star, social integral plus "
            "weighted length otherwise), as the planner reports it; null on failure",
    "raw_cost": "the tree path's objective before planner.optimize (= cost when the path is not optimised); "
                "null on failure",
    "optimized": "whether the returned path was optimised after the search (planner.optimize)",
    "near_radius_mode": "the RRT* neighbourhood radius: fixed or shrinking",
    "first_solution_iteration": "1-based iteration of the first path to the goal; null when none",
    "tree_size": "nodes of the search tree",
    "num_config_checks": "configurations checked for validity",
    "num_motion_checks": "straight motions checked for validity",
    "num_cost_evaluations": "motions whose cost was computed",
    "num_waypoints": "waypoints of the returned path (0 on failure)",
    "closest_distance_to_goal": "configuration distance of the tree's closest node to the goal (0 on success)",
    "waypoints": "the returned path, rows [x, y, psi1, psi2] (metres, radians); [] on failure",
    "cost_history": "the best objective after each iteration (null before the first solution)",
}

#: The fields of a path's measures (:func:`drake_social.experiments.records.path_costs`), recomputed from the
#: waypoints by the same code for every producer; null on failure.
PATH_FIELDS: dict[str, str] = {
    "F_multi": "the social integral along the path with weight 1 on every interest point (the paper's F; "
               "comparable across planners), dimensionless x configuration distance",
    "F_base": "the same integral with base-only weights (1 on the base, 0 elsewhere)",
    "F_planner": "the same integral with the planner's own interest-point weights (the scenario's "
                 "social.weights for rrt_star)",
    "path_length": "configuration-space length, the plain norm of [x, y, psi1, psi2] steps (metres and radians)",
    "base_length": "length of the base's XY track, metres",
}

#: The fields each producer sets from its context.
CONTEXT_FIELDS: dict[str, str] = {
    "scenario": "the scenario file (study: the group's scenario name)",
    "overrides": "the --set texts (study: the group's overrides) applied over the file, in order",
    "checker": "the validity checker that planned: planar, drake or numpy",
    "iterations": "K, samples drawn by the planner",
    "drake_verified": "plan: every segment of the path passes Drake's SceneGraphCollisionChecker (null: no path)",
    "objective": "bench: the algorithm's objective recomputed from the waypoints by this package (checks cost; "
                 "for OMPL's paths, the comparable cost)",
    "path_valid": "bench: every waypoint and motion of the path passes the run's checker again",
    "planning_times": "bench: planning_time of each repeat, seconds",
}

#: Every field of a run record: one name per quantity.
RUN_FIELDS: dict[str, str] = {**CONTEXT_FIELDS, **PLANNER_FIELDS, **PATH_FIELDS}

#: The fields every producer's record has (plan's result.json, bench's runs, a study's runs).
SHARED_FIELDS: tuple[str, ...] = (
    "algorithm", "success", "seed", "iterations", "planning_time", "optimize_time", "cost", "raw_cost", "optimized",
    "near_radius_mode", "first_solution_iteration", "tree_size", "num_config_checks", "num_motion_checks",
    "num_cost_evaluations", "num_waypoints", *PATH_FIELDS, "waypoints",
)


def json_lines(record: Mapping[str, Any]) -> str:
    """Strict JSON of ``record`` with one top-level key per line (arrays such as the waypoints stay on their
    line); non-finite numbers become null."""
    body = ",\n".join(f"  {json.dumps(k)}: {json.dumps(finite_or_none(v), allow_nan=False)}"
                      for k, v in record.items())
    return "{\n" + body + "\n}\n"


def write_json(path: str | Path, value: Any, *, indent: int | None = None) -> None:
    """Writes ``value`` as strict JSON (non-finite numbers as null) followed by a newline.

    Args:
        path: the file to write.
        value: dicts, lists, strings, numbers, booleans and None.
        indent: spaces per nesting level (None: one line).
    """
    Path(path).write_text(json.dumps(finite_or_none(value), indent=indent, allow_nan=False) + "\n")
