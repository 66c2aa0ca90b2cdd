"""Scenario schema: the shipped files load, bad input names its file and field."""

from __future__ import annotations

import dataclasses as dc
import math
import re
from pathlib import Path

import pytest

from drake_social.scenario import (
    ALGORITHMS,
    Bar,
    LShape,
    Polyline,
    Scenario,
    ScenarioError,
    load_scenario,
    validate_scenario,
)

# A small valid scenario, one YAML value per top-level key, so that each bad
# case below replaces exactly one entry and nothing else can be at fault.
GOOD = {
    "description": '"unit-test room"',
    "world": "{bounds: [0.0, 0.0, 8.0, 5.0], obstacles: [{center: [4.0, 0.6], size: [1.6, 0.8], yaw: 0.3}]}",
    "people": "[{x: 4.0, y: 3.8, theta: -1.5708, radius: 0.25, name: p0}, {x: 6.0, y: 1.5, theta: 2.4}]",
    "robot": "{base_radius: 0.35, link_lengths: [0.6, 0.5], link_width: 0.08,"
    " joint_lower: [-3.1416, -3.1416], joint_upper: [3.1416, 3.1416]}",
    "object": "!Bar {length: 1.5, thickness: 0.05}",
    "start": "[1.0, 2.5, 0.0, 1.5708]",
    "goal": "[7.0, 2.5, 0.0, 1.5708]",
    "social": "{sigma_h: 2.0, threshold: 0.2, weights: [1, 1, 1, 1, 1], length_weight: 0.0}",
    "planner": "{algorithm: social_rrt_star, iterations: 100}",
    "random_seed": "3",
}


def write_scenario(directory: Path, name: str = "case.yaml", **replace: str) -> Path:
    """Writes GOOD with some top-level entries replaced (None = dropped)."""
    entries = {**GOOD, **replace}
    text = "".join(f"{key}: {value}\n" for key, value in entries.items() if value is not None)
    path = directory / name
    path.write_text(text)
    return path


def expect_error(path: Path, *fragments: str, overrides: str | None = None) -> str:
    """Loads ``path``, expects a ScenarioError naming the file and every fragment."""
    with pytest.raises(ScenarioError) as info:
        load_scenario(path, overrides)
    message = str(info.value)
    assert str(path) in message, message
    for fragment in fragments:
        assert fragment in message, f"{fragment!r} not in {message!r}"
    return message


# ---- values that must load (the shipped files: tests/test_scenario_files.py) ----


def test_tiny_scenario_values(tiny_scenario):
    dut = tiny_scenario
    assert dut.world.bounds == [0.0, 0.0, 8.0, 5.0]
    assert len(dut.people) == 1
    assert dut.people[0].theta == pytest.approx(-math.pi / 2, abs=1e-4)
    assert isinstance(dut.object, Bar) and dut.object.length == pytest.approx(1.5)
    assert dut.start == pytest.approx([1.0, 2.5, 0.0, math.pi / 2], abs=1e-4)
    assert dut.planner.iterations == 300
    assert dut.random_seed == 1
    # Fields the file leaves out keep the paper's defaults.
    assert dut.social.sigma_h == 2.0
    assert dut.social.side_ratio == pytest.approx(2 / 3)
    assert dut.social.rear_ratio == 0.5
    assert dut.social.threshold == 0.2
    assert dut.social.weights is None


def test_good_case_loads_with_every_value(tmp_path):
    dut = load_scenario(write_scenario(tmp_path))
    assert dut.world.obstacles[0].yaw == pytest.approx(0.3)
    assert [p.name for p in dut.people] == ["p0", ""]
    assert dut.people[1].theta == pytest.approx(2.4)
    assert dut.robot.joint_upper == pytest.approx([3.1416, 3.1416])
    assert dut.social.weights == [1, 1, 1, 1, 1]
    assert dut.random_seed == 3


