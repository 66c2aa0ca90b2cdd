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

import collections
import csv
import dataclasses as dc
import functools
import hashlib
import io
import json
import logging
import os
import re
import tempfile
import time
from pathlib import Path
from typing import Callable, Optional, Sequence

import numpy as np

from drake_social.scenario import ALGORITHMS, CHECKERS, Scenario, ScenarioError
from drake_social.io.textfile import SHOWN_PATH_CHARACTERS, check_regular_file, read_yaml_file, shorten

__all__ = [
    "MAX_PAPER_RUNS",
    "MAX_RUNS",
    "MAX_STUDY_TASKS",
    "NAME_PATTERN",
    "PAPER_ALGORITHMS",
    "RECORD_FILES",
    "TIMING_FIELDS",
    "Group",
    "Study",
    "StudyOutputError",
    "StudyResult",
    "Sweep",
    "best_runs",
    "check_study",
    "comparable",
    "load_sweep",
    "output_names",
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
        (:func:`check_study` checks all of it before any run.)
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


#: The paper's planner settings, applied over every group of :func:`paper_study`:
#: the raw RRT* path (no optimisation) and the fixed near radius of Algorithm 2.
PAPER_PLANNER = "planner: {optimize: false, near_radius_mode: fixed}"


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
    Every group runs the paper's planner (:data:`PAPER_PLANNER`: the raw tree
    path and the fixed r_near), whatever the scenario files' defaults.
    """
    from drake_social.scenario import interest_point_count, Bar

    d = Path(scenario_dir)
    bar = "object: !Bar {length: 1.5, thickness: 0.05}"
    n = 3 + interest_point_count(Bar(length=1.5, thickness=0.05))
    groups = [
        Group("A", str(d / "office_bar.yaml"), overrides=(PAPER_PLANNER,), label="A: office, 1.5 m bar"),
        Group("B", str(d / "generic_L.yaml"), overrides=(PAPER_PLANNER,), label="B: generic map, L-shaped object"),
    ]
    for name, w in paper_weights(n).items():
        groups.append(Group(f"D_{name}", str(d / "generic_L.yaml"),
                            overrides=(bar, f"social: {{weights: {json.dumps(w)}}}", PAPER_PLANNER),
                            algorithms=("social_rrt_star",), label=f"D: generic map, bar, {name} weights {w}"))
    study = Study("paper", tuple(groups), runs=runs, iterations=iterations, seed=seed, simulate=simulate)
    check_study(study, "paper study")
    return study


#: Most runs per (group, algorithm) of a study (each run's seed is drawn up front).
MAX_RUNS = 10_000
#: Most tasks of a study (groups x algorithms x runs): every run's record is
#: kept in memory until the study is written (a few kilobytes each).
MAX_STUDY_TASKS = 100_000
#: (group, algorithm) pairs of :func:`paper_study`: A and B with the paper's
#: five planners, D with Social Risk-RRT* under three weightings.
PAPER_PAIRS = 2 * len(PAPER_ALGORITHMS) + len(paper_weights(5))
#: Most runs of :func:`paper_study` (``experiment paper --runs``): its
#: :data:`PAPER_PAIRS` pairs x runs stay within :data:`MAX_STUDY_TASKS`.
MAX_PAPER_RUNS = min(MAX_RUNS, MAX_STUDY_TASKS // PAPER_PAIRS)
#: Study, group and variant names: a letter, digit or ``_`` first, then
#: letters, digits, ``_``, ``-`` and ``.``; at most 100 characters. They name
#: output files (``arena_<group>.log``) and the default folder ``out/<study>``.
NAME_PATTERN = r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}"
_NAME_RULE = ("may contain only letters, digits, '_', '-' and '.' (not first), at most 100 characters, "
              "as it names output files")


@dc.dataclass
class Sweep:
    """The schema of a sweep file (``drake-social experiment sweep``), checked like a scenario's."""

    # The study's name (NAME_PATTERN): the default output folder out/<name>;
    # "" = the sweep file's stem.
    name: str = ""
    # Runs per (scenario, variant, algorithm), in [1, MAX_RUNS].
    runs: int = 10
    # K, samples per run, in [1, MAX_ITERATIONS] (replaces each scenario's planner.iterations).
    iterations: int = 2000
    # The study seed, >= 0; run r's planner seed is drawn from it (Study.run_seeds).
    seed: int = 0
    # true: also execute each path (kinematic simulation) and measure it.
    simulate: bool = False
    # Validity checker of the planner: planar, drake or numpy.
    checker: str = "planar"
    # Scenario files, relative to the sweep file's folder or else to the
    # working directory; at least one, with distinct file names (stems).
    scenarios: list[str] = dc.field(default_factory=list)
    # Planners of ALGORITHMS, each at most once; default: PAPER_ALGORITHMS.
    algorithms: list[str] = dc.field(default_factory=lambda: list(PAPER_ALGORITHMS))
    # Variant name (NAME_PATTERN) -> a partial scenario applied over each
    # scenario file, as --set (null or {} = the file as it is); default: {default: {}}.
    variants: dict[str, Optional[Scenario]] = dc.field(default_factory=lambda: {"default": None})


