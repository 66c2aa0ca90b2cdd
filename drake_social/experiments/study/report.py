"""REPORT.md of a study: tables, figures and the paper's claims checked in numbers.

Every claim line is computed from the records: a paired comparison over
seeds (run r of both sides planned with the same seed; pairs where either
side failed are left out) gives the medians, the median of the differences,
the wins and a one-sided Wilcoxon signed-rank p-value. The verdict is

* **supported**: the claimed side wins the median difference and p < :data:`ALPHA`;
* **not significant**: it wins the median difference, p >= ALPHA;
* **not supported**: it does not win the median difference (or no pair).

A claim made of several comparisons gets the weakest of their verdicts.
"""

from __future__ import annotations

import dataclasses as dc
import math
import platform
import os
from pathlib import Path
from typing import Sequence

import numpy as np

from drake_social.experiments.study.people_tables import people_tables
from drake_social.experiments.study.results import best_runs

__all__ = ["ALPHA", "OFF_SCALE_FACTOR", "Claim", "Comparison", "axis_stretch", "boxplot_values", "median_iqr", "paired",
           "figure_names", "paper_claims", "report_markdown", "write_figures"]

#: Significance level of the one-sided paired test.
ALPHA = 0.05
#: A group's boxplot leaves RRT* out (and gives its median in a note) only
#: when its runs would stretch the value axis to more than this many times
#: the other algorithms' size: the range of their runs, or their largest
#: magnitude when that is larger (:func:`axis_stretch`).
OFF_SCALE_FACTOR = 3.0
_ORDER = ("supported", "not significant", "not supported")
_SHORT = {"rrt_star": "RRT*", "social_rrt_star": "Risk-RRT* (multi-point)", "base_rrt_star": "Risk-RRT* (base-only)",
          "informed_social_rrt_star": "Informed (multi-point)", "informed_base_rrt_star": "Informed (base-only)"}


@dc.dataclass
class Comparison:
    """Side a against side b on one metric, paired over seeds.

    Attributes:
        a, b: ``(group, algorithm)`` of each side.
        metric: the record field compared.
        claim: "lower" or "higher": what a is claimed to be.
        n: pairs; median_a, median_b: medians over the pairs;
        median_diff: median of a - b; wins: pairs where a is strictly better;
        p: one-sided Wilcoxon signed-rank p-value (1 when every difference is 0).
    """

    a: tuple[str, str]
    b: tuple[str, str]
    metric: str
    claim: str
    n: int = 0
    median_a: float = math.nan
    median_b: float = math.nan
    median_diff: float = math.nan
    wins: int = 0
    p: float = math.nan

    @property
    def verdict(self) -> str:
        if self.n == 0 or not np.isfinite(self.median_diff):
            return "not supported"
        right = self.median_diff < 0 if self.claim == "lower" else self.median_diff > 0
        if not right:
            return "not supported"
        return "supported" if self.p < ALPHA else "not significant"

    def text(self, label_a: str, label_b: str, unit: str = "") -> str:
        return (f"{label_a} {self.median_a:.4g}{unit} vs {label_b} {self.median_b:.4g}{unit} "
                f"(median {self.metric}; paired median difference {self.median_diff:+.3g}, "
                f"{label_a} {self.claim} in {self.wins}/{self.n} seeds, Wilcoxon p = {self.p:.3g}: {self.verdict})")


def paired(records: Sequence[dict], a: tuple[str, str], b: tuple[str, str], metric: str,
           claim: str = "lower") -> Comparison:
    """Compares side a with side b on ``metric`` over the runs both solved."""
    from scipy.stats import wilcoxon

    def side(key):
        return {r["run"]: r.get(metric) for r in records
                if (r["group"], r["algorithm"]) == key and r["success"] and r.get(metric) is not None
                and np.isfinite(r.get(metric))}

    va, vb = side(a), side(b)
    runs = sorted(set(va) & set(vb))
    out = Comparison(a, b, metric, claim, n=len(runs))
    if not runs:
        return out
    x = np.array([va[r] for r in runs], float)
    y = np.array([vb[r] for r in runs], float)
    d = x - y
    out.median_a, out.median_b, out.median_diff = float(np.median(x)), float(np.median(y)), float(np.median(d))
    out.wins = int(np.sum(d < 0) if claim == "lower" else np.sum(d > 0))
    if np.all(d == 0):
        out.p = 1.0
    else:
        out.p = float(wilcoxon(d, alternative="less" if claim == "lower" else "greater").pvalue)
    return out


