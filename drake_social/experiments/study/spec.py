"""A study: what to run (groups, runs, K, seed), its checks and its tasks.

A :class:`Study` is a list of :class:`Group` s (one scenario with its
overrides and the algorithms planned on it), a run count, K and a seed.
:func:`check_study` checks all of it before any run; :func:`study_tasks`
turns it into plain-data tasks, one per (group, algorithm, run), and run
``r`` of every group and algorithm plans with the same seed, drawn from the
study's seed by ``numpy.random.SeedSequence(seed).spawn``, so comparisons pair
over seeds and the numbers never depend on which worker ran what.
:func:`paper_study` is the paper's Section V.
"""

from __future__ import annotations

import dataclasses as dc
import json
import re
from pathlib import Path
from typing import Optional, Sequence

import numpy as np

from drake_social.errors import ScenarioError
from drake_social.experiments.study.scenarios import check_run_settings, load_cached
from drake_social.io.textfile import read_yaml_file, shorten
from drake_social.limits import (ALGORITHMS, CHECKERS, MAX_ITERATIONS, MAX_PAPER_RUNS, MAX_RUNS, MAX_STUDY_TASKS,
                                 PAPER_ALGORITHMS, PAPER_OBJECTIVE, PAPER_PAIRS, PAPER_PLANNER, PAPER_WEIGHTINGS)
from drake_social.scenario.schema import Bar, Scenario, interest_point_count
from drake_social.scenario.shipped import SHIPPED_SCENARIOS

__all__ = [
    "MAX_PAPER_RUNS",
    "MAX_RUNS",
    "MAX_STUDY_TASKS",
    "NAME_PATTERN",
    "NAME_RULE",
    "PAPER_ALGORITHMS",
    "PAPER_OBJECTIVE",
    "PAPER_PAIRS",
    "PAPER_PLANNER",
    "PAPER_WEIGHTINGS",
    "Group",
    "Study",
    "algorithms_problem",
    "check_settings_and_names",
    "check_study",
    "paper_study",
    "paper_weights",
    "settings_problem",
    "study_tasks",
    "valid_name",
]

