"""A map's boxes are the SceneGraph's geometry: the plant registers them
(collision only), the planar checker reads them back unchanged, the replay
draws them as one mesh, and a plan on a generated map passes Drake's own check."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from pydrake.geometry import Role

from drake_social.collision.drake_checker import make_checker, verify_path
from drake_social.maps import office_floor_image, write_map
from drake_social.planning.algorithms import plan
from drake_social.model.plant import build_robot_diagram, environment_names
from drake_social.scenario import ScenarioError, load_scenario
from drake_social.sim import replay
from drake_social.sim.replay_map import boxes_mesh
from drake_social.world import world_model

from maps.test_map_scenario import write_scenario


@pytest.fixture
def room(tmp_path):
    extra = "  obstacles: [{center: [2.0, 4.0], size: [0.4, 0.4], yaw: 0.3}]\n"
    return load_scenario(write_scenario(tmp_path, extra=extra))


def test_the_plant_registers_the_maps_boxes_for_collision_only(room):
    world = world_model(room)
    names = environment_names(room)
    assert names[:1 + world.map_box_count] == world.box_names
    model = build_robot_diagram(room)
    inspector = model.diagram.scene_graph().model_inspector()
    proximity = {inspector.GetName(g) for g in inspector.GetAllGeometryIds(Role.kProximity)}
    illustration = {inspector.GetName(g) for g in inspector.GetAllGeometryIds(Role.kIllustration)}
    maps = {n for n in names if n.startswith("map[")}
    assert maps and maps <= proximity and not maps & illustration
    assert "obstacle[0]" in proximity and "obstacle[0]" in illustration


def test_the_planar_checker_reads_back_the_boxes_of_the_world_model(room):
    checker = make_checker(room, "planar")
    world = world_model(room)
    rows = {name: row for name, row in zip(checker.env_names, checker.env)}
    for name, centre, half, c, s in zip(world.box_names, world.boxes.centers, world.boxes.halves, world.boxes.cos,
                                        world.boxes.sin):
        kind, cx, cy, rc, rs, hx, hy, _ = rows[name]
        assert kind == 0
        np.testing.assert_allclose([cx, cy, hx, hy], [*centre, *half], rtol=0, atol=1e-12)
        # The same box whichever way round its axes were read.
        assert abs(rc * c + rs * s) == pytest.approx(1.0, abs=1e-12) or abs(rc * s - rs * c) == pytest.approx(
            1.0, abs=1e-12)


def test_the_robot_at_a_map_wall_is_reported_against_the_map_box(room):
    checker = make_checker(room, "planar")
    q = np.array([3.6, 2.0, 0.0, 1.0])  # the bar reaches into the wall at x = 4 .. 5
    contacts = checker.contacts(q)
    assert contacts and all(c.other.startswith("map[") for c in contacts)
    with pytest.raises(ScenarioError, match=r"start: configuration .* is in collision: .* with map\["):
        make_checker(load_scenario(room.world.map.replace("maps/room.yaml", "room_scenario.yaml"),
                                   ["start: [3.6, 2.0, 0.0, 1.0]"]), "planar", source="room_scenario.yaml")


def _wall_label() -> str:
    """The room's wall as a report names it, computed here from the image:
    its image rows and columns, and its world extent (origin 0, 0.5 m cells,
    image row 0 at the top of the 12-row image)."""
    from maps.test_map_scenario import RESOLUTION, room_image

    rows, cols = np.nonzero(room_image() == 0)
    height = room_image().shape[0]
    x0, x1 = cols.min() * RESOLUTION, (cols.max() + 1) * RESOLUTION
    y0, y1 = (height - 1 - rows.max()) * RESOLUTION, (height - rows.min()) * RESOLUTION
    return (f"the box of world.map room.yaml over image rows {rows.min()}-{rows.max()}, columns {cols.min()}-"
            f"{cols.max()} (x {x0:.2f} .. {x1:.2f} m, y {y0:.2f} .. {y1:.2f} m)")


@pytest.mark.parametrize("kind", ["planar", "drake"])
def test_a_contact_with_a_map_box_names_its_image_cells_and_world_coordinates(room, kind):
    """No figure numbers the map's boxes: a report says where map[j] is."""
    assert _wall_label() == ("the box of world.map room.yaml over image rows 3-11, columns 8-9 "
                             "(x 4.00 .. 5.00 m, y 0.00 .. 4.50 m)")
    checker = make_checker(room, kind)
    contacts = checker.contacts(np.array([3.6, 2.0, 0.0, 1.0]))
    names = {c.other for c in contacts}
    assert len(names) == 1 and re.fullmatch(r"map\[\d+\], " + re.escape(_wall_label()), names.pop())
    with pytest.raises(ScenarioError) as e:
        make_checker(load_scenario(room.world.map.replace("maps/room.yaml", "room_scenario.yaml"),
                                   ["start: [3.6, 2.0, 0.0, 1.0]"]), kind, source="room_scenario.yaml")
    assert _wall_label() in str(e.value)


def test_a_contact_with_the_outside_of_a_turned_map_names_it(tmp_path):
    path = write_scenario(tmp_path, origin=(0.0, 0.0, math.pi / 6), start="1.0, 3.0", goal="3.0, 5.0")
    scenario = load_scenario(path)
    world = world_model(scenario)
    outside = f"map[{world.map_box_count - 1}]"  # the last four boxes close the outside
    corner = world.boxes.corners[-1].mean(axis=0)  # well inside the last outside box
    labels = [c.other for c in make_checker(scenario, "planar").contacts(np.array([*corner, 0.0, 1.0]))]
    assert any(label.startswith(outside + ", the outside of world.map room.yaml's rectangle") for label in labels)