@dc.dataclass
class Claim:
    """One of the paper's claims and the comparisons that check it."""

    statement: str
    source: str
    lines: list[str]
    verdicts: list[str]

    @property
    def verdict(self) -> str:
        return max(self.verdicts, key=_ORDER.index) if self.verdicts else "not supported"

    def markdown(self) -> str:
        body = "\n".join(f"  - {line}" for line in self.lines)
        return f"- **{self.verdict.upper()}**: {self.statement} ({self.source})\n{body}"


def _median(records, group, algorithm, metric) -> float:
    v = [r[metric] for r in records if r["group"] == group and r["algorithm"] == algorithm and r["success"]
         and r.get(metric) is not None and np.isfinite(r[metric])]
    return float(np.median(v)) if v else math.nan


def _claim(statement: str, source: str, comparisons: list[tuple[Comparison, str, str, str]],
           extra: list[tuple[str, str]] = ()) -> Claim:
    lines, verdicts = [], []
    for c, la, lb, unit in comparisons:
        lines.append(f"{c.a[0]}: " + c.text(la, lb, unit) if c.a[0] == c.b[0] else c.text(la, lb, unit))
        verdicts.append(c.verdict)
    for line, verdict in extra:
        lines.append(line)
        verdicts.append(verdict)
    return Claim(statement, source, lines, verdicts)


def paper_claims(records: Sequence[dict]) -> list[Claim]:
    """The paper's claims (Sections V-A to V-D) checked on the records of
    :func:`~drake_social.experiments.study.paper_study` (groups A, B, D_*)."""
    s = _SHORT
    social = ("social_rrt_star", "base_rrt_star", "informed_social_rrt_star", "informed_base_rrt_star")
    claims = []
    claims.append(_claim(
        "every social planner has a lower social cost F (all points) than RRT*", "V-A, V-B",
        [(paired(records, (g, a), (g, "rrt_star"), "F_multi"), s[a], s["rrt_star"], "")
         for g in ("A", "B") for a in social]))
    claims.append(_claim(
        "Social Risk-RRT*'s paths are longer than RRT*'s (base path, metres)", "V-A, V-B",
        [(paired(records, (g, "social_rrt_star"), (g, "rrt_star"), "base_length", "higher"), s["social_rrt_star"],
          s["rrt_star"], " m") for g in ("A", "B")]))
    claims.append(_claim(
        "multi-point planners beat their base-only counterparts on F (all points) in both scenarios", "V-C",
        [(paired(records, (g, m), (g, b), "F_multi"), s[m], s[b], "")
         for g in ("A", "B") for m, b in (("social_rrt_star", "base_rrt_star"),
                                          ("informed_social_rrt_star", "informed_base_rrt_star"))]))
    claims.append(_claim(
        "on the generic map, multi-point Risk-RRT* beats the multi-point informed variant", "V-C",
        [(paired(records, ("B", "social_rrt_star"), ("B", "informed_social_rrt_star"), "F_multi"),
          s["social_rrt_star"], s["informed_social_rrt_star"], "")]))
    medians = {a: _median(records, "A", a, "F_multi") for a in social}
    finite = {a: m for a, m in medians.items() if np.isfinite(m)}
    best = min(finite, key=finite.get) if finite else None
    runner = min((a for a in finite if a != "informed_social_rrt_star"), key=finite.get, default=None)
    ranking = ", ".join(f"{s[a]} {m:.4g}" for a, m in sorted(finite.items(), key=lambda kv: kv[1]))
    extra = [(f"A: lowest median F among the social planners: {s[best] if best else 'none'} ({ranking})",
              "supported" if best == "informed_social_rrt_star" else "not supported")]
    comps = [] if runner is None else [(paired(records, ("A", "informed_social_rrt_star"), ("A", runner), "F_multi"),
                                        s["informed_social_rrt_star"], s[runner], "")]
    claims.append(_claim("on the office, the multi-point informed variant is the best planner", "V-C", comps, extra))
    claims.append(_claim(
        "the favoured part keeps farther from people (generic map, bar, Social Risk-RRT*; min surface distance)",
        "V-D",
        [(paired(records, ("D_base", "social_rrt_star"), ("D_object", "social_rrt_star"), "min_dist_base",
                 "higher"), "base weights: the base", "object weights: the base", " m"),
         (paired(records, ("D_object", "social_rrt_star"), ("D_base", "social_rrt_star"), "min_dist_object",
                 "higher"), "object weights: the object", "base weights: the object", " m")]))
    claims.append(_claim(
        "the favoured part meets less discomfort (length-normalised mean AGF of the part)", "V-D",
        [(paired(records, ("D_base", "social_rrt_star"), ("D_object", "social_rrt_star"), "agf_mean_base"),
          "base weights: the base", "object weights: the base", ""),
         (paired(records, ("D_object", "social_rrt_star"), ("D_base", "social_rrt_star"), "agf_mean_object"),
          "object weights: the object", "base weights: the object", "")]))
    return claims


