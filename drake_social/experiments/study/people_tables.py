"""REPORT.md's tables of the executed runs among walking people.

Read from the ``nav_*`` fields of the runs' records
(:data:`drake_social.io.records.NAV_FIELDS`), shown for the groups whose
executed runs had people moving (``nav_people_moving``): per part, the
minimum distance, the time in Hall's zones, the contacts and the space
compliance; per algorithm, the outcome, the safety stops and the motion.
"""

from __future__ import annotations

from typing import Callable, Sequence

__all__ = ["moving_people_groups", "people_tables"]

#: Per-part columns: (metric, header, format).
_PART_COLUMNS = (("min_dist", "min distance m", ".3g"), ("time_intimate", "intimate s", ".3g"),
                 ("time_personal", "personal s", ".3g"), ("time_social", "social s", ".3g"),
                 ("collisions", "contacts", ".3g"), ("collision_time", "contact s", ".3g"),
                 ("space_compliance", "space compliance", ".2f"))
#: Per-run columns: (field, header, format).
_RUN_COLUMNS = (("nav_time_to_goal", "time to goal s", ".3g"), ("nav_stop_count", "safety stops", ".3g"),
                ("nav_stopped_time", "stopped s", ".3g"), ("nav_speed_mean_base", "mean base speed m/s", ".3g"),
                ("nav_jerk_max_base", "max base jerk m/s^3", ".3g"))
_PARTS = ("base", "arm", "object", "robot")


def moving_people_groups(records: Sequence[dict]) -> list[str]:
    """The groups (in record order) with an executed run among moving people."""
    groups: list[str] = []
    for r in records:
        if r.get("nav_people_moving") == 1.0 and r["group"] not in groups:
            groups.append(r["group"])
    return groups


def people_tables(result, stat: Callable[[Sequence], str]) -> list[str]:
    """Markdown lines of the two tables (none when nobody walked in any run).

    Args:
        result: the :class:`~drake_social.experiments.study.results.StudyResult`.
        stat: formats a column of values (None and non-finite left out) with a
            format spec, e.g. the report's median [25th, 75th percentile].
    """
    groups = moving_people_groups(result.records)
    if not groups:
        return []
    runs_head = "| group | algorithm | reached | " + " | ".join(h for _, h, _ in _RUN_COLUMNS) + " |"
    parts_head = "| group | algorithm | part | " + " | ".join(h for _, h, _ in _PART_COLUMNS) + " |"
    runs = [runs_head, "|---|---|---:|" + "---:|" * len(_RUN_COLUMNS)]
    parts = [parts_head, "|---|---|---|" + "---:|" * len(_PART_COLUMNS)]
    for g in result.study.groups:
        if g.name not in groups:
            continue
        for a in g.algorithms:
            done = [r for r in result.records if r["group"] == g.name and r["algorithm"] == a and "nav_success" in r]
            if not done:
                continue
            reached = sum(1 for r in done if r["nav_success"] == 1.0)
            runs.append(f"| {g.name} | {a} | {reached}/{len(done)} | "
                        + " | ".join(stat([r.get(f) for r in done], fmt) for f, _, fmt in _RUN_COLUMNS) + " |")
            for p in _PARTS:
                parts.append(f"| {g.name} | {a} | {p} | " + " | ".join(
                    stat([r.get(f"nav_{m}_{p}") for r in done], fmt) for m, _, fmt in _PART_COLUMNS) + " |")
    return ["## Among walking people (executed runs)", "",
            "Each executed run measured against where the people actually were (`nav_*` fields of "
            "`results.csv`): surface-to-surface distances of each part to the nearest present person; seconds in "
            "Hall's intimate (< 0.45 m), personal (< 1.2 m) and social (< 3.6 m) zones; contacts (distance <= 0) "
            "counted where they start; space compliance = share of the time at >= 0.45 m from everyone; safety "
            "stops of the monitor. Cells: median [25th, 75th percentile] over the executed runs.", "",
            *runs, "", *parts]
