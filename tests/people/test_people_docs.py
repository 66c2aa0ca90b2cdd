"""docs/people.md says what the code does: the crowd's ranges, which crowd
points are checked against the robot, the radius of a people.csv read back."""

from __future__ import annotations

import dataclasses as dc
import re
from pathlib import Path

import numpy as np

from drake_social.people.crowd import crowd_problems
from drake_social.scenario import Crowd, CrowdPerson, load_scenario
from drake_social.scenario.crowd_rules import (MAX_CROWD_TIME_STEP, MAX_SPEED_FACTOR, MAX_SPEED_STD, MAX_WALKING_SPEED,
                                               MIN_WALKING_SPEED)
from drake_social.scenario.people_file import DEFAULT_RADIUS

ROOT = Path(__file__).resolve().parents[2]
DOC = (ROOT / "docs" / "people.md").read_text()


def _row(field: str) -> str:
    (row,) = [line for line in DOC.splitlines() if line.startswith(f"| `{field}")]
    return row


def test_the_crowd_table_gives_the_ranges_the_rules_enforce():
    speeds = f"({MIN_WALKING_SPEED:g}, {MAX_WALKING_SPEED:g}]"
    assert speeds in _row("people[].desired_speed")
    assert speeds in _row("speed_mean")
    assert f"drawn again until in {speeds}" in _row("people[].desired_speed")
    assert f"std in [0, {MAX_SPEED_STD:g}]" in _row("speed_mean")
    assert f"in [1, {MAX_SPEED_FACTOR:g}]" in _row("max_speed_factor")
    assert f"(0, {MAX_CROWD_TIME_STEP:g}]" in _row("time_step") and "< `relaxation_time`" in _row("time_step")


def test_the_rules_paragraph_checks_starts_not_goals_against_the_robot():
    rules = DOC[DOC.index("Rules: every start and goal"):]
    rules = " ".join(rules[:rules.index("\n\n")].split())
    assert "Goals are not checked against the robot" in rules
    # The code: a goal on the robot's base is accepted, a start there is not.
    tiny = load_scenario(ROOT / "scenarios" / "tiny.yaml")
    base = [float(v) for v in tiny.start[:2]]
    goal_on_robot = dc.replace(tiny, crowd=Crowd(people=[CrowdPerson(x=6.5, y=3.5, goals=[base])]))
    assert crowd_problems(goal_on_robot) == []
    start_on_robot = dc.replace(tiny, crowd=Crowd(people=[CrowdPerson(x=base[0], y=base[1], goals=[[6.5, 3.5]])]))
    assert [f for f, _ in crowd_problems(start_on_robot)] == ["crowd.people[0]"]


def test_people_csv_reads_back_with_the_default_radius_as_documented():
    text = " ".join(DOC.split())
    assert f"read back with the default radius ({DEFAULT_RADIUS:g} m)" in text
    assert np.isclose(DEFAULT_RADIUS, 0.25)
