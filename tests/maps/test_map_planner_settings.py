"""``map scenario`` sizes the planner to the map and says how much room the
robot with its bar has at the start and the goal (drake_social/map_tools.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_social.cli import main
from drake_social.collision.geometric import GeometricChecker
from drake_social.map_tools import (CARRYING_ARM, MAP_ITERATIONS_MAX, MAP_ITERATIONS_MIN, MAP_ITERATIONS_PER_M2, MAP_LARGE_SIDE,
                                    MAP_RANGE_LARGE, MAP_RANGE_SMALL, MAP_TIGHT_ROOM, map_planner_settings,
                                    write_map_scenario)
from drake_social.maps import office_floor_layout, write_map
from drake_social.scenario import load_scenario

from maps.test_map_scenario import RESOLUTION, room_image


def test_the_documented_rule_and_its_constants():
    assert (MAP_ITERATIONS_PER_M2, MAP_ITERATIONS_MIN, MAP_ITERATIONS_MAX) == (8.0, 2000, 100_000)
    assert (MAP_LARGE_SIDE, MAP_RANGE_SMALL, MAP_RANGE_LARGE, MAP_TIGHT_ROOM) == (25.0, 1.5, 2.5, 0.1)
    # 30 x 50 m: 8 x 1500 = 12,000 samples, the 2.5 m range, near radius 3.5 m.
    assert map_planner_settings([0, 0, 30, 50]) == {"iterations": 12000, "planning_range": 2.5, "near_radius": 3.5}
    assert map_planner_settings([-5, 2, 15, 16]) == {"iterations": 3000, "planning_range": 1.5, "near_radius": 2.5}


@pytest.mark.parametrize("side, reach", [(24.99, MAP_RANGE_SMALL), (25.0, MAP_RANGE_SMALL),
                                         (25.01, MAP_RANGE_LARGE)])
def test_the_range_changes_past_the_large_side(side, reach):
    for extent in ([0, 0, side, 10], [0, 0, 10, side]):
        dut = map_planner_settings(extent)
        assert (dut["planning_range"], dut["near_radius"]) == (reach, reach + 1.0)


@pytest.mark.parametrize("area, k", [
    (250.0, MAP_ITERATIONS_MIN),        # 2,000 exactly: the least
    (125.0, MAP_ITERATIONS_MIN),        # 1,000: raised to the least
    (375.0, 3000),                      # 3,000 exactly
    (375.0 + 1e-3, 4000),               # just above: rounded up to a thousand
    (375.0 - 1e-3, 3000),
    (12_500.0, MAP_ITERATIONS_MAX),     # 100,000 exactly: the most
    (12_500.0 + 200, MAP_ITERATIONS_MAX),  # above: capped
])
def test_the_samples_are_eight_per_square_metre_rounded_up_within_the_bounds(area, k):
    side = math.sqrt(area)
    assert map_planner_settings([0, 0, side, side])["iterations"] == k
    assert map_planner_settings([3, -1, 3 + area / 10, 9])["iterations"] == k


@pytest.fixture
def room_map(tmp_path):
    return write_map(tmp_path, "room", room_image(), RESOLUTION, (1.0, -2.0, 0.0))


def test_the_scenario_holds_the_settings_and_the_room_is_measured(room_map, tmp_path, capsys):
    out = tmp_path / "s.yaml"
    assert main(["map", "scenario", str(room_map), "--start", "2.5", "0", "--goal", "9", "0", "--out", str(out)]) == 0
    printed = capsys.readouterr().out.splitlines()
    scenario = load_scenario(out)
    # The room is 10 x 6 m: 480 samples' worth, so the least K and the paper's range.
    assert (scenario.planner.iterations, scenario.planner.planning_range, scenario.planner.near_radius) == (
        2000, 1.5, 2.5)
    assert printed[1] == ("  planner   K = 2,000, planning range 1.5 m, near radius 2.5 m: sized to the map's "
                          "10 x 6 m (docs/maps.md)")
    # The room at each end against the pure-numpy checker's clearance (an independent computation).
    reference = GeometricChecker(scenario)
    for line, q in zip(printed[2:4], (scenario.start, scenario.goal)):
        shown = float(line.split(" at the ")[1].split()[1])
        assert shown == pytest.approx(reference.clearance(np.asarray(q, float)), abs=0.005)
    written = write_map_scenario(room_map, tmp_path / "t.yaml", (2.5, 0.0), (9.0, 0.0))
    for room, q in ((written.start, scenario.start), (written.goal, scenario.goal)):
        assert room.clearance == pytest.approx(reference.clearance(np.asarray(q, float)), abs=1e-9)
        assert room.part in ("base", "link1", "link2", "object")
    # What is nearest is named: a wall of the room or a box of the map with its cells.
    for room in (written.start, written.goal):
        assert room.other.startswith("wall_") or " image rows " in room.other


def test_little_room_is_pointed_out(room_map, tmp_path, capsys):
    # The goal's bar reaches to x + 0.88 m; the map's wall begins at x = 5 m: at x = 3.95, 0.07 m of room.
    out = tmp_path / "s.yaml"
    assert main(["map", "scenario", str(room_map), "--start", "2.5", "0", "--goal", "3.95", "0", "--out",
                 str(out)]) == 0
    printed = capsys.readouterr().out.splitlines()
    goal = float(printed[3].split(" at the goal ")[1].split()[0])
    assert goal == pytest.approx(GeometricChecker(load_scenario(out)).clearance(np.array(
        [3.95, 0.0, *CARRYING_ARM])), abs=0.005)
    assert 0.0 < goal < MAP_TIGHT_ROOM and f"less than {MAP_TIGHT_ROOM:g} m" in printed[3]
    assert "less than" not in printed[2]


@pytest.mark.parametrize("clearance, pointed_out", [
    (MAP_TIGHT_ROOM, False), (np.nextafter(MAP_TIGHT_ROOM, 0.0), True), (np.nextafter(MAP_TIGHT_ROOM, 1.0), False),
    (0.0, True)])
def test_the_tight_room_threshold(clearance, pointed_out):
    from drake_social.map_tools import MapScenario, Room

    roomy = Room(1.0, "base", "wall_west")
    dut = MapScenario(path=None, planner={"iterations": 2000, "planning_range": 1.5, "near_radius": 2.5},
                      extent=[0.0, 0.0, 10.0, 6.0], start=roomy, goal=Room(float(clearance), "object", "map[1]"))
    lines = dut.lines()
    assert ("less than 0.1 m" in lines[2]) is pointed_out and "less than" not in lines[1]


def test_a_goal_across_a_50_m_floor_behind_a_door_is_found_with_the_written_settings(tmp_path):
    """A generated 50 x 30 m floor (seed 2): from the foot of the west corridor
    to the roomiest spot of the room at the far north-east end, behind its
    1.8-2.2 m door, as measured for the rule. The written settings (K =
    12,000, range 2.5 m) find it for seeds 0-2; the planner's defaults (K =
    2,000, range 1.5 m), all that map scenario wrote before, for none."""
    from drake_social.collision.drake_checker import make_checker
    from drake_social.planning.algorithms import plan
    from drake_social.scenario import PlannerOptions

    layout = office_floor_layout(50.0, 30.0, 0.05, np.random.default_rng(2))
    floor = write_map(tmp_path, "floor", layout.image(), 0.05)
    spine = layout.corridors[0]
    start = (0.5 * (spine[0] + spine[2]), spine[1] + 1.5)
    far = int(np.argmax([r[2] + r[3] for r in layout.rooms]))  # the north-east room
    x0, y0, x1, y1 = layout.rooms[far]
    door = layout.doors[far]
    assert 1.8 <= door[2] - door[0] <= 2.2 and x1 > 45.0 and y1 > 25.0
    first = write_map_scenario(floor, tmp_path / "s.yaml", start, (start[0], start[1] + 3.0))  # up the corridor
    checker = make_checker(load_scenario(first.path), "planar")
    grid = np.array([(x, y, *CARRYING_ARM) for x in np.arange(x0 + 0.5, x1 - 0.5, 0.1)
                     for y in np.arange(y0 + 0.5, y1 - 0.5, 0.1)])
    roomiest = grid[int(np.argmax(checker.clearances(grid)))]
    written = write_map_scenario(floor, tmp_path / "s.yaml", start, roomiest[:2], force=True)
    assert written.goal.clearance > 0.5
    scenario = load_scenario(written.path)
    assert (scenario.planner.iterations, scenario.planner.planning_range) == (12000, 2.5)
    assert all(plan(scenario, checker, seed=seed).success for seed in range(3))
    defaults = load_scenario(written.path)
    defaults.planner = PlannerOptions()
    assert not any(plan(defaults, checker, seed=seed).success for seed in range(3))