@dc.dataclass(frozen=True)
class Group:
    """One scenario (with overrides) and the algorithms planned on it.

    Attributes:
        name: the group's name in tables and file names (:data:`NAME_PATTERN`), unique in its study.
        scenario: the scenario file.
        overrides: YAML mappings applied over the file in turn (as ``--set``).
        algorithms: planners of :data:`drake_social.scenario.ALGORITHMS`, each at most once.
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
        name: "paper" or the sweep's name (:data:`NAME_PATTERN`).
        groups: the groups.
        runs: runs per (group, algorithm), in [1, :data:`MAX_RUNS`]; groups x
            algorithms x runs is at most :data:`MAX_STUDY_TASKS`.
        iterations: K, samples per run, in [1, ``MAX_ITERATIONS``].
        seed: the study seed; run r's seed is the r-th spawned SeedSequence's first word.
        simulate: also execute each path in the Drake diagram (kinematic mode).
        checker: validity checker of the planner: ``planar`` (the fast exact one), ``drake`` or ``numpy``.

    :func:`check_study` checks all of it before any run.
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

    def scenario(self, name: str, text: str | None = None) -> Scenario:
        """Group ``name``'s scenario with its overrides, loaded from ``text``
        (its file's text as the runs loaded it; None = the file read now)."""
        g = next(g for g in self.groups if g.name == name)
        text = read_yaml_file(g.scenario, "scenario") if text is None else text
        return load_cached(g.scenario, text, tuple(g.overrides), f"group {g.name}")


def paper_weights(num_points: int) -> dict[str, list[float]]:
    """Section V-D's weightings: object points 0.95 and the rest 0.05; base
    0.95 and the rest 0.05; equal (1 everywhere). Base, link-1 tip, link-2
    tip, then the object's points. Keyed by :data:`PAPER_WEIGHTINGS`, in its order."""
    obj = [0.05, 0.05, 0.05] + [0.95] * (num_points - 3)
    base = [0.95] + [0.05] * (num_points - 1)
    return dict(zip(PAPER_WEIGHTINGS, (obj, base, [1.0] * num_points)))


def paper_study(*, runs: int = 10, iterations: int = 2000, seed: int = 0, simulate: bool = False,
                scenario_dir: str | Path = SHIPPED_SCENARIOS) -> Study:
    """The paper's Section V (A, B and D; C is A and B's figures), on
    ``office_bar.yaml`` and ``generic_L.yaml`` of ``scenario_dir`` (by
    default the shipped ones, beside the package).

    D is "the generic map with the bar": generic_L.yaml with the office's
    1.5 m bar (``object: !Bar {length: 1.5, thickness: 0.05}``), 5 interest
    points, planned with Social Risk-RRT* under each of :func:`paper_weights`.
    Every group runs the paper's planner (:data:`PAPER_PLANNER`: the raw tree
    path and the fixed r_near) and objective (:data:`PAPER_OBJECTIVE`: the
    social integral alone), whatever the scenario files' defaults.
    """
    d = Path(scenario_dir)
    pins = (PAPER_PLANNER, PAPER_OBJECTIVE)  # last: nothing after them can undo them
    bar = "object: !Bar {length: 1.5, thickness: 0.05}"
    n = 3 + interest_point_count(Bar(length=1.5, thickness=0.05))
    groups = [
        Group("A", str(d / "office_bar.yaml"), overrides=pins, label="A: office, 1.5 m bar"),
        Group("B", str(d / "generic_L.yaml"), overrides=pins, label="B: generic map, L-shaped object"),
    ]
    for name, w in paper_weights(n).items():
        groups.append(Group(f"D_{name}", str(d / "generic_L.yaml"),
                            overrides=(bar, f"social: {{weights: {json.dumps(w)}}}", *pins),
                            algorithms=("social_rrt_star",), label=f"D: generic map, bar, {name} weights {w}"))
    study = Study("paper", tuple(groups), runs=runs, iterations=iterations, seed=seed, simulate=simulate)
    check_study(study, "paper study")
    return study


#: Study, group and variant names: a letter, digit or ``_`` first, then
#: letters, digits, ``_``, ``-`` and ``.``; at most 100 characters. They name
#: output files (``arena_<group>.log``) and the default folder ``out/<study>``.
NAME_PATTERN = r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}"
NAME_RULE = ("may contain only letters, digits, '_', '-' and '.' (not first), at most 100 characters, "
              "as it names output files")


def _shown(value) -> str:
    """A value of the user's as an error message repeats it (its repr, shortened)."""
    return shorten(repr(value))


def _name_shown(name) -> str:
    """A group's name as an error message repeats it: whole if it is a valid
    name (at most 100 characters), else shortened (:func:`_shown`)."""
    return repr(name) if isinstance(name, str) and valid_name(name) else _shown(name)


def valid_name(name: str) -> bool:
    return re.fullmatch(NAME_PATTERN, name) is not None


