"""The run record: one schema for a planning run, wherever it is recorded.

``plan`` writes one record as ``result.json``; ``bench`` keeps one per seeded
run in ``bench.json``; a study keeps one per task in ``results.json`` and
``results.csv``. All three name every quantity as :data:`RUN_FIELDS` does:
the planner's part comes from
:meth:`drake_social.planning.result.PlannerResult.to_record`, the path's
measures from :func:`drake_social.evaluation.records.path_costs`, and each
producer adds the fields of its context (:data:`CONTEXT_FIELDS`). A producer
may leave a field out (``bench`` keeps no ``cost_history``), never rename it.

A simulated run (``simulate``'s ``sim.json``, a study's executed runs) also
carries the social-navigation metrics over time of
:func:`drake_social.evaluation.nav_metrics.execution_metrics`, flat keys named
by :data:`NAV_FIELDS` (prefix :data:`NAV_PREFIX`); a study's executed runs
also carry :data:`EXECUTION_FIELDS`.

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

__all__ = ["CONTEXT_FIELDS", "EXECUTION_FIELDS", "NAV_FIELDS", "NAV_PREFIX", "PATH_FIELDS", "PLANNER_FIELDS", "RUN_FIELDS", "SHARED_FIELDS",
           "json_lines", "write_json"]

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

#: The fields of a path's measures (:func:`drake_social.evaluation.records.path_costs`), recomputed from the
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

#: The prefix of the metrics over time in a record (``nav_min_dist_base``).
NAV_PREFIX = "nav_"

#: The metrics over time of an executed run against where people were
#: (:func:`drake_social.evaluation.metrics.run_metrics`; its docstring's table
#: gives the definitions and the conventions: sample-and-hold for times spent,
#: trapezoid rule for means and integrals), with ``<part>`` one of base, arm,
#: object, robot (the whole robot) and ``<zone>`` one of Hall's intimate
#: (< 0.45 m), personal (< 1.2 m), social (< 3.6 m), public; distances are
#: surface to surface, metres. Null in JSON where the value is NaN or infinite.
NAV_FIELDS: dict[str, str] = {
    "nav_success": "1 when the goal was reached, else 0",
    "nav_time_to_goal": "seconds until the goal was reached; null when not reached",
    "nav_timeout": "1 when the goal was not reached within execution.time_limit, else 0",
    "nav_duration": "seconds from the first to the last logged sample",
    "nav_path_length_base": "length of the executed base XY track, metres",
    "nav_irregularity_base": "the executed base track's total heading change per metre, rad/m",
    "nav_speed_mean_<body>": "mean |v| of the base (body base) or of the object's interest points (body object) "
                             "over first divided differences of the samples, m/s",
    "nav_speed_max_<body>": "max |v| likewise, m/s",
    "nav_accel_mean_<body>": "mean |a| (2 x second divided differences), m/s^2",
    "nav_accel_max_<body>": "max |a|, m/s^2",
    "nav_jerk_mean_<body>": "mean |j| (6 x third divided differences), m/s^3",
    "nav_jerk_max_<body>": "max |j|, m/s^3",
    "nav_jerk_p95_<body>": "95th percentile of |j|, m/s^3",
    "nav_stopped_time": "seconds the safety monitor held the robot; null when the run recorded no stop flag",
    "nav_stop_count": "safety stops (runs of consecutive stopped samples); null likewise",
    "nav_stopped_share": "nav_stopped_time / nav_duration; null likewise or when no time passed",
    "nav_slowed_time": "seconds the slow-down's speed limit was in force (execution.slow_down); null when the run "
                       "recorded no limit",
    "nav_slow_stop_count": "stops of the slow-down (its limit 0: a person too close ahead); null likewise",
    "nav_slow_stopped_time": "seconds the slow-down's limit held the robot at 0; null likewise",
    "nav_people_count": "people in the run's log (present or not)",
    "nav_people_moving": "1 when anyone moved, turned, entered or left during the run, else 0",
    "nav_min_dist_<part>": "smallest distance of the part to any present person over the run, metres (null: "
                           "nobody present)",
    "nav_mean_dist_<part>": "time average of the part's distance to the nearest present person, metres (null: "
                            "nobody present)",
    "nav_time_<zone>_<part>": "seconds the part's distance to the nearest present person was in the zone "
                              "(nobody present: public)",
    "nav_share_<zone>_<part>": "nav_time_<zone>_<part> / nav_duration, 0..1 (the four zones sum to 1)",
    "nav_collisions_<part>": "contact episodes with people (distance <= 0), counted where they start",
    "nav_collisions_appeared_<part>": "of nav_collisions_<part>, those that start with a person appearing in "
                                      "contact (touching the part at the sample where they enter)",
    "nav_collisions_moving_<part>": "of nav_collisions_<part>, those that start, not by an appearance, while the "
                                    "robot is commanded to move (not held by the safety monitor or waiting for a "
                                    "replan over the step the contact began in: the base reads a hold at once, the "
                                    "arm's trajectory a control period later); the rest: a person walked into the "
                                    "held robot; null when the run recorded no stop flag",
    "nav_collision_time_<part>": "seconds in contact with a person",
    "nav_space_compliance_<part>": "share of the time the part kept >= 0.45 m from every present person, 0..1",
    "nav_agf_time_<part>": "time integral of the part's thresholded AGF sum over the present people at their "
                           "logged poses, seconds (AGF dimensionless)",
}

#: The fields of a study's executed run (``--simulate``) beside its
#: ``exec_``-prefixed :func:`~drake_social.evaluation.metrics.executed_metrics`
#: and its ``nav_*`` fields; ``sim.json`` holds the report's fields under
#: their :class:`~drake_social.sim.results.ExecutionReport` names.
EXECUTION_FIELDS: dict[str, str] = {
    "exec_reached": "whether the run reached the goal within execution.time_limit",
    "exec_time_to_goal": "seconds until the goal was reached; null when not reached",
    "exec_wall_time": "seconds of wall-clock time the simulation took",
    "exec_planned_cost": "the social cost Msc along the planned waypoints (sim.json: planned_social_cost)",
    "exec_cost": "the same cost function along the executed trajectory (sim.json: executed_social_cost): "
                 "against the people at t = 0, as the planner saw them, even when they walk; the cost among "
                 "the people where they were is nav_agf_time_<part>",
    "exec_cost_ratio": "exec_cost / exec_planned_cost; null when the planned cost is 0",
    "exec_max_deviation": "largest distance of a body point from its planned curve, metres",
    "exec_collision_free": "no executed configuration collides with what sim.json's collision_checked names: "
                           "obstacles, walls and people when the people stand still; obstacles and walls only "
                           "when they move (contact with walkers: nav_collisions_<part>)",
    "exec_within_limits": "no joint limit or room bound passed",
}

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
