"""The scenario: its schema, its loading and its validation.

* :mod:`drake_social.scenario.schema`: the dataclasses (every field commented,
  with its unit) and the values of the choice fields;
* :mod:`drake_social.scenario.load`: YAML read within limits, checked against
  the schema, overrides merged (``--set``, sweep variants), then validated;
* :mod:`drake_social.scenario.validate`: the value rules, each error stating
  the rule.

This package re-exports their public names, and the shared bounds and names of
:mod:`drake_social.limits` a scenario's fields are checked against, so that
``from drake_social.scenario import load_scenario, Scenario, ALGORITHMS``
is all a user needs. It does not import pydrake (see
:mod:`drake_social.scenario.load`).
"""

from drake_social.errors import ScenarioError
from drake_social.limits import (ALGORITHMS, CHECKERS, MAX_CONTROL_STEPS, MAX_DYNAMIC_PLANT_TIME_STEP,
                                 MAX_ITERATIONS, MAX_MOTION_STEPS, MAX_OBJECT_POINTS, MAX_PLANT_STEPS,
                                 MAX_REPLAY_FPS, MAX_TIME_LIMIT, MIN_CONTROL_PERIODS, SERVO_BANDWIDTH,
                                 SERVO_BASE_TIME_CONSTANT)
from drake_social.scenario.load import (MAX_YAML_DEPTH, MAX_YAML_NODES, check_node, check_yaml, compose_yaml,
                                        load_scenario, load_scenario_text)
from drake_social.scenario.schema import (EXECUTIONS, INFORMED_MODES, MAP_UNKNOWN, NEAR_RADIUS_MODES, PREDICTIONS, SIM_MODES, Bar, Box, Crowd,
                                          CrowdPerson, ExecutionOptions, LShape, Person, PlannerOptions, Polyline, Robot,
                                          Scenario, SocialCostOptions, World, interest_point_count)
from drake_social.scenario.validate import (drake_config_problem, period_count, plant_time_step_problem,
                                            replan_rate_problem, time_limit_problem, validate_planner_choice,
                                            validate_scenario)

__all__ = [
    "ALGORITHMS",
    "CHECKERS",
    "EXECUTIONS",
    "INFORMED_MODES",
    "MAP_UNKNOWN",
    "MAX_CONTROL_STEPS",
    "MAX_DYNAMIC_PLANT_TIME_STEP",
    "MAX_ITERATIONS",
    "MAX_MOTION_STEPS",
    "MAX_OBJECT_POINTS",
    "MAX_PLANT_STEPS",
    "MAX_REPLAY_FPS",
    "MAX_TIME_LIMIT",
    "MAX_YAML_DEPTH",
    "MAX_YAML_NODES",
    "MIN_CONTROL_PERIODS",
    "NEAR_RADIUS_MODES",
    "PREDICTIONS",
    "SERVO_BANDWIDTH",
    "SERVO_BASE_TIME_CONSTANT",
    "SIM_MODES",
    "Bar",
    "Box",
    "Crowd",
    "CrowdPerson",
    "ExecutionOptions",
    "LShape",
    "Person",
    "PlannerOptions",
    "Polyline",
    "Robot",
    "Scenario",
    "ScenarioError",
    "SocialCostOptions",
    "World",
    "check_node",
    "check_yaml",
    "compose_yaml",
    "drake_config_problem",
    "interest_point_count",
    "load_scenario",
    "load_scenario_text",
    "period_count",
    "plant_time_step_problem",
    "replan_rate_problem",
    "time_limit_problem",
    "validate_planner_choice",
    "validate_scenario",
]
