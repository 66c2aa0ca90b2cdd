"""The metrics over time in the records: names, the wiring from a simulated run, the report's tables."""

from __future__ import annotations

import math
import re
from types import SimpleNamespace

import numpy as np
import pytest

from drake_social.evaluation.metrics import RUN_PARTS, ZONES, execution_metrics, run_metrics
from drake_social.experiments.study.people_tables import moving_people_groups, people_tables
from drake_social.io.records import NAV_FIELDS, NAV_PREFIX
from drake_social.people import people_model
from drake_social.people.log import PeopleLog
from drake_social.scenario import load_scenario

_ROOM = """
description: "records"
world: {bounds: [0.0, 0.0, 20.0, 6.0]}
people:
  - {x: 10.0, y: 3.8, theta: -1.5707963267948966, radius: 0.25}
robot: {base_radius: 0.35, link_lengths: [0.6, 0.5], link_width: 0.08}
object: !Bar {length: 1.5, thickness: 0.05}
start: [1.0, 2.5, 0.0, 1.5707963267948966]
goal: [19.0, 2.5, 0.0, 1.5707963267948966]
execution: {time_limit: 40.0}
"""


@pytest.fixture
def scenario(tmp_path):
    path = tmp_path / "room.yaml"
    path.write_text(_ROOM)
    return load_scenario(path)


def _run(times, **extra):
    x = 1.0 + 0.5 * times
    q = np.column_stack([x, np.full_like(x, 2.5), np.zeros_like(x), np.full_like(x, math.pi / 2)])
    return SimpleNamespace(times=times, q=q, reached=True, time_to_goal=float(times[-2]) if len(times) > 1 else None,
                           **extra)


def _pattern(name: str) -> re.Pattern:
    alternatives = {"<part>": "|".join(RUN_PARTS), "<zone>": "|".join(ZONES.names), "<body>": "base|object"}
    for placeholder, words in alternatives.items():
        name = name.replace(placeholder, f"({words})")
    return re.compile(name + "$")


def test_every_metric_has_one_documented_field_name(scenario):
    times = np.linspace(0.0, 36.0, 361)
    dut = execution_metrics(scenario, _run(times, stopped=np.zeros(len(times), bool)))
    patterns = [_pattern(n) for n in NAV_FIELDS]
    for key in dut:
        assert key.startswith(NAV_PREFIX)
        assert sum(bool(p.match(key)) for p in patterns) == 1, key
    for name, pattern in zip(NAV_FIELDS, patterns):  # and every documented field is produced
        assert any(pattern.match(k) for k in dut), name


def test_a_run_without_a_people_log_is_measured_against_the_scenario_people(scenario):
    times = np.linspace(0.0, 36.0, 361)
    run = _run(times)  # no people, no stopped attribute: a simulator that logs neither
    dut = execution_metrics(scenario, run)
    log = PeopleLog.sample(people_model(scenario), times)
    expected = run_metrics(scenario, times, run.q, log, None, True, 40.0, time_to_goal=float(times[-2]))
    assert dut == pytest.approx({NAV_PREFIX + k: v for k, v in expected.items()}, nan_ok=True)
    assert dut["nav_min_dist_base"] == pytest.approx(1.3 - 0.6, abs=1e-9)
    assert math.isnan(dut["nav_stopped_time"]) and dut["nav_time_to_goal"] == pytest.approx(35.9)


