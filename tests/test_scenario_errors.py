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
                             "(Person: x, y, theta, radius, name), got null")


def test_people_as_a_mapping(tmp_path):
    dut = _bad(tmp_path, PEOPLE, "people: {x: 4.0, y: 3.8}")
    assert _message(dut) == (f"{dut}: line 7: people: must be a list of mappings "
                             "(Person: x, y, theta, radius, name), got a mapping")


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
