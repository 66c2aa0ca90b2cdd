"""The closed-loop crowd study (``drake-social experiment crowd``): seeded
episodes among walking people, the paper's plan-once planner against 10 Hz
replanning, measured per body part.

An **episode** is one closed-loop run (kinematic simulation, the planner in
the diagram) of one scenario with one variant. Episode ``k`` of a study has
the seed ``s_k``, drawn from the study's seed by
``numpy.random.SeedSequence(seed).spawn`` (as a study's run seeds,
:meth:`~drake_social.experiments.study.Study.run_seeds`); the same ``s_k``
for every scenario and variant, so the variants **pair** over episodes. The
seed perturbs the scenario (:func:`perturb`):

* ``random_seed = s_k``: the planner's samples (the first plan and every
  replan) and the preferred speeds the social-force crowd draws for people
  without ``desired_speed``;
* every scripted walker (a :class:`~drake_social.scenario.schema.Person`
  with a ``trajectory``) starts late by a delay ``d_i`` uniform in
  ``[0, jitter]`` seconds: ``d_i = jitter * u``, ``u`` the first
  ``random()`` of ``numpy.random.default_rng(SeedSequence([s_k,
  JITTER_TAG, i]))``, ``i`` the walker's index in ``scenario.people``
  (:func:`~drake_social.people.jitter.walker_delays`). Every time of its trajectory is shifted by
  ``d_i``: the walker stands at its first point ``d_i`` seconds longer
  (where it is at t = 0 does not change, nor a loop's period). The tag keeps
  these draws apart from the planner's ``default_rng([seed, replan_index])``.

The variants (:data:`VARIANTS`) are scenario overrides: ``plan_once`` (the
paper's Social Risk-RRT*, planned once at t = 0), ``replan_base``
(replanning, base-only Risk-RRT*), ``replan_multi`` (replanning, the paper's
multi-point weights) and ``replan_speed`` (``replan_multi`` with Kirby's
speed-scaled AGF). An episode's record (:func:`run_episode`) has the
social-navigation metrics over time per part
(:func:`~drake_social.evaluation.nav_metrics.execution_metrics`, ``nav_*``)
and the replanning statistics (:func:`replan_stats`).

A task carries its scenario's text, its variant's overrides and its seed
(plain data): the records never depend on the executor or the number of
workers, except where a replan hit its wall-clock budget
(``replan_deadline_hits`` > 0: then the search stopped at a machine-dependent
iteration).
"""

from __future__ import annotations

import dataclasses as dc
import inspect
import logging
import math
import time
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from drake_social.arguments import (Rule, check_arguments, require_choices, require_file_names, require_instance,
                                    require_int, require_number)
from drake_social.errors import ScenarioError
from drake_social.experiments.study.executors import map_tasks
from drake_social.experiments.study.scenarios import load_cached
from drake_social.io.textfile import read_yaml_file
from drake_social.limits import CROWD_SCENARIOS, CROWD_VARIANTS, MAX_EPISODES, MAX_JITTER, MAX_TIME_LIMIT
from drake_social.people.jitter import JITTER_TAG, delay_walkers, has_people, walker_delays
from drake_social.scenario import Scenario, time_limit_problem

__all__ = ["CROWD_SETTINGS", "DEFAULT_SCENARIOS", "JITTER_TAG", "MAX_EPISODES", "TRACE_STEP", "VARIANTS", "CrowdResult",
           "CrowdStudy", "check_crowd_settings", "check_crowd_study", "crowd_tasks", "episode_scenario", "episode_seeds",
           "perturb", "replan_stats", "replanning_available", "run_crowd", "run_episode", "walker_delays"]

_log = logging.getLogger(__name__)

#: The scenarios of the study by default (relative to the working directory).
DEFAULT_SCENARIOS = CROWD_SCENARIOS
#: Variant name -> the scenario overrides (YAML, as ``--set``) that make it
#: (the names: :data:`drake_social.limits.CROWD_VARIANTS`, in this order).
VARIANTS: dict[str, tuple[str, ...]] = {
    "plan_once": ("planner: {replan: false, algorithm: social_rrt_star}",),
    "replan_base": ("planner: {replan: true, algorithm: base_rrt_star}",),
    "replan_multi": ("planner: {replan: true, algorithm: social_rrt_star}",),
    "replan_speed": ("planner: {replan: true, algorithm: social_rrt_star}", "social: {speed_scaling: true}"),
}
#: Seconds between the samples of an episode's trace (the snapshots' data).
TRACE_STEP = 0.25