def sweep_comparisons(result) -> list[str]:
    """For a sweep: in each group, every algorithm against the group's first,
    on F (all points), paired over seeds."""
    lines = []
    for g in result.study.groups:
        ref = g.algorithms[0]
        for a in g.algorithms[1:]:
            c = paired(result.records, (g.name, a), (g.name, ref), "F_multi")
            lines.append(f"- {g.name}: " + c.text(a, ref))
    return lines


# ---- tables -----------------------------------------------------------------------

_SUMMARY = (("F_multi", "F all points", ".4g"), ("F_base", "F base only", ".4g"), ("path_length", "C-space length", ".3g"),
            ("base_length", "base path m", ".3g"), ("irregularity", "irregularity rad/m", ".3g"),
            ("min_dist_robot", "min distance m", ".3g"), ("planning_time", "planning s", ".3g"))


def median_iqr(values, fmt: str) -> str:
    """``"median [25th, 75th percentile]"`` of the finite values (None and NaN
    left out), each in ``fmt``; "n/a" when there is none."""
    v = np.asarray([x for x in values if x is not None and np.isfinite(x)], float)
    if not len(v):
        return "n/a"
    q25, med, q75 = np.percentile(v, [25, 50, 75])
    return f"{med:{fmt}} [{q25:{fmt}}, {q75:{fmt}}]"


def summary_table(result) -> list[str]:
    lines = ["| group | algorithm | success | " + " | ".join(h for _, h, _ in _SUMMARY) + " |",
             "|---|---|---:|" + "---|" * len(_SUMMARY)]
    for g in result.study.groups:
        for a in g.algorithms:
            runs = [r for r in result.records if r["group"] == g.name and r["algorithm"] == a]
            ok = [r for r in runs if r["success"]]
            cells = [median_iqr([r.get(f) for r in (runs if f == "planning_time" else ok)], fmt) for f, _, fmt in _SUMMARY]
            lines.append(f"| {g.name} | {a} | {len(ok)}/{len(runs)} | " + " | ".join(cells) + " |")
    return lines


def parts_table(result, groups: Sequence[str] | None = None) -> list[str]:
    """Per-part medians: min distance, intimate + personal share, AGF max and mean."""

    lines = ["| group | algorithm | part | min distance m | intimate+personal share | social share | AGF max | "
             "AGF mean |", "|---|---|---|---:|---:|---:|---:|---:|"]
    for g in result.study.groups:
        if groups is not None and g.name not in groups:
            continue
        for a in g.algorithms:
            ok = [r for r in result.records if r["group"] == g.name and r["algorithm"] == a and r["success"]]
            if not ok:
                continue
            parts = [k.removeprefix("min_dist_") for k in ok[0] if k.startswith("min_dist_")]
            for p in parts:
                close = [r.get(f"zone_intimate_{p}", math.nan) + r.get(f"zone_personal_{p}", math.nan) for r in ok]
                cells = [median_iqr([r.get(f"{m}_{p}") for r in ok], fmt) for m, fmt in (("min_dist", ".3g"),)]
                cells.append(median_iqr(close, ".2f"))
                cells += [median_iqr([r.get(f"{m}_{p}") for r in ok], fmt)
                          for m, fmt in (("zone_social", ".2f"), ("agf_max", ".3g"), ("agf_mean", ".3g"))]
                lines.append(f"| {g.name} | {a} | {p} | " + " | ".join(cells) + " |")
    return lines


# ---- figures ----------------------------------------------------------------------


def _finite(values) -> np.ndarray:
    return np.asarray([v for v in values if v is not None and np.isfinite(v)], float)


def axis_stretch(values: Sequence[float], others: Sequence[float]) -> float:
    """How many times wider a value axis becomes when ``values`` join ``others``.

    The range of both together over the others' size: their range, or their
    largest magnitude when that is larger. A combined axis at most a few times
    the others' size keeps them readable, whether their runs are spread
    (their range) or (nearly) equal, e.g. one run each (their magnitude: 10.3
    beside 16.6, or 1 beside 2.5, both fit). None and NaN are left out; 1
    when either side has no value, or when every other value is 0 (drawn at 0
    on any axis: nothing of them is squeezed).
    """
    v, o = _finite(values), _finite(others)
    if not len(v) or not len(o):
        return 1.0
    size = max(float(o.max() - o.min()), float(np.abs(o).max()))
    if size == 0.0:
        return 1.0
    both = float(max(v.max(), o.max()) - min(v.min(), o.min()))
    return both / size


