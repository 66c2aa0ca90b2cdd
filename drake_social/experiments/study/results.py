"""A finished study of any kind: its records, and the CSV of their scalar fields.

One record per task: a planning run
(:func:`drake_social.experiments.study.runs.run_task`) or a crowd episode
(:func:`drake_social.experiments.study.crowd_episode.run_episode`). The
record files are written by :mod:`.framework` (each kind names its own:
:mod:`.kinds`); :func:`best_runs` and :func:`comparable` read a planning
study's records.
"""

from __future__ import annotations

import csv
import dataclasses as dc
import io
from typing import Any, Sequence

from drake_social.scenario.schema import Scenario

__all__ = [
    "TIMING_FIELDS",
    "StudyOutputError",
    "StudyResult",
    "best_runs",
    "comparable",
    "results_csv",
]

#: Record fields that measure the machine, not the method (left out of comparisons).
TIMING_FIELDS = ("planning_time", "exec_wall_time", "progress_time")


def comparable(record: dict) -> dict:
    """The record without :data:`TIMING_FIELDS` (what must not depend on the machine)."""
    return {k: v for k, v in record.items() if k not in TIMING_FIELDS}


@dc.dataclass
class StudyResult:
    """A finished study of any kind.

    Attributes:
        study: what was run: a :class:`~drake_social.experiments.study.Study`
            or a :class:`~drake_social.experiments.study.crowd.CrowdStudy`.
        records: one per task, in task order.
        wall_time: seconds for all tasks (executor start-up included).
        executor, workers: where they ran.
        scenario_texts: the study's name of a scenario (a group's name, a
            crowd scenario's file stem, a recorded crowd's window) -> the
            text its tasks loaded (read once, before the first task).
        tasks: the plain-data tasks the records came from, in the same
            order (what a kind's outputs may need beyond the records: a
            recorded crowd's window files); empty when not kept.
    """

    study: Any
    records: list[dict]
    wall_time: float
    executor: str = "process"
    workers: int = 1
    scenario_texts: dict[str, str] = dc.field(default_factory=dict)
    tasks: list[dict] = dc.field(default_factory=list)

    def scenario(self, name: str, **options) -> Scenario:
        """The scenario ``name`` ran on, from the text read before the tasks
        (the file may have changed since): the study's ``scenario(name,
        text, **options)`` (a crowd study's take the ``variant``)."""
        return self.study.scenario(name, self.scenario_texts.get(name), **options)


def best_runs(records: Sequence[dict]) -> dict[tuple[str, str], dict]:
    """(group, algorithm) -> the successful run of lowest planner cost (its own
    objective: length for rrt_star, its weights' social cost otherwise)."""
    best: dict[tuple[str, str], dict] = {}
    for r in records:
        if not r["success"]:
            continue
        k = (r["group"], r["algorithm"])
        if k not in best or (r["cost"], r["run"]) < (best[k]["cost"], best[k]["run"]):
            best[k] = r
    return best


class StudyOutputError(OSError):
    """A finished study's outputs could not all be written; the message says
    where its records were kept."""


def results_csv(records: Sequence[dict], non_scalar: Sequence[str]) -> str:
    """Every field of every record but ``non_scalar``, one row per record (empty cell: no value)."""
    columns: list[str] = []
    for r in records:
        columns += [k for k in r if k not in non_scalar and k not in columns]
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for r in records:
        writer.writerow(["" if r.get(c) is None else (repr(r[c]) if isinstance(r[c], float) else r[c])
                         for c in columns])
    return buf.getvalue()
