"""Sweep files are read and checked like scenario files, and every study is
checked before its first run: limits, types, names, duplicates, and errors
that name the sweep file, the scenario file (with its folder) and the variant."""

from __future__ import annotations

import collections
from pathlib import Path

import pytest

from drake_social.cli import main
from drake_social.experiments.study import (
    MAX_RUNS,
    MAX_STUDY_TASKS,
    Group,
    Study,
    load_sweep,
    paper_study,
    run_study,
    study_tasks,
)
from drake_social.scenario import ScenarioError
from drake_social.io.textfile import shorten

TINY = Path(__file__).resolve().parent.parent.parent / "scenarios" / "tiny.yaml"
NAME_RULE = ("may contain only letters, digits, '_', '-' and '.' (not first), at most 100 characters, as it names "
             "output files")


def _sweep(tmp_path: Path, body: str, head: str = f"runs: 1\niterations: 20\nscenarios: [{TINY}]\n") -> Path:
    path = tmp_path / "sweep.yaml"
    path.write_text(head + body)
    return path


def _error(path: Path) -> str:
    with pytest.raises(ScenarioError) as info:
        load_sweep(path)
    return str(info.value)


# ---- limits (item 9)


def test_a_billion_runs_is_refused_at_once(tmp_path, capsys):
    dut = _sweep(tmp_path, "", head=f"runs: 1000000000\nscenarios: [{TINY}]\n")
    assert _error(dut) == f"{dut}: line 1: runs: must be an integer in [1, 10,000], got 1000000000"
    assert MAX_RUNS == 10_000
    assert main(["experiment", "paper", "--runs", "1000000000", "--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err.endswith("argument --runs: must be an integer in [1, 7,692], got 1000000000\n")
    with pytest.raises(ScenarioError) as info:
        paper_study(runs=10**9, scenario_dir=TINY.parent)
    assert str(info.value) == "paper study: runs: must be an integer in [1, 10,000], got 1000000000"


def test_the_total_number_of_runs_is_bounded(tmp_path):
    variants = ", ".join(f"v{i}: {{}}" for i in range(20))
    dut = _sweep(tmp_path, f"algorithms: [rrt_star]\nvariants: {{{variants}}}\n",
                 head=f"runs: 5001\nscenarios: [{TINY}]\n")
    assert _error(dut) == (f"{dut}: runs: 20 groups x their algorithms x 5001 runs = 100,020 runs; a study may "
                           f"have at most {MAX_STUDY_TASKS:,}")
    with pytest.raises(ScenarioError, match=r"^study: runs: 20 groups x their algorithms x 5001 runs = 100,020"):
        study_tasks(Study("s", tuple(Group(f"g{i}", str(TINY), algorithms=("rrt_star",)) for i in range(20)),
                          runs=5001))


def test_iterations_beyond_the_planner_limit_name_the_sweep(tmp_path):
    dut = _sweep(tmp_path, "", head=f"iterations: 100000000\nscenarios: [{TINY}]\n")
    assert _error(dut) == f"{dut}: line 1: iterations: must be an integer in [1, 10,000,000], got 100000000"


def test_an_alias_bomb_in_a_sweep_is_refused_like_in_a_scenario(tmp_path):
    lines = ["v0: &a0 {description: [lol, lol, lol, lol, lol, lol, lol, lol, lol]}"]
    lines += [f"v{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, 10)]
    dut = _sweep(tmp_path, "variants:\n" + "".join(f"  {line}\n" for line in lines))
    assert _error(dut) == (f"{dut}: line 10: more than 100,000 YAML nodes (aliases counted as the nodes they "
                           f"repeat); a document may have at most 100,000")
    lines = ["m0: &m0 {a: 1, b: 2, c: 3}"] + [f"m{i}: &m{i} {{<<: [{', '.join([f'*m{i - 1}'] * 9)}]}}"
                                                for i in range(1, 12)]
    dut = _sweep(tmp_path, "".join(f"{line}\n" for line in lines))
    assert "more than 100,000 YAML nodes" in _error(dut)


@pytest.mark.parametrize("depth", [40, 1000])
def test_deep_nesting_in_a_sweep_is_refused(tmp_path, depth):
    dut = _sweep(tmp_path, "variants: {v: {social: {weights: " + "[" * depth + "]" * depth + "}}}\n")
    assert _error(dut) == (f"{dut}: line 4: nested more than 32 levels deep (aliases included); at most 32 are "
                           f"allowed")
    dut = _sweep(tmp_path, "variants:\n" + "".join("  " * (i + 1) + f"k{i}:\n" for i in range(depth)))
    assert "nested more than 32 levels deep" in _error(dut)


# ---- types (item 15) and values


@pytest.mark.parametrize("text, shown", [('"false"', "'false'"), ("'no'", "'no'"), ("0", "'0'"), ("[]", "a list")])
def test_simulate_must_be_a_boolean(tmp_path, text, shown):
    dut = _sweep(tmp_path, f"simulate: {text}\n")
    assert _error(dut) == f"{dut}: line 4: simulate: must be true or false, got {shown}"


@pytest.mark.parametrize("field, text, allowed, shown", [
    ("runs", "2.5", "an integer", "'2.5'"),
    ("runs", "true", "an integer", "'true'"),
    ("seed", "abc", "an integer", "'abc'"),
    ("name", "[a]", "a string", "a list"),
    ("scenarios", "tiny.yaml", "a list of strings", "'tiny.yaml'"),
    ("algorithms", "{a: 1}", "a list of strings", "a mapping"),
    ("variants", "[a, b]", "a mapping of names to mappings (Scenario: description, world,", "a list"),
])
def test_every_field_is_type_checked_with_its_line(tmp_path, field, text, allowed, shown):
    dut = _sweep(tmp_path, f"{field}: {text}\n", head="checker: planar\n")
    message = _error(dut)
    assert message.startswith(f"{dut}: line 2: {field}: must be {allowed}") and message.endswith(f", got {shown}")


def test_a_checker_typo_is_refused_before_any_run(tmp_path):
    dut = _sweep(tmp_path, "checker: plnar\n")
    assert _error(dut) == f"{dut}: line 4: checker: unknown checker 'plnar'; allowed: planar, drake, numpy"
    with pytest.raises(ScenarioError, match=r"^study: checker: unknown checker 'plnar'; allowed: planar, drake"):
        run_study(Study("s", (Group("g", str(TINY), algorithms=("rrt_star",)),), runs=1, iterations=10,
                        checker="plnar"))


def test_a_variant_may_set_the_object_with_its_tag(tmp_path):
    dut = load_sweep(_sweep(tmp_path, "variants: {short: {object: !Bar {length: 1.2, thickness: 0.05}}}\n"))
    assert dut.groups[0].overrides == ("{object: !Bar {length: 1.2, thickness: 0.05}}",)


# ---- names (items 12, 13)


def test_two_scenarios_with_the_same_file_name_are_refused(tmp_path):
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "tiny.yaml").write_text(TINY.read_text())
    dut = _sweep(tmp_path, "", head="scenarios: [a/tiny.yaml, b/tiny.yaml]\n")
    assert _error(dut) == (f"{dut}: line 1: scenarios[1]: {tmp_path / 'b' / 'tiny.yaml'} has the same name 'tiny' "
                           f"as scenarios[0] ({tmp_path / 'a' / 'tiny.yaml'}); groups are named <scenario file "
                           f"name>-<variant>, so the scenario files of a sweep need distinct names (output files would "
                           f"collide on a file system that ignores case)")
    dut = _sweep(tmp_path, "", head=f"scenarios: [{TINY}, {TINY}]\n")
    assert "scenarios[1]: " in _error(dut) and "has the same name 'tiny' as scenarios[0]" in _error(dut)


@pytest.mark.parametrize("name", ["a/b", "..", ".hidden", "two words", "a\\\\b", "x" * 101, "é"])
def test_a_variant_name_that_cannot_name_a_file_is_refused_before_running(tmp_path, name):
    dut = _sweep(tmp_path, f'variants: {{"{name}": {{}}}}\n')
    shown = shorten(name.replace("\\\\", "\\"))
    assert _error(dut) == f"{dut}: line 4: variants.{shown}: a variant name {NAME_RULE}"


def test_a_variant_name_must_be_a_string(tmp_path):
    dut = _sweep(tmp_path, "variants: {1: {}}\n")
    assert _error(dut) == f"{dut}: line 4: variants: names must be non-empty strings, got '1'"


def test_a_study_name_that_cannot_name_a_folder_is_refused(tmp_path):
    dut = _sweep(tmp_path, "name: ../outside\n")
    assert _error(dut) == f"{dut}: line 4: name: '../outside': a study name {NAME_RULE}"


def test_group_names_and_planners_are_checked_at_the_door_of_run_study():
    for groups, message in [
        ((Group("a/b", str(TINY), algorithms=("rrt_star",)),), f"group 'a/b': a group name {NAME_RULE}"),
        ((Group("g", str(TINY), algorithms=("rrt_star",)), Group("g", str(TINY), algorithms=("rrt_star",))),
         "group 'g': two groups have this name (letter case aside); their records and arena logs would mix"),
        ((Group("g", str(TINY), algorithms=("rrt_star",)), Group("G", str(TINY), algorithms=("rrt_star",))),
         "group 'G': two groups have this name (letter case aside); their records and arena logs would mix"),
        ((Group("g", str(TINY), algorithms=("rrt_star", "rrt_star")),),
         "group 'g': algorithms[1]: rrt_star is listed twice (its runs would be recorded twice)"),
    ]:
        with pytest.raises(ScenarioError) as info:
            run_study(Study("s", groups, runs=1, iterations=10))
        assert str(info.value) == f"study: {message}"


# ---- errors name the file and the option (item 17)


def test_duplicate_algorithms_are_refused(tmp_path):
    dut = _sweep(tmp_path, "algorithms: [social_rrt_star, social_rrt_star]\n")
    assert _error(dut) == f"{dut}: line 4: algorithms[1]: social_rrt_star is listed twice (its runs would be " \
                          f"recorded twice)"


def test_a_bad_scenario_names_the_sweep_and_the_scenario_with_its_folder(tmp_path):
    (tmp_path / "maps").mkdir()
    bad = tmp_path / "maps" / "tiny.yaml"
    bad.write_text(TINY.read_text().replace("bounds: [0.0, 0.0, 8.0, 5.0]", "bounds: [0.0, 0.0, -8.0, 5.0]"))
    dut = _sweep(tmp_path, "", head="scenarios: [maps/tiny.yaml]\n")
    assert _error(dut) == (f"{dut}: line 1: scenarios[0]: {bad}: world.bounds: must be [x_min, y_min, x_max, y_max] "
                           f"with max > min, got [0.0, 0.0, -8.0, 5.0]")


def test_an_override_error_names_the_sweep_and_the_variant(tmp_path):
    dut = _sweep(tmp_path, "variants: {good: {}, wrong: {social: {sigma_h: -1}}}\n")
    assert _error(dut) == (f"{dut}: {TINY} (variants.wrong '{{social: {{sigma_h: -1}}}}'): social.sigma_h: "
                           f"must be > 0, got -1.0")
    dut = _sweep(tmp_path, "variants: {wrong: {social: {sigma: 1}}}\n")
    assert _error(dut) == (f"{dut}: line 4: variants.wrong.social.sigma: unknown field in variants.wrong.social; "
                           f"allowed: sigma_h, side_ratio, rear_ratio, threshold, weights, length_weight, resolution, "
                           f"speed_scaling")


def test_paper_scenario_dir_errors_name_the_folder(tmp_path, capsys):
    for name in ("office_bar.yaml", "generic_L.yaml"):
        (tmp_path / name).write_text((TINY.parent / name).read_text())
    bad = tmp_path / "office_bar.yaml"
    bad.write_text(bad.read_text().replace("random_seed:", "random_seed: -1\nunused_seed:"))
    assert main(["experiment", "paper", "--runs", "1", "--scenario-dir", str(tmp_path),
                 "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"drake-social: error: {bad}: line ") and "unused_seed: unknown field" in err
    assert not (tmp_path / "out").exists()
    (tmp_path / "generic_L.yaml").unlink()
    (tmp_path / "generic_L.yaml").mkdir()
    assert main(["experiment", "paper", "--scenario-dir", str(tmp_path)]) == 2
    assert capsys.readouterr().err == (f"drake-social: error: {tmp_path / 'generic_L.yaml'}: is a directory, not a "
                                       f"scenario file (--scenario-dir)\n")


def test_a_tag_of_no_yaml_type_and_a_bad_file_stem_are_named(tmp_path):
    dut = _sweep(tmp_path, "name: !Foo x\n")
    assert _error(dut) == f"{dut}: line 4: name: must be a string without a tag, got !Foo 'x'"
    dut = tmp_path / "my sweep.yaml"
    dut.write_text(f"scenarios: [{TINY}]\n")
    assert _error(dut) == f"{dut}: name: 'my sweep': a study name {NAME_RULE} (it is the file's stem: set name:)"


# ---- review of the loader: bad characters, tags and file names in a sweep


def test_a_nul_or_control_character_in_a_sweep_file_is_refused(tmp_path):
    for char, code in (("\x00", "#x0000"), ("\x1b", "#x001b")):
        dut = _sweep(tmp_path, f"name: a{char}b\n")
        assert _error(dut) == (f"{dut}: not valid YAML: line 4, column 8: unacceptable character {code}: special "
                               f"characters are not allowed")


@pytest.mark.parametrize("body, message", [
    ("seed: !!int abc\n", "line 4: seed: must be an integer, got !!int 'abc'"),
    ("simulate: !!bool maybe\n", "line 4: simulate: must be true or false, got !!bool 'maybe'"),
    ("name: !!python/name:os.system x\n", "line 4: name: must be a string, got !!python/name:os.system 'x'"),
    ("? [a]\n: 1\n", "line 4: a key must be a field name (name, runs, iterations, seed, simulate, checker, scenarios, "
                     "algorithms, variants), got a list"),
    ("variants: {? [a]: {}}\n", "line 4: variants: names must be non-empty strings, got a list"),
    ("variants: !!set {a}\n", "line 4: variants: must be a mapping of names to mappings (Scenario: description, "
                              "world, people, crowd, people_file, people_file_ids, robot, object, start, goal, social, planner, "
                                  "execution, random_seed) "
                              "or nulls without a tag, got !!set a mapping"),
    ("variants: {a: {world: !Bar {}}}\n", "line 4: variants.a.world: must be a mapping (World: bounds, obstacles, "
                                          "wall_thickness, map, unknown) without a tag, got !Bar a mapping"),
])
def test_unusual_yaml_in_a_sweep_is_named(tmp_path, body, message):
    dut = _sweep(tmp_path, body)
    assert _error(dut) == f"{dut}: {message}"


def test_a_nul_in_a_scenario_name_is_refused(tmp_path, capsys):
    dut = _sweep(tmp_path, "", head='runs: 1\nscenarios: ["a\\0b.yaml"]\n')
    assert _error(dut) == (f"{dut}: line 2: scenarios[0]: must be printable text (the characters a YAML file may "
                           "hold), got U+0000 in 'a\\x00b.yaml'")
    assert main(["experiment", "sweep", str(dut), "--out", str(tmp_path / "o")]) == 2
    assert "Traceback" not in capsys.readouterr().err


def test_an_empty_scenario_name_is_not_the_working_directory(tmp_path):
    dut = _sweep(tmp_path, "", head='runs: 1\nscenarios: [""]\n')
    assert _error(dut) == f"{dut}: line 2: scenarios[0]: '': an empty file name; a scenario file is needed"


def test_a_missing_scenario_names_both_places_searched(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "studies").mkdir()
    dut = _sweep(tmp_path / "studies", "", head="runs: 1\nscenarios: [sub/none.yaml]\n")
    assert _error(dut) == (f"{dut}: line 2: scenarios[0]: sub/none.yaml: no such scenario file, neither beside the "
                           f"sweep ({tmp_path / 'studies' / 'sub' / 'none.yaml'}) nor in the working directory "
                           f"({tmp_path / 'sub' / 'none.yaml'})")


def test_a_listed_scenario_too_big_or_not_utf8_names_the_sweep(tmp_path):
    huge = tmp_path / "huge.yaml"
    with open(huge, "wb") as f:
        f.truncate(5_000_000)
    dut = _sweep(tmp_path, "", head=f"runs: 1\nscenarios: [{TINY}, huge.yaml]\n")
    assert _error(dut) == (f"{dut}: line 2: scenarios[1]: {huge}: 5,000,000 bytes; a scenario file may have at most "
                           f"4,194,304 bytes")
    huge.write_bytes(TINY.read_bytes() + b"# \xff\n")
    assert _error(dut).startswith(f"{dut}: line 2: scenarios[1]: {huge}: not a text (UTF-8) file: byte ")


def test_a_variant_may_make_the_file_valid(tmp_path):
    kpneg = tmp_path / "kpneg.yaml"
    kpneg.write_text(TINY.read_text() + "execution: {kp: -1.0}\n")
    dut = _sweep(tmp_path, "variants: {a: {execution: {kp: 1.5}}}\n", head="runs: 1\nscenarios: [kpneg.yaml]\n")
    study = load_sweep(dut)
    assert [g.name for g in study.groups] == ["kpneg-a"]
    # a variant that leaves the file's value as it is: the file is named, as the scenario at fault
    dut = _sweep(tmp_path, "variants: {a: {execution: {kp: 1.5}}, b: {}}\n", head="runs: 1\nscenarios: [kpneg.yaml]\n")
    assert _error(dut) == f"{dut}: line 2: scenarios[0]: {kpneg}: execution.kp: must be > 0, got -1.0"


def test_each_scenario_and_variant_is_loaded_once(tmp_path, monkeypatch):
    from drake_social.experiments.study import scenarios as study_scenarios

    calls = []
    real = study_scenarios.load_scenario_text

    def counted(text, source, overrides=None, **kw):
        calls.append((source, tuple(overrides or ())))
        return real(text, source, overrides, **kw)

    monkeypatch.setattr(study_scenarios, "load_scenario_text", counted)
    monkeypatch.setattr(study_scenarios, "_loaded", collections.OrderedDict())
    variants = ", ".join(f"v{i}: {{social: {{length_weight: {i / 10}}}}}" for i in range(20))
    dut = _sweep(tmp_path, f"variants: {{{variants}}}\n")
    study = load_sweep(dut)
    tasks = study_tasks(study)
    assert len(study.groups) == 20 and len(tasks) == 20 * 5
    assert len(calls) == 20 and len(set(calls)) == 20


def test_figures_use_the_scenario_the_runs_loaded(tmp_path):
    scenario = tmp_path / "tiny.yaml"
    scenario.write_text(TINY.read_text())
    result = run_study(Study("s", (Group("g", str(scenario), algorithms=("rrt_star",)),), runs=1, iterations=10))
    scenario.write_text(TINY.read_text().replace("bounds: [0.0, 0.0, 8.0, 5.0]", "bounds: [0.0, 0.0, 9.0, 5.0]"))
    assert result.scenario("g").world.bounds == [0.0, 0.0, 8.0, 5.0]
    scenario.unlink()
    assert result.scenario("g").world.bounds == [0.0, 0.0, 8.0, 5.0]


# ---- settings a study makes for every run, names that differ in case, long names (review items 9, 10, 11)


@pytest.mark.parametrize("variant, field, instead", [
    ("{planner: {iterations: 5}}", "planner.iterations", "the sweep's iterations:"),
    ("{planner: {goal_bias: 0.1, algorithm: rrt_star}}", "planner.algorithm", "the sweep's algorithms:"),
    ("{random_seed: 3}", "random_seed", "the sweep's seed: (each run's planner seed is drawn from it)"),
    ("{execution: {mode: dynamic}}", "execution.mode", "nothing: a study simulates every run in kinematic mode"),
])
def test_a_variant_may_not_set_what_the_study_sets_for_every_run(tmp_path, variant, field, instead):
    dut = _sweep(tmp_path, f"variants:\n  fine: {{}}\n  a: {variant}\n")
    assert _error(dut) == (f"{dut}: line 6: variants.a.{field}: a study sets it for every run, so a variant "
                           f"cannot: use {instead}")


def test_variant_and_scenario_names_that_differ_only_in_case_are_refused(tmp_path):
    dut = _sweep(tmp_path, "variants: {a: {}, A: {social: {length_weight: 1.0}}}\n")
    assert _error(dut) == (f"{dut}: line 4: variants.A: differs from variants.a only in letter case; their output "
                           f"files would collide on a file system that ignores case")
    (tmp_path / "sub").mkdir()
    for name in ("tiny.yaml", "Tiny.yaml"):
        (tmp_path / "sub" / name).write_text(TINY.read_text())
    dut = _sweep(tmp_path, "", head="runs: 1\nscenarios: [sub/tiny.yaml, sub/Tiny.yaml]\n")
    assert _error(dut) == (f"{dut}: line 2: scenarios[1]: {tmp_path / 'sub' / 'Tiny.yaml'} has the same name, letter "
                           f"case aside, 'Tiny' as scenarios[0] ({tmp_path / 'sub' / 'tiny.yaml'}); groups are named "
                           f"<scenario file name>-<variant>, so the scenario files of a sweep need distinct names "
                           f"(output files would collide on a file system that ignores case)")


def test_a_long_variant_name_is_blamed_for_a_long_group_name(tmp_path):
    name = "v" * 100
    dut = _sweep(tmp_path, f"variants:\n  ok: {{}}\n  {name}: {{}}\n")
    group = f"tiny-{name}"
    assert _error(dut) == (f"{dut}: line 6: variants.{name}: the group name {shorten(repr(group))} (<scenario file "
                           f"name>-<variant>) has 105 characters; at most 100 are allowed: shorten the variant's name "
                           f"(or rename {TINY})")


def test_the_paper_runs_argument_bound_is_the_real_one(tmp_path, capsys):
    from drake_social.cli import build_parser
    from drake_social.experiments.study import MAX_PAPER_RUNS, PAPER_PAIRS

    study = paper_study(runs=MAX_PAPER_RUNS)  # the largest the argument allows passes the study's own check
    assert study.runs * sum(len(g.algorithms) for g in study.groups) <= MAX_STUDY_TASKS
    with pytest.raises(ScenarioError):
        paper_study(runs=MAX_PAPER_RUNS + 1)
    assert MAX_PAPER_RUNS == 100_000 // 13
    assert sum(len(g.algorithms) for g in study.groups) == PAPER_PAIRS == 13  # limits' count is the study's
    assert main(["experiment", "paper", "--runs", str(MAX_PAPER_RUNS + 1), "--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err.endswith("argument --runs: must be an integer in [1, 7,692], got 7693\n")
    parser = build_parser()
    experiment = parser._subparsers._group_actions[0].choices["experiment"]
    paper = experiment._subparsers._group_actions[0].choices["paper"]
    assert "at most 7,692 (the study's 13 group x algorithm pairs x N runs stay within 100,000" in \
        " ".join(paper.format_help().split())


def test_an_alias_error_names_the_aliass_line(tmp_path):
    dut = _sweep(tmp_path, "", head=f"seed: &n 0\nscenarios: [{TINY}]\nruns: *n\n")
    assert _error(dut) == f"{dut}: line 3: runs: must be an integer in [1, 10,000], got 0"


@pytest.mark.parametrize("field, text, value", [
    ("runs", "0", 0), ("iterations", "100000000", 10**8), ("seed", "-1", -1), ("checker", "plnar", "plnar"),
    ("name", "a/b", "a/b"),
])
def test_a_sweep_and_a_study_check_their_settings_with_the_same_words(tmp_path, field, text, value):
    dut = _sweep(tmp_path, f"{field}: {text}\n", head=f"scenarios: [{TINY}]\n")
    settings = {"runs": 1, "iterations": 10, **{field: value}}
    name = settings.pop("name", "s")
    with pytest.raises(ScenarioError) as info:
        study_tasks(Study(name, (Group("g", str(TINY), algorithms=("rrt_star",)),), **settings))
    assert str(info.value).startswith(f"study: {field}: ")
    assert _error(dut) == f"{dut}: line 2: {field}: " + str(info.value).removeprefix(f"study: {field}: ")


def test_the_checkers_have_one_home():
    from drake_social import cli, scenario
    from drake_social.experiments import study
    from drake_social.collision import drake_checker as checker

    assert cli.CHECKERS is study.CHECKERS is checker.CHECKERS is scenario.CHECKERS


def test_the_depth_limit_leaves_room_for_what_the_comment_says(tmp_path):
    import yaml

    from drake_social.scenario.load import MAX_YAML_DEPTH, _limited_loader

    def depth(text):
        loader = _limited_loader(yaml)(text)
        return loader._height[id(loader.get_single_node())]

    root = TINY.parent.parent
    assert depth((root / "scenarios" / "office_bar.yaml").read_text()) == 6
    assert depth((root / "studies" / "example_sweep.yaml").read_text()) == 6
    assert depth("variants: {a: {world: {obstacles: [{center: [1, 2]}]}}}") == 8 <= MAX_YAML_DEPTH


def test_a_long_variant_name_is_named_whole_in_its_fields(tmp_path):
    # A variant name may have 100 characters; the dotted field of an error inside
    # it names it whole, not cut in the middle of the field.
    name = "v" * 95
    path = _sweep(tmp_path, f"variants: {{{name}: {{social: {{sigma_hh: 1}}}}}}\n")
    assert _error(path) == (f"{path}: line 4: variants.{name}.social.sigma_hh: unknown field in "
                            f"variants.{name}.social; allowed: sigma_h, side_ratio, rear_ratio, threshold, weights, "
                            "length_weight, resolution, speed_scaling")


def test_a_variant_name_with_a_control_character_is_refused_escaped(tmp_path):
    path = _sweep(tmp_path, 'variants: {"v\\aw": {}}\n')
    assert _error(path) == f"{path}: line 4: variants.'v\\x07w': names must be printable text, got U+0007 in 'v\\x07w'"


ADMISSIBLE = "{planner: {informed_mode: admissible}, social: {length_weight: 0}}"


def test_a_variant_invalid_with_a_study_algorithm_is_refused_before_any_run(tmp_path, capsys):
    # Valid with the file's own planner.algorithm, but an informed planner of the
    # study needs length_weight > 0: it failed inside the runs, naming no file.
    dut = _sweep(tmp_path, f"algorithms: [social_rrt_star, informed_social_rrt_star]\nvariants: {{adm: {ADMISSIBLE}}}\n")
    message = (f"{dut}: {TINY} (variants.adm) with the study's algorithm informed_social_rrt_star: "
               "planner.informed_mode: 'admissible' needs social.length_weight > 0")
    assert _error(dut) == message
    out = tmp_path / "o"
    assert main(["experiment", "sweep", str(dut), "--out", str(out)]) == 2
    assert capsys.readouterr().err.splitlines()[-1] == f"drake-social: error: {message}"
    assert not out.exists()


def test_a_study_group_invalid_with_its_algorithm_is_refused_by_its_check(tmp_path):
    study = Study("s", (Group("g", str(TINY), overrides=(ADMISSIBLE,), algorithms=("informed_social_rrt_star",)),),
                  runs=1, iterations=10)
    with pytest.raises(ScenarioError) as info:
        study_tasks(study)
    assert str(info.value) == (f"{TINY} (group g) with the study's algorithm informed_social_rrt_star: "
                               "planner.informed_mode: 'admissible' needs social.length_weight > 0")


def test_a_long_group_name_is_named_whole(tmp_path):
    # Group names may have 100 characters; the duplicate's field was cut at 80.
    name = "g" * 100
    study = Study("s", (Group(name, str(TINY)), Group(name.upper(), str(TINY))), runs=1, iterations=10)
    with pytest.raises(ScenarioError) as info:
        study_tasks(study)
    assert str(info.value) == (f"study: group {name.upper()!r}: two groups have this name (letter case aside); "
                               "their records and arena logs would mix")


def test_a_bench_scenario_invalid_with_a_bench_algorithm_is_refused_before_any_run(tmp_path, monkeypatch):
    from drake_social.experiments.bench import planners as bench_module

    def no_run(*args, **kwargs):
        raise AssertionError("a planner ran before every scenario was checked")

    monkeypatch.setattr(bench_module, "plan", no_run)
    bad = tmp_path / "adm.yaml"
    text = TINY.read_text()
    assert "\nsocial:" not in text and "\nplanner: {" in text
    bad.write_text(text.replace("\nplanner: {", "\nplanner: {informed_mode: admissible, ", 1)
                   + "\nsocial: {length_weight: 0}\n")
    with pytest.raises(ScenarioError) as info:
        bench_module.run_bench(scenario_paths=[TINY, bad], algorithms=["social_rrt_star", "informed_social_rrt_star"],
                               iterations=10, seeds=1, include_ompl=False, include_checker=False,
                               out_dir=tmp_path / "o")
    assert str(info.value) == (f"{bad} with the bench's algorithm informed_social_rrt_star: planner.informed_mode: "
                               "'admissible' needs social.length_weight > 0")