@pytest.mark.parametrize(
    "object_yaml, kind, n_weights",
    [
        ("!Bar {length: 2.0, thickness: 0.04}", Bar, 5),
        ("!LShape {lengths: [3.0, 2.0], thickness: 0.05}", LShape, 6),
        ("!Polyline {points: [[0, -1], [0, 1], [1, 1], [1, 0]], thickness: 0.05}", Polyline, 5),
        ("!Bar {length: 2.0, interest_points: [[0, -1], [0, 0], [0, 1]]}", Bar, 6),
    ],
)
def test_object_kinds_and_their_weight_count(tmp_path, object_yaml, kind, n_weights):
    ok = "{weights: [%s]}" % ", ".join(["1"] * n_weights)
    dut = load_scenario(write_scenario(tmp_path, object=object_yaml, social=ok))
    assert isinstance(dut.object, kind)
    assert len(dut.social.weights) == n_weights
    bad = "{weights: [%s]}" % ", ".join(["1"] * (n_weights - 1))
    expect_error(write_scenario(tmp_path, object=object_yaml, social=bad), "social.weights", str(n_weights))


@pytest.mark.parametrize(
    "field, broken",
    [
        ("social.side_ratio", lambda s: dc.replace(s, social=dc.replace(s.social, side_ratio=0.0))),
        ("social.rear_ratio", lambda s: dc.replace(s, social=dc.replace(s.social, rear_ratio=math.nan))),
        ("planner.collision_resolution",
         lambda s: dc.replace(s, planner=dc.replace(s.planner, collision_resolution=-0.05))),
        ("robot.joint_lower", lambda s: dc.replace(s, robot=dc.replace(s.robot, joint_lower=[math.nan, -math.pi]))),
    ],
    ids=["side_ratio", "rear_ratio", "collision_resolution", "joint_lower"],
)
def test_the_default_scenario_is_valid_until_one_field_breaks(field, broken):
    """The dataclass defaults (the paper's values) pass validate_scenario as
    they are, and the same check refuses them once one field is made bad, so
    the first call is not vacuous."""
    dut = Scenario()
    assert validate_scenario(dut, source="defaults") is None
    assert (dut.social.side_ratio, dut.social.rear_ratio) == (pytest.approx(2 / 3), 0.5)
    assert dut.planner.collision_resolution == 0.05
    with pytest.raises(ScenarioError, match=rf"^defaults: {re.escape(field)}: must be"):
        validate_scenario(broken(dut), source="defaults")
    assert validate_scenario(dut) is None  # dc.replace left the defaults alone


# ---- every kind of bad input --------------------------------------------------

