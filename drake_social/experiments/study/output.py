"""A study's output set: the records, the figures, REPORT.md and the Planner Arena files.

The records (:func:`~drake_social.experiments.study.results.write_records`)
are written first, so that an error in a later file never costs the
finished runs.
"""

from __future__ import annotations

from pathlib import Path

from drake_social.experiments.study import arena, report
from drake_social.experiments.study.results import RECORD_FILES, StudyResult, write_records
from drake_social.experiments.study.spec import Study

__all__ = ["output_names", "write_study"]


def output_names(study: Study) -> list[str]:
    """Every file name :func:`write_study` may write for ``study``, known
    before any run (so that an output folder can refuse what is in their
    way up front): the records, the figures, the arena logs, ``arena.db``
    and ``REPORT.md``."""
    return [*RECORD_FILES, *report.figure_names(study), *(arena.log_name(g) for g in study.groups), "arena.db",
            "REPORT.md"]


def write_study(result: StudyResult, out_dir: str | Path, *, scenario_loader=None) -> list[str]:
    """Writes results.csv, results.json, the figures, REPORT.md and the Planner
    Arena log (``arena_<scenario>.log``, one experiment per scenario) and, when
    OMPL's statistics script is importable, ``arena.db``, into ``out_dir``.

    The records (:func:`write_records`) are written first: when a later file
    fails, they are complete in ``out_dir``.

    Returns:
        The names of the written files.
    """
    out = Path(out_dir)
    names = write_records(result, out)
    figures = report.write_figures(result, out)
    names += figures
    logs = arena.write_logs(result, out)
    names += logs
    if arena.build_database([out / n for n in logs], out / "arena.db") is not None:
        logs.append("arena.db")
        names.append("arena.db")
    (out / "REPORT.md").write_text(report.report_markdown(result, figures, arena_files=logs))
    names.append("REPORT.md")
    return names
