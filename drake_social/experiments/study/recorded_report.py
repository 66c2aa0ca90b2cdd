"""The recorded-crowd benchmark's outputs after its records: the windows'
scenario files, the figures and REPORT.md (``drake-social experiment crowd
--recording``; the records and the output set are the study framework's).

Files: ``window_<k>.yaml`` and ``window_<k>_people.csv`` (each window's
scenario, as its episodes ran it before the overrides: ``drake-social
simulate window_0.yaml --replan`` runs it again), ``boxplots_<recording>.png``
(intimate and personal zone time, minimum distance per part and variant,
every window's episodes), ``snapshots_window_<k>.png`` (the traced episode
of every variant at a few times) and ``REPORT.md``.

Comparisons pair the variants over (window, episode) (the records'
``episode``), with the studies' paired one-sided Wilcoxon test
(:func:`~drake_social.experiments.study.crowd_report.compare`): every
replanning variant against ``plan_once`` on :data:`CLAIMS`. The targets
(:func:`target_lines`) are issue 32's: the goal reached while the people are
present in at least :data:`CROSSING_TARGET` of the episodes, no contact begun
while the robot was commanded to move, and over every periodic replan a
median wall time of at most :data:`REPLAN_MEDIAN_TARGET` and a 99th
percentile within ``planner.replan_budget``.
"""

from __future__ import annotations

import math
import os
import platform
from pathlib import Path
from typing import Sequence

import numpy as np

from drake_social.experiments.study.crowd_report import PARTS, claim_line, compare, label, parts_table
from drake_social.experiments.study.report import ALPHA, median_iqr

__all__ = ["CLAIMS", "CROSSING_TARGET", "REPLAN_MEDIAN_TARGET", "claim_lines", "episode_table", "figure_names",
           "output_names", "report_markdown", "target_lines", "window_files", "window_table", "write_figures",
           "write_outputs", "write_window_files"]

#: Share of the episodes in which a variant should cross while people are present.
CROSSING_TARGET = 0.8
#: Replan time targets: median (seconds), and the 99th percentile within the scenario's budget.
REPLAN_MEDIAN_TARGET = 0.01
#: (metric, claim): a replanning variant's is claimed lower/higher than plan_once's.
CLAIMS = (("crossed", "higher"), ("goal_distance_end", "lower"), ("nav_time_to_goal", "lower"),
          ("nav_collisions_moving_robot", "lower"), ("nav_collisions_robot", "lower"),
          ("nav_time_intimate_robot", "lower"), ("nav_time_intimate_object", "lower"),
          ("nav_min_dist_robot", "higher"), ("nav_stopped_time", "lower"))


def window_files(study) -> list[str]:
    """Each window's scenario and people file."""
    return [f for name in study.window_names() for f in (f"{name}.yaml", f"{name}_people.csv")]


def figure_names(study) -> list[str]:
    """The boxplots of the recording and, with a traced episode, each window's snapshots."""
    return [f"boxplots_{study.stem}.png"] + ([f"snapshots_{name}.png" for name in study.window_names()]
                                             if study.trace_episode is not None else [])


def output_names(study) -> list[str]:
    """Every file name :func:`write_outputs` may write (known before any episode)."""
    return [*window_files(study), *figure_names(study), "REPORT.md"]


def claim_lines(records: Sequence[dict], stem: str, variants: Sequence[str]) -> list[str]:
    """:data:`CLAIMS` of every replanning variant against ``plan_once``, paired over (window, episode)."""
    if "plan_once" not in variants:
        return []
    return [claim_line(compare(records, stem, v, "plan_once", metric, claim), stem)
            for v in variants if v != "plan_once" for metric, claim in CLAIMS]


def _runs(records, variant, window=None) -> list[dict]:
    return [r for r in records if r["variant"] == variant and (window is None or r["window"] == window)]


def _sum(runs, field) -> int:
    return int(sum(r.get(field) or 0 for r in runs if r.get(field) is None or np.isfinite(r.get(field))))


def target_lines(records: Sequence[dict], variants: Sequence[str], budgets: dict[str, float]) -> list[str]:
    """Issue 32's targets per variant over every window's episodes
    (``budgets``: variant -> ``planner.replan_budget``, seconds); ``plan_once``
    gets the crossing and contact lines as a reference."""
    lines = []
    for v in variants:
        runs = _runs(records, v)
        if not runs:
            continue
        n = len(runs)
        tag = "target" if v != "plan_once" else "reference"
        crossed = sum(1 for r in runs if r["crossed"] == 1.0)
        lines.append(f"- **{'MET' if crossed >= CROSSING_TARGET * n else 'MISSED'}** ({tag}): {label(v)}: crossed "
                     f"while people were present in {crossed}/{n} episodes = {100 * crossed / n:.0f} % (target >= "
                     f"{100 * CROSSING_TARGET:.0f} %)")
        moving, appeared, contacts = (_sum(runs, f"nav_collisions{c}_robot") for c in ("_moving", "_appeared", ""))
        lines.append(f"- **{'MET' if moving == 0 else 'MISSED'}** ({tag}): {label(v)}: contacts begun while the robot "
                     f"was commanded to move: {moving} (target 0); of all {contacts} contact(s), {appeared} by a person "
                     f"appearing in contact and {contacts - moving - appeared} of a person walking into the held robot")
        if v == "plan_once":
            continue
        times = np.asarray([t for r in runs for t in r.get("replan_times", ())], float)
        if not len(times):
            lines.append(f"- **MISSED** (target): {label(v)}: no periodic replan was logged")
            continue
        med, p99 = float(np.median(times)), float(np.percentile(times, 99))
        budget = budgets.get(v, math.nan)
        hits = _sum(runs, "replan_deadline_hits")
        ok = med <= REPLAN_MEDIAN_TARGET and p99 <= budget
        lines.append(f"- **{'MET' if ok else 'MISSED'}** (target): {label(v)}: replan time over {len(times)} replans: "
                     f"median {1000 * med:.3g} ms (target <= {1000 * REPLAN_MEDIAN_TARGET:g} ms), 99th percentile "
                     f"{1000 * p99:.3g} ms (target <= the budget {1000 * budget:g} ms), {hits} deadline hits")
    return lines