BAD_VALUES = [
    # negative or zero sizes
    ("neg_base", {"robot": "{base_radius: -0.35}"}, ["robot.base_radius", "> 0"]),
    ("neg_link", {"robot": "{link_lengths: [0.6, -0.5]}"}, ["robot.link_lengths", "> 0"]),
    ("zero_width", {"robot": "{link_width: 0.0}"}, ["robot.link_width", "> 0"]),
    ("neg_obstacle", {"world": "{bounds: [0, 0, 8, 5], obstacles: [{center: [4, 1], size: [-1, 1]}]}"},
     ["world.obstacles[0].size", "> 0"]),
    ("neg_wall", {"world": "{bounds: [0, 0, 8, 5], wall_thickness: -0.1}"}, ["world.wall_thickness"]),
    ("neg_person", {"people": "[{x: 4, y: 3, radius: -0.2}]"}, ["people[0].radius", "> 0"]),
    ("neg_bar", {"object": "!Bar {length: -1.5}"}, ["object.length", "> 0"]),
    ("zero_thickness", {"object": "!Bar {length: 1.5, thickness: 0}"}, ["object.thickness", "> 0"]),
    ("neg_L", {"object": "!LShape {lengths: [3.0, -2.0]}"}, ["object.lengths", "> 0"]),
    ("neg_sigma", {"social": "{sigma_h: -2.0}"}, ["social.sigma_h", "> 0"]),
    ("neg_resolution", {"social": "{resolution: 0.0}"}, ["social.resolution", "> 0"]),
    ("neg_lambda", {"social": "{length_weight: -1.0}"}, ["social.length_weight", "in [0, 1e+06]"]),
    ("neg_range", {"planner": "{planning_range: -1.0}"}, ["planner.planning_range", "> 0"]),
    ("neg_near", {"planner": "{near_radius: 0.0}"}, ["planner.near_radius", "> 0"]),
    ("zero_dist_w", {"planner": "{distance_weights: [1, 1, 0, 1]}"}, ["planner.distance_weights"]),
    ("zero_side", {"social": "{side_ratio: 0.0}"}, ["social.side_ratio", "> 0"]),
    ("neg_side", {"social": "{side_ratio: -0.5}"}, ["social.side_ratio", "> 0"]),
    ("zero_rear", {"social": "{rear_ratio: 0.0}"}, ["social.rear_ratio", "> 0"]),
    ("neg_rear", {"social": "{rear_ratio: -0.5}"}, ["social.rear_ratio", "> 0"]),
    ("zero_coll_res", {"planner": "{collision_resolution: 0.0}"}, ["planner.collision_resolution", "> 0"]),
    ("neg_coll_res", {"planner": "{collision_resolution: -0.05}"}, ["planner.collision_resolution", "> 0"]),
    # NaN (YAML .nan) and infinity
    ("nan_base", {"robot": "{base_radius: .nan}"}, ["robot.base_radius", "finite"]),
    ("nan_theta", {"people": "[{x: 4, y: 3, theta: .nan}]"}, ["people[0]", "finite"]),
    ("nan_start", {"start": "[1.0, .nan, 0.0, 0.0]"}, ["start", "finite"]),
    ("inf_goal", {"goal": "[.inf, 2.5, 0.0, 0.0]"}, ["goal", "finite"]),
    ("nan_bounds", {"world": "{bounds: [0, 0, .nan, 5]}"}, ["world.bounds", "finite"]),
    ("nan_yaw", {"world": "{bounds: [0, 0, 8, 5], obstacles: [{center: [4, 1], size: [1, 1], yaw: .nan}]}"},
     ["world.obstacles[0].yaw", "finite"]),
    ("nan_sigma", {"social": "{sigma_h: .nan}"}, ["social.sigma_h", "finite"]),
    ("nan_threshold", {"social": "{threshold: .nan}"}, ["social.threshold", "finite"]),
    ("nan_weight", {"social": "{weights: [1, 1, .nan, 1, 1]}"}, ["social.weights", "finite"]),
    ("nan_bias", {"planner": "{goal_bias: .nan}"}, ["planner.goal_bias", "finite"]),
    ("nan_side", {"social": "{side_ratio: .nan}"}, ["social.side_ratio", "finite"]),
    ("inf_rear", {"social": "{rear_ratio: .inf}"}, ["social.rear_ratio", "finite"]),
    ("nan_coll_res", {"planner": "{collision_resolution: .nan}"}, ["planner.collision_resolution", "finite"]),
    # NaN compares false both ways, so only the finiteness check can refuse it
    # (start and goal keep psi = 0 inside the remaining limit).
    ("nan_lower", {"robot": "{joint_lower: [.nan, -3.1416]}", "start": "[1.0, 2.5, 0.0, 0.0]",
                   "goal": "[7.0, 2.5, 0.0, 0.0]"}, ["robot.joint_lower", "finite"]),
    ("nan_upper", {"robot": "{joint_upper: [3.1416, .nan]}", "start": "[1.0, 2.5, 0.0, 0.0]",
                   "goal": "[7.0, 2.5, 0.0, 0.0]"}, ["robot.joint_upper", "finite"]),
    ("inf_lower", {"robot": "{joint_lower: [-.inf, -3.1416]}"}, ["robot.joint_lower", "finite"]),
    ("nan_interest", {"object": "!Bar {length: 1.5, interest_points: [[0, .nan]]}"},
     ["object.interest_points[0]", "finite"]),
    # outside the bounds
    ("person_out", {"people": "[{x: 4, y: 3}, {x: 9.5, y: 2.0}]"}, ["people[1]", "outside world.bounds"]),
    ("person_below", {"people": "[{x: 4, y: -0.1}]"}, ["people[0]", "outside world.bounds"]),
    ("start_out", {"start": "[-0.5, 2.5, 0.0, 0.0]"}, ["start", "outside world.bounds"]),
    ("goal_out", {"goal": "[7.0, 5.2, 0.0, 0.0]"}, ["goal", "outside world.bounds"]),
    ("empty_bounds", {"world": "{bounds: [8, 0, 0, 5]}"}, ["world.bounds", "max > min"]),
    # wrong-length vectors
    ("start_3", {"start": "[1.0, 2.5, 0.0]"}, ["start", "4 values"]),
    ("goal_5", {"goal": "[7.0, 2.5, 0.0, 0.0, 0.0]"}, ["goal", "4 values"]),
    ("bounds_3", {"world": "{bounds: [0, 0, 8]}"}, ["world.bounds", "4 values"]),
    ("center_3", {"world": "{bounds: [0, 0, 8, 5], obstacles: [{center: [4, 1, 0], size: [1, 1]}]}"},
     ["world.obstacles[0].center", "2 values"]),
    ("size_1", {"world": "{bounds: [0, 0, 8, 5], obstacles: [{center: [4, 1], size: [1]}]}"},
     ["world.obstacles[0].size", "2 values"]),
    ("links_3", {"robot": "{link_lengths: [0.6, 0.5, 0.4]}"}, ["robot.link_lengths", "2 values"]),
    ("lower_1", {"robot": "{joint_lower: [-3.0]}"}, ["robot.joint_lower", "2 values"]),
    ("L_1", {"object": "!LShape {lengths: [3.0]}"}, ["object.lengths", "2 values"]),
    ("poly_1", {"object": "!Polyline {points: [[0, 0]]}"}, ["object.points", "at least 2"]),
    ("poly_point_3", {"object": "!Polyline {points: [[0, 0], [1, 0, 0]]}"}, ["object.points[1]", "2 values"]),
    ("dist_w_3", {"planner": "{distance_weights: [1, 1, 1]}"}, ["planner.distance_weights", "4 values"]),
    # weights of the wrong length / sign (the bar has 5 interest points)
    ("weights_4", {"social": "{weights: [1, 1, 1, 1]}"}, ["social.weights", "5 values"]),
    ("weights_6", {"social": "{weights: [1, 1, 1, 1, 1, 1]}"}, ["social.weights", "5 values"]),
    ("weights_neg", {"social": "{weights: [1, -1, 1, 1, 1]}"}, ["social.weights", "in [0, 1e+06]"]),
    # joints out of range
    ("start_psi1", {"start": "[1.0, 2.5, 3.5, 0.0]"}, ["start[2]", "psi1", "joint range"]),
    ("goal_psi2", {"goal": "[7.0, 2.5, 0.0, -4.0]"}, ["goal[3]", "psi2", "joint range"]),
    ("narrow_range", {"robot": "{joint_lower: [-1.0, -1.0], joint_upper: [1.0, 1.0]}",
                      "start": "[1.0, 2.5, 0.0, 1.5]"}, ["start[3]", "[-1.0, 1.0]"]),
    ("upper_le_lower", {"robot": "{joint_lower: [0.0, 0.0], joint_upper: [0.0, 1.0]}"}, ["robot.joint_upper"]),
    # unknown names and other out-of-range options
    ("algorithm", {"planner": "{algorithm: rrt_sharp}"}, ["planner.algorithm", "rrt_sharp", *ALGORITHMS]),
    ("informed_mode", {"planner": "{informed_mode: fancy}"}, ["planner.informed_mode", "paper", "admissible"]),
    ("admissible_no_lambda", {"planner": "{algorithm: informed_social_rrt_star, informed_mode: admissible}"},
     ["planner.informed_mode", "length_weight"]),
    ("iterations", {"planner": "{iterations: 0}"}, ["planner.iterations", "must be in [1, 10000000]"]),
    ("goal_bias", {"planner": "{goal_bias: 1.0}"}, ["planner.goal_bias", "[0, 1)"]),
    ("threshold", {"social": "{threshold: 1.0}"}, ["social.threshold", "[0, 1)"]),
    ("seed", {"random_seed": "-1"}, ["random_seed", ">= 0"]),
]


