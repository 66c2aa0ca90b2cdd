"""The one check of a path given to be executed (no Drake here).

A path to execute is an (N, 4) array of configurations ``[x, y, psi1,
psi2]`` (metres, radians), 2 <= N <= :data:`~drake_social.limits.MAX_WAYPOINTS`,
from the scenario's start to its goal. :func:`check_waypoints` refuses,
before anything runs, a path that

* is not such an array (a wrong shape is never reshaped),
* holds a value that is not a finite number,
* puts the base centre outside ``world.bounds`` or a joint outside
  ``robot.joint_lower`` / ``robot.joint_upper``,
* does not start at the scenario's start and end at its goal (each
  coordinate within :data:`ENDPOINT_TOLERANCE`),
* has a configuration in collision, or a straight segment between two
  waypoints that collides (the validity checker of the run decides).

The error (:class:`~drake_social.scenario.ScenarioError`) names the source
(the file and line of a CSV, the function and argument of the API), the
waypoint, the field and what is allowed. ``simulate --path``
(:func:`drake_social.app.read_path_csv`), :func:`drake_social.sim.run.simulate`
and :func:`drake_social.sim.diagram.build_diagram` all use it.

Example::

    from drake_social.collision.drake_checker import make_checker
    from drake_social.waypoints import check_waypoints

    checker = make_checker(scenario, "planar")
    path = check_waypoints(scenario, [scenario.start, scenario.goal], checker, source="my script")
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from drake_social.arguments import real_array, require_checker, require_scenario
from drake_social.scenario.geometry import configuration_limits
from drake_social.limits import MAX_WAYPOINTS
from drake_social.people import people_model
from drake_social.collision.validity import ValidityChecker
from drake_social.scenario import Scenario, ScenarioError

__all__ = ["ENDPOINT_TOLERANCE", "FIELDS", "check_waypoints", "waypoint_array"]

#: Largest difference (metres for x, y; radians for psi1, psi2) between the
#: first waypoint and the scenario's start, and the last and its goal. The
#: planner's paths start and end there exactly and ``path.csv`` holds them to
#: 17 digits, so this only forgives a hand-written file's rounding.
ENDPOINT_TOLERANCE = 1e-9

#: The names of a waypoint's four values, in order.
FIELDS = ("x", "y", "psi1", "psi2")


def waypoint_array(waypoints: Any, source: str, *, fewest: int = 2) -> np.ndarray:
    """``waypoints`` as a new (N, 4) float array, ``fewest`` <= N <= MAX_WAYPOINTS, refused otherwise.

    Args:
        waypoints: an array or nested sequence of real numbers
            (:func:`~drake_social.arguments.real_array`; NaN and infinities
            are left to :func:`check_waypoints`, which names the waypoint).
        source: who passed it, for the message (``"simulate: waypoints"``).
        fewest: 2 for a path from a start to a goal; 1 where one
            configuration stands for the path (a replanning robot that never
            found a path holds where it is).

    Raises:
        TypeError: not an array of real numbers (strings, booleans, complex,
            None, other objects, a masked array).
        ScenarioError: the wrong shape (never reshaped) or number of rows.
    """
    what = "the start, ..., the goal" if fewest > 1 else "a path, or the one configuration held"
    return real_array(waypoints, source, "", (None, 4), layout="rows [x, y, psi1, psi2]", rows=(fewest, MAX_WAYPOINTS),
                      rows_note=f"({what}; limits.MAX_WAYPOINTS)", row_name="waypoint",
                      finite=False, error=ScenarioError)


def check_waypoints(
    scenario: Scenario,
    waypoints: Any,
    checker: ValidityChecker,
    *,
    source: str,
    lines: Sequence[int] | None = None,
    check_segments: bool = True,
) -> np.ndarray:
    """Refuses a path that must not be executed in ``scenario``; returns it as an (N, 4) float array.

    Args:
        scenario: the scenario the path is for.
        waypoints: (N, 4) configurations ``[x, y, psi1, psi2]`` (metres, radians).
        checker: the validity checker of the run (collisions of the
            configurations and of the straight segments between them).
        source: who gave the path, for the message: a file (``"path.csv
            (--path)"``) or a function and argument (``"simulate: waypoints"``).
        lines: the file line of each waypoint, to name it (a CSV's rows).
        check_segments: also check every straight motion between consecutive
            waypoints (``checker.are_motions_valid``).

    Returns:
        The waypoints as a new (N, 4) float array.

    Raises:
        TypeError: ``scenario`` or ``checker`` is not one, or the waypoints
            are not real numbers.
        ScenarioError: ``<source>: <waypoint>: <field>: <what is allowed>``
            for the first waypoint (or segment) at fault; see the module
            docstring for the rules.
    """
    require_scenario(scenario, "check_waypoints")
    require_checker(checker, "check_waypoints")
    their = getattr(checker, "scenario", None)
    if isinstance(their, Scenario) and their is not scenario and _checked_world(their) != _checked_world(scenario):
        raise ScenarioError(f"{source}: the checker {type(checker).__name__} was made for another scenario (its "
                            "room, people, robot or object differ): make the checker of this scenario, "
                            "make_checker(scenario, kind)")
    wp = waypoint_array(waypoints, source)
    if lines is not None and len(lines) != len(wp):
        raise ValueError(f"check_waypoints: {len(lines)} line numbers for {len(wp)} waypoints")

    def where(i: int) -> str:
        i = int(i)
        return f"waypoint {i}" if lines is None else f"line {lines[i]} (waypoint {i})"

    def fail(i: int, message: str):
        raise ScenarioError(f"{source}: {where(i)}: {message}")

    bad = ~np.isfinite(wp)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        fail(i, f"{FIELDS[j]}: must be a finite number, got {float(wp[i, j])!r}")

    lower, upper = configuration_limits(scenario)
    where_limit = ("world.bounds", "world.bounds", "robot.joint_lower/joint_upper", "robot.joint_lower/joint_upper")
    outside = (wp < lower) | (wp > upper)
    if outside.any():
        i, j = np.argwhere(outside)[0]
        what = "the room" if j < 2 else "the joint range"
        fail(i, f"{FIELDS[j]}: {float(wp[i, j])!r} is outside {what} [{float(lower[j])!r}, {float(upper[j])!r}] "
                f"({where_limit[j]})")

    for row, name, ordinal in ((0, "start", "first"), (len(wp) - 1, "goal", "last")):
        q = np.asarray(getattr(scenario, name), float)
        if not np.all(np.abs(wp[row] - q) <= ENDPOINT_TOLERANCE):
            fail(row, f"the {ordinal} waypoint {wp[row].tolist()} is not the scenario's {name} {q.tolist()} "
                      f"(to within {ENDPOINT_TOLERANCE:g} per coordinate): a path runs from the scenario's start "
                      f"to its goal; make this row the {name}, or set the scenario's {name} to it "
                      f"(e.g. --set \"{name}: {wp[row].tolist()}\")")

    kind = type(checker).__name__
    valid = _answers(checker, "are_valid", (wp,), len(wp))
    if not valid.all():
        i = int(np.argmin(valid))
        contacts = getattr(checker, "contacts", None)
        touching = "; ".join(str(c) for c in contacts(wp[i])) if callable(contacts) else ""
        fail(i, f"configuration {wp[i].tolist()} is in collision ({kind}){': ' + touching if touching else ''}; "
                "every waypoint must be collision-free")
    if check_segments:
        moves = _answers(checker, "are_motions_valid", (wp[:-1], wp[1:]), len(wp) - 1)
        if not moves.all():
            i = int(np.argmin(moves))
            to = f"waypoint {i + 1}" if lines is None else f"line {lines[i + 1]}"
            how = getattr(checker, "motion_check", None)
            fail(i, f"the straight motion to {to} collides ({kind}{', ' + how if isinstance(how, str) else ''}); "
                    "every segment must be collision-free")
    return wp


def _checked_world(scenario: Scenario) -> tuple:
    """What a validity checker of ``scenario`` checks against, to compare:
    the room, the people's bodies (at t = 0), the robot and the object."""
    people = people_model(scenario).state_at(0.0)
    bodies = tuple(np.ascontiguousarray(a).tobytes() for a in (people.positions, people.headings, people.radii))
    return repr((scenario.world, scenario.robot, scenario.object)), bodies


def _answers(checker: ValidityChecker, method: str, arguments: tuple, n: int) -> np.ndarray:
    """``checker.<method>(*arguments)`` as an (n,) bool array, or the error naming the method."""
    answer = np.asarray(getattr(checker, method)(*arguments))
    if answer.shape != (n,) or answer.dtype.kind not in "biu":
        raise TypeError(f"{type(checker).__name__}.{method} must return ({n},) booleans (one per "
                        f"{'configuration' if method == 'are_valid' else 'motion'}), got an array of {answer.dtype} "
                        f"of shape {answer.shape}")
    return answer.astype(bool)