#: The rule of each setting of a crowd study (:class:`CrowdStudy`'s fields,
#: ``run_crowd_experiment``'s keyword arguments): :func:`check_crowd_settings`.
CROWD_SETTINGS: dict[str, Rule] = {
    "name": lambda v, who, name: require_instance(v, str, who, name, "a string"),
    "scenarios": require_file_names,
    "variants": lambda v, who, name: require_choices(v, who, name, tuple(VARIANTS)),
    "episodes": lambda v, who, name: require_int(v, who, name, minimum=1, maximum=MAX_EPISODES),
    "seed": lambda v, who, name: require_int(v, who, name, minimum=0),
    "jitter": lambda v, who, name: require_number(v, who, name, minimum=0.0, maximum=MAX_JITTER, unit="seconds"),
    "time_limit": lambda v, who, name: require_number(v, who, name, positive=True, maximum=MAX_TIME_LIMIT,
                                                      unit="seconds", optional=True),
    "trace_episode": lambda v, who, name: require_int(v, who, name, minimum=0, optional=True),
}


def check_crowd_settings(who: str, settings: dict) -> None:
    """Checks a crowd study's settings (:data:`CROWD_SETTINGS`, and
    ``trace_episode`` below ``episodes``) as ``who``'s arguments.

    Raises:
        TypeError: an unknown setting or one of the wrong kind; ValueError: a
            value out of range; each naming ``who`` and the setting.
    """
    check_arguments(who, CROWD_SETTINGS, settings)
    trace, episodes = settings.get("trace_episode"), settings.get("episodes", CrowdStudy.episodes)
    if trace is not None and not trace < episodes:
        raise ValueError(f"{who}: trace_episode must be one of the {episodes} episodes, in [0, {episodes - 1}], or "
                         f"None, got {trace}")


@dc.dataclass(frozen=True)
class CrowdStudy:
    """What a crowd study runs.

    Attributes:
        name: the study's name (the default output folder ``out/<name>``).
        scenarios: scenario files (distinct stems; each has people).
        variants: names of :data:`VARIANTS`, in the report's order.
        episodes: episodes per (scenario, variant), in [1, MAX_EPISODES].
        seed: the study seed (>= 0); episode k's seed is ``episode_seeds(seed, episodes)[k]``.
        jitter: the largest start delay of a scripted walker, seconds, in [0, MAX_JITTER].
        time_limit: simulated seconds per episode, in (0, MAX_TIME_LIMIT]
            and within each scenario's rules of a run's length
            (:func:`~drake_social.scenario.time_limit_problem`, checked by
            :func:`crowd_tasks`); None = each scenario's ``execution.time_limit``.
        trace_episode: the episode (in [0, episodes)) whose trace (robot,
            people and plans over time) every variant keeps for the
            snapshots; None = none.

    Raises:
        TypeError, ValueError: a setting of the wrong kind or out of range
            (:func:`check_crowd_settings`); ScenarioError: two scenario
            files of the same name.
    """

    name: str = "crowd"
    scenarios: tuple[str, ...] = DEFAULT_SCENARIOS
    variants: tuple[str, ...] = CROWD_VARIANTS
    episodes: int = 20
    seed: int = 0
    jitter: float = 5.0
    time_limit: float | None = None
    trace_episode: int | None = 0

    def __post_init__(self) -> None:
        check_crowd_settings("CrowdStudy", dc.asdict(self))
        stems = [Path(s).stem for s in self.scenarios]
        if len({s.casefold() for s in stems}) != len(stems):
            raise ScenarioError(f"crowd study: scenarios: the file names {stems} must be distinct (records are keyed "
                                "by them)")

    def seeds(self) -> list[int]:
        """Episode k's seed, shared by every scenario and variant."""
        return episode_seeds(self.seed, self.episodes)

    def to_json_dict(self) -> dict:
        return dc.asdict(self)