@pytest.mark.parametrize("replace, fragments", [c[1:] for c in BAD_VALUES], ids=[c[0] for c in BAD_VALUES])
def test_bad_value_raises_scenario_error_naming_the_field(tmp_path, replace, fragments):
    expect_error(write_scenario(tmp_path, **replace), *fragments)


BAD_SCHEMA = [
    ("top_level_key", {"colour": "red"}, ["colour", "unknown"]),
    ("nested_key", {"planner": "{algorithm: rrt_star, iteratoins: 10}"}, ["iteratoins", "unknown"]),
    ("person_key", {"people": "[{x: 4, y: 3, heading: 1.0}]"}, ["heading", "unknown"]),
    ("object_key", {"object": "!Bar {length: 1.5, width: 0.1}"}, ["width", "unknown"]),
    ("unknown_tag", {"object": "!Disc {radius: 1.0}"}, ["Disc"]),
    ("wrong_type", {"planner": "{iterations: 3.5}"}, ["iterations"]),
    # pydrake names the value, not the field, for a string in a float field.
    ("string_for_float", {"robot": "{base_radius: big}"}, ["'big'"]),
]


@pytest.mark.parametrize("replace, fragments", [c[1:] for c in BAD_SCHEMA], ids=[c[0] for c in BAD_SCHEMA])
def test_unknown_keys_and_types_are_errors_naming_the_file(tmp_path, replace, fragments):
    """yaml_load_typed rejects them; load_scenario adds the file name."""
    expect_error(write_scenario(tmp_path, **replace), *fragments)


