"""The door checks of the simulation's builders and runs.

:func:`~drake_social.sim.station.make_station`,
:func:`~drake_social.sim.autonomy.make_autonomy`,
:func:`~drake_social.sim.diagram.build_diagram` and
:func:`~drake_social.sim.run.simulate` check their arguments here, once,
before anything is built: the scenario validated, the mode and execution in
force, the waypoints to execute, whether the run replans. Each error names
the public function (``who``), the argument and what is allowed.
"""

from __future__ import annotations

import numpy as np
from pydrake.geometry import Meshcat

from drake_social.arguments import require_checker, require_choice, require_instance, require_scenario
from drake_social.collision.validity import ValidityChecker
from drake_social.scenario import (EXECUTIONS, SIM_MODES, Scenario, ScenarioError, plant_time_step_problem,
                                    replan_rate_problem, validate_scenario)
from drake_social.waypoints import check_waypoints

__all__ = ["check_diagram_options", "check_diagram_waypoints", "resolve_replan"]


def resolve_replan(scenario: Scenario, replan, given_path: bool, planner: bool, who: str) -> bool:
    """Whether a run replans: ``replan``, or with None ``scenario.planner.replan`` when it plans.

    Args:
        given_path: the path is given (waypoints), not planned.
        planner: the built-in planner gives the path (not a path source
            outside the diagram).

    Raises:
        TypeError: ``replan`` is not None, True or False.
        ValueError: ``replan=True`` with given waypoints or without the
            built-in planner, or for a scenario whose ``planner.replan_rate``
            is more than one replan per control period.
    """
    require_instance(replan, (bool, np.bool_), who, "replan", "True, False or None", optional=True)
    if replan is None:
        return bool(scenario.planner.replan) and planner and not given_path
    if replan and given_path:
        raise ValueError(f"{who}: replan=True replans the path; with given waypoints nothing is planned "
                         "(leave out the waypoints, or replan)")
    if replan and not planner:
        raise ValueError(f"{who}: replan=True needs the built-in planner (leave out the path source)")
    problem = replan_rate_problem(scenario.planner.replan_rate, scenario.execution) if replan else None
    if problem:
        raise ValueError(f"{who}: replan=True: the scenario's planner.replan_rate {problem}")
    return bool(replan)


def check_diagram_options(
    scenario: Scenario,
    *,
    mode: str | None,
    execution: str | None,
    checker: ValidityChecker | None,
    meshcat: Meshcat | None,
    who: str,
) -> tuple[str, str]:
    """The arguments of a builder or a run but its waypoints: the scenario
    validated, the mode and execution known, the checker and Meshcat of their kinds.

    Returns:
        The mode and execution in force.

    Raises:
        TypeError: as :func:`~drake_social.sim.diagram.build_diagram`.
        ValueError: as :func:`~drake_social.sim.diagram.build_diagram`.
        ScenarioError: as :func:`~drake_social.sim.diagram.build_diagram`.
    """
    require_scenario(scenario, who)
    require_choice(mode, who, "mode", SIM_MODES, optional=True)
    require_choice(execution, who, "execution", EXECUTIONS, optional=True)
    require_checker(checker, who, optional=True)
    require_instance(meshcat, Meshcat, who, "meshcat", "a pydrake.geometry.Meshcat", optional=True)
    # also one changed in code after loading; this checks the Drake settings
    # too (contact approximation, integration scheme, accuracy, realtime rate)
    validate_scenario(scenario, source=f"{who}: scenario")
    mode = mode or scenario.execution.mode
    problem = plant_time_step_problem(scenario.execution, mode)  # the scenario's mode was checked above
    if problem:
        raise ScenarioError(f"{who}: scenario: {problem[0]}: {problem[1]}")
    return mode, execution or scenario.execution.execution


def check_diagram_waypoints(scenario: Scenario, waypoints, checker: ValidityChecker | None, who: str) -> np.ndarray:
    """The waypoints to execute checked by :func:`~drake_social.waypoints.check_waypoints`
    with ``checker``, or the exact planar checker when it is None (the
    planner's default: the checker of the run)."""
    if checker is None:
        from drake_social.collision.drake_checker import make_checker

        checker = make_checker(scenario, "planar")
    return check_waypoints(scenario, waypoints, checker, source=f"{who}: waypoints")

