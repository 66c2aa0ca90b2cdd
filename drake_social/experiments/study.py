"""Studies: scenarios x algorithms x seeds x overrides, measured per body part.

A :class:`Study` is a list of :class:`Group` s (one scenario with its
overrides and the algorithms planned on it), a run count, K and a seed.
:func:`study_tasks` turns it into plain-data tasks, one per (group,
algorithm, run); run ``r`` of every group and algorithm plans with the same
seed, drawn from the study's seed by ``numpy.random.SeedSequence(seed).spawn``,
so comparisons pair over seeds and the numbers never depend on which worker
ran what. :func:`run_task` (in any process) loads the scenario from its text,
plans, measures the path (:mod:`drake_social.experiments.metrics`) and, with
``simulate``, executes it and measures the executed trajectory too.

* :func:`paper_study`: the paper's Section V (A: office_bar with the bar,
  B: generic_L with the L, the five algorithms; D: generic_L with the bar,
  Social Risk-RRT* under three weightings).
* :func:`load_sweep`: a study from a YAML file (``drake-social experiment sweep``).
* :func:`run_study`: runs the tasks on an executor (:mod:`.executors`).
* :func:`write_study`: results.csv, results.json, the figures, REPORT.md and
  the Planner Arena log and database, as one output set; the records first,
  so that an error in a later file never costs the finished runs
  (:func:`write_records` writes them alone, :func:`rescue_records` into a
  new folder when the output folder cannot take them).
"""

from __future__ import annotations

import csv
import dataclasses as dc
import functools
import io
import json
import logging
import tempfile
import time
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from drake_social.scenario import ALGORITHMS, ScenarioError

__all__ = [
    "PAPER_ALGORITHMS",
    "RECORD_FILES",
    "TIMING_FIELDS",
    "Group",
    "Study",
    "StudyOutputError",
    "StudyResult",
    "best_runs",
    "comparable",
    "load_sweep",
    "paper_study",
    "rescue_records",
    "run_study",
    "run_task",
    "study_tasks",
    "write_records",
    "write_study",
]

_log = logging.getLogger(__name__)

#: The paper's algorithms, in its order (the non-social baseline first).
PAPER_ALGORITHMS = ("rrt_star", "social_rrt_star", "base_rrt_star", "informed_social_rrt_star",
                    "informed_base_rrt_star")
#: Record fields that measure the machine, not the method (left out of comparisons).
TIMING_FIELDS = ("planning_time", "exec_wall_time", "progress_time")
#: Points of the anytime curve kept per run (evenly spaced iterations, the last included).
PROGRESS_POINTS = 50


@dc.dataclass(frozen=True)
class Group:
    """One scenario (with overrides) and the algorithms planned on it.

    Attributes:
        name: the group's name in tables and file names (letters, digits, _ -).
        scenario: the scenario file.
        overrides: YAML mappings applied over the file in turn (as ``--set``).
        algorithms: planners of :data:`drake_social.scenario.ALGORITHMS`.
        label: a human description (tables, figure titles).
    """

    name: str
    scenario: str
    overrides: tuple[str, ...] = ()
    algorithms: tuple[str, ...] = PAPER_ALGORITHMS
    label: str = ""


@dc.dataclass(frozen=True)
class Study:
    """What to run.

    Attributes:
        name: "paper" or the sweep's name.
        groups: the groups.
        runs: runs per (group, algorithm), >= 1.
        iterations: K, samples per run, >= 1.
        seed: the study seed; run r's seed is the r-th spawned SeedSequence's first word.
        simulate: also execute each path in the Drake diagram (kinematic mode).
        checker: validity checker of the planner (``planar``: the fast exact one).
    """

    name: str
    groups: tuple[Group, ...]
    runs: int = 10
    iterations: int = 2000
    seed: int = 0
    simulate: bool = False
    checker: str = "planar"

    def run_seeds(self) -> list[int]:
        """The planner seed of each run index (shared by every group and algorithm)."""
        return [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(self.seed).spawn(self.runs)]

    def to_json_dict(self) -> dict:
        return dc.asdict(self)


def paper_weights(num_points: int) -> dict[str, list[float]]:
    """Section V-D's weightings: object points 0.95 and the rest 0.05; base
    0.95 and the rest 0.05; equal (1 everywhere). Base, link-1 tip, link-2
    tip, then the object's points."""
    obj = [0.05, 0.05, 0.05] + [0.95] * (num_points - 3)
    base = [0.95] + [0.05] * (num_points - 1)
    return {"object": obj, "base": base, "equal": [1.0] * num_points}