def episode_seeds(seed: int, episodes: int) -> list[int]:
    """The seeds of ``episodes`` episodes from the study seed (as :meth:`Study.run_seeds`)."""
    return [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(seed).spawn(episodes)]


def perturb(scenario: Scenario, seed: int, jitter: float) -> tuple[Scenario, dict[int, float]]:
    """Episode ``seed`` of ``scenario``: ``random_seed = seed`` and every
    scripted walker's trajectory times shifted by its
    :func:`~drake_social.people.jitter.walker_delays`.

    Returns:
        ``(the episode's scenario (a copy; scenario is not changed), the delays)``.
    """
    people, delays = delay_walkers(scenario, seed, jitter)
    return dc.replace(scenario, people=people, random_seed=int(seed)), delays


def _first(r) -> bool:
    """The first plan of a replanning run (``replan_index`` 0, or status "initial"; it may be a wait)."""
    return r.status == "initial" or getattr(r, "replan_index", None) == 0


def replan_stats(replans: Sequence | None) -> dict[str, float]:
    """The replanning statistics of an episode from its replan log
    (``SimulationResult.replans``: ``ReplanResult`` s with ``status``,
    ``changed``, ``plan_time`` and ``deadline_hit``).

    The first plan (status ``"initial"``: ``planner.iterations``, no deadline)
    is left out: the rest are the periodic replans.

    Returns:
        ``replans`` (count), ``replan_changes`` (the path changed),
        ``replan_waits`` (status ``"wait"``: no safe path, the robot held),
        ``replan_evasions`` (status ``"evade"``: the robot stepped aside),
        ``replan_searches`` (replans that grew a search tree),
        ``replan_time_median`` / ``_p95`` / ``_max`` (wall seconds; NaN
        without replans), ``replan_search_time_median`` (of the replans
        that searched; NaN without any), ``replan_deadline_hits``; all NaN when
        ``replans`` is None (a plan-once episode).
    """
    keys = ("replans", "replan_changes", "replan_waits", "replan_evasions", "replan_searches", "replan_time_median",
            "replan_time_p95", "replan_time_max", "replan_search_time_median", "replan_deadline_hits")
    if replans is None:
        return dict.fromkeys(keys, math.nan)
    periodic = [r for r in replans if not _first(r)]
    times = np.array([r.plan_time for r in periodic], float)
    searched = np.array([r.plan_time for r in periodic if getattr(r, "searched", True)], float)
    return {
        "replans": float(len(periodic)),
        "replan_changes": float(sum(bool(r.changed) for r in periodic)),
        "replan_waits": float(sum(r.status == "wait" for r in periodic)),
        "replan_evasions": float(sum(r.status == "evade" for r in periodic)),
        "replan_searches": float(len(searched)),
        "replan_time_median": float(np.median(times)) if len(times) else math.nan,
        "replan_time_p95": float(np.percentile(times, 95)) if len(times) else math.nan,
        "replan_time_max": float(times.max()) if len(times) else math.nan,
        "replan_search_time_median": float(np.median(searched)) if len(searched) else math.nan,
        "replan_deadline_hits": float(sum(bool(r.deadline_hit) for r in periodic)),
    }


def crowd_tasks(study: CrowdStudy) -> list[dict]:
    """Plain-data tasks, one per (scenario, variant, episode), in that order.

    Raises:
        ScenarioError: a scenario file cannot be read, or with a variant is
            invalid, or the study's ``time_limit`` breaks its rules of a run's
            length (too few or too many control periods or plant steps).
    """
    tasks = []
    seeds = study.seeds()
    for source in study.scenarios:
        text = read_yaml_file(source, "scenario")
        for variant in study.variants:
            scenario = load_cached(str(source), text, VARIANTS[variant], f"variant {variant}")  # checked up front
            if not has_people(scenario):
                raise ScenarioError(f"{source}: has no people: a crowd study needs walking people")
            # The study's time limit in place of the scenario's: the same rules of a run's length.
            problem = None if study.time_limit is None else time_limit_problem(study.time_limit, scenario.execution,
                                                                               "time_limit")
            if problem:
                raise ScenarioError(f"{source}: the crowd study's time_limit (--time-limit) {problem[1]}")
            for k, seed in enumerate(seeds):
                tasks.append({"index": len(tasks), "scenario": Path(source).stem, "source": str(source),
                              "scenario_text": text, "variant": variant, "overrides": list(VARIANTS[variant]),
                              "episode": k, "seed": seed, "jitter": float(study.jitter),
                              "time_limit": study.time_limit, "trace": k == study.trace_episode})
    return tasks