def test_malformed_yaml_names_the_file(tmp_path):
    path = tmp_path / "broken.yaml"
    path.write_text("world: {bounds: [0, 0, 8, 5]\nstart: [1, 2")
    expect_error(path)


def test_missing_file_is_a_scenario_error(tmp_path):
    expect_error(tmp_path / "nowhere.yaml", "no such scenario file")


def test_validate_scenario_names_its_source():
    dut = Scenario(start=[1.0, 1.0, 0.0])
    with pytest.raises(ScenarioError, match=r"^my-source: start: must have 4 values"):
        validate_scenario(dut, source="my-source")


# ---- overrides ------------------------------------------------------------------


def test_overrides_replace_seed_and_weights_and_keep_the_rest(tmp_path):
    path = write_scenario(tmp_path)
    base = load_scenario(path)
    dut = load_scenario(path, "random_seed: 42\nsocial: {weights: [1, 0, 0, 0, 0]}")
    assert (base.random_seed, dut.random_seed) == (3, 42)
    assert dut.social.weights == [1, 0, 0, 0, 0]
    # Fields the overrides leave out, nested ones included, stay as in the file.
    assert dut.social.sigma_h == base.social.sigma_h == 2.0
    assert dut.social.threshold == base.social.threshold
    assert dut.planner.iterations == base.planner.iterations == 100
    assert dut.people == base.people
    assert dut.start == base.start
    # Loading with overrides does not leak into a later load of the same file.
    assert load_scenario(path).random_seed == 3