def _describe_runs(values: np.ndarray) -> str:
    """``"range 20 to 92"``, or ``"runs all at 10.3"`` when they are equal."""
    lo, hi = float(values.min()), float(values.max())
    if f"{lo:.3g}" == f"{hi:.3g}":
        return f"runs all at {lo:.3g}" if lo == hi else f"runs all near {lo:.3g}"
    return f"range {lo:.3g} to {hi:.3g}"


def boxplot_values(records: Sequence[dict], group: str, algorithms: Sequence[str],
                   factor: float = OFF_SCALE_FACTOR) -> tuple[dict[str, list[float]], str | None]:
    """The final costs F of a group's boxplot, and the note under it.

    Every algorithm's successful runs are shown, except RRT* (which ignores
    the people, so its costs can be orders of magnitude above the others')
    when :func:`axis_stretch` of its runs against the other algorithms' runs
    exceeds ``factor``; the note then says so, with its median.

    Args:
        records: the study's records (``group``, ``algorithm``, ``success``, ``F_multi``).
        group: the group's name.
        algorithms: the group's algorithms, in the boxplot's order.
        factor: the largest stretch of the axis that RRT* may cause and be shown.

    Returns:
        ``(values, note)``: algorithm -> F of its successful runs; the note or None.
    """
    values = {a: [r["F_multi"] for r in records if r["group"] == group and r["algorithm"] == a and r["success"]]
              for a in algorithms}
    if "rrt_star" not in values or len(values) < 2:
        return values, None
    others = [v for a, vs in values.items() if a != "rrt_star" for v in vs]
    stretch = axis_stretch(values["rrt_star"], others)
    if stretch <= factor:
        return values, None
    o = _finite(others)
    med = _median(records, group, "rrt_star", "F_multi")
    del values["rrt_star"]
    return values, (f"RRT* not shown: its median F = {med:.4g}; its runs would stretch the axis "
                    f"{stretch:.3g}x the others' size ({_describe_runs(o)}; shown up to {factor:g}x)")


def figure_names(study) -> list[str]:
    """The file names :func:`write_figures` writes for ``study``: for each
    group of several algorithms ``boxplot_``, ``cost_profile_`` and
    ``paths_<group>.png``; when there are groups of one algorithm,
    ``paths_single_algorithm_groups.png`` and
    ``boxplot_single_algorithm_groups.png``."""
    names = [f"{kind}_{g.name}.png" for g in study.groups if len(g.algorithms) > 1
             for kind in ("boxplot", "cost_profile", "paths")]
    if any(len(g.algorithms) == 1 for g in study.groups):
        names += ["paths_single_algorithm_groups.png", "boxplot_single_algorithm_groups.png"]
    return names


def write_figures(result, out: Path) -> list[str]:
    """Boxplots of F per group, cost against distance and best paths; returns the file names."""
    from drake_social.viz.path import cost_profile_figure
    from drake_social.viz.study import boxplot_figure, paths_side_by_side

    names = []
    best = best_runs(result.records)

    def scenario_of(g):
        return result.scenario(g.name)

    def save(fig, name):
        fig.savefig(out / name, dpi=110)
        names.append(name)

    multi = [g for g in result.study.groups if len(g.algorithms) > 1]
    for g in multi:
        scen = scenario_of(g)
        values, note = boxplot_values(result.records, g.name, g.algorithms)
        save(boxplot_figure(values, title=f"{g.label or g.name}: final cost F(q_end), all interest points, "
                            f"{result.study.runs} runs of K = {result.study.iterations}",
                            ylabel="F(q_end)  (weights 1 on every point)", note=note), f"boxplot_{g.name}.png")
        paths = {a: np.asarray(best[(g.name, a)]["waypoints"]) if (g.name, a) in best else np.zeros((0, 4))
                 for a in g.algorithms}
        save(cost_profile_figure(scen, paths, title=f"{g.label or g.name}: social cost S(q) along the best run of "
                                 "each algorithm (all points)"), f"cost_profile_{g.name}.png")
        pair = [a for a in ("rrt_star", "social_rrt_star") if a in g.algorithms] or list(g.algorithms[:2])
        panels = {f"{a}: F = {best[(g.name, a)]['F_multi']:.3g}" if (g.name, a) in best else f"{a}: no path":
                  paths[a] for a in pair}
        save(paths_side_by_side(scen, panels, title=f"{g.label or g.name}: best paths"), f"paths_{g.name}.png")
    singles = [g for g in result.study.groups if len(g.algorithms) == 1]
    if singles:  # e.g. the weight study: the best path of each group side by side
        scen = scenario_of(singles[0])
        panels, owns = {}, {}
        for g in singles:
            key = (g.name, g.algorithms[0])
            label = f"{g.name}: F = {best[key]['F_multi']:.3g}" if key in best else f"{g.name}: no path"
            panels[label] = np.asarray(best[key]["waypoints"]) if key in best else np.zeros((0, 4))
            owns[label] = scenario_of(g)
        save(paths_side_by_side(scen, panels, scenarios=owns, title="best path of each group (heat map: the people's "
                                "unweighted field)"), "paths_single_algorithm_groups.png")
        values = {g.name: [r["F_multi"] for r in result.records if r["group"] == g.name and r["success"]]
                  for g in singles}
        save(boxplot_figure(values, title="final cost F(q_end), all interest points, weight 1",
                            ylabel="F(q_end)"), "boxplot_single_algorithm_groups.png")
    return names