def check_crowd_study(study: CrowdStudy) -> list[dict]:
    """The study's tasks (:func:`crowd_tasks`), once the simulator is known to
    replan when a variant asks for it.

    Raises:
        ScenarioError: as :func:`crowd_tasks`; a replanning variant where
            :func:`replanning_available` is False.
    """
    if any(VARIANTS[v] != VARIANTS["plan_once"] for v in study.variants) and not replanning_available():
        raise ScenarioError(f"crowd study: variants {list(study.variants)}: {_NO_REPLANNING}")
    return crowd_tasks(study)


def episode_scenario(task: dict) -> tuple[Scenario, dict[int, float]]:
    """The perturbed scenario of a task (:func:`perturb`) and its walkers' delays."""
    base = load_cached(task["source"], task["scenario_text"], tuple(task["overrides"]), f"variant {task['variant']}")
    return perturb(base, task["seed"], task["jitter"])


def replanning_available() -> bool:
    """Whether :func:`~drake_social.sim.run.simulate` replans in the loop
    (``simulate(..., replan=True)``, issue 21's replanning planner system)."""
    from drake_social.sim.run import simulate

    return "replan" in inspect.signature(simulate).parameters


_NO_REPLANNING = ("the replanning variants need simulate(..., replan=True) (issue 21's replanning planner system), "
                  "which this installation does not have; run --variants plan_once")


def _simulate(scenario: Scenario, checker, time_limit):
    from drake_social.sim.run import simulate

    options = {}
    if scenario.planner.replan:
        # Replanning is the diagram's; a simulator without it would silently plan once.
        if not replanning_available():
            raise RuntimeError(_NO_REPLANNING)
        options["replan"] = True
    # analyze=False: the executed trajectory's own analysis (social cost
    # against the plan, the room's collision check) is not the study's and
    # costs more than the run; the metrics over time are measured from the log.
    run = simulate(scenario, mode="kinematic", checker=checker, time_limit=time_limit, analyze=False, **options)
    if scenario.planner.replan and getattr(run, "replans", None) is None:
        raise RuntimeError("simulate(..., replan=True) returned no replan log (SimulationResult.replans)")
    return run


def run_episode(task: dict) -> dict:
    """Runs one episode (closed loop, kinematic) and measures it; a record of plain data.

    The record: the task's keys (``scenario``, ``variant``, ``episode``,
    ``seed``, ``jitter``), ``delays`` (walker index -> start delay, s),
    ``reached``, ``time_to_goal``, ``sim_time``, ``wall_time`` (seconds of
    simulation, planning included), ``plan_time_initial`` (the first plan's
    wall seconds), ``plan_found`` (the first plan found a path), every ``nav_*`` metric
    (:func:`~drake_social.evaluation.nav_metrics.execution_metrics`: per
    part, contacts, zone times, minimum distance, time to goal, stops,
    success), :func:`replan_stats`, ``replan_times`` (every periodic replan's
    wall seconds) and, when ``task["trace"]``, ``trace``: the episode
    sampled every :data:`TRACE_STEP` seconds (``times``, ``q``, the people's
    ``positions``, ``headings``, ``present``, ``radii``, ``names``) and
    ``plans`` ([t, waypoints] of every path followed, from its start).
    """
    from drake_social.collision.drake_checker import make_checker
    from drake_social.evaluation.nav_metrics import execution_metrics

    scenario, delays = episode_scenario(task)
    checker = make_checker(scenario, "planar", parallelism=1)
    t0 = time.perf_counter()
    run = _simulate(scenario, checker, task["time_limit"])
    wall = time.perf_counter() - t0
    replans = getattr(run, "replans", None) if scenario.planner.replan else None
    record = {key: task[key] for key in ("index", "scenario", "variant", "episode", "seed", "jitter")}
    record["delays"] = {str(i): d for i, d in delays.items()}
    record.update({
        "plan_found": (float(math.isfinite(replans[0].cost)) if replans
                       else float(run.planner is not None and bool(run.planner.success))),
        "reached": float(bool(run.reached)),
        "time_to_goal": math.nan if run.time_to_goal is None else float(run.time_to_goal),
        "sim_time": float(run.sim_time),
        "wall_time": float(wall),
        "plan_time_initial": (float(replans[0].plan_time) if replans
                              else float(run.planner.wall_time) if run.planner is not None else math.nan),
    })
    record.update(execution_metrics(scenario, run))
    record.update(replan_stats(replans))
    # Microseconds: finer is the machine's noise (and 3000 replans an episode make records.json large).
    record["replan_times"] = [round(float(r.plan_time), 6) for r in replans if not _first(r)] if replans else []
    if task.get("trace"):
        record["trace"] = _trace(run, replans)
    return record