def settings_problem(name, runs, iterations, seed, simulate, checker) -> tuple[str, str] | None:
    """The first of a study's settings that is not allowed, as (field, what is
    allowed and what it is), or None: the one check of a :class:`Study` and a sweep file."""
    for field, value, low, high in (("runs", runs, 1, MAX_RUNS), ("iterations", iterations, 1, MAX_ITERATIONS)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
            return field, f"must be an integer in [{low}, {high:,}], got {_shown(value)}"
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        return "seed", f"must be an integer >= 0, got {_shown(seed)}"
    if not isinstance(simulate, bool):
        return "simulate", f"must be true or false, got {_shown(simulate)}"
    if checker not in CHECKERS:
        return "checker", f"unknown checker {_shown(checker)}; allowed: {', '.join(CHECKERS)}"
    if not isinstance(name, str) or not valid_name(name):
        return "name", f"{_shown(name)}: a study name {NAME_RULE}"
    return None


def algorithms_problem(algorithms: Sequence[str]) -> tuple[Optional[int], str] | None:
    """The first problem of a list of planners, as (its index or None, what is
    wrong), or None: at least one, each of ALGORITHMS, none twice."""
    if not algorithms:
        return None, f"needs at least one of {', '.join(ALGORITHMS)}"
    for i, a in enumerate(algorithms):
        if a not in ALGORITHMS:
            return i, f"unknown algorithm {_shown(a)}; allowed: {', '.join(ALGORITHMS)}"
        if a in algorithms[:i]:
            return i, f"{a} is listed twice (its runs would be recorded twice)"
    return None


def check_study(study: Study, source: str = "study") -> dict[str, str]:
    """Checks a study before any run: its limits, names and planners, and
    that every group's scenario file reads and loads with its overrides and
    is valid with each of the study's algorithms.

    Args:
        study: the study.
        source: how errors name it (the sweep file, or the command).

    Returns:
        Group name -> its scenario file's text (each file read once).

    Raises:
        ScenarioError: ``<source>: <field>: <what is allowed>, got <value>``,
            or the scenario error of a group (naming its file and overrides).
    """
    check_settings_and_names(study, source)
    return _group_texts(study)


def check_settings_and_names(study: Study, source: str) -> None:
    """:func:`check_study`'s checks that read no file: limits, names, planners."""
    def fail(field: str, message: str):
        raise ScenarioError(f"{source}: {field}: {message}")

    problem = settings_problem(study.name, study.runs, study.iterations, study.seed, study.simulate, study.checker)
    if problem is not None:
        fail(*problem)
    if not study.groups:
        fail("groups", "a study needs at least one group")
    seen: set[str] = set()
    for g in study.groups:
        if not isinstance(g.name, str) or not valid_name(g.name):
            fail(f"group {_shown(g.name)}", f"a group name {NAME_RULE}")
        if g.name.casefold() in seen:
            fail(f"group {_name_shown(g.name)}", "two groups have this name (letter case aside); their records and arena "
                                            "logs would mix")
        seen.add(g.name.casefold())
        problem = algorithms_problem(g.algorithms)
        if problem is not None:
            i, message = problem
            fail(f"group {_name_shown(g.name)}: algorithms" + ("" if i is None else f"[{i}]"), message)
    tasks = study.runs * sum(len(g.algorithms) for g in study.groups)
    if tasks > MAX_STUDY_TASKS:
        fail("runs", f"{len(study.groups)} groups x their algorithms x {study.runs} runs = {tasks:,} runs; a study "
                     f"may have at most {MAX_STUDY_TASKS:,}")


def _group_texts(study: Study) -> dict[str, str]:
    """Group name -> its scenario file's text, each file read once, each
    group's scenario and overrides checked to load (:func:`load_cached`) and with
    each of the study's algorithms."""
    files: dict[str, str] = {}
    texts = {}
    for g in study.groups:
        if g.scenario not in files:
            files[g.scenario] = read_yaml_file(g.scenario, "scenario")
        texts[g.name] = files[g.scenario]
        scenario = load_cached(g.scenario, texts[g.name], tuple(g.overrides), f"group {g.name}")
        for algorithm in g.algorithms:
            check_run_settings(scenario, algorithm, study.iterations, f"{g.scenario} (group {g.name})")
    return texts


def study_tasks(study: Study) -> list[dict]:
    """One plain-data task per (group, algorithm, run), in a fixed order.

    Raises:
        ScenarioError: the study is invalid (:func:`check_study`) or a group's
            scenario or overrides are: nothing has run yet.
    """
    texts = check_study(study)
    seeds = study.run_seeds()
    tasks = []
    for group in study.groups:
        text = texts[group.name]
        for algorithm in group.algorithms:
            for run, seed in enumerate(seeds):
                tasks.append({
                    "index": len(tasks), "group": group.name, "scenario": Path(group.scenario).name,
                    "source": group.scenario, "scenario_text": text, "overrides": list(group.overrides),
                    "override_name": f"group {group.name}", "algorithm": algorithm, "run": run, "seed": seed,
                    "iterations": study.iterations, "simulate": study.simulate, "checker": study.checker,
                })
    return tasks
