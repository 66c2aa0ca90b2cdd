"""The one study framework: a study of any kind (:mod:`.kinds`) run on an
executor and written as one output set.

:func:`run_study` turns the study into its kind's tasks (checked before any
run) and maps its kind's per-task function over them on an executor
(:func:`~drake_social.experiments.study.executors.map_tasks`: in this
process, a process pool or Dask); the records come back in task order and
never depend on the executor or the number of workers (each task carries its
seed). :func:`write_study` writes the records first (:func:`write_records`:
the kind's CSV and JSON files), then the kind's outputs after them, so that
an error in a later file never costs the finished tasks;
:func:`rescue_records` writes the records into a new folder when the output
folder cannot take them.
"""

from __future__ import annotations

import json
import logging
import tempfile
import time
from pathlib import Path
from typing import Callable

from drake_social.experiments.study.executors import map_tasks
from drake_social.experiments.study.kinds import kind_of
from drake_social.experiments.study.results import StudyResult, results_csv
from drake_social.io.json_numbers import finite_or_none

__all__ = ["count", "output_names", "record_files", "rescue_records", "run_study", "write_records", "write_study"]

_log = logging.getLogger(__name__)


def run_study(study, *, tasks: list[dict] | None = None, executor: str = "process", workers: int = 1,
              scheduler: str | None = None, progress: Callable[[int, int, dict], None] | None = None) -> StudyResult:
    """Runs every task of ``study`` on an executor (see
    :func:`~drake_social.experiments.study.executors.map_tasks`).

    Args:
        study: a study of any kind (:data:`~drake_social.experiments.study.kinds.KINDS`).
        tasks: its kind's tasks, when the caller has made (and so checked) them already; None = made here.
        executor, workers, scheduler: where the tasks go.
        progress: optional ``progress(done, total, record)`` after each task.

    Raises:
        ScenarioError: the study or one of its scenarios is invalid (before any task ran).
    """
    kind = kind_of(study)
    tasks = kind.tasks(study) if tasks is None else tasks
    t0 = time.perf_counter()
    records = map_tasks(kind.run, tasks, executor=executor, workers=workers, scheduler=scheduler, progress=progress)
    wall = time.perf_counter() - t0
    _log.info("study %s: %s in %.1f s", study.name, count(study, len(records)), wall)
    texts = {task[kind.scenario_key]: task["scenario_text"] for task in tasks}
    return StudyResult(study, records, wall, executor, workers, scenario_texts=texts, tasks=tasks)


def count(study, n: int) -> str:
    """``n`` records of ``study`` in words: "1 run", "12 episodes"."""
    unit = kind_of(study).unit
    return f"{n} {unit}{'' if n == 1 else 's'}"


def record_files(study) -> tuple[str, str]:
    """The records' CSV and JSON files of ``study``'s kind."""
    return kind_of(study).record_files


def output_names(study) -> list[str]:
    """Every file name :func:`write_study` may write for ``study``, known
    before any task (so that an output folder can refuse what is in their
    way up front): the record files, then its kind's outputs."""
    kind = kind_of(study)
    return [*kind.record_files, *kind.output_names(study)]


def write_records(result: StudyResult, out_dir: str | Path) -> list[str]:
    """Writes the records of every task into ``out_dir`` (created when
    missing): the CSV (the scalar fields, one row per task) and the JSON
    (the study's settings, its seeds, where it ran, and every record).

    Returns:
        The names of the written files.
    """
    kind = kind_of(result.study)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    csv_name, json_name = kind.record_files
    (out / csv_name).write_text(results_csv(result.records, kind.non_scalar))
    meta = {"study": result.study.to_json_dict(), "seeds": result.study.run_seeds(), "wall_time": result.wall_time,
            "executor": result.executor, "workers": result.workers}
    (out / json_name).write_text(json.dumps(finite_or_none({**meta, kind.records_key: result.records}),
                                            allow_nan=False) + "\n")
    return list(kind.record_files)


def rescue_records(result: StudyResult) -> Path:
    """Writes the records (:func:`write_records`) into a new folder of the
    system's temporary directory (``$TMPDIR``), for when the output folder
    cannot take them; returns the folder."""
    folder = Path(tempfile.mkdtemp(prefix="drake-social-records-"))
    write_records(result, folder)
    return folder


def write_study(result: StudyResult, out_dir: str | Path) -> list[str]:
    """Writes the records (:func:`write_records`) first, then the outputs
    of the study's kind (figures, REPORT.md, ...), into ``out_dir``: when a
    later file fails, the records are complete there.

    Returns:
        The names of the written files.
    """
    out = Path(out_dir)
    names = write_records(result, out)
    return names + kind_of(result.study).write_outputs(result, out)
