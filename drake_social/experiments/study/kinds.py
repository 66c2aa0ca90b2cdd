"""The kinds of study, one table: what a kind brings to the one framework.

A study of any kind is a frozen dataclass with a ``name``, ``run_seeds()``
(the seed of each run index, shared across its scenarios and variants, so
that comparisons pair), ``to_json_dict()`` and ``scenario(name, text,
...)`` (a scenario it ran, from the text its tasks loaded). Its kind
(:data:`KINDS`, :func:`kind_of`) adds what differs: how the study becomes
plain-data tasks (checked before any run), the module-level function that
runs one task in any process, how its records are filed, and the outputs it
writes after them. The framework (:mod:`.framework`) does the rest for
every kind: the executors, the record files, the output set, the rescue of
the records.

=========  =====================================  ===================================
kind       a task                                 its outputs after the records
=========  =====================================  ===================================
planning   one planner run of a group's scenario  figures, REPORT.md (the paper's
           (:class:`~.spec.Study`: sweeps, the    claims or a sweep's comparisons),
           paper's; :func:`~.runs.run_task`)      Planner Arena logs and database
crowd      one closed-loop episode of a scenario  per-part boxplots, snapshots,
           and a variant (:class:`~.crowd.        REPORT.md (paired claims, the
           CrowdStudy`; :func:`~.crowd_episode.   targets)
           run_episode`)
recorded   one closed-loop episode of a window    the windows' scenario files,
crowd      of a recording and a variant           boxplots, snapshots, REPORT.md
           (:class:`~.recorded.                   (paired claims, the targets)
           RecordedCrowdStudy`; :func:`~.
           recorded.run_window_episode`)
=========  =====================================  ===================================
"""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path
from typing import Any, Callable

from drake_social.experiments.study import arena, crowd_report, recorded_report, report
from drake_social.experiments.study.crowd import CrowdStudy, check_crowd_study
from drake_social.experiments.study.crowd_episode import run_episode
from drake_social.experiments.study.recorded import RecordedCrowdStudy, check_recorded_study, run_window_episode
from drake_social.experiments.study.results import StudyResult
from drake_social.experiments.study.runs import run_task
from drake_social.experiments.study.spec import Study, study_tasks

__all__ = ["KINDS", "StudyKind", "kind_of"]


@dc.dataclass(frozen=True)
class StudyKind:
    """What one kind of study brings to the framework.

    Attributes:
        unit: what one task's record is, in messages ("run", "episode").
        record_files: the records' CSV (their scalar fields) and JSON (all of
            them, with the study's settings and seeds) files.
        records_key: the key of the records' list in the JSON file.
        non_scalar: the record fields left out of the CSV.
        scenario_key: the task field that names a task's scenario in the
            study (:attr:`StudyResult.scenario_texts`' keys).
        tasks: the study's plain-data tasks, in a fixed order; raises
            ScenarioError (nothing has run) when the study or a scenario is invalid.
        run: one task -> its record; a module-level function (workers import it by name).
        describe: a record in a progress line ("A social_rrt_star run 3").
        output_names: every file name ``write_outputs`` may write for a study.
        write_outputs: writes the outputs after the records into a folder;
            returns their names.
        later_outputs: what ``write_outputs`` writes, in messages.
    """

    unit: str
    record_files: tuple[str, str]
    records_key: str
    non_scalar: tuple[str, ...]
    scenario_key: str
    tasks: Callable[[Any], list[dict]]
    run: Callable[[dict], dict]
    describe: Callable[[dict], str]
    output_names: Callable[[Any], list[str]]
    write_outputs: Callable[[StudyResult, Path], list[str]]
    later_outputs: str


def _planning_output_names(study: Study) -> list[str]:
    """The figures, the arena logs, ``arena.db`` and ``REPORT.md``."""
    return [*report.figure_names(study), *(arena.log_name(g) for g in study.groups), "arena.db", "REPORT.md"]


def _write_planning_outputs(result: StudyResult, out: Path) -> list[str]:
    """The figures, the Planner Arena log of each group (``arena_<group>.log``)
    and, when OMPL's statistics script is importable, ``arena.db``, then REPORT.md."""
    figures = report.write_figures(result, out)
    logs = arena.write_logs(result, out)
    names = figures + logs
    if arena.build_database([out / n for n in logs], out / "arena.db") is not None:
        logs.append("arena.db")
        names.append("arena.db")
    (out / "REPORT.md").write_text(report.report_markdown(result, figures, arena_files=logs))
    return [*names, "REPORT.md"]


#: Each kind of study, by the type of its spec.
KINDS: dict[type, StudyKind] = {
    Study: StudyKind(
        unit="run", record_files=("results.csv", "results.json"), records_key="runs",
        non_scalar=("waypoints", "progress", "progress_time", "overrides"), scenario_key="group",
        tasks=study_tasks, run=run_task, describe=lambda r: f"{r['group']} {r['algorithm']} run {r['run']}",
        output_names=_planning_output_names, write_outputs=_write_planning_outputs,
        later_outputs="the figures, REPORT.md and the arena files"),
    CrowdStudy: StudyKind(
        unit="episode", record_files=("records.csv", "records.json"), records_key="episodes",
        non_scalar=("delays", "replan_times", "trace"), scenario_key="scenario",
        tasks=check_crowd_study, run=run_episode,
        describe=lambda r: f"{r['scenario']} {r['variant']} episode {r['episode']}",
        output_names=crowd_report.output_names, write_outputs=crowd_report.write_outputs,
        later_outputs="the figures and REPORT.md"),
    RecordedCrowdStudy: StudyKind(
        unit="episode", record_files=("records.csv", "records.json"), records_key="episodes",
        non_scalar=("delays", "replan_times", "trace"), scenario_key="window_name",
        tasks=check_recorded_study, run=run_window_episode,
        describe=lambda r: f"{r['scenario']} window {r['window']} {r['variant']} episode {r['window_episode']}",
        output_names=recorded_report.output_names, write_outputs=recorded_report.write_outputs,
        later_outputs="the windows' scenario files, the figures and REPORT.md"),
}


def kind_of(study) -> StudyKind:
    """The kind of ``study`` (:data:`KINDS`).

    Raises:
        TypeError: ``study`` is of no kind.
    """
    try:
        return KINDS[type(study)]
    except KeyError:
        raise TypeError(f"not a study: {type(study).__name__}; a study is one of "
                        f"{', '.join(k.__name__ for k in KINDS)}") from None
