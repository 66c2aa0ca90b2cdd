"""The crowd study's outputs after its records: the figures and REPORT.md
(``drake-social experiment crowd``; the records and the output set are the
study framework's, :mod:`.framework`).

Figures, per scenario: ``boxplots_<scenario>.png`` (intimate and personal
zone time, minimum distance per part and variant) and
``snapshots_<scenario>.png`` (the traced episode of every variant at a few
times).

Comparisons pair the variants over episodes (episode k of every variant has
the same seed and the same walkers' delays): :func:`compare` reuses the
studies' paired test (:func:`drake_social.experiments.study.report.paired`:
medians, median of the differences a - b, wins, one-sided Wilcoxon
signed-rank p-value, the verdict at ``ALPHA``), every episode that ran
counting (a timed-out episode too; a metric that is NaN, e.g. the time to
goal of one that did not arrive, leaves its pair out).

:data:`CLAIMS` are the comparisons of the issue (what multi-point replanning
buys over base-only replanning, replanning over planning once, speed scaling
over the fixed AGF); :func:`target_lines` checks the issue's targets
(no collision with people, success >= 95 %, replan time median <= 0.05 s and
95th percentile <= the budget) on the replanning variants; its contact line
splits the contacts as ``nav_collisions_moving_robot`` and
``nav_collisions_appeared_robot`` do (the robot commanded to move, a person
appearing in contact, the rest: a person walked into the held robot).
"""

from __future__ import annotations

import math
import os
import platform
from pathlib import Path
from typing import Sequence

import numpy as np

from drake_social.experiments.study.report import ALPHA, Comparison, median_iqr, paired

__all__ = ["CLAIMS", "PARTS", "PART_METRICS", "SUCCESS_TARGET", "claim_line", "claim_lines", "compare", "figure_names",
           "label", "output_names", "parts_table", "report_markdown", "target_lines", "variant_table",
           "write_figures", "write_outputs"]

#: The per-part metrics of the tables and boxplots: (metric, header, unit, format).
PART_METRICS = (("time_intimate", "intimate s", "s", ".3g"), ("time_personal", "personal s", "s", ".3g"),
                ("min_dist", "min distance m", "m", ".3g"), ("collisions", "contacts", "", ".3g"))
PARTS = ("base", "arm", "object", "robot")
#: Success share the issue asks of the replanning variants.
SUCCESS_TARGET = 0.95
#: Replan time targets: median and 95th percentile (None = the scenario's budget), seconds.
REPLAN_MEDIAN_TARGET = 0.05
_LABEL = {"plan_once": "plan-once (paper)", "replan": "replanning (default)", "replan_base": "replanning base-only",
          "replan_multi": "replanning multi-point", "replan_speed": "replanning multi-point + speed scaling"}
_WORDS = {"time_intimate": "intimate-zone time", "time_personal": "personal-zone time", "min_dist": "minimum distance",
          "collisions": "contacts", "collisions_moving": "contacts begun while moving", "time_to_goal": "time to goal",
          "stopped_time": "stopped time", "stop_count": "safety stops",
          "crossed": "crossings while people are present", "goal_distance_end": "distance to the goal at the end"}
#: The unit of a metric without a part that is not in seconds.
_UNITS = {"stop_count": "", "crossed": "", "goal_distance_end": "m"}

#: (a, b, metric (a ``nav_`` field), claim): a is claimed lower/higher than b.
CLAIMS = (
    ("replan_multi", "replan_base", "nav_time_intimate_object", "lower"),
    ("replan_multi", "replan_base", "nav_time_intimate_arm", "lower"),
    ("replan_multi", "replan_base", "nav_time_personal_object", "lower"),
    ("replan_multi", "replan_base", "nav_min_dist_object", "higher"),
    ("replan_multi", "plan_once", "nav_time_intimate_robot", "lower"),
    ("replan_multi", "plan_once", "nav_collisions_robot", "lower"),
    ("replan_multi", "plan_once", "nav_min_dist_robot", "higher"),
    ("replan_multi", "plan_once", "nav_stopped_time", "lower"),
    ("replan_multi", "plan_once", "nav_time_to_goal", "lower"),
    ("replan_speed", "replan_multi", "nav_time_personal_robot", "lower"),
    ("replan_speed", "replan_multi", "nav_time_intimate_robot", "lower"),
)


