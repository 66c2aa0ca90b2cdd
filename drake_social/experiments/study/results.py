"""A finished study's records: the result, the best runs, and the record files.

One record per run (see :func:`drake_social.experiments.study.runs.run_task`);
:func:`write_records` writes them as results.csv and results.json
(:data:`RECORD_FILES`) before any other output, and :func:`rescue_records`
into a new folder when the output folder cannot take them.
"""

from __future__ import annotations

import csv
import dataclasses as dc
import io
import json
import tempfile
from pathlib import Path
from typing import Sequence

from drake_social.experiments.study.scenarios import load_cached
from drake_social.experiments.study.spec import Group, Study
from drake_social.io.json_numbers import finite_or_none
from drake_social.io.textfile import read_yaml_file
from drake_social.scenario.schema import Scenario

__all__ = [
    "RECORD_FILES",
    "TIMING_FIELDS",
    "StudyOutputError",
    "StudyResult",
    "best_runs",
    "comparable",
    "rescue_records",
    "results_csv",
    "write_records",
]

#: Record fields that measure the machine, not the method (left out of comparisons).
TIMING_FIELDS = ("planning_time", "exec_wall_time", "progress_time")


def comparable(record: dict) -> dict:
    """The record without :data:`TIMING_FIELDS` (what must not depend on the machine)."""
    return {k: v for k, v in record.items() if k not in TIMING_FIELDS}


@dc.dataclass
class StudyResult:
    """A finished study.

    Attributes:
        study: what was run.
        records: one per task, in task order (see :func:`~drake_social.experiments.study.runs.run_task`).
        wall_time: seconds for all runs (executor start-up included).
        executor, workers: where they ran.
    """

    study: Study
    records: list[dict]
    wall_time: float
    executor: str = "process"
    workers: int = 1
    #: Group name -> the scenario text its runs loaded (read once, before the first run).
    scenario_texts: dict[str, str] = dc.field(default_factory=dict)

    def group(self, name: str) -> Group:
        return next(g for g in self.study.groups if g.name == name)

    def scenario(self, name: str) -> Scenario:
        """The scenario group ``name`` ran on, from the text read before the runs (the file may have changed since)."""
        g = self.group(name)
        text = self.scenario_texts[name] if name in self.scenario_texts else read_yaml_file(g.scenario, "scenario")
        return load_cached(g.scenario, text, tuple(g.overrides), f"group {g.name}")


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
    where its records (:data:`RECORD_FILES`) were kept."""

_NON_SCALAR = ("waypoints", "progress", "progress_time", "overrides")
#: The files holding every run's record, written before any other output.
RECORD_FILES = ("results.csv", "results.json")


def results_csv(records: Sequence[dict]) -> str:
    """Every scalar field of every record, one row per run (empty cell: no value)."""
    columns: list[str] = []
    for r in records:
        columns += [k for k in r if k not in _NON_SCALAR and k not in columns]
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for r in records:
        writer.writerow(["" if r.get(c) is None else (repr(r[c]) if isinstance(r[c], float) else r[c])
                         for c in columns])
    return buf.getvalue()


def write_records(result: StudyResult, out_dir: str | Path) -> list[str]:
    """Writes the records of every run: results.csv and results.json
    (:data:`RECORD_FILES`) into ``out_dir`` (created when missing).

    Returns:
        The names of the written files.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.csv").write_text(results_csv(result.records))
    meta = {"study": result.study.to_json_dict(), "seeds": result.study.run_seeds(), "wall_time": result.wall_time,
            "executor": result.executor, "workers": result.workers}
    (out / "results.json").write_text(json.dumps(finite_or_none({**meta, "runs": result.records}), allow_nan=False) + "\n")
    return list(RECORD_FILES)


def rescue_records(result: StudyResult) -> Path:
    """Writes the records (:func:`write_records`) into a new folder of the
    system's temporary directory (``$TMPDIR``), for when the output folder
    cannot take them; returns the folder."""
    folder = Path(tempfile.mkdtemp(prefix="drake-social-records-"))
    write_records(result, folder)
    return folder
