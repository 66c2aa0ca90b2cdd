"""Every scenario error names its source, line and field (issue 9, part 3).

One test per bad input the issue lists; each message is compared whole, so
that a vaguer one ("could not convert string to float") cannot come back.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drake_social.cli import load_with_overrides, main, read_path_csv
from drake_social.scenario import ScenarioError, check_yaml, load_scenario
from drake_social.io.textfile import shorten

TINY = Path(__file__).resolve().parent.parent / "scenarios" / "tiny.yaml"
PEOPLE = 'people:\n  - {x: 4.0, y: 3.8, theta: -1.5708, radius: 0.25, name: "standing"}  # faces south'


def _bad(tmp_path: Path, old: str, new: str) -> Path:
    text = TINY.read_text()
    assert text.count(old) == 1
    path = tmp_path / "bad.yaml"
    path.write_text(text.replace(old, new))
    return path


def _message(path: Path, overrides=None) -> str:
    with pytest.raises(ScenarioError) as info:
        load_with_overrides(path, overrides)
    return str(info.value)


def test_a_word_in_the_bounds_names_the_element(tmp_path):
    dut = _bad(tmp_path, "bounds: [0.0, 0.0, 8.0, 5.0]", "bounds: [0, 0, eight, 5]")
    assert _message(dut) == f"{dut}: line 4: world.bounds[2]: must be a number, got 'eight'"


def test_a_word_for_the_start(tmp_path):
    dut = _bad(tmp_path, "start: [1.0, 2.5, 0.0, 1.5708]", "start: abc")
    assert _message(dut) == f"{dut}: line 14: start: must be a list of numbers, got 'abc'"


def test_a_null_start(tmp_path):
    dut = _bad(tmp_path, "start: [1.0, 2.5, 0.0, 1.5708]", "start: null")
    assert _message(dut) == f"{dut}: line 14: start: must be a list of numbers, got null"


def test_null_people(tmp_path):
    dut = _bad(tmp_path, PEOPLE, "people: null")
    assert _message(dut) == (f"{dut}: line 7: people: must be a list of mappings "
                             "(Person: x, y, theta, radius, name, trajectory, loop), got null")


def test_people_as_a_mapping(tmp_path):
    dut = _bad(tmp_path, PEOPLE, "people: {x: 4.0, y: 3.8}")
    assert _message(dut) == (f"{dut}: line 7: people: must be a list of mappings "
                             "(Person: x, y, theta, radius, name, trajectory, loop), got a mapping")


def test_a_word_for_the_iterations(tmp_path):
    dut = _bad(tmp_path, "iterations: 300", "iterations: many")
    assert _message(dut) == f"{dut}: line 18: planner.iterations: must be an integer, got 'many'"


def test_an_unknown_nested_key_names_its_section(tmp_path):
    dut = _bad(tmp_path, "  link_width: 0.08\n", "  link_width: 0.08\n  wheels: 4\n")
    assert _message(dut) == (f"{dut}: line 13: robot.wheels: unknown field in robot; allowed: base_radius, "
                             "link_lengths, link_width, joint_lower, joint_upper")


def test_an_unknown_object_type_lists_the_allowed_tags(tmp_path):
    dut = _bad(tmp_path, "!Bar", "!Stick")
    assert _message(dut) == f"{dut}: line 13: object: unknown type !Stick; allowed: !Bar, !LShape, !Polyline"


def test_the_execution_section_gets_the_same_checks(tmp_path):
    dut = _bad(tmp_path, "random_seed: 1\n", "random_seed: 1\nexecution: {kp: fast, arm_max_jerk: null}\n")
    assert _message(dut) == f"{dut}: line 17: execution.kp: must be a number, got 'fast'"
    dut = _bad(tmp_path, "random_seed: 1\n", "random_seed: 1\nexecution: {gears: 3}\n")
    assert "line 17: execution.gears: unknown field in execution; allowed: mode, execution, kp," in _message(dut)


def test_a_value_error_from_a_set_names_the_set_not_the_file(tmp_path):
    text = "robot: {base_radius: -1}"
    assert _message(TINY, [text]) == f"{TINY} (--set {text!r}): robot.base_radius: must be > 0, got -1.0"
    # The file's own errors still name the file, even with a harmless --set.
    bad = _bad(tmp_path, "base_radius: 0.35", "base_radius: -1")
    assert _message(bad, ["random_seed: 3"]) == f"{bad}: robot.base_radius: must be > 0, got -1.0"
    # ... and a --set that repairs the file is not blamed for anything.
    assert load_with_overrides(bad, ["robot: {base_radius: 0.3}"]).robot.base_radius == 0.3
    # A --set that repairs nothing and breaks nothing leaves the blame where it is.
    message = _message(TINY, ["random_seed: 3", text, "social: {sigma_h: 1.5}"])
    assert message.startswith(f"{TINY} (--set {text!r}): robot.base_radius")


def test_a_type_error_from_a_set_names_the_set():
    text = "start: null"
    assert _message(TINY, [text]) == f"{TINY} (--set {text!r}): line 1: start: must be a list of numbers, got null"


def test_a_duplicate_key_is_refused_with_file_and_line(tmp_path):
    dut = tmp_path / "dup.yaml"
    dut.write_text(TINY.read_text() + "random_seed: 7\n")
    assert _message(dut) == f"{dut}: line 19: random_seed: duplicate key (first at line 16)"
    dut.write_text(TINY.read_text().replace("  base_radius: 0.35\n", "  base_radius: 0.35\n  base_radius: 0.4\n"))
    assert _message(dut) == f"{dut}: line 11: robot.base_radius: duplicate key (first at line 10)"


def test_a_directory_is_named_as_such(tmp_path, capsys):
    assert _message(tmp_path) == f"{tmp_path}: is a directory, not a scenario file"
    assert main(["show", str(tmp_path), "--out", str(tmp_path / "out")]) == 2
    assert capsys.readouterr().err == f"drake-social: error: {tmp_path}: is a directory, not a scenario file\n"
    assert main(["bench", "--scenarios", str(tmp_path), "--out", str(tmp_path / "out")]) == 2
    assert "is a directory, not a scenario file (--scenarios)" in capsys.readouterr().err


def test_an_empty_file_says_what_a_scenario_is(tmp_path):
    dut = tmp_path / "empty.yaml"
    dut.write_text("# nothing\n")
    assert _message(dut).startswith(f"{dut}: empty; a scenario is a mapping (description, world, people")


def test_values_drakes_loader_accepts_still_load():
    """The pre-check is no stricter than yaml_load_typed where the value is fine."""
    check_yaml("random_seed: '3'\nsocial: {sigma_h: .inf, weights: null, threshold: 1}\nplanner: {optimize: true}\n"
               "object: !LShape {lengths: [1, 2]}\nworld: {bounds: [0, 0, 8, '5']}", "text")
    dut = load_scenario(TINY, ["random_seed: 2.0", "object: !Polyline {points: [[0, 0], [0, 1]]}"])
    assert dut.random_seed == 2 and dut.object.points == [[0.0, 0.0], [0.0, 1.0]]


def test_a_path_csv_error_names_the_line_and_column(tmp_path, tiny_scenario):
    dut = tmp_path / "path.csv"
    dut.write_text("x,y,psi1,psi2\n1,2.5,0,1.5708\n3,abc,0,1\n6.5,2.5,0,1.5708\n")
    with pytest.raises(ScenarioError) as info:
        read_path_csv(dut, tiny_scenario)
    assert str(info.value) == f"{dut}: line 3: y: must be a finite number, got 'abc' (--path)"
    dut.write_text("x,y,psi1,psi2\n1,2.5,0,1.5708\n3,2,nan,1\n")
    with pytest.raises(ScenarioError, match=r"line 3: psi1: must be a finite number, got 'nan'"):
        read_path_csv(dut, tiny_scenario)
    dut.write_text("x,y,psi1,psi2\n1,2.5,0\n")
    with pytest.raises(ScenarioError, match=r"line 2: needs 4 numbers x,y,psi1,psi2, got 3 values"):
        read_path_csv(dut, tiny_scenario)
    with pytest.raises(ScenarioError, match="is a directory"):
        read_path_csv(tmp_path, tiny_scenario)
    dut.write_text("x,y,psi1,psi2\n1,2.5,0,1.5708\n6.5,2.5,0,1.5708\n")
    np.testing.assert_array_equal(read_path_csv(dut, tiny_scenario), [[1, 2.5, 0, 1.5708], [6.5, 2.5, 0, 1.5708]])


def test_a_resolution_too_fine_for_the_room_names_the_least_allowed():
    """Every motion's social cost is sampled in at most MAX_MOTION_STEPS steps:
    the least resolution is the longest displacement bound in the room over
    that. By hand for tiny: its 8 x 5 m diagonal, the elbow 0.6 m from the
    shoulder turning 2 pi with psi1, and the bar's ends (0.5, +-0.75) m from
    the elbow turning 4 pi with psi1 + psi2."""
    import math

    from drake_social.limits import MAX_MOTION_STEPS

    longest = math.hypot(8.0, 5.0) + 0.6 * 2 * math.pi + math.hypot(0.5, 0.75) * 4 * math.pi
    least = longest / MAX_MOTION_STEPS
    assert _message(TINY, ["social: {resolution: 0.000001}"]) == (
        f"{TINY} (--set 'social: {{resolution: 0.000001}}'): social.resolution: must be >= {least:.3g} m for this "
        f"world and robot (a motion may move a point {longest:.4g} m, sampled in at most 1,000,000 steps), got 1e-06")
    assert load_with_overrides(TINY, [f"social: {{resolution: {least * 1.0001}}}"]).social.resolution > least


# ---- the limits of the shared YAML parser (compose_yaml): the same for scenario
# files, --set overrides and sweep files (tests/experiments/test_study.py).


def _laughs(levels: int = 10, item: str = "lol") -> list[str]:
    """A "billion laughs": each level is a list of nine aliases of the one before (9^levels leaves)."""
    lines = [f"l0: &l0 [{', '.join([item] * 9)}]"]
    lines += [f"l{i}: &l{i} [{', '.join([f'*l{i - 1}'] * 9)}]" for i in range(1, levels)]
    return lines


def _depth_message(source, line: int) -> str:
    return f"{source}: line {line}: nested more than 32 levels deep (aliases included); at most 32 are allowed"


def _nodes_message(source, line: int) -> str:
    return (f"{source}: line {line}: more than 100,000 YAML nodes (aliases counted as the nodes they repeat); "
            f"a document may have at most 100,000")


@pytest.mark.parametrize("field", ["description", "world", "start", "object"])
def test_an_alias_bomb_is_refused_while_it_is_read(tmp_path, field):
    """Under a known field too (not only refused as an unknown key), and in --set:
    refused while it is composed, at the line whose aliases pass the node limit."""
    lines = _laughs()
    dut = tmp_path / "bomb.yaml"
    dut.write_text(f"{field}:\n" + "".join(f"  - {{{line}}}\n" for line in lines))
    assert _message(dut) == _nodes_message(dut, 7)  # the level of 9^6 leaves
    text = "{" + ", ".join(lines) + "}"
    assert _message(TINY, [text]) == _nodes_message(f"{TINY} (--set {shorten(repr(text))})", 1)


def test_a_merge_key_bomb_is_refused(tmp_path):
    lines = ["m0: &m0 {a: 1, b: 2, c: 3}"] + [f"m{i}: &m{i} {{<<: [{', '.join([f'*m{i - 1}'] * 9)}]}}"
                                                for i in range(1, 12)]
    dut = tmp_path / "merge.yaml"
    dut.write_text("\n".join(lines) + "\n")
    assert _message(dut) == _nodes_message(dut, 6)


def test_a_recursive_alias_is_refused(tmp_path):
    dut = tmp_path / "loop.yaml"
    dut.write_text(TINY.read_text().replace("robot:\n", "robot: &r\n  extra: *r\n"))
    assert _message(dut) == (f"{dut}: line 10: an alias inside the node it refers to (a recursive YAML "
                             f"structure)")


@pytest.mark.parametrize("depth", [33, 1000, 100_000])
def test_deep_flow_nesting_is_refused_not_a_recursion_error(tmp_path, depth):
    dut = tmp_path / "deep.yaml"
    dut.write_text("start: " + "[" * depth + "]" * depth + "\n")
    assert _message(dut) == _depth_message(dut, 1)
    text = "social: {weights: " + "[" * depth + "]" * depth + "}"
    assert _message(TINY, [text]) == _depth_message(f"{TINY} (--set {shorten(repr(text))})", 1)
    text = "{a: " * depth + "}" * depth
    assert _message(TINY, [text]) == _depth_message(f"{TINY} (--set {shorten(repr(text))})", 1)


def test_deep_block_nesting_is_refused(tmp_path):
    dut = tmp_path / "deep.yaml"
    dut.write_text("".join("  " * i + f"k{i}:\n" for i in range(1000)) + "  " * 1000 + "x\n")
    assert _message(dut) == _depth_message(dut, 32)  # the key k31 on line 32 is the 33rd level
    dut.write_text("".join("  " * i + "-\n" for i in range(1000)) + "  " * 1000 + "x\n")
    assert _message(dut) == _depth_message(dut, 33)


def test_depth_through_aliases_counts(tmp_path):
    """A 20-deep anchor used 20 levels down is 40 deep once expanded."""
    dut = tmp_path / "deep.yaml"
    deep = "[" * 20 + "]" * 20
    dut.write_text(f"a: &a {deep}\nb: {'[' * 20}*a{']' * 20}\n")
    assert _message(dut) == _depth_message(dut, 2)


@pytest.mark.slow
def test_a_document_of_too_many_plain_nodes_is_refused(tmp_path):
    dut = tmp_path / "wide.yaml"
    dut.write_text("start: [" + ", ".join(["0"] * 100_000) + "]\n")
    assert _message(dut) == _nodes_message(dut, 1)


@pytest.mark.slow
def test_the_limits_leave_real_scenarios_alone(tmp_path):
    """2,000 obstacles and 300 people (the crowds to come) and the shipped files load."""
    obstacles = "".join(f"    - {{center: [{10 + (i % 50) * 1.5}, {10 + (i // 50) * 1.5}], size: [0.5, 0.5]}}\n"
                        for i in range(2000))
    people = "".join(f"  - {{x: {5 + (i % 30) * 3}, y: {80 + (i // 30) * 1.5}, theta: 0.0, radius: 0.25}}\n"
                     for i in range(300))
    dut = tmp_path / "crowd.yaml"
    dut.write_text("world:\n  bounds: [0, 0, 100, 100]\n  obstacles:\n" + obstacles + "people:\n" + people +
                   "start: [2, 2, 0, 0]\ngoal: [5, 5, 0, 0]\n")
    scenario = load_scenario(dut)
    assert (len(scenario.world.obstacles), len(scenario.people)) == (2000, 300)
    for name in ("tiny", "office_bar", "generic_L"):
        load_scenario(TINY.parent / f"{name}.yaml")


# ---- execution: what a run may record


@pytest.mark.parametrize("override, message", [
    ("execution: {time_limit: 1200}", "execution.time_limit: must be in (0, 600] seconds, got 1200.0"),
    ("execution: {time_limit: .inf}", "execution.time_limit: must be finite numbers, got inf"),
    ("execution: {replay_fps: 1000}", "execution.replay_fps: must be <= 60 frames per second, got 1000.0"),
    ("execution: {control_period: 0.002, plant_time_step: 0.001}",
     "execution.control_period: must be >= execution.time_limit / 60,000 = 0.005 s (a run may take at most "
     "60,000 control periods), got 0.002"),
    ("execution: {time_limit: 600, control_period: 0.009}",
     "execution.control_period: must be >= execution.time_limit / 60,000 = 0.01 s (a run may take at most "
     "60,000 control periods), got 0.009"),
    ("execution: {plant_time_step: 0.0005}",
     "execution.plant_time_step: must be >= execution.time_limit / 300,000 = 0.001 s (a run may take at most "
     "300,000 plant steps), got 0.0005"),
])
def test_execution_numbers_that_grow_a_run_are_bounded(override, message):
    assert _message(TINY, [override]) == f"{TINY} (--set {override!r}): {message}"


def test_the_bounds_themselves_are_accepted():
    dut = load_scenario(TINY, ["execution: {time_limit: 600, replay_fps: 60, control_period: 0.01, "
                               "plant_time_step: 0.002}"])
    assert (dut.execution.time_limit, dut.execution.replay_fps) == (600.0, 60.0)
    dut = load_scenario(TINY, ["execution: {time_limit: 60, control_period: 0.001, plant_time_step: 0.0002}"])
    assert (dut.execution.control_period, dut.execution.plant_time_step) == (0.001, 0.0002)


def test_simulate_refuses_a_time_limit_beyond_the_bound(tiny_scenario):
    from drake_social.sim.run import simulate

    with pytest.raises(ValueError, match=r"^simulate: time_limit must be in \(0, 600\] seconds, got 1200.0$"):
        simulate(tiny_scenario, waypoints=np.array([tiny_scenario.start, tiny_scenario.goal]), time_limit=1200.0,
                 analyze=False)
    fine = load_scenario(TINY, ["execution: {control_period: 0.005, plant_time_step: 0.001}"])
    with pytest.raises(ValueError, match=r"^simulate: time_limit must be <= 60,000 \* execution.control_period 0.005 "
                                         r"= 300 s \(a run may take at most 60,000 control periods\), got 600.0$"):
        simulate(fine, waypoints=np.array([fine.start, fine.goal]), time_limit=600.0, analyze=False)


# ---- replanning: one replan and one run stay bounded

ABOVE_60 = 60.00000000000001  # math.nextafter(60.0, inf)
ABOVE_100 = 100.00000000000001  # math.nextafter(100.0, inf): its period 1 / rate is below 0.01


@pytest.mark.parametrize("override, message", [
    ("planner: {replan: true, replan_rate: 1e9}",
     "planner.replan_rate: must be <= 1 / execution.control_period = 100 Hz (at most one replan per control "
     "period: the sequencer takes a new path once per period), got 1000000000.0"),
    (f"planner: {{replan: true, replan_rate: {ABOVE_100!r}}}",
     "planner.replan_rate: must be <= 1 / execution.control_period = 100 Hz (at most one replan per control "
     "period: the sequencer takes a new path once per period), got 100.00000000000001"),
    ("{planner: {replan: true, replan_rate: 51}, execution: {control_period: 0.02}}",
     "planner.replan_rate: must be <= 1 / execution.control_period = 50 Hz (at most one replan per control "
     "period: the sequencer takes a new path once per period), got 51.0"),
    ("planner: {replan_rate: 1e-320}", "planner.replan_rate: must have a finite period 1 / replan_rate, got 1e-320"),
    ("planner: {replan_horizon: 1e9}", "planner.replan_horizon: must be in (0, 600] seconds, got 1000000000.0"),
    ("planner: {replan_horizon: 600.0000000000001}",
     "planner.replan_horizon: must be in (0, 600] seconds, got 600.0000000000001"),
    ("planner: {replan_budget: 1e9}", "planner.replan_budget: must be in (0, 60] seconds, got 1000000000.0"),
    ("planner: {safety_horizon: 600.0000000000001}",
     "planner.safety_horizon: must be in (0, 600] seconds, got 600.0000000000001"),
    ("planner: {safety_horizon: 0.0}", "planner.safety_horizon: must be > 0, got 0.0"),
    (f"planner: {{replan_budget: {ABOVE_60!r}}}",
     "planner.replan_budget: must be in (0, 60] seconds, got 60.00000000000001"),
    ("planner: {replan_iterations: 10001}",
     "planner.replan_iterations: must be in [1, 10,000] (samples of one replan's search), got 10001"),
    ("planner: {replan_iterations: 10000000}",
     "planner.replan_iterations: must be in [1, 10,000] (samples of one replan's search), got 10000000"),
    ("planner: {replan_iterations: 0}",
     "planner.replan_iterations: must be in [1, 10,000] (samples of one replan's search), got 0"),
])
def test_replanning_settings_beyond_their_bounds_are_refused_naming_the_field(override, message):
    assert _message(TINY, [override]) == f"{TINY} (--set {override!r}): {message}"


def test_the_safety_horizon_at_and_within_its_bounds_loads():
    import math

    for value in (600.0, math.nextafter(600.0, 0.0), 5e-324, 2.0):
        assert load_scenario(TINY, [f"planner: {{safety_horizon: {value!r}}}"]).planner.safety_horizon == value


def test_replanning_settings_at_and_just_within_their_bounds_load():
    import math

    dut = load_scenario(TINY, ["planner: {replan: true, replan_rate: 100, replan_horizon: 600, replan_budget: 60, "
                               "replan_iterations: 10000}"])
    p = dut.planner
    assert (p.replan_rate, p.replan_horizon, p.replan_budget, p.replan_iterations) == (100.0, 600.0, 60.0, 10_000)
    below = {name: math.nextafter(value, 0.0) for name, value in (("rate", 100.0), ("horizon", 600.0),
                                                                  ("budget", 60.0))}
    dut = load_scenario(TINY, [f"planner: {{replan: true, replan_rate: {below['rate']!r}, "
                               f"replan_horizon: {below['horizon']!r}, "
                               f"replan_budget: {below['budget']!r}, replan_iterations: 9999}}"])
    assert dut.planner.replan_rate == below["rate"] and dut.planner.replan_budget == below["budget"]
    # At most one replan per control period, whatever the period: 1 / 50 Hz is 0.02 s.
    dut = load_scenario(TINY, ["{planner: {replan: true, replan_rate: 50}, execution: {control_period: 0.02}}"])
    assert 1.0 / dut.planner.replan_rate == dut.execution.control_period
    # A scenario that does not replan keeps its rate whatever its control period (10 Hz, 0.5 s) ...
    slow = "{planner: {replan_rate: 10}, execution: {control_period: 0.5, plant_time_step: 0.5, kp: 1.5}}"
    assert load_scenario(TINY, [slow]).planner.replan_rate == 10.0
    # The smallest positive rate whose period is finite: no periodic replan within the run.
    assert load_scenario(TINY, ["planner: {replan_rate: 1e-300}"]).planner.replan_rate == 1e-300


def test_turning_replanning_on_checks_the_rate_against_the_control_period(tmp_path, capsys):
    """... and turning replanning on checks it then: --replan (exit 2, one line), simulate(replan=True)."""
    from drake_social.sim.run import simulate

    slow = "{planner: {replan_rate: 10}, execution: {control_period: 0.5, plant_time_step: 0.5, kp: 1.5}}"
    out = tmp_path / "out"
    assert main(["simulate", str(TINY), "--replan", "--no-replay", "--set", slow, "--out", str(out)]) == 2
    assert capsys.readouterr().err == (
        f"drake-social: error: {TINY} (--replan): planner.replan_rate: must be <= 1 / execution.control_period = "
        "2 Hz (at most one replan per control period: the sequencer takes a new path once per period), got 10.0\n")
    assert not out.exists()
    with pytest.raises(ValueError, match=r"^simulate: replan=True: the scenario's planner.replan_rate must be <= 1 / "
                                         r"execution.control_period = 2 Hz .*, got 10.0$"):
        simulate(load_scenario(TINY, [slow]), replan=True, analyze=False)


def test_the_replanner_system_refuses_a_rate_beyond_one_per_control_period(tiny_scenario):
    from drake_social.control import ReplanningPlannerSystem

    class Never:
        def plan(self, *args, **kwargs):
            raise AssertionError("not called")

    assert ReplanningPlannerSystem(tiny_scenario, Never(), rate=100.0).period == 0.01
    with pytest.raises(ValueError, match=r"^ReplanningPlannerSystem: rate must be <= 1 / execution.control_period "
                                         r"= 100 Hz .*, got 100.00000000000001$"):
        ReplanningPlannerSystem(tiny_scenario, Never(), rate=ABOVE_100)


# ---- review of the loader: characters YAML refuses, unusual keys and tags (exit 2, never a traceback)


@pytest.mark.parametrize("char, code", [("\x00", "#x0000"), ("\x01", "#x0001"), ("\x7f", "#x007f"),
                                        ("\udcff", "#xdcff")])
def test_a_control_character_or_nul_is_refused_in_a_file_and_a_set(tmp_path, capsys, char, code):
    dut = tmp_path / "nul.yaml"
    if char != "\udcff":
        dut.write_text(f"description: a{char}b\n")
        assert main(["show", str(dut), "--out", str(tmp_path / "o")]) == 2
        assert capsys.readouterr().err == (f"drake-social: error: {dut}: not valid YAML: line 1, column 15: "
                                           f"unacceptable character {code}: special characters are not allowed\n")
    # a --set as the shell passes it (an invalid byte arrives as a lone surrogate)
    assert main(["show", str(TINY), "--set", f"description: {char}", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"drake-social: error: {TINY} (--set ")
    assert f"not valid YAML: line 1, column 14: unacceptable character {code}" in err
    assert "Traceback" not in err


def test_a_sparse_file_of_nuls_at_the_size_limit_is_refused(tmp_path, capsys):
    from drake_social.io.textfile import MAX_YAML_FILE_BYTES

    dut = tmp_path / "zeros.yaml"
    with open(dut, "wb") as f:
        f.truncate(MAX_YAML_FILE_BYTES)
    assert main(["show", str(dut), "--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err == (f"drake-social: error: {dut}: not valid YAML: line 1, column 1: unacceptable "
                                       f"character #x0000: special characters are not allowed\n")


@pytest.mark.parametrize("override, message", [
    ("? [a]\n: 1", "line 1: a key must be a field name (description, world, people, crowd, people_file, "
                   "people_file_ids, robot, object, start, goal, social, planner, execution, random_seed), got a list"),
    ("{a: 1}: 2", "line 1: a key must be a field name (description, world, people, crowd, people_file, "
                  "people_file_ids, robot, object, start, goal, social, planner, execution, random_seed), got a mapping"),
    ("world: {? [1]: 2}", "line 1: world: a key must be a field name (bounds, obstacles, wall_thickness, map, unknown), got a list"),
    ("social: {weights: {? [1]: 2}}", "line 1: social.weights: must be a list of numbers, got a mapping"),
    ("!Foo 3: 1", "line 1: 3: unknown field at the top level; allowed: description, world, people, crowd, "
                  "people_file, people_file_ids, robot, object, start, goal, social, planner, execution, random_seed"),
])
def test_keys_that_are_not_field_names(override, message):
    assert _message(TINY, [override]) == f"{TINY} (--set {override!r}): {message}"


@pytest.mark.parametrize("override, message", [
    ("description: !!python/object:os.system x", "description: must be a string, got !!python/object:os.system 'x'"),
    ("description: !!python/name:os.system x", "description: must be a string, got !!python/name:os.system 'x'"),
    ("description: !!binary \"a\"", "description: must be a string, got !!binary 'a'"),
    ("random_seed: !!int abc", "random_seed: must be an integer, got !!int 'abc'"),
    ("random_seed: !!int 0x", "random_seed: must be an integer, got !!int '0x'"),
    ("social: {threshold: !!float abc}", "social.threshold: must be a number, got !!float 'abc'"),
    ("social: {threshold: !!float .}", "social.threshold: must be a number, got !!float '.'"),
    ("planner: {optimize: !!bool maybe}", "planner.optimize: must be true or false, got !!bool 'maybe'"),
    ("execution: {time_limit: !!timestamp x}", "execution.time_limit: must be a number, got !!timestamp 'x'"),
    ("execution: {time_limit: !!timestamp 2001-01-01}",
     "execution.time_limit: must be a number, got '2001-01-01'"),
    ("description: !Foo x", "description: must be a string without a tag, got !Foo 'x'"),
    ("world: !Bar {}", "world: must be a mapping (World: bounds, obstacles, wall_thickness, map, unknown) without a tag, got !Bar "
                       "a mapping"),
    ("world: !!set {a}", "world: must be a mapping (World: bounds, obstacles, wall_thickness, map, unknown) without a tag, got "
                         "!!set a mapping"),
    ("people: !!omap []", "people: must be a list of mappings (Person: x, y, theta, radius, name, trajectory, loop) without a tag, got "
                          "!!omap a list"),
    ("start: !Bar [1, 1, 0, 0]", "start: must be a list of numbers without a tag, got !Bar a list"),
])
def test_tags_whose_value_does_not_fit_are_named(override, message):
    assert _message(TINY, [override]) == f"{TINY} (--set {override!r}): line 1: {message}"


def test_standard_tags_that_fit_still_load():
    scenario = load_with_overrides(TINY, ["random_seed: !!int 7", "description: !!str 12",
                                          "social: {threshold: !!float 0.25}", "object: !Bar {length: 1.0}"])
    assert (scenario.random_seed, scenario.description, scenario.social.threshold) == (7, "12", 0.25)


# ---- error messages repeat at most 80 characters of the input (review item 7)


def _short(message: str, total: int) -> None:
    # The file's name, two shortened quotes (80 characters each, with their counts), the words
    # and at most the list of a section's fields.
    from dataclasses import fields

    from drake_social.scenario.schema import PlannerOptions

    allowed = len(", ".join(f.name for f in fields(PlannerOptions)))
    assert len(message) < len(str(TINY)) + 2 * 110 + allowed + 150, message[:1000]
    assert message.count("x" * 81) == 0
    assert f"... ({total:,} characters)" in message


@pytest.mark.slow
def test_a_long_list_is_not_repeated_whole():
    override = f"social: {{weights: [{', '.join(['1'] * 99_000)}]}}"
    message = _message(TINY, [override])
    assert message.startswith(f"{TINY} (--set '{override[:79]}... ({len(override) + 2:,} characters)): "
                              f"social.weights: must have 5 values, got 99000: [1.0, 1.0, ")
    _short(message, len(str([1.0] * 99_000)))


def test_a_long_set_and_long_words_are_cut_short():
    override = "random_seed: -1\ndescription: '" + "a" * 4000 + "'"
    message = _message(TINY, [override])
    assert message == f"{TINY} (--set {repr(override)[:80]}... ({len(repr(override)):,} characters)): random_seed: " \
                      f"must be >= 0, got -1"
    long = "x" * 5000
    _short(_message(TINY, [f"planner: {{algorithm: {long}}}"]), 5002)
    _short(_message(TINY, [f"planner: {{{long[:1000]}: 1}}"]), 1000)
    _short(_message(TINY, [f"random_seed: {long}"]), 5002)
    _short(_message(TINY, [f"world: {{obstacles: [{{center: [{', '.join(['1'] * 3000)}]}}]}}"]),
           len(str([1.0] * 3000)))


def test_a_long_path_line_is_cut_short(tmp_path, tiny_scenario, capsys):
    dut = tmp_path / "path.csv"
    dut.write_text("x" * 1_000_000 + "\n")
    with pytest.raises(ScenarioError) as info:
        read_path_csv(dut, tiny_scenario)
    assert len(str(info.value)) < 700 and "xx" not in str(info.value)  # a line that is not the header: not repeated
    assert str(info.value).endswith(" (--path)")
    dut.write_text("x,y,psi1,psi2\n" + "1," * 100_000 + "\n")
    with pytest.raises(ScenarioError) as info:
        read_path_csv(dut, tiny_scenario)
    _short(str(info.value), 200_002)


# ---- --path files: a byte limit of MAX_WAYPOINTS rows, LF/CRLF lines only, a BOM skipped (review item 8)


def test_the_path_byte_limit_follows_the_waypoint_limit(tmp_path, tiny_scenario):
    from drake_social.limits import MAX_WAYPOINTS
    from drake_social.io.textfile import MAX_PATH_FILE_BYTES

    assert MAX_PATH_FILE_BYTES == (MAX_WAYPOINTS + 1) * 256 < 3_000_000
    # the longest rows plan writes (17 significant digits, exponents, signs) fit with room to spare
    row = ",".join(["-1.2345678901234567e-300"] * 4) + "\r\n"
    assert len(row) * (MAX_WAYPOINTS + 1) < MAX_PATH_FILE_BYTES / 2
    dut = tmp_path / "big.csv"
    with open(dut, "wb") as f:
        f.truncate(MAX_PATH_FILE_BYTES + 1)
    with pytest.raises(ScenarioError) as info:
        read_path_csv(dut, tiny_scenario)
    assert str(info.value) == (f"{dut}: {MAX_PATH_FILE_BYTES + 1:,} bytes; a path file may have at most "
                               f"{MAX_PATH_FILE_BYTES:,} bytes (--path)")


@pytest.mark.parametrize("separator", ["\x0c", "\x0b", "\x1c", "\u2028", "\x85"])
def test_only_lf_and_crlf_end_a_path_line(tmp_path, tiny_scenario, separator):
    dut = tmp_path / "path.csv"
    dut.write_text(f"x,y,psi1,psi2\r\n1.0,2.5,0.0,1.5708\r\n{separator}\r\n6.5,2.5,0.0,nan\r\n", newline="")
    with pytest.raises(ScenarioError) as info:
        read_path_csv(dut, tiny_scenario)
    assert str(info.value) == f"{dut}: line 4: psi2: must be a finite number, got 'nan' (--path)"


def test_a_byte_order_mark_is_skipped_and_the_header_error_names_the_option(tmp_path, tiny_scenario):
    dut = tmp_path / "path.csv"
    dut.write_text("\ufeffx,y,psi1,psi2\r\n1.0,2.5,0.0,1.5708\r\n6.5,2.5,0.0,1.5708\r\n", newline="")
    np.testing.assert_array_equal(read_path_csv(dut, tiny_scenario), [[1.0, 2.5, 0.0, 1.5708], [6.5, 2.5, 0.0, 1.5708]])
    dut.write_text("x;y;psi1;psi2\n")
    with pytest.raises(ScenarioError) as info:
        read_path_csv(dut, tiny_scenario)
    assert str(info.value) == (f"{dut}: line 1: the header must be 'x,y,psi1,psi2' (as plan writes it); this is not "
                               f"a path CSV (--path)")


def test_an_alias_error_names_the_aliass_line():
    override = "random_seed: &a 1\nstart: *a"
    assert _message(TINY, [override]) == (f"{TINY} (--set {override!r}): line 2: start: must be a list of numbers, "
                                          f"got '1'")


@pytest.mark.parametrize("time_limit, period", [(270, 0.0045), (9, 0.00015), (37, 37 / 60_000), (600, 0.01)])
def test_exactly_the_most_control_periods_is_accepted(time_limit, period):
    scenario = load_with_overrides(TINY, [f"execution: {{time_limit: {time_limit}, control_period: {period!r}, "
                                          f"plant_time_step: {period!r}}}"])
    assert scenario.execution.control_period == period
    with pytest.raises(ScenarioError, match="a run may take at most 60,000 control periods"):
        load_with_overrides(TINY, [f"execution: {{time_limit: {time_limit}, control_period: {period * 0.999!r}, "
                                   f"plant_time_step: {period * 0.999!r}}}"])


@pytest.mark.parametrize("time_limit, step", [(270, 0.0009), (151, 151 / 300_000), (302, 302 / 300_000)])
def test_exactly_the_most_plant_steps_is_accepted(time_limit, step):
    scenario = load_with_overrides(TINY, [f"execution: {{time_limit: {time_limit}, plant_time_step: {step!r}, "
                                          f"control_period: {min(0.01, time_limit / 100)!r}}}"])
    assert scenario.execution.plant_time_step == step


@pytest.mark.parametrize("escaped, code", [(r"a\0b", "U+0000"), (r"\ud800", "U+D800"), (r"bell\a", "U+0007"),
                                           (r"del\x7f", "U+007F")])
def test_a_control_character_made_by_an_escape_is_refused_like_one_in_the_text(escaped, code):
    # The reader refuses these characters in the file; a quoted scalar's escape
    # makes them all the same (a lone surrogate crashed plan's figures).
    text = f'description: "{escaped}"'
    value = repr(eval(f'"{escaped}"'))
    assert _message(TINY, [text]) == (
        f"{TINY} (--set {shorten(repr(text))}): line 1: description: must be printable text (the characters a "
        f"YAML file may hold), got {code} in {value}")


def test_tabs_line_breaks_and_unicode_in_text_still_load():
    dut = load_with_overrides(TINY, ['description: "caf\\u00e9\\tsmile \\U0001F600\\nsecond line"'])
    assert dut.description == "café\tsmile \U0001F600\nsecond line"


def test_an_unknown_key_with_a_control_character_is_shown_escaped():
    # Printed raw, 'random_\x01seed' reads as the valid field random_seed.
    text = '"random_\\x01seed": 3'
    assert _message(TINY, [text]).startswith(
        f"{TINY} (--set {shorten(repr(text))}): line 1: 'random_\\x01seed': unknown field at the top level; allowed: ")


@pytest.mark.parametrize("override, field, key", [
    ("!!int random_seed: 3", "", "!!int 'random_seed'"),
    ("!Foo random_seed: 3", "", "!Foo 'random_seed'"),
    ("social: {!!binary sigma_h: 1}", "social: ", "!!binary 'sigma_h'"),
    ("? !!null\n: 3", "", "null"),
])
def test_a_field_name_under_a_tag_is_not_called_unknown(override, field, key):
    # It was "random_seed: unknown field ...; allowed: ..., random_seed".
    fields = ("sigma_h, side_ratio, rear_ratio, threshold, weights, length_weight, resolution, speed_scaling" if field
              else "description, world, people, crowd, people_file, people_file_ids, robot, object, start, goal, social, "
                   "planner, execution, random_seed")
    assert _message(TINY, [override]) == (
        f"{TINY} (--set {override!r}): line 1: {field}a key must be a field name ({fields}) as plain text, without "
        f"a tag, got {key}")


# ---- execution: Drake's settings, checked with the scenario (not only when a diagram is built)


@pytest.mark.parametrize("override, message", [
    ("execution: {integration_scheme: foo}",
     "execution.integration_scheme: unknown scheme 'foo'; allowed: bogacki_shampine3, cenic, explicit_euler, "
     "implicit_euler, radau1, radau3, runge_kutta2, runge_kutta3, runge_kutta5, semi_explicit_euler, "
     "velocity_implicit_euler"),
    ("execution: {contact_approximation: bar}",
     "execution.contact_approximation: unknown approximation 'bar'; allowed: tamsi, sap, similar, lagged"),
    ("execution: {accuracy: 0}", "execution.accuracy: must be > 0, got 0.0"),
    ("execution: {accuracy: -1e-3}", "execution.accuracy: must be > 0, got -0.001"),
    ("execution: {accuracy: .nan}", "execution.accuracy: must be a finite number, got nan"),
    ("execution: {target_realtime_rate: -1}",
     "execution.target_realtime_rate: must be >= 0 (0 = as fast as possible), got -1.0"),
    ("execution: {target_realtime_rate: .inf}", "execution.target_realtime_rate: must be a finite number, got inf"),
])
def test_drakes_execution_settings_are_checked_with_the_scenario(override, message):
    assert _message(TINY, [override]) == f"{TINY} (--set {override!r}): {message}"


def test_the_drake_settings_bounds_are_accepted():
    dut = load_scenario(TINY, ["execution: {contact_approximation: lagged, integration_scheme: cenic, "
                               "accuracy: 1e-9, target_realtime_rate: 0}"])
    assert (dut.execution.contact_approximation, dut.execution.integration_scheme) == ("lagged", "cenic")
    assert (dut.execution.accuracy, dut.execution.target_realtime_rate) == (1e-9, 0.0)


def test_the_integration_schemes_are_drakes():
    from pydrake.systems.analysis import GetIntegrationSchemes

    from drake_social.limits import INTEGRATION_SCHEMES

    assert list(INTEGRATION_SCHEMES) == list(GetIntegrationSchemes())


def test_simulate_refuses_an_unknown_integration_scheme_with_exit_2(tmp_path, capsys):
    override = "execution: {integration_scheme: foo}"
    assert main(["simulate", str(TINY), "--set", override, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert f"{TINY} (--set {override!r}): execution.integration_scheme: unknown scheme 'foo'; allowed: " in err
    assert "Traceback" not in err


# ---- the objectives' weights: costs stay finite

ABOVE_1E6 = 1000000.0000000001  # math.nextafter(1e6, inf)


@pytest.mark.parametrize("field, override", [
    ("social.length_weight", "social: {length_weight: %r}"),
    ("planner.replan_length_weight", "planner: {replan_length_weight: %r}"),
    ("social.weights", "social: {weights: [1, 1, 1, 1, %r]}"),
])
def test_objective_weights_are_bounded_at_max_cost_weight(field, override):
    """At MAX_COST_WEIGHT and just below they load; just above and 1e308 (whose costs overflowed to inf,
    so that every path was equally dear) are refused naming the field; -0.0 loads, the smallest negative
    does not."""
    import math

    from drake_social.limits import MAX_COST_WEIGHT

    assert MAX_COST_WEIGHT == 1e6 and math.nextafter(MAX_COST_WEIGHT, math.inf) == ABOVE_1E6
    for fine in (MAX_COST_WEIGHT, math.nextafter(MAX_COST_WEIGHT, 0.0), 0.0):
        load_scenario(TINY, [override % fine])
    for bad in (ABOVE_1E6, 1e308, -5e-324):
        shown = f"[1.0, 1.0, 1.0, 1.0, {bad!r}]" if field == "social.weights" else repr(bad)
        assert _message(TINY, [override % bad]) == (
            f"{TINY} (--set {(override % bad)!r}): {field}: must be in [0, 1e+06], got {shown}")


# ---- the courtesy bounds of the interactive prediction

ABOVE_20 = 20.000000000000004  # math.nextafter(20.0, inf)
ABOVE_1E6 = 1000000.0000000001  # math.nextafter(1e6, inf)


@pytest.mark.parametrize("override, message", [
    ("planner: {courtesy_deceleration: 0}", "planner.courtesy_deceleration: must be in (0, 20] m/s^2, got 0.0"),
    ("planner: {courtesy_deceleration: -1.5}", "planner.courtesy_deceleration: must be in (0, 20] m/s^2, got -1.5"),
    (f"planner: {{courtesy_deceleration: {ABOVE_20!r}}}",
     "planner.courtesy_deceleration: must be in (0, 20] m/s^2, got 20.000000000000004"),
    ("planner: {courtesy_deceleration: .nan}", "planner.courtesy_deceleration: must be finite numbers, got nan"),
    ("planner: {courtesy_deviation: 0}", "planner.courtesy_deviation: must be in (0, 100] metres, got 0.0"),
    ("planner: {courtesy_deviation: 100.00000000000001}",
     "planner.courtesy_deviation: must be in (0, 100] metres, got 100.00000000000001"),
    ("planner: {courtesy_deviation: .inf}", "planner.courtesy_deviation: must be finite numbers, got inf"),
    ("planner: {courtesy_weight: -1e-300}", "planner.courtesy_weight: must be in [0, 1e+06], got -1e-300"),
    (f"planner: {{courtesy_weight: {ABOVE_1E6!r}}}",
     "planner.courtesy_weight: must be in [0, 1e+06], got 1000000.0000000001"),
    ("planner: {prediction: psychic}",
     "planner.prediction: unknown prediction 'psychic'; allowed: constant_velocity, perfect, interactive"),
])
def test_courtesy_settings_beyond_their_bounds_are_refused_naming_the_field(override, message):
    assert _message(TINY, [override]) == f"{TINY} (--set {override!r}): {message}"


def test_courtesy_settings_at_and_just_within_their_bounds_load():
    import math

    dut = load_scenario(TINY, ["planner: {prediction: interactive, courtesy_deceleration: 20, courtesy_deviation: 100, "
                               "courtesy_weight: 1e6}"])
    p = dut.planner
    assert (p.prediction, p.courtesy_deceleration, p.courtesy_deviation, p.courtesy_weight) == \
        ("interactive", 20.0, 100.0, 1e6)
    tiny = math.nextafter(0.0, 1.0)
    dut = load_scenario(TINY, [f"planner: {{courtesy_deceleration: {tiny!r}, courtesy_deviation: {tiny!r}, "
                               "courtesy_weight: 0}"])
    assert (dut.planner.courtesy_deceleration, dut.planner.courtesy_deviation, dut.planner.courtesy_weight) == \
        (tiny, tiny, 0.0)