def _view(records: Sequence[dict]) -> list[dict]:
    """The records as :func:`paired` reads them: group = scenario, algorithm =
    variant, run = episode, success = the episode ran."""
    return [{**r, "group": r["scenario"], "algorithm": r["variant"], "run": r["episode"], "success": True}
            for r in records]


def compare(records: Sequence[dict], scenario: str, a: str, b: str, metric: str, claim: str = "lower") -> Comparison:
    """Variant a against variant b on ``metric`` in ``scenario``, paired over
    episodes (:func:`~drake_social.experiments.study.report.paired`)."""
    return paired(_view(records), (scenario, a), (scenario, b), metric, claim)


def _metric_words(metric: str) -> tuple[str, str]:
    """``nav_time_intimate_object`` -> ("object intimate-zone time", "s")."""
    name = metric.removeprefix("nav_")
    for part in PARTS:
        if name.endswith("_" + part):
            base = name[: -len(part) - 1]
            unit = "m" if base.startswith("min_dist") else "" if base.startswith("collisions") else "s"
            return f"{part} {_WORDS.get(base, base)}", unit
    return _WORDS.get(name, name), _UNITS.get(name, "s")


def label(variant: str) -> str:
    """A variant's name in the report's words."""
    return _LABEL[variant]


def claim_line(c: Comparison, scenario: str) -> str:
    """One claim line: ``- **SUPPORTED**: office_walkers: replanning multi-point vs
    replanning base-only: object intimate-zone time lower in 14/20 paired episodes
    (median 1.2 s vs 3.4 s, median difference -0.8 s, Wilcoxon p = 0.012)``."""
    what, unit = _metric_words(c.metric)
    u = f" {unit}" if unit else ""
    if c.n == 0:
        return (f"- **{c.verdict.upper()}**: {scenario}: {_LABEL[c.a[1]]} vs {_LABEL[c.b[1]]}: {what} {c.claim}: no "
                "paired episode has a value on both sides")
    return (f"- **{c.verdict.upper()}**: {scenario}: {_LABEL[c.a[1]]} vs {_LABEL[c.b[1]]}: {what} {c.claim} in "
            f"{c.wins}/{c.n} paired episodes (median {c.median_a:.4g}{u} vs {c.median_b:.4g}{u}, median difference "
            f"{c.median_diff:+.3g}{u}, one-sided Wilcoxon p = {c.p:.3g})")


def claim_lines(records: Sequence[dict], scenarios: Sequence[str], variants: Sequence[str]) -> list[str]:
    """The :data:`CLAIMS` whose two variants ran, per scenario."""
    lines = []
    for s in scenarios:
        for a, b, metric, claim in CLAIMS:
            if a in variants and b in variants:
                lines.append(claim_line(compare(records, s, a, b, metric, claim), s))
    return lines


def _runs(records, scenario, variant) -> list[dict]:
    return [r for r in records if r["scenario"] == scenario and r["variant"] == variant]


def _values(runs, field) -> np.ndarray:
    return np.asarray([r[field] for r in runs if r.get(field) is not None and np.isfinite(r[field])], float)