def _trace(run, replans) -> dict:
    """The episode every :data:`TRACE_STEP` seconds, and the paths it followed."""
    times = np.asarray(run.times, float)
    if not len(times):
        return {"times": [], "q": [], "plans": []}
    marks = np.arange(times[0], times[-1] + 1e-9, TRACE_STEP)
    idx = np.minimum(np.searchsorted(times, marks), len(times) - 1)
    out = {"times": times[idx].tolist(), "q": np.asarray(run.q)[idx].tolist()}
    people = run.people
    if people is not None and people.count:
        out.update(positions=people.positions[idx].tolist(), headings=people.headings[idx].tolist(),
                   present=people.present[idx].astype(bool).tolist(), radii=np.asarray(people.radii).tolist(),
                   names=list(people.names))
    if replans:
        plans = [[float(r.t), np.asarray(r.waypoints, float).tolist()] for r in replans
                 if r.status == "initial" or r.changed or r.status == "wait"]
    else:
        plans = [[0.0, np.asarray(run.waypoints, float).tolist()]]
    out["plans"] = plans
    return out


@dc.dataclass
class CrowdResult:
    """A finished crowd study.

    Attributes:
        study: what was run.
        records: one per episode, in task order (scenario, variant, episode).
        wall_time: seconds for all episodes (executor start-up included).
        executor, workers: where they ran.
        scenario_texts: scenario stem -> the text its episodes loaded.
    """

    study: CrowdStudy
    records: list[dict]
    wall_time: float
    executor: str = "process"
    workers: int = 1
    scenario_texts: dict[str, str] = dc.field(default_factory=dict)
    sources: dict[str, str] = dc.field(default_factory=dict)

    def scenario(self, stem: str, variant: str = "plan_once") -> Scenario:
        """Scenario ``stem`` with ``variant``'s overrides, from the text its episodes loaded."""
        return load_cached(self.sources[stem], self.scenario_texts[stem], VARIANTS[variant], f"variant {variant}")


def run_crowd(study: CrowdStudy, *, executor: str = "process", workers: int = 1, scheduler: str | None = None,
              progress: Callable[[int, int, dict], None] | None = None) -> CrowdResult:
    """Runs every episode of ``study`` on an executor
    (:func:`~drake_social.experiments.study.executors.map_tasks`: in this
    process, a process pool or Dask); the records in task order."""
    tasks = check_crowd_study(study)
    t0 = time.perf_counter()
    records = map_tasks(run_episode, tasks, executor=executor, workers=workers, scheduler=scheduler,
                        progress=progress)
    wall = time.perf_counter() - t0
    _log.info("crowd study %s: %d episodes in %.1f s", study.name, len(records), wall)
    texts = {t["scenario"]: t["scenario_text"] for t in tasks}
    sources = {t["scenario"]: t["source"] for t in tasks}
    return CrowdResult(study, records, wall, executor, workers, scenario_texts=texts, sources=sources)