def window_table(windows: Sequence[dict]) -> list[str]:
    """One row per window: where it is in the recording, its crowd, the turn, the room and the task."""
    lines = ["| window | recording t, s | people present: mean [min, max] | at t = 0 | flow axis, deg | turned by, "
             "deg | room, m | task, m | start / goal clearance, m |", "|---|---|---:|---:|---:|---:|---|---:|---:|"]
    for w in windows:
        lines.append(f"| {w['name']} | {w['start']:g} .. {w['end']:g} | {w['people_mean']:.1f} [{w['people_min']}, "
                     f"{w['people_max']}] | {w['people_t0']} | {math.degrees(w['flow_angle']):.0f} | "
                     f"{math.degrees(w['rotation']):.0f} | {w['bounds'][2]:g} x {w['bounds'][3]:g} | "
                     f"{w['task_length']:.1f} | {w['clearance_start']:.2f} / {w['clearance_goal']:.2f} |")
    return lines


_EPISODE_COLUMNS = (("time_to_goal", "time to goal s", ".3g"), ("goal_distance_end", "to goal at end m", ".3g"),
                    ("nav_stopped_time", "stopped s", ".3g"), ("replan_changes", "changes", ".3g"),
                    ("replan_waits", "waits", ".3g"), ("replan_evasions", "side-steps", ".3g"),
                    ("replan_time_median", "replan median s", ".3g"), ("wall_time", "episode wall s", ".3g"))


def episode_table(records: Sequence[dict], windows: Sequence[dict], variants: Sequence[str]) -> list[str]:
    """Per window and variant: crossings, contacts by cause, and the medians of :data:`_EPISODE_COLUMNS`."""
    lines = ["| window | variant | crossed | contacts: moving / appeared / held | "
             + " | ".join(h for _, h, _ in _EPISODE_COLUMNS) + " |",
             "|---|---|---:|---:|" + "---:|" * len(_EPISODE_COLUMNS)]
    for k, w in enumerate(windows):
        for v in variants:
            runs = _runs(records, v, k)
            if not runs:
                continue
            crossed = sum(1 for r in runs if r["crossed"] == 1.0)
            moving, appeared, contacts = (_sum(runs, f"nav_collisions{c}_robot") for c in ("_moving", "_appeared", ""))
            lines.append(f"| {w['name']} | {v} | {crossed}/{len(runs)} | {moving} / {appeared} / "
                         f"{contacts - moving - appeared} | "
                         + " | ".join(median_iqr([r.get(f) for r in runs], fmt) for f, _, fmt in _EPISODE_COLUMNS)
                         + " |")
    return lines


def _windows(result) -> list[dict]:
    """Each window's summary, in window order (from the tasks)."""
    seen: dict[int, dict] = {}
    for task in result.tasks:
        seen.setdefault(task["window"], task["window_summary"])
    return [seen[k] for k in sorted(seen)]


