"""A study from a sweep file (``drake-social experiment sweep``).

The file is read and checked as a scenario file is (the same size, depth and
alias limits, then the :class:`Sweep` schema: fields, types, lines), then its
values; every scenario with every variant is loaded before any run.
"""

from __future__ import annotations

import dataclasses as dc
import os
from pathlib import Path
from typing import Optional

from drake_social.errors import ScenarioError
from drake_social.experiments.study.scenarios import check_run_settings, load_cached
from drake_social.experiments.study.spec import (NAME_RULE, PAPER_ALGORITHMS, Group, Study, algorithms_problem,
                                                 check_settings_and_names, settings_problem, valid_name)
from drake_social.io.textfile import SHOWN_PATH_CHARACTERS, check_regular_file, read_yaml_file, shorten
from drake_social.scenario.load import check_yaml
from drake_social.scenario.schema import Scenario

__all__ = ["Sweep", "load_sweep"]

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
    import yaml  # PyYAML, imported where a file is read, as the scenario loader does

    path = Path(path)
    root = check_yaml(read_yaml_file(path, "sweep"), str(path), Sweep)
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
    problem = settings_problem(name, runs, iterations, seed, simulate, checker)
    if problem is not None:
        field, message = problem
        fail(field, message + ("" if field != "name" or "name" in nodes else " (it is the file's stem: set name:)"))
    algorithms = value("algorithms")
    problem = algorithms_problem(algorithms)
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
            fail(f"scenarios[{i}]", f"{candidate} has {same} {shorten(repr(candidate.stem))} as scenarios[{j}] ({files[j]}); "
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
        if not valid_name(vname):
            fail(f"variants.{shorten(vname)}", f"a variant name {NAME_RULE}", key_node)
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
            if valid_name(group):
                continue
            if not valid_name(f.stem):
                fail(f"scenarios[{i}]", f"the group name {shorten(repr(group))} (<scenario file name>-<variant>) "
                     f"{NAME_RULE}: rename {f}", nodes["scenarios"].value[i])
            fail(f"variants.{vname}", f"the group name {shorten(repr(group))} (<scenario file name>-<variant>) has "
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
                scenario = load_cached(str(f), text, texts, f"variants.{vname}")
            except ScenarioError as e:
                if str(e).startswith(f"{f} (variants.{vname} "):
                    raise ScenarioError(f"{path}: {e}") from None
                fail(f"scenarios[{i}]", str(e), nodes["scenarios"].value[i])
            for algorithm in algorithms:  # the study plans with these, not the file's planner.algorithm
                try:
                    check_run_settings(scenario, algorithm, iterations, f"{f} (variants.{vname})")
                except ScenarioError as e:
                    raise ScenarioError(f"{path}: {e}") from None
            group = f"{f.stem}-{vname}"
            groups.append(Group(group, str(f), overrides=texts, algorithms=tuple(algorithms),
                                label=f"{f.stem}, {vname}" + (f": {texts[0]}" if texts else "")))
    study = Study(name, tuple(groups), runs=runs, iterations=iterations, seed=seed, simulate=simulate, checker=checker)
    check_settings_and_names(study, str(path))  # every group was loaded and checked above
    return study