def paper_study(*, runs: int = 10, iterations: int = 2000, seed: int = 0, simulate: bool = False,
                scenario_dir: str | Path = "scenarios") -> Study:
    """The paper's Section V (A, B and D; C is A and B's figures).

    D is "the generic map with the bar": generic_L.yaml with the office's
    1.5 m bar (``object: !Bar {length: 1.5, thickness: 0.05}``), 5 interest
    points, planned with Social Risk-RRT* under each of :func:`paper_weights`.
    """
    from drake_social.scenario import interest_point_count, Bar

    d = Path(scenario_dir)
    bar = "object: !Bar {length: 1.5, thickness: 0.05}"
    n = 3 + interest_point_count(Bar(length=1.5, thickness=0.05))
    groups = [
        Group("A", str(d / "office_bar.yaml"), label="A: office, 1.5 m bar"),
        Group("B", str(d / "generic_L.yaml"), label="B: generic map, L-shaped object"),
    ]
    for name, w in paper_weights(n).items():
        groups.append(Group(f"D_{name}", str(d / "generic_L.yaml"),
                            overrides=(bar, f"social: {{weights: {json.dumps(w)}}}"),
                            algorithms=("social_rrt_star",), label=f"D: generic map, bar, {name} weights {w}"))
    return Study("paper", tuple(groups), runs=runs, iterations=iterations, seed=seed, simulate=simulate)


def load_sweep(path: str | Path) -> Study:
    """A study from a YAML file (see ``studies/example_sweep.yaml``)::

        name: lambda_sweep        # the study's name
        runs: 3                   # runs per (scenario, variant, algorithm)
        iterations: 500           # K
        seed: 0                   # the study seed
        simulate: false           # also execute each path
        scenarios:                # files, relative to this YAML's folder or the working directory
          - scenarios/tiny.yaml
        algorithms: [social_rrt_star, base_rrt_star]
        variants:                 # name -> a YAML mapping applied over each scenario (as --set)
          default: {}
          lambda_0.5: {social: {length_weight: 0.5}}

    Groups are scenario x variant, named ``<scenario stem>-<variant>``.

    Raises:
        ScenarioError: the file or a field is invalid (named with the allowed values).
    """
    import yaml

    path = Path(path)
    if not path.is_file():
        raise ScenarioError(f"{path}: no such sweep file")
    try:
        spec = yaml.safe_load(path.read_text())
    except yaml.YAMLError as e:
        raise ScenarioError(f"{path}: not valid YAML: {e}") from e
    if not isinstance(spec, dict):
        raise ScenarioError(f"{path}: must be a YAML mapping with scenarios, algorithms, ...")
    allowed = {"name", "runs", "iterations", "seed", "simulate", "scenarios", "algorithms", "variants", "checker"}
    unknown = sorted(set(spec) - allowed)
    if unknown:
        raise ScenarioError(f"{path}: unknown keys {unknown}; allowed: {', '.join(sorted(allowed))}")

    def integer(key: str, default: int, minimum: int) -> int:
        value = spec.get(key, default)
        if not isinstance(value, int) or isinstance(value, bool) or value < minimum:
            raise ScenarioError(f"{path}: {key}: must be an integer >= {minimum}, got {value!r}")
        return value

    scenarios = spec.get("scenarios")
    if not isinstance(scenarios, list) or not scenarios or not all(isinstance(s, str) for s in scenarios):
        raise ScenarioError(f"{path}: scenarios: must be a non-empty list of scenario files")
    files = []
    for s in scenarios:
        candidate = path.parent / s if not Path(s).is_absolute() and (path.parent / s).is_file() else Path(s)
        if not candidate.is_file():
            raise ScenarioError(f"{path}: scenarios: no such scenario file {s!r}")
        files.append(candidate)
    algorithms = spec.get("algorithms", list(PAPER_ALGORITHMS))
    if not isinstance(algorithms, list) or not algorithms or any(a not in ALGORITHMS for a in algorithms):
        raise ScenarioError(f"{path}: algorithms: must be a non-empty list of {', '.join(ALGORITHMS)}; "
                            f"got {algorithms!r}")
    variants = spec.get("variants", {"default": {}})
    if not isinstance(variants, dict) or not variants or any(not isinstance(v, (dict, type(None))) for v in
                                                             variants.values()):
        raise ScenarioError(f"{path}: variants: must map names to YAML mappings (overrides), got {variants!r}")
    groups = []
    for f in files:
        for vname, override in variants.items():
            texts = (yaml.safe_dump(override, default_flow_style=True).strip(),) if override else ()
            groups.append(Group(f"{f.stem}-{vname}", str(f), overrides=texts, algorithms=tuple(algorithms),
                                label=f"{f.stem}, {vname}" + (f": {texts[0]}" if texts else "")))
    study = Study(str(spec.get("name", path.stem)), tuple(groups), runs=integer("runs", 10, 1),
                  iterations=integer("iterations", 2000, 1), seed=integer("seed", 0, 0),
                  simulate=bool(spec.get("simulate", False)), checker=str(spec.get("checker", "planar")))
    for g in groups:  # every override is checked here, before any run (the error names the file and field)
        _load(Path(g.scenario).name, Path(g.scenario).read_text(), g.overrides)
    return study


