"""Each bad person of a scenario is refused at load, naming the file, the field and the rule."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from drake_social.scenario.geometry import arm_geometry
from drake_social.people.proximity import part_distances
from drake_social.scenario import ScenarioError, load_scenario
from drake_social.scenario.people_rules import robot_clearance, segment_box_distance

TINY = Path(__file__).resolve().parents[2] / "scenarios" / "tiny.yaml"
PEOPLE = 'people:\n  - {x: 4.0, y: 3.8, theta: -1.5708, radius: 0.25, name: "standing"}  # faces south'
SEG0 = "segment 0 (from point 0 {a} to point 1 {b}, [t, x, y])"


def _load(tmp_path: Path, person: str):
    text = TINY.read_text()
    assert text.count(PEOPLE) == 1
    path = tmp_path / "bad.yaml"
    path.write_text(text.replace(PEOPLE, f"people:\n  - {person}"))
    return path


def _message(tmp_path: Path, person: str) -> str:
    path = _load(tmp_path, person)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ")
    return message[len(str(path)) + 2:]


@pytest.mark.parametrize("person, message", [
    ("{trajectory: [[0, 6, 4]]}", "people[0].trajectory: needs at least 2 points [t, x, y], got 1"),
    ("{trajectory: [[0, 6, 4], [1, 6]]}",
     "people[0].trajectory[1]: must be [t, x, y] (seconds, metres, metres), got [1.0, 6.0]"),
    ("{trajectory: [[0, 6, 4], [.nan, 6, 3]]}", "people[0].trajectory[1]: must be finite numbers, got [nan, 6.0, 3.0]"),
    ("{trajectory: [[0, 6, 4], [1, .inf, 3]]}", "people[0].trajectory[1]: must be finite numbers, got [1.0, inf, 3.0]"),
    ("{trajectory: [[-1, 6, 4], [1, 6, 3]]}", "people[0].trajectory[0]: time t must be >= 0 seconds, got -1"),
    ("{trajectory: [[0, 6, 4], [2, 6, 3], [2, 6, 2]]}",
     "people[0].trajectory[2]: time t must be > 2, the time of point 1 (times strictly increasing), got 2"),
    ("{trajectory: [[0, 6, 4], [2, 6, 3], [1, 6, 2]]}",
     "people[0].trajectory[2]: time t must be > 2, the time of point 1 (times strictly increasing), got 1"),
    ("{x: 5, y: 4, trajectory: [[0, 6, 4], [1, 6, 3]]}",
     "people[0]: x, y (5, 4) must be left out (0, 0) or equal the trajectory's first point (6, 4): the person "
     "starts there"),
    ("{trajectory: [[0, 6, 4], [1, 6, 3]], loop: true}",
     "people[0].loop: needs a closed route: the trajectory's last point (6, 3) must be its first (6, 4)"),
    ("{x: 6, y: 4, loop: true}", "people[0].loop: needs a trajectory (a person without one stands still)"),
    # A 1 m square at 3.3 m/s: each quarter turn needs 0.5 s, each side lasts 0.3 s.
    ("{trajectory: [[0, 5, 3], [0.3, 6, 3], [0.6, 6, 4], [0.9, 5, 4], [1.2, 5, 3]], loop: true}",
     "people[0].loop: the heading of the looping route does not repeat within 8 periods: every turn (at 3.14 "
     "rad/s) is cut short by the next segment; make the segments longer"),
    ("{trajectory: [[0, 2.5, 1.5], [4, 6, 0.5]]}",
     "people[0].trajectory: " + SEG0.format(a="(0, 2.5, 1.5)", b="(4, 6, 0.5)") + " passes through "
     "world.obstacles[0] (the body's centre comes 0 m from it, closer than its radius 0.25 m)"),
    ("{trajectory: [[0, 6, 4], [3, 6, 1.2], [6, 2.5, 1.2]]}",  # 0.2 m above the desk's top edge (y = 1)
     "people[0].trajectory: segment 1 (from point 1 (3, 6, 1.2) to point 2 (6, 2.5, 1.2), [t, x, y]) passes "
     "through world.obstacles[0] (the body's centre comes 0.2 m from it, closer than its radius 0.25 m)"),
    ("{trajectory: [[0, 6, 4], [1, 7.9, 4]]}",
     "people[0].trajectory: " + SEG0.format(a="(0, 6, 4)", b="(1, 7.9, 4)") + " takes the body (radius 0.25 m) "
     "out of world.bounds [0.0, 0.0, 8.0, 5.0] into the walls; the whole body must stay inside"),
    ("{x: 4, y: 1.1}",
     "people[0]: the position (4, 1.1) puts the body (radius 0.25 m) inside world.obstacles[0] (its centre is "
     "0.1 m from the box); a person must start clear of the obstacles"),
    ("{x: 0.5, y: 2.5}",
     "people[0]: the position (0.5, 2.5) puts the body (radius 0.25 m) into the robot's base at its start "
     "configuration [1.0, 2.5, 0.0, 1.5708] (overlap 0.1 m); a person must start clear of the robot"),
    ("{trajectory: [[0, 0.5, 2.5], [5, 0.5, 4.5]]}",
     "people[0].trajectory[0]: the first point (0.5, 2.5) puts the body (radius 0.25 m) into the robot's base at "
     "its start configuration [1.0, 2.5, 0.0, 1.5708] (overlap 0.1 m); a person must start clear of the robot"),
])
def test_each_bad_person_is_refused_naming_the_field(tmp_path, person, message):
    assert _message(tmp_path, person) == message


def test_good_walkers_load(tmp_path):
    # 0.3 m above the desk (clear of a 0.25 m body), a closed loop, x/y equal to the first point.
    for person in ("{trajectory: [[0, 6, 4], [3, 6, 1.3], [6, 2.5, 1.3]]}",
                   "{x: 6, y: 4, trajectory: [[0, 6, 4], [2, 6, 3], [4, 7, 3], [6, 6, 4]], loop: true}"):
        path = _load(tmp_path, person)
        assert load_scenario(path).people[0].trajectory[0] == [0.0, 6.0, 4.0]


def test_segment_box_distance_matches_dense_sampling():
    rng = np.random.default_rng(5)
    for _ in range(100):
        a = rng.uniform(-3, 3, 2)
        b = a if rng.uniform() < 0.2 else rng.uniform(-3, 3, 2)  # a point, or a segment
        centres, sizes, yaws = rng.uniform(-1, 1, (4, 2)), rng.uniform(0.2, 2, (4, 2)), rng.uniform(-4, 4, 4)
        yaws[0] = 0.0
        sizes[1, 0] = 1e-3  # a thin wall
        dut = segment_box_distance(a, b, centres, sizes, yaws)
        pts = a + np.linspace(0, 1, 4001)[:, None] * (b - a)
        for k in range(4):
            c, s = math.cos(yaws[k]), math.sin(yaws[k])
            local = (pts - centres[k]) @ np.array([[c, -s], [s, c]])  # rows R^T (p - c)
            d = np.hypot(*np.maximum(np.abs(local) - sizes[k] / 2, 0).T).min()
            assert dut[k] == pytest.approx(d, abs=2e-3 * np.hypot(*(b - a)) + 1e-12)
    # Crossing a box without an end inside it, and an axis-parallel segment beside one, by hand.
    assert segment_box_distance([-2, 0], [2, 0.5], [[0, 0]], [[1, 1]], [0.0])[0] == 0.0
    assert segment_box_distance([-2, 0.8], [2, 0.8], [[0, 0]], [[1, 1]], [0.0])[0] == pytest.approx(0.3)
    assert segment_box_distance([0, 2], [0, 2], [[0, 0]], [[1, 1]], [math.pi / 4])[0] == \
        pytest.approx(2 - math.sqrt(0.5))


def test_robot_clearance_is_the_proximity_modules_robot_distance():
    from drake_social.scenario import Scenario
    geometry = arm_geometry(Scenario())
    rng = np.random.default_rng(7)
    for _ in range(50):
        q = np.concatenate([rng.uniform(0, 3, 2), rng.uniform(-math.pi, math.pi, 2)])
        centres, radii = rng.uniform(-1, 4, (5, 2)), rng.uniform(0.1, 0.4, 5)
        values, parts = robot_clearance(geometry, q, centres, radii)
        for k in range(5):
            d = part_distances(geometry, q[None], centres[k][None], radii[k:k + 1])
            assert values[k] == pytest.approx(d["robot"][0], abs=1e-12)
            assert d[parts[k]][0] == pytest.approx(values[k], abs=1e-12)


def test_starts_checked_in_batches_still_name_the_person_inside_a_box(tiny_scenario_path, monkeypatch):
    from drake_social.scenario import people_rules

    monkeypatch.setattr(people_rules, "_SEGMENT_BATCH", 2)  # one start per batch
    people = ", ".join(f"{{x: {1.0 + 0.7 * i}, y: 4.3}}" for i in range(4)) + ", {x: 4.0, y: 0.9}"
    with pytest.raises(ScenarioError, match=r"people\[4\]: the position \(4, 0.9\) puts the body .* inside "
                                            r"world.obstacles\[0\]"):
        load_scenario(tiny_scenario_path, [f"people: [{people}]"])
