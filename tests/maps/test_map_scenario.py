"""A map in a scenario: world.map read relative to the scenario file, bounds
from the map, its boxes in the world model, the plant and the checkers, and
each bad input a clear error naming the file and the field."""

from __future__ import annotations

import os
import textwrap

import numpy as np
import pytest

from drake_social.maps import OCCUPIED, UNKNOWN, map_boxes, read_map, write_map
from drake_social.scenario import ScenarioError, load_scenario
from drake_social.world import world_model

# A 6 x 10 m room at 0.5 m (12 rows, 20 columns), image order (row 0 = top =
# north): free (255) inside, an unknown (205) band along the top row, a wall
# (0) across columns 8-9 of rows 3-11 (a gap in rows 1-2 at the north).
RESOLUTION = 0.5


def room_image() -> np.ndarray:
    image = np.full((12, 20), 255, np.uint8)
    image[0, :] = 205
    image[3:12, 8:10] = 0
    return image


SCENARIO = """\
description: "a map room"
world:
  map: {map}
{extra}people: []
robot: {{base_radius: 0.3, link_lengths: [0.4, 0.3], link_width: 0.06}}
object: !Bar {{length: 0.6, thickness: 0.04}}
start: [{start}, 0.0, 1.0]
goal: [{goal}, 0.0, 1.0]
"""


def write_scenario(folder, *, map_name="maps/room.yaml", start="1.5, 2.0", goal="8.5, 2.0", extra="",
                   origin=(0.0, 0.0, 0.0)):
    (folder / "maps").mkdir(exist_ok=True)
    write_map(folder / "maps", "room", room_image(), RESOLUTION, origin)
    path = folder / "room_scenario.yaml"
    path.write_text(SCENARIO.format(map=map_name, start=start, goal=goal, extra=textwrap.indent(extra, "")))
    return path


def test_the_map_is_found_beside_the_scenario_and_gives_the_bounds(tmp_path, monkeypatch):
    path = write_scenario(tmp_path)
    monkeypatch.chdir("/")  # the map is found relative to the scenario file, not the working directory
    scenario = load_scenario(path)
    assert scenario.world.map == str(tmp_path / "maps" / "room.yaml")
    assert scenario.world.bounds == [0.0, 0.0, 10.0, 6.0]


def test_given_bounds_are_kept_and_a_turned_map_bounds_its_corners(tmp_path):
    path = write_scenario(tmp_path, extra="  bounds: [-1.0, -1.0, 11.0, 7.0]\n")
    assert load_scenario(path).world.bounds == [-1.0, -1.0, 11.0, 7.0]
    # Turned by 90 degrees about the origin (1, 0): x' = 1 - y, y' = x; the room spans x in [-5, 1], y in [0, 10].
    path = write_scenario(tmp_path, origin=(1.0, 0.0, np.pi / 2), start="-1.0, 1.5", goal="-1.0, 8.5")
    np.testing.assert_allclose(load_scenario(path).world.bounds, [-5.0, 0.0, 1.0, 10.0], atol=1e-12)


def test_a_set_override_names_a_map_relative_to_the_scenario_file(tmp_path, monkeypatch):
    path = write_scenario(tmp_path)
    plain = tmp_path / "plain.yaml"
    plain.write_text(path.read_text().replace("  map: maps/room.yaml\n", "  wall_thickness: 0.1\n"))
    assert load_scenario(plain).world.bounds == [0.0, 0.0, 10.0, 10.0]  # the schema's default room
    monkeypatch.chdir("/")
    scenario = load_scenario(plain, ["world: {map: maps/room.yaml}"])
    assert scenario.world.map == str(tmp_path / "maps" / "room.yaml")
    assert scenario.world.bounds == [0.0, 0.0, 10.0, 6.0]
    # Bounds given by any source are kept.
    assert load_scenario(plain, ["world: {bounds: [0, 0, 12, 7]}", "world: {map: maps/room.yaml}"]
                         ).world.bounds == [0.0, 0.0, 12.0, 7.0]