def study_tasks(study: Study) -> list[dict]:
    """One plain-data task per (group, algorithm, run), in a fixed order."""
    seeds = study.run_seeds()
    tasks = []
    for group in study.groups:
        text = Path(group.scenario).read_text()
        for algorithm in group.algorithms:
            for run, seed in enumerate(seeds):
                tasks.append({
                    "index": len(tasks), "group": group.name, "scenario": Path(group.scenario).name,
                    "scenario_text": text, "overrides": list(group.overrides), "algorithm": algorithm,
                    "run": run, "seed": seed, "iterations": study.iterations, "simulate": study.simulate,
                    "checker": study.checker,
                })
    return tasks


# ---- in the worker --------------------------------------------------------------


@functools.lru_cache(maxsize=16)
def _load(name: str, text: str, overrides: tuple[str, ...]):
    """The scenario of a task (loaded once per process and overrides)."""
    from drake_social.scenario import load_scenario

    with tempfile.TemporaryDirectory(prefix="drake-social-task-") as d:
        path = Path(d) / name
        path.write_text(text)
        try:
            return load_scenario(path, list(overrides))
        except ScenarioError as e:  # name the study's file, not the temporary copy
            raise ScenarioError(str(e).replace(str(path), name)) from None


@functools.lru_cache(maxsize=16)
def _checker(name: str, text: str, overrides: tuple[str, ...], kind: str):
    from drake_social.model.checker import make_checker

    return make_checker(_load(name, text, overrides), kind, parallelism=1)


def run_task(task: dict) -> dict:
    """Plans one task and measures it; returns a record of plain data.

    The record has the task's keys (without the scenario text), ``success``,
    ``cost`` (the planner's objective), ``planning_time`` (s),
    ``first_solution_iteration``, ``tree_size``, every metric of
    :func:`~drake_social.experiments.metrics.path_metrics` (NaN on failure),
    ``waypoints``, the anytime curve ``progress`` ([iteration, best cost]
    at :data:`PROGRESS_POINTS` iterations) and ``progress_time`` (seconds
    since the start of solve at those iterations); with ``simulate``, the
    ``exec_*`` metrics.
    """
    from drake_social.experiments.metrics import executed_metrics, path_metrics
    from drake_social.planning.objective import SocialObjective
    from drake_social.planning.variants import make_objective, plan

    key = (task["scenario"], task["scenario_text"], tuple(task["overrides"]))
    scenario = _load(*key)
    checker = _checker(*key, task["checker"])
    k = int(task["iterations"])
    marks = set(np.unique(np.linspace(1, k, min(k, PROGRESS_POINTS)).round().astype(int)).tolist())
    curve: list[list[float]] = []
    stamps: list[float] = []
    t0 = time.perf_counter()

    def progress(iteration: int, best: float) -> None:
        if iteration in marks:
            stamps.append(time.perf_counter() - t0)
            curve.append([iteration, best if np.isfinite(best) else None])

    result = plan(scenario, checker, algorithm=task["algorithm"], iterations=k, seed=int(task["seed"]),
                  progress=progress)
    objective = make_objective(scenario, task["algorithm"])
    weights = objective.social.weights if isinstance(objective, SocialObjective) else None
    record = {key: task[key] for key in ("index", "group", "scenario", "overrides", "algorithm", "run", "seed",
                                         "iterations")}
    record.update({
        "success": bool(result.success),
        "cost": float(result.cost) if result.success else None,
        "planning_time": float(result.wall_time),
        "first_solution_iteration": result.first_solution_iteration,
        "tree_size": int(result.tree_size),
        "num_waypoints": int(len(result.waypoints)),
    })
    if result.success:
        record.update(path_metrics(scenario, result.waypoints, weights))
    if task["simulate"] and result.success:
        record.update(_execute(scenario, result.waypoints, checker, executed_metrics))
    record["waypoints"] = np.asarray(result.waypoints, float).tolist()
    record["progress"] = curve
    record["progress_time"] = stamps
    return record


