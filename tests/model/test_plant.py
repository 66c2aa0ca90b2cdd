"""The Drake plant of a scenario: forward kinematics = numpy kinematics; the room's shapes."""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.geometry import Role

from drake_social.scenario.geometry import arm_geometry
from drake_social.model.plant import build_robot_diagram, environment_names
from drake_social.model.robot_model import COLLISION_HEIGHT
from drake_social.scenario import Bar, Box, LShape, Person, Polyline

OBJECTS = {
    "bar": Bar(length=1.5, thickness=0.05),
    "L": LShape(lengths=[3.0, 2.0], thickness=0.05),
    "polyline": Polyline(
        points=[[0.0, -0.5], [0.3, 0.2], [0.1, 0.8], [-0.4, 1.1]],
        thickness=0.05,
        interest_points=[[0.3, 0.2], [-0.4, 1.1], [0.05, 0.05]],
    ),
}


@pytest.mark.parametrize("kind", list(OBJECTS))
def test_drake_forward_kinematics_equals_numpy(tiny_scenario, kind, rng):
    scenario = dc.replace(tiny_scenario, object=OBJECTS[kind])
    geometry = arm_geometry(scenario)
    model = build_robot_diagram(scenario)
    plant = model.diagram.plant()
    context = plant.CreateDefaultContext()
    frames = [plant.GetBodyByName("base", model.robot).body_frame()]
    frames += [plant.GetFrameByName(n, model.robot) for n in ("link1_tip", "gripper")]
    frames += [plant.GetFrameByName(f"object_point_{k + 1}", model.robot) for k in range(len(geometry.object_interest))]
    gripper = frames[2]
    # Joint angles well beyond one turn as well: the kinematics must not wrap.
    qs = rng.uniform([-3.0, -3.0, -7.0, -7.0], [11.0, 8.0, 7.0, 7.0], size=(1000, 4))
    expected = geometry.interest_points(qs)
    got = np.empty_like(expected)
    yaw = np.empty(len(qs))
    for i, q in enumerate(qs):
        plant.SetPositions(context, q)
        for j, f in enumerate(frames):
            X = f.CalcPoseInWorld(context)
            got[i, j] = X.translation()[:2]
            assert X.translation()[2] == 0.0
        R = gripper.CalcPoseInWorld(context).rotation().matrix()
        yaw[i] = math.atan2(R[1, 0], R[0, 0])
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9)
    # The gripper's x axis points along link 2, at psi1 + psi2.
    wrapped = np.angle(np.exp(1j * (yaw - qs[:, 2] - qs[:, 3])))
    np.testing.assert_allclose(wrapped, 0.0, atol=1e-9)


def _environment(scenario):
    """(query, keep_alive): the QueryObject refers into the diagram and its
    context without owning them, so callers must hold ``keep_alive``."""
    diagram = build_robot_diagram(scenario).diagram
    context = diagram.CreateDefaultContext()
    query = diagram.scene_graph().get_query_output_port().Eval(diagram.scene_graph().GetMyContextFromRoot(context))
    return query, (diagram, context)


def _distance_to(query, name: str, p) -> float:
    inspector = query.inspector()
    (gid,) = [g for g in inspector.GetAllGeometryIds(Role.kProximity) if inspector.GetName(g) == name]
    for r in query.ComputeSignedDistanceToPoint([p[0], p[1], COLLISION_HEIGHT / 2], threshold=np.inf):
        if r.id_G == gid:
            return r.distance
    raise AssertionError(f"no distance to {name}")


def test_environment_shapes_at_hand_computed_distances(tiny_scenario):
    scenario = dc.replace(
        tiny_scenario,
        world=dc.replace(
            tiny_scenario.world,
            obstacles=[Box(center=[6.0, 2.0], size=[1.0, 0.4], yaw=math.pi / 4)],
            wall_thickness=0.2,
        ),
        people=[Person(x=2.0, y=3.0, theta=math.pi / 4, radius=0.3, name="ana"), Person(x=5.0, y=4.0)],
    )
    dut, _keep_alive = _environment(scenario)
    assert environment_names(scenario) == [
        "obstacle[0]", "person[0] 'ana'", "person[1]", "wall_south", "wall_north", "wall_west", "wall_east",
    ]
    # Rotated box: a point 1 m along the box's own x axis from its centre is 0.5 m out.
    p = np.array([6.0, 2.0]) + np.array([math.cos(math.pi / 4), math.sin(math.pi / 4)])
    assert _distance_to(dut, "obstacle[0]", p) == pytest.approx(0.5, abs=1e-9)
    # ... and one along its y axis is 1 - 0.2 = 0.8 m out.
    p = np.array([6.0, 2.0]) + np.array([-math.sin(math.pi / 4), math.cos(math.pi / 4)])
    assert _distance_to(dut, "obstacle[0]", p) == pytest.approx(0.8, abs=1e-9)
    # People are discs of their radius (the default is 0.25 m).
    assert _distance_to(dut, "person[0] 'ana'", [3.0, 3.0]) == pytest.approx(0.7, abs=1e-9)
    assert _distance_to(dut, "person[1]", [5.0, 3.0]) == pytest.approx(0.75, abs=1e-9)
    # Walls stand outside the 8 x 5 m bounds; the corners are closed.
    assert _distance_to(dut, "wall_west", [1.5, 2.5]) == pytest.approx(1.5, abs=1e-9)
    assert _distance_to(dut, "wall_east", [7.0, 2.5]) == pytest.approx(1.0, abs=1e-9)
    assert _distance_to(dut, "wall_south", [4.0, 0.25]) == pytest.approx(0.25, abs=1e-9)
    assert _distance_to(dut, "wall_north", [4.0, 4.0]) == pytest.approx(1.0, abs=1e-9)
    assert _distance_to(dut, "wall_south", [-0.15, -0.1]) < 0.0  # inside the closed corner
    assert _distance_to(dut, "wall_north", [8.15, 5.1]) < 0.0
    # Outside the room beyond the wall thickness: positive again.
    assert _distance_to(dut, "wall_west", [-0.5, 2.5]) == pytest.approx(0.3, abs=1e-9)


def test_empty_room_has_only_walls(tiny_scenario):
    scenario = dc.replace(tiny_scenario, world=dc.replace(tiny_scenario.world, obstacles=[]), people=[])
    query, _keep_alive = _environment(scenario)
    inspector = query.inspector()
    names = {inspector.GetName(g) for g in inspector.GetAllGeometryIds(Role.kProximity)}
    assert {n for n in names if not n.startswith("mobile_manipulator")} == {
        "wall_south", "wall_north", "wall_west", "wall_east",
    }