def test_the_world_model_holds_the_obstacles_then_the_maps_boxes(tmp_path):
    extra = "  obstacles: [{center: [2.0, 4.0], size: [0.4, 0.4]}]\n"
    scenario = load_scenario(write_scenario(tmp_path, extra=extra))
    world = world_model(scenario)
    grid = read_map(tmp_path / "maps" / "room.yaml")
    boxes = map_boxes(grid)
    assert world.map_box_count == len(boxes.yaws) == len(world.boxes) - 1
    assert world.box_names == ["obstacle[0]"] + [f"map[{j}]" for j in range(len(boxes.yaws))]
    np.testing.assert_array_equal(world.boxes.centers[1:], boxes.centers)
    np.testing.assert_array_equal(world.boxes.sizes[1:], boxes.sizes)
    # The wall (rows 3-11 of the image = grid rows 0-8, columns 8-9) and the unknown top row.
    areas = np.prod(world.boxes.sizes[1:], axis=1).sum()
    assert areas == pytest.approx((9 * 2 + 20) * RESOLUTION**2)
    # unknown: free leaves the top row out.
    free = load_scenario(write_scenario(tmp_path, extra="  unknown: free\n"))
    assert np.prod(world_model(free).boxes.sizes, axis=1).sum() == pytest.approx(9 * 2 * RESOLUTION**2)


def test_an_edited_map_is_read_again(tmp_path):
    path = write_scenario(tmp_path)
    before = world_model(load_scenario(path)).map_box_count
    image = room_image()
    image[10, 2] = 0  # one more occupied cell (grid row 1, column 2)
    stat = os.stat(tmp_path / "maps" / "room.pgm")
    write_map(tmp_path / "maps", "room", image, RESOLUTION)
    # The same size and modification time (a coarse clock): the new file is still told apart.
    os.utime(tmp_path / "maps" / "room.pgm", ns=(stat.st_atime_ns, stat.st_mtime_ns))
    assert os.stat(tmp_path / "maps" / "room.pgm").st_size == stat.st_size
    after = world_model(load_scenario(path))
    assert after.map_box_count == before + 1
    assert after.map.classes[1, 2] == OCCUPIED


@pytest.mark.parametrize("start, goal, field, what", [
    ("4.25, 2.0", "8.5, 2.0", "start", "occupied cell"),   # column 8, row 4 (grid): the wall
    ("1.5, 2.0", "6.0, 5.75", "goal", "unknown cell"),     # the unknown top row
])
def test_a_start_or_goal_in_an_occupied_or_unknown_cell_is_refused(tmp_path, start, goal, field, what):
    path = write_scenario(tmp_path, start=start, goal=goal)
    with pytest.raises(ScenarioError) as e:
        load_scenario(path)
    message = str(e.value)
    assert message.startswith(f"{path}: {field}: the base centre") and what in message
    assert "room.yaml" in message and "image row" in message


def test_an_unknown_goal_cell_is_fine_when_unknown_cells_are_free(tmp_path):
    path = write_scenario(tmp_path, goal="6.0, 5.75", extra="  unknown: free\n")
    assert load_scenario(path).world.unknown == "free"


@pytest.mark.parametrize("extra, map_name, field, words", [
    ("", "maps/none.yaml", "world.map", ["none.yaml"]),
    ("", "''", "world.map", ["must name a map_server YAML file"]),
    ("  unknown: wall\n", "maps/room.yaml", "world.unknown", ["obstacle, free", "'wall'"]),
])
def test_bad_map_fields_name_the_file_and_the_field(tmp_path, extra, map_name, field, words):
    path = write_scenario(tmp_path, map_name=map_name, extra=extra)
    with pytest.raises(ScenarioError) as e:
        load_scenario(path)
    message = str(e.value)
    assert message.startswith(f"{path}: ") and f" {field}: " in message
    for word in words:
        assert word in message