def _execute(scenario, waypoints, checker, executed_metrics) -> dict:
    from drake_social.sim.run import simulate

    run = simulate(scenario, mode="kinematic", waypoints=np.asarray(waypoints, float), analyze=True,
                   analysis_checker=checker)
    r = run.report
    out = {
        "exec_reached": bool(run.reached),
        "exec_time_to_goal": run.time_to_goal,
        "exec_wall_time": float(run.wall_time),
        "exec_planned_cost": r.planned_social_cost if r else None,
        "exec_cost": r.executed_social_cost if r else None,
        "exec_cost_ratio": (r.executed_social_cost / r.planned_social_cost
                            if r and r.planned_social_cost > 0 else None),
        "exec_max_deviation": r.max_point_deviation["max"] if r else None,
        "exec_collision_free": bool(r.collision_free) if r else None,
    }
    if len(run.times) > 1:
        out.update(executed_metrics(scenario, run.times, run.q))
    return out


def comparable(record: dict) -> dict:
    """The record without :data:`TIMING_FIELDS` (what must not depend on the machine)."""
    return {k: v for k, v in record.items() if k not in TIMING_FIELDS}


# ---- running --------------------------------------------------------------------


@dc.dataclass
class StudyResult:
    """A finished study.

    Attributes:
        study: what was run.
        records: one per task, in task order (see :func:`run_task`).
        wall_time: seconds for all runs (executor start-up included).
        executor, workers: where they ran.
    """

    study: Study
    records: list[dict]
    wall_time: float
    executor: str = "process"
    workers: int = 1

    def group(self, name: str) -> Group:
        return next(g for g in self.study.groups if g.name == name)


def run_study(study: Study, *, executor: str = "process", workers: int = 1, scheduler: str | None = None,
              progress: Callable[[int, int, dict], None] | None = None) -> StudyResult:
    """Runs every task of ``study`` (see :func:`~drake_social.experiments.executors.map_tasks`)."""
    from drake_social.experiments.executors import map_tasks

    tasks = study_tasks(study)
    t0 = time.perf_counter()
    records = map_tasks(run_task, tasks, executor=executor, workers=workers, scheduler=scheduler,
                        progress=progress)
    wall = time.perf_counter() - t0
    _log.info("study %s: %d runs in %.1f s", study.name, len(records), wall)
    return StudyResult(study, records, wall, executor, workers)


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


# ---- writing --------------------------------------------------------------------


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
    from drake_social.experiments.bench import _finite  # non-finite floats -> None (strict JSON)

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.csv").write_text(results_csv(result.records))
    meta = {"study": result.study.to_json_dict(), "seeds": result.study.run_seeds(), "wall_time": result.wall_time,
            "executor": result.executor, "workers": result.workers}
    (out / "results.json").write_text(json.dumps(_finite({**meta, "runs": result.records}), allow_nan=False) + "\n")
    return list(RECORD_FILES)


def rescue_records(result: StudyResult) -> Path:
    """Writes the records (:func:`write_records`) into a new folder of the
    system's temporary directory (``$TMPDIR``), for when the output folder
    cannot take them; returns the folder."""
    folder = Path(tempfile.mkdtemp(prefix="drake-social-records-"))
    write_records(result, folder)
    return folder


def write_study(result: StudyResult, out_dir: str | Path, *, scenario_loader=None) -> list[str]:
    """Writes results.csv, results.json, the figures, REPORT.md and the Planner
    Arena log (``arena_<scenario>.log``, one experiment per scenario) and, when
    OMPL's statistics script is importable, ``arena.db``, into ``out_dir``.

    The records (:func:`write_records`) are written first: when a later file
    fails, they are complete in ``out_dir``.

    Returns:
        The names of the written files.
    """
    from drake_social.experiments import arena, report

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