def test_overrides_can_replace_lists_and_the_object(tmp_path):
    path = write_scenario(tmp_path)
    dut = load_scenario(
        path,
        "people: [{x: 1.0, y: 1.0, theta: 0.5}]\n"
        "object: !LShape {lengths: [3.0, 2.0]}\n"
        "social: {weights: [1, 1, 1, 2, 2, 2]}",
    )
    assert len(dut.people) == 1 and dut.people[0].theta == 0.5
    assert isinstance(dut.object, LShape)
    assert dut.social.weights == [1, 1, 1, 2, 2, 2]


@pytest.mark.parametrize(
    "overrides, fragments",
    [
        ("random_sed: 4", ["(overrides", "random_sed"]),
        ("planner: {algoritm: rrt_star}", ["(overrides", "algoritm"]),
        ("random_seed: [1, 2", ["(overrides"]),
        ("random_seed: 1.5", ["(overrides", "random_seed"]),
    ],
)
def test_bad_override_is_named_as_such(tmp_path, overrides, fragments):
    message = expect_error(write_scenario(tmp_path), *fragments, overrides=overrides)
    assert message.startswith(f"{tmp_path / 'case.yaml'} (overrides {overrides!r}): ")


@pytest.mark.parametrize(
    "overrides, fragments",
    [
        ("social: {weights: [1, 0, 0]}", ["social.weights", "5 values"]),
        ("planner: {algorithm: astar}", ["planner.algorithm", "astar"]),
        ("start: [1.0, 2.5, 0.0, 9.0]", ["start[3]", "joint range"]),
        ("random_seed: -5", ["random_seed"]),
    ],
)
def test_overridden_values_are_validated(tmp_path, overrides, fragments):
    expect_error(write_scenario(tmp_path), *fragments, overrides=overrides)


# ---- the package's parts -----------------------------------------------------------------


def test_the_package_re_exports_each_name_from_its_one_home():
    """Each public name is defined (assigned, a def or a class) in exactly one
    of the package's modules, limits.py or errors.py, and the package gives that object."""
    import ast
    import importlib

    import drake_social.scenario as dut

    homes = ["drake_social.scenario.schema", "drake_social.scenario.load", "drake_social.scenario.validate",
             "drake_social.limits", "drake_social.errors"]
    defined: dict[str, list[str]] = {}
    for home in homes:
        module = importlib.import_module(home)
        for node in ast.parse(Path(module.__file__).read_text()).body:
            names = ([t.id for t in node.targets if isinstance(t, ast.Name)] if isinstance(node, ast.Assign) else
                     [node.name] if isinstance(node, (ast.FunctionDef, ast.ClassDef)) else [])
            for name in names:
                defined.setdefault(name, []).append(home)
    for name in dut.__all__:
        assert len(defined.get(name, [])) == 1, (name, defined.get(name))
        assert getattr(dut, name) is getattr(importlib.import_module(defined[name][0]), name)


@pytest.mark.parametrize("obj, vertices, interest", [
    (Bar(length=2.0), [[0, -1], [0, 1]], [[0, -1], [0, 1]]),
    (LShape(lengths=[3.0, 2.0]), [[0, -1.5], [0, 1.5], [2, 1.5]], [[0, -1.5], [0, 1.5], [2, 1.5]]),
    (Polyline(points=[[0, 0], [1, 0], [1, 1], [0.5, 2]]), [[0, 0], [1, 0], [1, 1], [0.5, 2]], [[0, 0], [0.5, 2]]),
])
def test_each_object_type_knows_its_vertices_and_default_interest_points(obj, vertices, interest):
    import numpy as np

    from drake_social.scenario import interest_point_count

    np.testing.assert_array_equal(obj.polyline(), vertices)
    np.testing.assert_array_equal(obj.default_interest_points(), interest)
    assert interest_point_count(obj) == len(interest)
    assert interest_point_count(dc.replace(obj, interest_points=[[0.0, 0.0]] * 5)) == 5
