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
speed-scaled AGF).

This module says what a crowd study runs (:class:`CrowdStudy`, its checked
tasks: :func:`check_crowd_study`); it is a kind of study of the one
framework (:mod:`.kinds`): one episode is
:func:`~drake_social.experiments.study.crowd_episode.run_episode` (the
social-navigation metrics over time per part, ``nav_*``, and the replanning
statistics), REPORT.md and the figures are :mod:`.crowd_report`'s, and the
executors, the records and the output set are the framework's.

A task carries its scenario's text, its variant's overrides and its seed
(plain data): the records never depend on the executor or the number of
workers, except where a replan hit its wall-clock budget
(``replan_deadline_hits`` > 0: then the search stopped at a machine-dependent
iteration).
"""

from __future__ import annotations

import dataclasses as dc
import inspect
from pathlib import Path

import numpy as np

from drake_social.arguments import (Rule, check_arguments, require_choices, require_file_names, require_instance,
                                    require_int, require_number)
from drake_social.errors import ScenarioError
from drake_social.experiments.study.scenarios import load_cached
from drake_social.io.textfile import read_yaml_file
from drake_social.limits import CROWD_SCENARIOS, CROWD_VARIANTS, MAX_EPISODES, MAX_JITTER, MAX_TIME_LIMIT
from drake_social.people.jitter import JITTER_TAG, delay_walkers, has_people, walker_delays
from drake_social.scenario import Scenario, time_limit_problem
from drake_social.scenario.shipped import shipped_scenario

__all__ = ["CROWD_SETTINGS", "DEFAULT_SCENARIOS", "JITTER_TAG", "MAX_EPISODES", "NO_REPLANNING", "VARIANTS",
           "CrowdStudy", "check_crowd_settings", "check_crowd_study", "check_trace_episode", "crowd_tasks",
           "episode_scenario", "episode_seeds", "perturb", "replanning_available", "walker_delays"]

#: The scenarios of the study by default: the shipped ones
#: (:data:`drake_social.limits.CROWD_SCENARIOS`), found beside the package
#: whatever the working folder (:func:`~drake_social.scenario.shipped.shipped_scenario`).
DEFAULT_SCENARIOS = tuple(str(shipped_scenario(name)) for name in CROWD_SCENARIOS)
#: Variant name -> the scenario overrides (YAML, as ``--set``) that make it
#: (the names: :data:`drake_social.limits.CROWD_VARIANTS`, in this order).
VARIANTS: dict[str, tuple[str, ...]] = {
    "plan_once": ("planner: {replan: false, algorithm: social_rrt_star}",),
    "replan_base": ("planner: {replan: true, algorithm: base_rrt_star}",),
    "replan_multi": ("planner: {replan: true, algorithm: social_rrt_star}",),
    "replan_speed": ("planner: {replan: true, algorithm: social_rrt_star}", "social: {speed_scaling: true}"),
}

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
    check_trace_episode(who, settings, CrowdStudy.episodes)


def check_trace_episode(who: str, settings: dict, episodes: int) -> None:
    """Refuses a ``trace_episode`` of ``settings`` that is not one of its
    episodes (``settings["episodes"]``, else ``episodes``).

    Raises:
        ValueError: naming ``who`` and the episodes.
    """
    trace, episodes = settings.get("trace_episode"), settings.get("episodes", episodes)
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

    def run_seeds(self) -> list[int]:
        """Episode k's seed, shared by every scenario and variant."""
        return episode_seeds(self.seed, self.episodes)

    def to_json_dict(self) -> dict:
        return dc.asdict(self)

    def scenario(self, stem: str, text: str | None = None, variant: str = "plan_once") -> Scenario:
        """Scenario file ``stem`` of the study with ``variant``'s overrides,
        loaded from ``text`` (the file's text as its episodes loaded it; None
        = the file read now)."""
        source = next(s for s in self.scenarios if Path(s).stem == stem)
        text = read_yaml_file(source, "scenario") if text is None else text
        return load_cached(str(source), text, VARIANTS[variant], f"variant {variant}")


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


def crowd_tasks(study: CrowdStudy) -> list[dict]:
    """Plain-data tasks, one per (scenario, variant, episode), in that order.

    Raises:
        ScenarioError: a scenario file cannot be read, or with a variant is
            invalid, or the study's ``time_limit`` breaks its rules of a run's
            length (too few or too many control periods or plant steps).
    """
    tasks = []
    seeds = study.run_seeds()
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
        raise ScenarioError(f"crowd study: variants {list(study.variants)}: {NO_REPLANNING}")
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


#: Why a replanning variant cannot run where :func:`replanning_available` is False.
NO_REPLANNING = ("the replanning variants need simulate(..., replan=True) (issue 21's replanning planner system), "
                  "which this installation does not have; run --variants plan_once")
