"""The crowd study's output set: records.csv and records.json (every
episode, written first), the figures and REPORT.md.

Figures, per scenario: ``boxplots_<scenario>.png`` (intimate and personal
zone time, minimum distance per part and variant) and
``snapshots_<scenario>.png`` (the traced episode of every variant at a few
times).
"""

from __future__ import annotations

import json
from pathlib import Path
from drake_social.experiments.crowd import CrowdResult, CrowdStudy
from drake_social.experiments.crowd_report import PARTS, report_markdown
from drake_social.experiments.study.results import results_csv
from drake_social.io.json_numbers import finite_or_none

__all__ = ["RECORD_FILES", "crowd_output_names", "figure_names", "write_crowd", "write_crowd_records"]

#: The files holding every episode's record, written before any other output.
RECORD_FILES = ("records.csv", "records.json")
#: Record fields that are not scalars (left out of records.csv).
_NON_SCALAR = ("delays", "replan_times", "trace")
#: The boxplots' metrics: (label, nav_ metric prefix).
_BOX_METRICS = (("intimate-zone time, s", "time_intimate"), ("personal-zone time, s", "time_personal"),
                ("minimum distance to a person, m", "min_dist"))


def figure_names(study: CrowdStudy) -> list[str]:
    """The figure files :func:`write_crowd` writes for ``study``."""
    stems = [Path(s).stem for s in study.scenarios]
    return [f"boxplots_{s}.png" for s in stems] + ([f"snapshots_{s}.png" for s in stems]
                                                   if study.trace_episode is not None else [])


def crowd_output_names(study: CrowdStudy) -> list[str]:
    """Every file name :func:`write_crowd` may write (known before any episode)."""
    return [*RECORD_FILES, *figure_names(study), "REPORT.md"]


def write_crowd_records(result: CrowdResult, out_dir: str | Path) -> list[str]:
    """Writes records.csv (the scalar fields) and records.json (everything) into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    scalars = [{k: v for k, v in r.items() if k not in _NON_SCALAR} for r in result.records]
    (out / "records.csv").write_text(results_csv(scalars))
    meta = {"study": result.study.to_json_dict(), "seeds": result.study.seeds(), "wall_time": result.wall_time,
            "executor": result.executor, "workers": result.workers}
    (out / "records.json").write_text(json.dumps(finite_or_none({**meta, "episodes": result.records}),
                                                 allow_nan=False) + "\n")
    return list(RECORD_FILES)


def write_figures(result: CrowdResult, out: Path) -> list[str]:
    """The boxplots and snapshots of every scenario; returns the file names."""
    from drake_social.viz.crowd import part_boxplots_figure, snapshots_figure

    names = []
    variants = list(result.study.variants)
    for stem in dict.fromkeys(r["scenario"] for r in result.records):
        runs = [r for r in result.records if r["scenario"] == stem]
        values = {label: {p: {v: [r.get(f"nav_{m}_{p}") for r in runs if r["variant"] == v] for v in variants}
                          for p in PARTS} for label, m in _BOX_METRICS}
        fig = part_boxplots_figure(values, title=f"{stem}: {result.study.episodes} paired episodes per variant, "
                                   "per body part (surface distance to the nearest person)")
        fig.savefig(out / f"boxplots_{stem}.png", dpi=100)
        names.append(f"boxplots_{stem}.png")
        traced = {v: r["trace"] for v in variants for r in runs if r["variant"] == v and "trace" in r}
        if traced:
            episode = next(r for r in runs if "trace" in r)
            fig = snapshots_figure(result.scenario(stem), traced,
                                   title=f"{stem}, episode {episode['episode']} (seed {episode['seed']}): robot, "
                                   "people, base track so far (red, dashed) and the path followed then (blue)")
            fig.savefig(out / f"snapshots_{stem}.png", dpi=90)
            names.append(f"snapshots_{stem}.png")
    return names


def write_crowd(result: CrowdResult, out_dir: str | Path) -> list[str]:
    """Writes the records (first), the figures and REPORT.md into ``out_dir``; returns the file names."""
    out = Path(out_dir)
    names = write_crowd_records(result, out)
    figures = write_figures(result, out)
    names += figures
    budgets = {stem: float(result.scenario(stem, v).planner.replan_budget)
               for stem in result.scenario_texts for v in result.study.variants[:1]}
    (out / "REPORT.md").write_text(report_markdown(result, figures, budgets))
    names.append("REPORT.md")
    return names



def run_crowd_study(study: CrowdStudy, out: str | Path, *, executor: str = "process", workers: int = 1,
                    scheduler: str | None = None, progress=None) -> tuple[CrowdResult, list[str], Exception | None]:
    """Runs ``study`` (:func:`~drake_social.experiments.crowd.run_crowd`) and
    writes its outputs into ``out`` as one output set (staged, swapped in at
    once: :class:`~drake_social.io.outputs.OutputSet`).

    When a figure or REPORT.md fails, the records alone are committed.

    Returns:
        ``(the result, the names written, the error of the outputs after the records or None)``.

    Raises:
        ScenarioError: a scenario or variant is invalid (before any episode).
    """
    from drake_social.experiments.crowd import check_crowd_study, run_crowd
    from drake_social.io.outputs import OutputSet

    check_crowd_study(study)  # every scenario and variant loaded and checked before the output folder is taken
    failure = None
    with OutputSet(out, "experiment", names=crowd_output_names(study)) as outputs:
        result = run_crowd(study, executor=executor, workers=workers, scheduler=scheduler, progress=progress)
        try:
            names = write_crowd(result, outputs.folder)
        except Exception as e:  # the finished episodes are kept: the set becomes the records
            failure = e
            for name in crowd_output_names(study):
                if (outputs.folder / name).is_file():
                    (outputs.folder / name).unlink()
            names = write_crowd_records(result, outputs.folder)
    return result, names, failure
