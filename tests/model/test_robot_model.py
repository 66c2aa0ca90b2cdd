"""The generated SDFormat model: file in sync, limits, and shapes equal to the 2-D capsules."""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest
from pydrake.geometry import Box as DrakeBox
from pydrake.geometry import Cylinder, QueryObject, Role
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

from drake_social.scenario.geometry import arm_geometry
from drake_social.model.plant import build_robot_diagram
from drake_social.model.robot_model import COLLISION_HEIGHT, ROBOT_BODIES, default_model_path, models_dir, robot_sdf
from drake_social.scenario import Bar, LShape, Polyline, Scenario

OBJECTS = {
    "bar": Bar(length=1.5, thickness=0.05),
    "L": LShape(lengths=[3.0, 2.0], thickness=0.06),
    # A repeated vertex (zero-length segment) and a bend back: awkward on purpose.
    "polyline": Polyline(points=[[0.1, -0.4], [0.1, -0.4], [0.5, 0.3], [-0.2, 0.9]], thickness=0.04),
}


def test_checked_in_model_is_the_generated_default():
    dut = robot_sdf(Scenario())
    assert default_model_path().read_text() == dut, (
        "models/mobile_manipulator.sdf is stale; regenerate it with "
        "default_model_path().write_text(robot_sdf(Scenario()))"
    )


def test_model_file_resolves_as_package_url():
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlantSceneGraph(builder, 0.0)
    parser = Parser(plant)
    parser.package_map().AddPackageXml(str(models_dir() / "package.xml"))
    (dut,) = parser.AddModels(url="package://drake_social/mobile_manipulator.sdf")
    plant.Finalize()
    assert plant.GetModelInstanceName(dut) == "mobile_manipulator"
    assert {plant.get_body(b).name() for b in plant.GetBodyIndices(dut)} == {"carriage", *ROBOT_BODIES}


def test_joint_limits_come_from_the_scenario(tiny_scenario):
    scenario = dc.replace(
        tiny_scenario,
        robot=dc.replace(tiny_scenario.robot, joint_lower=[-2.0, -2.5], joint_upper=[1.0, 2.75]),
    )
    plant = build_robot_diagram(scenario).diagram.plant()
    np.testing.assert_array_equal(plant.GetPositionLowerLimits(), [0.0, 0.0, -2.0, -2.5])
    np.testing.assert_array_equal(plant.GetPositionUpperLimits(), [8.0, 5.0, 1.0, 2.75])


def test_mass_matrix_is_positive_definite_despite_the_massless_carriage(tiny_scenario):
    diagram = build_robot_diagram(tiny_scenario).diagram
    plant = diagram.plant()
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, [1.0, 2.0, 0.3, -1.2])
    eig = np.linalg.eigvalsh(plant.CalcMassMatrix(context))
    assert eig.min() > 1e-3
    # The base translation carries every mass: 20 + 1 + 1 + 0.5 kg.
    M = plant.CalcMassMatrix(context)
    assert M[0, 0] == pytest.approx(22.5, abs=1e-9)
    assert M[1, 1] == pytest.approx(22.5, abs=1e-9)


# QueryObjects refer into their diagram and context without owning them: keep
# those alive for the whole session (a dangling query crashed at random).
_KEEP_ALIVE: list = []


def _robot_shapes(scenario: Scenario, q: np.ndarray):
    """(body name, shape, X_WG, query, id) of every robot collision geometry at q."""
    diagram = build_robot_diagram(scenario).diagram
    plant = diagram.plant()
    context = diagram.CreateDefaultContext()
    plant.SetPositions(plant.GetMyMutableContextFromRoot(context), q)
    scene_graph = diagram.scene_graph()
    query: QueryObject = scene_graph.get_query_output_port().Eval(scene_graph.GetMyContextFromRoot(context))
    _KEEP_ALIVE.append((diagram, context))
    inspector = query.inspector()
    out = []
    for gid in inspector.GetAllGeometryIds(Role.kProximity):
        body = plant.GetBodyFromFrameId(inspector.GetFrameId(gid))
        out.append((body.name(), inspector.GetShape(gid), query.GetPoseInWorld(gid), query, gid))
    return out


@pytest.mark.parametrize("kind", list(OBJECTS))
def test_every_collision_shape_is_an_extrusion_of_the_shared_slab(tiny_scenario, kind):
    scenario = dc.replace(tiny_scenario, object=OBJECTS[kind])
    shapes = _robot_shapes(scenario, np.array([2.0, 2.0, 0.7, -2.1]))
    assert len(shapes) > 0
    for _, shape, X_WG, _, _ in shapes:
        # Vertical axis, centred at half height, spanning the whole slab.
        np.testing.assert_allclose(X_WG.rotation().matrix()[:, 2], [0, 0, 1], atol=1e-12)
        assert X_WG.translation()[2] == pytest.approx(COLLISION_HEIGHT / 2, abs=1e-12)
        if isinstance(shape, Cylinder):
            assert shape.length() == pytest.approx(COLLISION_HEIGHT)
        else:
            assert isinstance(shape, DrakeBox)
            assert shape.height() == pytest.approx(COLLISION_HEIGHT)  # Drake: width x, depth y, height z


@pytest.mark.parametrize("kind", list(OBJECTS))
def test_robot_shapes_are_exactly_the_numpy_discs_and_capsules(tiny_scenario, kind, rng):
    """SceneGraph's distance from random points to each body = the 2-D capsule distance."""
    scenario = dc.replace(tiny_scenario, object=OBJECTS[kind])
    q = np.array([4.0, 2.5, 0.4, 2.2])
    geometry = arm_geometry(scenario)
    seg = geometry.segments(q)
    radii = geometry.segment_radii
    body_of_segment = ["link1", "link2"] + ["object"] * (len(seg) - 2)
    shapes = _robot_shapes(scenario, q)
    query = shapes[0][3]
    points = rng.uniform([0.0, -0.5], [8.0, 5.5], size=(300, 2))
    for body in ROBOT_BODIES:
        ids = {gid for name, *_, gid in shapes if name == body}
        if body == "base":
            expected = np.hypot(*(points - q[:2]).T) - geometry.base_radius
        else:
            idx = [s for s, b in enumerate(body_of_segment) if b == body]
            expected = np.min([_seg_dist(points, seg[s, 0], seg[s, 1]) - radii[s] for s in idx], axis=0)
        got = []
        for p in points:
            d = [
                r.distance
                for r in query.ComputeSignedDistanceToPoint([p[0], p[1], COLLISION_HEIGHT / 2], threshold=np.inf)
                if r.id_G in ids
            ]
            got.append(min(d))
        got = np.array(got)
        outside = expected > 1e-6  # inside a union the per-shape minimum is not the union's depth
        np.testing.assert_allclose(got[outside], expected[outside], atol=1e-9)
        assert np.all(got[~outside] <= 1e-9)
        assert outside.sum() > 250


def _seg_dist(p, a, b):
    d = b - a
    dd = d @ d
    t = np.zeros(len(p)) if dd == 0 else np.clip((p - a) @ d / dd, 0.0, 1.0)
    return np.hypot(*(p - (a + t[:, None] * d)).T)


def test_generated_numbers_round_trip_exactly():
    scenario = Scenario(robot=dc.replace(Scenario().robot, link_lengths=[0.1 + 0.2, math.pi / 7]))
    dut = robot_sdf(scenario)
    assert repr(0.1 + 0.2) in dut and repr(math.pi / 7) in dut