def test_boxes_mesh_covers_each_footprint_once():
    rng = np.random.default_rng(4)
    k = 50
    centres, sizes, yaws = rng.uniform(-5, 5, (k, 2)), rng.uniform(0.1, 2, (k, 2)), rng.uniform(-3, 3, k)
    c, s = np.cos(yaws), np.sin(yaws)
    local = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * 0.5
    corners = centres[:, None] + np.einsum("kij,kvj->kvi", np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], 1),
                                           local[None] * sizes[:, None])
    vertices, faces = boxes_mesh(corners, 1.2)
    assert vertices.shape == (3, 8 * k) and faces.shape == (3, 10 * k) and faces.dtype == np.int32
    v = vertices.T[faces.T]  # (10K, 3, 3)
    normal = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    area = np.linalg.norm(normal, axis=1) / 2
    top = np.abs(normal[:, 2]) > 0
    # The tops face up and cover the footprints; the sides have the perimeters times the height.
    assert (normal[top, 2] > 0).all()
    np.testing.assert_allclose(area[top].reshape(k, 2).sum(1), sizes.prod(1), rtol=1e-9)
    np.testing.assert_allclose(area[~top].reshape(k, 8).sum(1), 2 * sizes.sum(1) * 1.2, rtol=1e-9)
    # Each side faces away from its box's centre.
    mid = v[~top].mean(1)[:, :2] - np.repeat(centres, 8, axis=0)
    assert (np.einsum("ij,ij->i", normal[~top, :2], mid) > 0).all()


def test_the_replay_draws_the_map_as_one_mesh(room):
    meshcat = replay.make_meshcat()
    replay.draw_overlays(meshcat, room)
    assert meshcat.HasPath(f"{replay.OVERLAY_PREFIX}/map")
    assert not meshcat.HasPath(f"{replay.OVERLAY_PREFIX}/map/0")


@pytest.mark.slow
def test_a_plan_on_a_generated_office_floor_passes_drakes_check(tmp_path):
    image = office_floor_image(20.0, 14.0, 0.05, np.random.default_rng(5))
    write_map(tmp_path, "floor", image, 0.05)
    text = (f"world: {{map: floor.yaml}}\npeople: [{{x: 9.0, y: 7.0, theta: 0.0, radius: 0.25}}]\n"
            "object: !Bar {length: 1.5, thickness: 0.05}\nstart: [2.2, 10.5, -1.2292, 2.8]\n"
            "goal: [18.0, 7.0, -1.2292, 2.8]\nplanner: {iterations: 2000, planning_range: 2.5, near_radius: 3.0}\n")
    (tmp_path / "s.yaml").write_text(text)
    scenario = load_scenario(tmp_path / "s.yaml")
    result = plan(scenario, make_checker(scenario, "planar"))
    assert result.success
    assert verify_path(scenario, result.waypoints) is None
    world = world_model(scenario)
    assert world.map_box_count > 10 and math.isclose(world.bounds[2], 20.0)


def test_drakes_whole_room_checker_refuses_a_room_too_large_for_one_scene_graph(tiny_scenario):
    from drake_social.collision.drake_checker import MAX_DRAKE_CHECKER_SHAPES, SceneGraphChecker
    from drake_social.scenario import Box
    from drake_social.world import with_obstacles

    big = with_obstacles(tiny_scenario, [Box(center=[100.0 + i, 0.0], size=[0.2, 0.2])
                                         for i in range(MAX_DRAKE_CHECKER_SHAPES)])
    with pytest.raises(ScenarioError, match=r"world: 2,00\d shapes .* at most 2,000: use the planar checker"):
        SceneGraphChecker(big)
    with pytest.raises(ScenarioError, match="use the planar checker"):
        make_checker(big, "drake")


def test_the_map_picture_is_four_bytes_a_cell(room):
    from drake_social.maps import OCCUPIED, UNKNOWN
    from drake_social.viz.world import MAP_OCCUPIED_RGBA, map_rgba

    grid = world_model(room).map
    rgba = map_rgba(grid)
    assert rgba.dtype == np.uint8 and rgba.shape == (*grid.shape, 4)
    np.testing.assert_array_equal(rgba[grid.classes == OCCUPIED][0], np.round(np.multiply(MAP_OCCUPIED_RGBA, 255)))
    assert (rgba[grid.classes == UNKNOWN][:, 3] > 0).all() and (rgba[(grid.classes != OCCUPIED) &
                                                                    (grid.classes != UNKNOWN)] == 0).all()


def test_the_map_mesh_costs_a_replay_under_0_3_kb_a_box(tmp_path):
    """replay_map's stated cost: the page grows by at most 0.3 kB per box of
    the map (vertices and faces packed once, whatever the run's length)."""
    from drake_social.experiments.bench.maps import map_bench_scenario
    from drake_social.sim.replay_map import draw_map_mesh
    from drake_social.sim.replay_pack import compact_page

    world = world_model(load_scenario(map_bench_scenario(tmp_path, width=16.0, height=14.0, resolution=0.05)))
    meshcat = replay.make_meshcat()
    before = len(compact_page(meshcat.StaticHtml()))
    assert draw_map_mesh(meshcat, world, "/drake_social/map") == world.map_box_count > 300
    grown = len(compact_page(meshcat.StaticHtml())) - before
    assert 0.2e3 * world.map_box_count < grown < 0.3e3 * world.map_box_count