def test_a_bad_map_file_is_named_with_its_own_field(tmp_path):
    path = write_scenario(tmp_path)
    yaml_file = tmp_path / "maps" / "room.yaml"
    yaml_file.write_text(yaml_file.read_text().replace("resolution: 0.5", "resolution: 0"))
    with pytest.raises(ScenarioError) as e:
        load_scenario(path)
    message = str(e.value)
    assert message.startswith(f"{path}: world.map: ") and str(yaml_file) in message and "resolution" in message


def test_a_person_inside_a_map_box_is_refused_naming_the_cells(tmp_path):
    extra = "people: [{x: 4.5, y: 2.0, theta: 0.0, radius: 0.25}]\n"
    path = write_scenario(tmp_path)
    path.write_text(path.read_text().replace("people: []\n", extra))
    with pytest.raises(ScenarioError) as e:
        load_scenario(path)
    message = str(e.value)
    assert f"{path}: people[0]: " in message and "world.map room.yaml over image rows 3-11, columns 8-9" in message


def test_a_turned_map_is_closed_outside_its_rectangle(tmp_path):
    # Turned by 30 degrees: the default bounds (the extent) reach beyond the rectangle at its corners.
    path = write_scenario(tmp_path, origin=(0.0, 0.0, np.pi / 6), start="1.0, 3.0", goal="3.0, 5.0")
    scenario = load_scenario(path)
    world = world_model(scenario)
    grid = read_map(tmp_path / "maps" / "room.yaml")
    cells = map_boxes(grid)
    assert world.map_box_count == len(cells.yaws) + 4
    # Points of the bounds outside the rectangle lie in an outside box; points inside the rectangle in none.
    rng = np.random.default_rng(3)
    x0, y0, x1, y1 = scenario.world.bounds
    points = rng.uniform([x0, y0], [x1, y1], (4000, 2))
    u, v = grid.to_map(points).T
    outside = (u < 0) | (u > grid.width_m) | (v < 0) | (v > grid.height_m)
    extra = world.boxes.corners[-4:]
    c, s = np.cos(world.boxes.yaws[-4:]), np.sin(world.boxes.yaws[-4:])
    rel = points[:, None, :] - world.boxes.centers[-4:]
    lu, lv = c * rel[..., 0] + s * rel[..., 1], -s * rel[..., 0] + c * rel[..., 1]
    inside_box = (np.abs(lu) <= world.boxes.halves[-4:, 0]) & (np.abs(lv) <= world.boxes.halves[-4:, 1])
    assert outside.any() and inside_box[outside].any(1).all()
    assert not inside_box[~outside & (u > 1e-6) & (v > 1e-6)].any()
    assert extra.shape == (4, 4, 2)
    # A start outside the rectangle is refused; with unknown cells free the outside is free.
    with pytest.raises(ScenarioError, match=r"start: the base centre \(6.5, 0.5\) lies outside world.map"):
        load_scenario(write_scenario(tmp_path, origin=(0.0, 0.0, np.pi / 6), start="6.5, 0.5", goal="3.0, 5.0"))
    free = load_scenario(write_scenario(tmp_path, origin=(0.0, 0.0, np.pi / 6), start="1.0, 3.0", goal="3.0, 5.0",
                                        extra="  unknown: free\n"))
    assert world_model(free).map_box_count == len(map_boxes(grid, "free").yaws)
    # A person in the outside is named so.
    path = write_scenario(tmp_path, origin=(0.0, 0.0, np.pi / 6), start="1.0, 3.0", goal="3.0, 5.0")
    text = path.read_text().replace("people: []\n", "people: [{x: 6.5, y: 0.5, theta: 0.0}]\n")
    path.write_text(text)
    with pytest.raises(ScenarioError, match=r"people\[0\]: .*the outside of world.map room.yaml"):
        load_scenario(path)