def report_markdown(result, figures: Sequence[str], budgets: dict[str, float]) -> str:
    """The whole REPORT.md of a recorded-crowd study's
    :class:`~drake_social.experiments.study.results.StudyResult`."""
    st = result.study
    variants = list(st.variants)
    windows = _windows(result)
    seeds = st.run_seeds()
    overrides = "; ".join(f"`{v}`: " + ", ".join(f"`{o}`" for o in st.overrides(v)) for v in variants)
    limit = "the window's length" if st.time_limit is None else f"{st.time_limit:g} s"
    lines = [f"# drake-social experiment crowd --recording {Path(st.recording).name}", "",
             f"{len(result.records)} closed-loop episodes (kinematic) on {len(windows)} windows of {st.window_length:g} s "
             f"of `{st.recording}` (layout {st.layout}, t = frame / {st.fps:g}) with at least {st.min_people} "
             f"people present on average, chosen densest first: {st.episodes} episode(s) per window and variant, "
             f"study seed {st.seed} (episode seeds {seeds[:3]}{'...' if len(seeds) > 3 else ''}, shared by every "
             f"window and variant: paired), time limit {limit}. Wall time {result.wall_time:.1f} s on "
             f"{result.workers} worker(s) ({result.executor}), {os.cpu_count()} CPUs, "
             f"{platform.processor() or platform.machine()}, {platform.platform()}.", "",
             f"Overrides of each variant, in order: {overrides}.", "",
             "Each window's people are turned so that their flow runs along y, across the robot's task along +x; the "
             "start and the goal lie outside the flow, at least 1 m from everyone present at t = 0 (window_<k>.yaml "
             "says how each was made). A **crossing** is the goal reached while the window still has people "
             "(`crossed`: time to goal <= the last time anyone is present). Contacts (distance <= 0) are counted "
             "where they start, by cause: begun with the robot commanded to move (neither held by the safety monitor "
             "nor waiting for a replan), of a person appearing in contact (a recorded track that begins inside the "
             "robot), and the rest: a person walked into the held robot.", "",
             "## Windows", ""] + window_table(windows)
    lines += ["", "## Claims", "",
              f"Paired over (window, episode), one-sided Wilcoxon signed-rank test at {ALPHA} (SUPPORTED: the claimed "
              "side wins the median difference and p < 0.05; NOT SIGNIFICANT: it wins, p >= 0.05; NOT SUPPORTED: it "
              "does not win).", ""]
    lines += claim_lines(result.records, st.stem, variants) or ["- (plan_once and a replanning variant did not both run)"]
    lines += ["", "## Targets (issue 32)", ""] + target_lines(result.records, variants, budgets)
    lines += ["", "## Episodes", "", "Crossed and contacts: counts over the episodes; the other cells: median [25th, "
              "75th percentile].", ""] + episode_table(result.records, windows, variants)
    lines += ["", "## Per body part (every window)", ""] + parts_table(result.records, [st.stem], variants)
    lines += ["", "## Figures", ""] + [f"![{n}]({n})" for n in figures]
    lines += ["", "Per-episode records: `records.csv` (scalars) and `records.json` (with every replan's wall time and "
              "the traced episodes); each window's scenario: `window_<k>.yaml` and `window_<k>_people.csv`.", ""]
    return "\n".join(lines)


#: The boxplots' metrics: (label, nav_ metric prefix).
_BOX_METRICS = (("intimate-zone time, s", "time_intimate"), ("personal-zone time, s", "time_personal"),
                ("minimum distance to a person, m", "min_dist"))


def write_window_files(result, out: Path) -> list[str]:
    """Each window's scenario and people file (from its tasks' text); returns the names."""
    names = []
    done = set()
    for task in result.tasks:
        if task["window"] in done:
            continue
        done.add(task["window"])
        (out / task["people_name"]).write_text(task["people_text"])
        (out / f"{task['window_name']}.yaml").write_text(task["scenario_text"])
        names += [f"{task['window_name']}.yaml", task["people_name"]]
    return names


def write_figures(result, out: Path) -> list[str]:
    """The boxplots over every window and each window's snapshots (its scenario
    read from ``out``, where :func:`write_window_files` put it); returns the names."""
    from drake_social.viz.crowd import part_boxplots_figure, snapshots_figure

    st = result.study
    variants = list(st.variants)
    records = result.records
    values = {lab: {p: {v: [r.get(f"nav_{m}_{p}") for r in records if r["variant"] == v] for v in variants}
                    for p in PARTS} for lab, m in _BOX_METRICS}
    fig = part_boxplots_figure(values, title=f"{st.stem}: {len(_windows(result))} windows x {st.episodes} paired "
                               "episode(s) per variant, per body part (surface distance to the nearest person)")
    names = [f"boxplots_{st.stem}.png"]
    fig.savefig(out / names[0], dpi=100)
    for w in _windows(result):
        k = w["index"]
        traced = {r["variant"]: r["trace"] for r in records if r["window"] == k and "trace" in r}
        if not traced:
            continue
        episode = next(r for r in records if r["window"] == k and "trace" in r)
        scenario = st.scenario(w["name"], result.scenario_texts[w["name"]], folder=out)
        fig = snapshots_figure(scenario, traced, title=f"{st.stem} {w['name']} (t = {w['start']:g} .. {w['end']:g} s "
                               f"of the recording), episode {episode['window_episode']}: robot, people, base track so "
                               "far (red, dashed) and the path followed then (blue)")
        fig.savefig(out / f"snapshots_{w['name']}.png", dpi=90)
        names.append(f"snapshots_{w['name']}.png")
    return names


def write_outputs(result, out: Path) -> list[str]:
    """Writes the windows' files, the figures and REPORT.md into ``out`` (the
    records are there already); returns the file names."""
    files = write_window_files(result, out)
    figures = write_figures(result, out)
    st = result.study
    first = _windows(result)[0]["name"] if result.tasks else None
    budgets = {} if first is None else {
        v: float(st.scenario(first, result.scenario_texts[first], folder=out, variant=v).planner.replan_budget)
        for v in st.variants}
    (out / "REPORT.md").write_text(report_markdown(result, figures, budgets))
    return [*files, *figures, "REPORT.md"]