def _shown(value) -> str:
    """A value of the user's as an error message repeats it (its repr, shortened)."""
    return shorten(repr(value))


def _name_shown(name) -> str:
    """A group's name as an error message repeats it: whole if it is a valid
    name (at most 100 characters), else shortened (:func:`_shown`)."""
    return repr(name) if isinstance(name, str) and _valid_name(name) else _shown(name)


def _valid_name(name: str) -> bool:
    return re.fullmatch(NAME_PATTERN, name) is not None


def _settings_problem(name, runs, iterations, seed, simulate, checker) -> tuple[str, str] | None:
    """The first of a study's settings that is not allowed, as (field, what is
    allowed and what it is), or None: the one check of a :class:`Study` and a sweep file."""
    from drake_social.scenario import MAX_ITERATIONS

    for field, value, low, high in (("runs", runs, 1, MAX_RUNS), ("iterations", iterations, 1, MAX_ITERATIONS)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
            return field, f"must be an integer in [{low}, {high:,}], got {_shown(value)}"
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        return "seed", f"must be an integer >= 0, got {_shown(seed)}"
    if not isinstance(simulate, bool):
        return "simulate", f"must be true or false, got {_shown(simulate)}"
    if checker not in CHECKERS:
        return "checker", f"unknown checker {_shown(checker)}; allowed: {', '.join(CHECKERS)}"
    if not isinstance(name, str) or not _valid_name(name):
        return "name", f"{_shown(name)}: a study name {_NAME_RULE}"
    return None


def _algorithms_problem(algorithms: Sequence[str]) -> tuple[Optional[int], str] | None:
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
    _check_settings_and_names(study, source)
    return _group_texts(study)


def _check_settings_and_names(study: Study, source: str) -> None:
    """:func:`check_study`'s checks that read no file: limits, names, planners."""
    def fail(field: str, message: str):
        raise ScenarioError(f"{source}: {field}: {message}")

    problem = _settings_problem(study.name, study.runs, study.iterations, study.seed, study.simulate, study.checker)
    if problem is not None:
        fail(*problem)
    if not study.groups:
        fail("groups", "a study needs at least one group")
    seen: set[str] = set()
    for g in study.groups:
        if not isinstance(g.name, str) or not _valid_name(g.name):
            fail(f"group {_shown(g.name)}", f"a group name {_NAME_RULE}")
        if g.name.casefold() in seen:
            fail(f"group {_name_shown(g.name)}", "two groups have this name (letter case aside); their records and arena "
                                            "logs would mix")
        seen.add(g.name.casefold())
        problem = _algorithms_problem(g.algorithms)
        if problem is not None:
            i, message = problem
            fail(f"group {_name_shown(g.name)}: algorithms" + ("" if i is None else f"[{i}]"), message)
    tasks = study.runs * sum(len(g.algorithms) for g in study.groups)
    if tasks > MAX_STUDY_TASKS:
        fail("runs", f"{len(study.groups)} groups x their algorithms x {study.runs} runs = {tasks:,} runs; a study "
                     f"may have at most {MAX_STUDY_TASKS:,}")


def _group_texts(study: Study) -> dict[str, str]:
    """Group name -> its scenario file's text, each file read once, each
    group's scenario and overrides checked to load (:func:`_load`) and with
    each of the study's algorithms."""
    files: dict[str, str] = {}
    texts = {}
    for g in study.groups:
        if g.scenario not in files:
            files[g.scenario] = read_yaml_file(g.scenario, "scenario")
        texts[g.name] = files[g.scenario]
        scenario = _load(g.scenario, texts[g.name], tuple(g.overrides), f"group {g.name}")
        for algorithm in g.algorithms:
            _check_run_settings(scenario, algorithm, study.iterations, f"{g.scenario} (group {g.name})")
    return texts


def _check_run_settings(scenario: Scenario, algorithm: str, iterations: int, source: str) -> None:
    """Checks ``scenario`` as a study's run plans it, with the study's
    ``algorithm`` and ``iterations`` (:func:`~drake_social.scenario.validate_planner_choice`).

    Raises:
        ScenarioError: ``<source> with the study's algorithm <algorithm>: <field>: ...``.
    """
    from drake_social.scenario import validate_planner_choice

    validate_planner_choice(scenario, algorithm, iterations, f"{source} with the study's algorithm {algorithm}")


def _flow(node, yaml, seen=None) -> None:
    """Sets a composed node tree to YAML flow style (one-line override text)."""
    seen = set() if seen is None else seen
    if id(node) in seen or isinstance(node, yaml.ScalarNode):
        return
    seen.add(id(node))
    node.flow_style = True
    for child in node.value:
        for n in (child if isinstance(child, tuple) else (child,)):
            _flow(n, yaml, seen)


def _sweep_scenario(sweep: Path, name: str) -> Path:
    """The regular file a sweep's ``scenarios`` entry names: relative to the
    sweep's folder if it is there, else to the working directory.

    Raises:
        ScenarioError: as :func:`~drake_social.io.textfile.check_regular_file`; a
            file in neither place is named in both.
    """
    if name == "" or Path(name).is_absolute():
        check_regular_file(name, "scenario")
        return Path(name)
    local = sweep.parent / name
    if os.path.lexists(local) or not os.path.lexists(name):  # lexists: False for a name with a NUL, too
        if not os.path.lexists(local) and local != Path(name) and "\0" not in name:
            raise ScenarioError(f"{shorten(name, SHOWN_PATH_CHARACTERS)}: no such scenario file, neither beside the sweep "
                                f"({shorten(str(local), SHOWN_PATH_CHARACTERS)}) nor in the "
                                f"working directory ({Path.cwd() / name})")
        check_regular_file(local, "scenario")
        return local
    check_regular_file(name, "scenario")
    return Path(name)


#: Scenario fields a study sets for every run (``run_task``), with what a sweep sets them by.
_STUDY_SETTINGS = {
    ("random_seed",): "the sweep's seed: (each run's planner seed is drawn from it)",
    ("planner", "iterations"): "the sweep's iterations:",
    ("planner", "algorithm"): "the sweep's algorithms:",
    ("execution", "mode"): "nothing: a study simulates every run in kinematic mode",
}


def _refuse_study_settings(node, field: str, source: str, yaml) -> None:
    """Refuses a variant that sets a field the study sets for every run
    (:data:`_STUDY_SETTINGS`): it would be ignored without a word."""
    if not isinstance(node, yaml.MappingNode):
        return
    for key_node, value_node in node.value:
        for path, instead in _STUDY_SETTINGS.items():
            at = key_node
            if key_node.value != path[0]:
                continue
            if len(path) == 2:
                if not isinstance(value_node, yaml.MappingNode):
                    continue
                at = next((k for k, _ in value_node.value if k.value == path[1]), None)
                if at is None:
                    continue
            raise ScenarioError(f"{source}: line {at.start_mark.line + 1}: {field}.{'.'.join(path)}: a study sets it "
                                f"for every run, so a variant cannot: use {instead}")


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

    The file is read and checked as a scenario file is (the same size, depth
    and alias limits, then the :class:`Sweep` schema: fields, types, lines),
    then its values; every scenario with every variant is loaded before any
    run. Groups are scenario x variant, named ``<scenario stem>-<variant>``.

    Raises:
        ScenarioError: the file or a field is invalid (named with the allowed
            values), or a scenario or variant is: the message names this file,
            the scenario file and the variant.
    """
    import yaml

    from drake_social.scenario import check_node, compose_yaml

    path = Path(path)
    root = compose_yaml(read_yaml_file(path, "sweep"), str(path))
    if root is None:
        raise ScenarioError(f"{path}: empty; a sweep is a mapping ({', '.join(f.name for f in dc.fields(Sweep))})")
    check_node(Sweep, root, str(path))
    nodes = {k.value: v for k, v in root.value}

    def fail(key: str, message: str, node=None):
        node = nodes.get(key) if node is None else node
        line = f"line {node.start_mark.line + 1}: " if node is not None else ""
        raise ScenarioError(f"{path}: {line}{key}: {message}")

    def value(key: str):  # the schema check above has checked its type
        if key not in nodes:
            return getattr(Sweep(), key)
        return yaml.SafeLoader("").construct_object(nodes[key], deep=True)

    runs, iterations, seed = int(value("runs")), int(value("iterations")), int(value("seed"))  # 1e3 is an integer
    checker, simulate = value("checker"), value("simulate")
    name = value("name") or path.stem
    problem = _settings_problem(name, runs, iterations, seed, simulate, checker)
    if problem is not None:
        field, message = problem
        fail(field, message + ("" if field != "name" or "name" in nodes else " (it is the file's stem: set name:)"))
    algorithms = value("algorithms")
    problem = _algorithms_problem(algorithms)
    if problem is not None:
        i, message = problem
        fail("algorithms" if i is None else f"algorithms[{i}]", message,
             None if i is None or "algorithms" not in nodes else nodes["algorithms"].value[i])

    scenarios = value("scenarios")
    if not scenarios:
        fail("scenarios", "needs at least one scenario file")
    files: list[Path] = []
    stems: dict[str, int] = {}  # file name, letter case aside -> its index
    for i, s in enumerate(scenarios):
        try:
            candidate = _sweep_scenario(path, s)
        except ScenarioError as e:
            fail(f"scenarios[{i}]", str(e), nodes["scenarios"].value[i])
        j = stems.get(candidate.stem.casefold())
        if j is not None:
            same = "the same name" if files[j].stem == candidate.stem else "the same name, letter case aside,"
            fail(f"scenarios[{i}]", f"{candidate} has {same} {_shown(candidate.stem)} as scenarios[{j}] ({files[j]}); "
                 f"groups are named <scenario file name>-<variant>, so the scenario files of a sweep need distinct "
                 f"names (output files would collide on a file system that ignores case)", nodes["scenarios"].value[i])
        stems[candidate.stem.casefold()] = i
        files.append(candidate)

    variants: dict[str, tuple[str, ...]] = {}
    variant_nodes = {k.value: (k, v) for k, v in nodes["variants"].value} if "variants" in nodes else {}
    if "variants" in nodes and not variant_nodes:
        fail("variants", "needs at least one variant (e.g. default: {})")
    folded: dict[str, str] = {}  # variant name, letter case aside -> the name
    for vname, (key_node, node) in variant_nodes.items():
        if not _valid_name(vname):
            fail(f"variants.{shorten(vname)}", f"a variant name {_NAME_RULE}", key_node)
        if vname.casefold() in folded:
            fail(f"variants.{vname}", f"differs from variants.{folded[vname.casefold()]} only in letter case; their "
                 f"output files would collide on a file system that ignores case", key_node)
        folded[vname.casefold()] = vname
        _refuse_study_settings(node, f"variants.{vname}", str(path), yaml)
        empty = (isinstance(node, yaml.ScalarNode) or not node.value)  # null (checked by the schema) or {}
        if not empty:
            _flow(node, yaml)
        variants[vname] = () if empty else (yaml.serialize(node, width=10**9).strip(),)
    if not variant_nodes:
        variants = {"default": ()}
    for i, f in enumerate(files):  # names first: they are cheaper to check than the scenarios
        for vname in variants:
            group = f"{f.stem}-{vname}"
            if _valid_name(group):
                continue
            if not _valid_name(f.stem):
                fail(f"scenarios[{i}]", f"the group name {_shown(group)} (<scenario file name>-<variant>) "
                     f"{_NAME_RULE}: rename {f}", nodes["scenarios"].value[i])
            fail(f"variants.{vname}", f"the group name {_shown(group)} (<scenario file name>-<variant>) has "
                 f"{len(group)} characters; at most 100 are allowed: shorten the variant's name (or rename {f})",
                 variant_nodes[vname][0])

    groups = []
    for i, f in enumerate(files):
        try:
            text = read_yaml_file(f, "scenario")
        except ScenarioError as e:
            fail(f"scenarios[{i}]", str(e), nodes["scenarios"].value[i])
        for vname, texts in variants.items():
            # Every group is loaded before any run, the file with its variant
            # (a variant may make a value of the file valid); an error names
            # the stage at fault, the file or the variant.
            try:
                scenario = _load(str(f), text, texts, f"variants.{vname}")
            except ScenarioError as e:
                if str(e).startswith(f"{f} (variants.{vname} "):
                    raise ScenarioError(f"{path}: {e}") from None
                fail(f"scenarios[{i}]", str(e), nodes["scenarios"].value[i])
            for algorithm in algorithms:  # the study plans with these, not the file's planner.algorithm
                try:
                    _check_run_settings(scenario, algorithm, iterations, f"{f} (variants.{vname})")
                except ScenarioError as e:
                    raise ScenarioError(f"{path}: {e}") from None
            group = f"{f.stem}-{vname}"
            groups.append(Group(group, str(f), overrides=texts, algorithms=tuple(algorithms),
                                label=f"{f.stem}, {vname}" + (f": {texts[0]}" if texts else "")))
    study = Study(name, tuple(groups), runs=runs, iterations=iterations, seed=seed, simulate=simulate, checker=checker)
    _check_settings_and_names(study, str(path))  # every group was loaded and checked above
    return study


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


# ---- in the worker --------------------------------------------------------------


def _load(source: str, text: str, overrides: tuple[str, ...], overrides_name: str = "overrides") -> Scenario:
    """The scenario of ``text`` with ``overrides``, loaded once per pair and
    process while it is among the last :data:`_LOADED_MOST` loaded (keyed by
    their digest, whatever the groups are called); errors name ``source``."""
    from drake_social.scenario import load_scenario_text

    key = _load_key(text, overrides)
    scenario = _loaded.get(key)
    if scenario is None:
        scenario = load_scenario_text(text, source, list(overrides), overrides_name=overrides_name)
        _loaded[key] = scenario
        if len(_loaded) > _LOADED_MOST:
            _loaded.popitem(last=False)
    _loaded.move_to_end(key)
    return scenario


#: The most scenarios :func:`_load` keeps (the least recently used go first).
_LOADED_MOST = 64
_loaded: "collections.OrderedDict[bytes, Scenario]" = collections.OrderedDict()


def _load_key(text: str, overrides: tuple[str, ...]) -> bytes:
    digest = hashlib.sha256()
    for part in (text, *overrides):
        data = part.encode("utf-8", "surrogatepass")
        digest.update(len(data).to_bytes(8, "little") + data)
    return digest.digest()


@functools.lru_cache(maxsize=16)
def _checker(source: str, text: str, overrides: tuple[str, ...], overrides_name: str, kind: str):
    from drake_social.collision.drake_checker import make_checker

    return make_checker(_load(source, text, overrides, overrides_name), kind, parallelism=1)


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
    from drake_social.planning.algorithms import make_objective, plan

    key = (task["source"], task["scenario_text"], tuple(task["overrides"]), task["override_name"])
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

    run = simulate(scenario, mode="kinematic", waypoints=np.asarray(waypoints, float), checker=checker, analyze=True,
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
        "exec_within_limits": bool(r.within_limits) if r else None,
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
    #: Group name -> the scenario text its runs loaded (read once, before the first run).
    scenario_texts: dict[str, str] = dc.field(default_factory=dict)

    def group(self, name: str) -> Group:
        return next(g for g in self.study.groups if g.name == name)

    def scenario(self, name: str) -> Scenario:
        """The scenario group ``name`` ran on, from the text read before the runs (the file may have changed since)."""
        g = self.group(name)
        text = self.scenario_texts[name] if name in self.scenario_texts else read_yaml_file(g.scenario, "scenario")
        return _load(g.scenario, text, tuple(g.overrides), f"group {g.name}")


def run_study(study: Study, *, executor: str = "process", workers: int = 1, scheduler: str | None = None,
              progress: Callable[[int, int, dict], None] | None = None) -> StudyResult:
    """Runs every task of ``study`` (see :func:`~drake_social.experiments.study.executors.map_tasks`)."""
    from drake_social.experiments.study.executors import map_tasks

    tasks = study_tasks(study)
    t0 = time.perf_counter()
    records = map_tasks(run_task, tasks, executor=executor, workers=workers, scheduler=scheduler,
                        progress=progress)
    wall = time.perf_counter() - t0
    _log.info("study %s: %d runs in %.1f s", study.name, len(records), wall)
    texts = {task["group"]: task["scenario_text"] for task in tasks}
    return StudyResult(study, records, wall, executor, workers, scenario_texts=texts)


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
    from drake_social.experiments.bench.planners import _finite  # non-finite floats -> None (strict JSON)

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


def output_names(study: Study) -> list[str]:
    """Every file name :func:`write_study` may write for ``study``, known
    before any run (so that an output folder can refuse what is in their
    way up front): the records, the figures, the arena logs, ``arena.db``
    and ``REPORT.md``."""
    from drake_social.experiments.study import arena
    from drake_social.experiments.study import report

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
    from drake_social.experiments.study import arena
    from drake_social.experiments.study import report

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