def target_lines(records: Sequence[dict], scenarios: Sequence[str], variants: Sequence[str],
                 budgets: dict[str, float]) -> list[str]:
    """The issue's targets per scenario and replanning variant: no contact
    with a person in any episode, success >= :data:`SUCCESS_TARGET`, and
    over every periodic replan of the episodes a median wall time <=
    :data:`REPLAN_MEDIAN_TARGET` and a 95th percentile <= the scenario's
    ``planner.replan_budget`` (``budgets``: scenario -> seconds). Plan-once
    variants get the contact and success lines only, as a reference."""
    lines = []
    for s in scenarios:
        for v in variants:
            runs = _runs(records, s, v)
            if not runs:
                continue
            n = len(runs)
            touched = sum(1 for r in runs if (r.get("nav_collisions_robot") or 0) > 0)
            contacts = int(sum(r.get("nav_collisions_robot") or 0 for r in runs))
            moving, appeared = (_values(runs, f"nav_collisions_{c}_robot") for c in ("moving", "appeared"))
            stops = _values(runs, "nav_stop_count")
            reached = sum(1 for r in runs if r["reached"] == 1.0)
            tag = "target" if v != "plan_once" else "reference"
            lines.append(f"- **{'MET' if touched == 0 else 'MISSED'}** ({tag}): {s}, {_LABEL[v]}: collisions with "
                         f"people: {contacts} contact(s) in {touched}/{n} episodes, {int(moving.sum())} begun with "
                         f"the robot commanded to move, {int(appeared.sum())} by a person appearing in contact, the "
                         f"rest walked into the held robot (safety stops: "
                         f"{int(stops.sum()) if len(stops) else 0} in all, median {np.median(stops) if len(stops) else 0:g} "
                         f"per episode)")
            lines.append(f"- **{'MET' if reached >= SUCCESS_TARGET * n else 'MISSED'}** ({tag}): {s}, {_LABEL[v]}: "
                         f"success {reached}/{n} = {100 * reached / n:.1f} % (target >= {100 * SUCCESS_TARGET:.0f} %)")
            if v == "plan_once":
                continue
            times = np.asarray([t for r in runs for t in r.get("replan_times", ())], float)
            if not len(times):
                lines.append(f"- **MISSED** (target): {s}, {_LABEL[v]}: no periodic replan was logged")
                continue
            med, p95 = float(np.median(times)), float(np.percentile(times, 95))
            budget = budgets.get(s, math.nan)
            hits = int(sum(r.get("replan_deadline_hits") or 0 for r in runs))
            ok = med <= REPLAN_MEDIAN_TARGET and p95 <= budget
            lines.append(f"- **{'MET' if ok else 'MISSED'}** (target): {s}, {_LABEL[v]}: replan time over {len(times)} "
                         f"replans: median {med:.3g} s (target <= {REPLAN_MEDIAN_TARGET:g} s), 95th percentile "
                         f"{p95:.3g} s (target <= the budget {budget:g} s), max {times.max():.3g} s, {hits} deadline hits")
    return lines


_VARIANT_COLUMNS = (("nav_time_to_goal", "time to goal s", ".3g"), ("nav_stop_count", "safety stops", ".3g"),
                    ("nav_stopped_time", "stopped s", ".3g"), ("replans", "replans", ".4g"),
                    ("replan_changes", "changes", ".3g"), ("replan_waits", "waits", ".3g"),
                    ("replan_time_median", "replan median s", ".3g"), ("replan_time_p95", "replan p95 s", ".3g"),
                    ("replan_deadline_hits", "deadline hits", ".3g"), ("plan_time_initial", "first plan s", ".3g"),
                    ("wall_time", "episode wall s", ".3g"))


def variant_table(records: Sequence[dict], scenarios: Sequence[str], variants: Sequence[str]) -> list[str]:
    """Per scenario and variant: success, and the medians [IQR] of the episode columns."""
    lines = ["| scenario | variant | success | " + " | ".join(h for _, h, _ in _VARIANT_COLUMNS) + " |",
             "|---|---|---:|" + "---:|" * len(_VARIANT_COLUMNS)]
    for s in scenarios:
        for v in variants:
            runs = _runs(records, s, v)
            if runs:
                reached = sum(1 for r in runs if r["reached"] == 1.0)
                lines.append(f"| {s} | {v} | {reached}/{len(runs)} | "
                             + " | ".join(median_iqr([r.get(f) for r in runs], fmt) for f, _, fmt in _VARIANT_COLUMNS) + " |")
    return lines


def parts_table(records: Sequence[dict], scenarios: Sequence[str], variants: Sequence[str]) -> list[str]:
    """Per scenario, variant and part: the medians [IQR] of :data:`PART_METRICS`."""
    lines = ["| scenario | variant | part | " + " | ".join(h for _, h, _, _ in PART_METRICS) + " |",
             "|---|---|---|" + "---:|" * len(PART_METRICS)]
    for s in scenarios:
        for v in variants:
            runs = _runs(records, s, v)
            for p in PARTS if runs else ():
                lines.append(f"| {s} | {v} | {p} | " + " | ".join(
                    median_iqr([r.get(f"nav_{m}_{p}") for r in runs], fmt) for m, _, _, fmt in PART_METRICS) + " |")
    return lines