def test_a_logged_people_and_stop_flag_are_used_and_resampled_to_the_run(scenario):
    times = np.linspace(0.0, 36.0, 361)
    coarse = np.linspace(0.0, 36.0, 37)
    # The person walks along y = 3.8 with the robot's base: 1.3 m above it all the time.
    log = PeopleLog(times=coarse, positions=np.stack([1.0 + 0.5 * coarse, np.full_like(coarse, 3.8)], -1)[:, None],
                    headings=np.zeros((37, 1)), velocities=np.broadcast_to([0.5, 0.0], (37, 1, 2)),
                    present=np.ones((37, 1), bool), radii=[0.25], names=("walker",))
    stopped = (times >= 10.0) & (times < 12.0)
    dut = execution_metrics(scenario, _run(times, people=log, stopped=stopped))
    assert dut["nav_mean_dist_base"] == pytest.approx(1.3 - 0.6, abs=1e-9)
    assert dut["nav_min_dist_base"] == pytest.approx(1.3 - 0.6, abs=1e-9)
    assert dut["nav_people_moving"] == 1.0
    assert dut["nav_stop_count"] == 1.0 and dut["nav_stopped_time"] == pytest.approx(2.0, abs=1e-9)
    none = execution_metrics(scenario, _run(times, people=None, stopped=stopped))  # a log saying: nobody
    assert none["nav_min_dist_robot"] == math.inf and none["nav_people_count"] == 0.0
    assert execution_metrics(scenario, _run(np.zeros(0))) == {}


def test_the_report_tables_show_groups_with_walking_people_only():
    def record(group, moving, run, dist):
        out = {"group": group, "algorithm": "rrt_star", "run": run, "success": True}
        if moving is not None:
            out.update({"nav_success": 1.0, "nav_people_moving": moving, "nav_stop_count": float(run),
                        **{f"nav_min_dist_{p}": dist for p in RUN_PARTS}})
        return out

    groups = [SimpleNamespace(name=n, algorithms=("rrt_star",)) for n in ("still", "walk", "plan_only")]
    records = [record("still", 0.0, 0, 1.0), record("walk", 1.0, 0, 0.5), record("walk", 1.0, 1, 0.7),
               record("walk", 1.0, 2, 0.9), record("plan_only", None, 0, 0.0)]
    result = SimpleNamespace(records=records, study=SimpleNamespace(groups=groups))
    assert moving_people_groups(records) == ["walk"]
    lines = people_tables(result, lambda values, fmt: "|".join(f"{v:{fmt}}" for v in values if v is not None))
    rows = [line for line in lines if line.startswith("| walk")]
    assert len(rows) == 1 + len(RUN_PARTS)  # one run row, one row per part
    assert rows[0].startswith("| walk | rrt_star | 3/3 |") and "| 0|1|2 |" in rows[0]
    assert all("| 0.5|0.7|0.9 |" in row for row in rows[1:])
    assert not any("still" in line or "plan_only" in line for line in lines)
    assert people_tables(SimpleNamespace(records=records[:1], study=SimpleNamespace(groups=groups)), str) == []


def test_report_markdown_has_the_walking_tables_when_people_moved():
    from drake_social.experiments.study.report import report_markdown
    from drake_social.experiments.study.results import StudyResult
    from drake_social.experiments.study.spec import Group, Study

    study = Study(name="walk_check", groups=(Group("walk", "scenarios/tiny.yaml", algorithms=("rrt_star",)),),
                  runs=2, iterations=10, simulate=True)

    def record(run, moving):
        return {"group": "walk", "algorithm": "rrt_star", "run": run, "success": True, "cost": 1.0,
                "planning_time": 0.1, "F_multi": 1.0, "nav_success": 1.0, "nav_people_moving": moving,
                "nav_stop_count": 2.0, **{f"nav_time_intimate_{p}": 1.5 for p in RUN_PARTS}}

    still = report_markdown(StudyResult(study, [record(0, 0.0), record(1, 0.0)], 1.0), figures=[])
    assert "Among walking people" not in still
    walking = report_markdown(StudyResult(study, [record(0, 1.0), record(1, 0.0)], 1.0), figures=[])
    section = walking[walking.index("## Among walking people"):walking.index("## Figures")]
    assert "| walk | rrt_star | 2/2 |" in section and "| walk | rrt_star | object |" in section
    assert section.count("1.5 [1.5, 1.5]") == len(RUN_PARTS)  # the intimate seconds of each part: median [IQR]