# ---- the report -------------------------------------------------------------------


def report_markdown(result, figures: Sequence[str], arena_files: Sequence[str] = (), claims=None) -> str:
    """The whole REPORT.md."""
    st = result.study
    paper = st.name == "paper"
    lines = [f"# drake-social experiment {st.name}", "",
             f"{len(result.records)} runs: {st.runs} per (group, algorithm), K = {st.iterations}, study seed "
             f"{st.seed} (run seeds {st.run_seeds()[:3]}{'...' if st.runs > 3 else ''}, shared by every group and "
             f"algorithm), checker `{st.checker}`{', executed in the kinematic simulation' if st.simulate else ''}. "
             f"Wall time {result.wall_time:.1f} s on {result.workers} worker(s) ({result.executor}), "
             f"{os.cpu_count()} CPUs, {platform.platform()}.", "",
             "F is the paper's final cost F(q_end) with weight 1 on every interest point, whatever weights the "
             "planner used; the best run of an algorithm is the one of lowest cost by its own objective. "
             "Cells: median [25th, 75th percentile] over the successful runs (planning time: all runs).", "",
             "## Groups", ""]
    lines += [f"- `{g.name}`: {g.label or g.scenario} ({Path(g.scenario).name}"
              + (f", overrides {list(g.overrides)}" if g.overrides else "") + ")" for g in st.groups]
    lines += ["", "## Claims", ""]
    if claims is None and paper:
        claims = paper_claims(result.records)
    if claims:
        lines += ["Paired over seeds, one-sided Wilcoxon signed-rank test at "
                  f"{ALPHA}; see `drake_social/experiments/study/report.py` for the verdict rule.", ""]
        lines += [c.markdown() for c in claims]
    else:
        lines += ["Each algorithm against the group's first, on F, paired over seeds:", ""]
        lines += sweep_comparisons(result) or ["- (one algorithm per group: nothing to compare)"]
    lines += ["", "## Results", ""] + summary_table(result)
    part_groups = [g.name for g in st.groups if g.name.startswith("D_")] if paper else None
    lines += ["", "## Per body part" + (" (weight study D)" if paper else ""), "",
              "Surface-to-surface distances to the nearest person's body; zone shares of the base's arc length "
              "(Hall: intimate < 0.45 m, personal < 1.2 m, social < 3.6 m); AGF: sum over people, thresholded.", ""]
    lines += parts_table(result, part_groups)
    if paper:
        lines += ["", "Per-part tables of every group are in `results.csv` (`min_dist_<part>`, `zone_<zone>_<part>`, "
                  "`agf_max_<part>`, `agf_mean_<part>`)."]
    walking = people_tables(result, median_iqr)
    lines += ["", *walking] if walking else []
    lines += ["", "## Figures", ""] + [f"![{n}]({n})" for n in figures]
    if arena_files:
        lines += ["", "## Planner Arena", "",
                  "OMPL benchmark logs (one experiment per scenario and group) and the database OMPL's "
                  "`ompl_benchmark_statistics.py` built from them, for plannerarena.org: "
                  + ", ".join(f"`{n}`" for n in arena_files) + "."]
    lines += ["", "Raw per-run results: `results.csv` (scalars) and `results.json` (with waypoints and anytime "
              "curves).", ""]
    return "\n".join(lines)