def report_markdown(result, figures: Sequence[str], budgets: dict[str, float]) -> str:
    """The whole REPORT.md of a crowd study's
    :class:`~drake_social.experiments.study.results.StudyResult`."""
    st = result.study
    scenarios = list(dict.fromkeys(r["scenario"] for r in result.records)) or [s for s in result.scenario_texts]
    variants = list(st.variants)
    seeds = st.run_seeds()
    limit = "each scenario's execution.time_limit" if st.time_limit is None else f"{st.time_limit:g} s"
    lines = [f"# drake-social experiment crowd ({st.name})", "",
             f"{len(result.records)} closed-loop episodes (kinematic): {st.episodes} per (scenario, variant), study "
             f"seed {st.seed} (episode seeds {seeds[:3]}{'...' if len(seeds) > 3 else ''}, shared by every scenario "
             f"and variant: paired), scripted walkers' start delays uniform in [0, {st.jitter:g}] s, time limit "
             f"{limit}. Wall time "
             f"{result.wall_time:.1f} s on {result.workers} worker(s) ({result.executor}), {os.cpu_count()} CPUs, "
             f"{platform.processor() or platform.machine()}, {platform.platform()}.", "",
             "Variants: " + "; ".join(f"`{v}` ({_LABEL[v]})" for v in variants) + ". Metrics over time against "
             "where the people were (`nav_*` of `records.csv`): surface-to-surface distances of each part (base, "
             "arm, object, the whole robot) to the nearest present person; seconds in Hall's intimate (< 0.45 m) "
             "and personal (< 1.2 m) zones; contacts (distance <= 0) counted where they start, and of them those "
             "begun with the robot commanded to move (neither held by the safety monitor nor waiting for a replan) "
             "and those of a person appearing in contact; safety stops of the monitor; success = the goal reached "
             "within the time limit.", "",
             "## Claims", "",
             f"Paired over episodes, one-sided Wilcoxon signed-rank test at {ALPHA} (SUPPORTED: the claimed side wins "
             "the median difference and p < 0.05; NOT SIGNIFICANT: it wins, p >= 0.05; NOT SUPPORTED: it does not "
             "win).", ""]
    lines += claim_lines(result.records, scenarios, variants) or ["- (fewer than two of the compared variants ran)"]
    lines += ["", "## Targets (issue 21)", ""] + target_lines(result.records, scenarios, variants, budgets)
    lines += ["", "## Episodes", "", "Cells: median [25th, 75th percentile] over the episodes.", ""]
    lines += variant_table(result.records, scenarios, variants)
    lines += ["", "## Per body part", ""] + parts_table(result.records, scenarios, variants)
    lines += ["", "## Figures", ""] + [f"![{n}]({n})" for n in figures]
    lines += ["", "Per-episode records: `records.csv` (scalars) and `records.json` (with the walkers' delays, every "
              "replan's wall time and the traced episodes).", ""]
    return "\n".join(lines)


# ---- the figures and the outputs after the records ------------------------------------

#: The boxplots' metrics: (label, nav_ metric prefix).
_BOX_METRICS = (("intimate-zone time, s", "time_intimate"), ("personal-zone time, s", "time_personal"),
                ("minimum distance to a person, m", "min_dist"))


def figure_names(study) -> list[str]:
    """The figure files :func:`write_figures` writes for a
    :class:`~drake_social.experiments.study.crowd.CrowdStudy`."""
    stems = [Path(s).stem for s in study.scenarios]
    return [f"boxplots_{s}.png" for s in stems] + ([f"snapshots_{s}.png" for s in stems]
                                                   if study.trace_episode is not None else [])


def output_names(study) -> list[str]:
    """Every file name :func:`write_outputs` may write (known before any episode)."""
    return [*figure_names(study), "REPORT.md"]


def write_figures(result, out: Path) -> list[str]:
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


def write_outputs(result, out: Path) -> list[str]:
    """Writes the figures and REPORT.md into ``out`` (the records are there
    already); returns the file names."""
    figures = write_figures(result, out)
    budgets = {stem: float(result.scenario(stem, variant=v).planner.replan_budget)
               for stem in result.scenario_texts for v in result.study.variants[:1]}
    (out / "REPORT.md").write_text(report_markdown(result, figures, budgets))
    return [*figures, "REPORT.md"]
