"""Walking people are moving bodies in SceneGraph: Drake's queries see them
where they are at the context's time; standing people stay anchored in the plant."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.geometry import Role

from drake_social.control import PARKED_DEPTH
from drake_social.model.robot_model import COLLISION_HEIGHT
from drake_social.people import PeopleState, ScenarioPeople
from drake_social.sim import station as station_module
from drake_social.sim.station import make_station

BASE_RADIUS, PERSON_RADIUS = 0.35, 0.25  # scenarios/tiny.yaml
#: Drake measures cylinder to cylinder by GJK: within about 1e-6 m of the exact distance.
DISTANCE_TOL = 1e-5


class Walkers:
    """tiny's person walking west along y = 3.8 at 0.5 m/s from x = 4, and a
    second one who enters at t = 1 s (absent before)."""

    count, static = 2, False

    def state_at(self, t):
        return PeopleState(t=t, positions=[[4.0 - 0.5 * t, 3.8], [6.0, 1.5]], headings=[np.pi, 0.0],
                           velocities=[[-0.5, 0.0], [0.0, 0.0]], radii=[PERSON_RADIUS, 0.3],
                           names=("standing", "late"), present=[True, t >= 1.0])


@pytest.fixture
def walking(monkeypatch):
    monkeypatch.setattr(station_module, "people_model", lambda scenario: ScenarioPeople([Walkers()]))


def _ids(built, name):
    inspector = built.scene_graph.model_inspector()
    return [g for g in inspector.GetAllGeometryIds(Role.kProximity) if inspector.GetName(g) == name]


def _context(station, scenario):
    """A context of the station alone, its commands holding the robot at the scenario's start."""
    context = station.diagram.CreateDefaultContext()
    station.diagram.GetInputPort("wheel_speeds").FixValue(context, np.zeros(4))
    station.diagram.GetInputPort("arm_command").FixValue(context, np.concatenate([scenario.start[2:], np.zeros(4)]))
    return context


def _base(built):
    plant = built.plant
    (geometry,) = plant.GetCollisionGeometriesForBody(plant.GetBodyByName("base", built.robot))
    return geometry


@pytest.mark.parametrize("mode", ["kinematic", "dynamic"])
def test_queries_see_the_people_where_they_walk(tiny_scenario, walking, mode):
    built = make_station(tiny_scenario, mode=mode)
    assert built.diagram.GetSubsystemByName("people_geometry") is not None
    # Not anchored in the plant: only the moving body carries the person's name.
    (person,) = _ids(built, "person[0] 'standing'")
    (late,) = _ids(built, "person[1] 'late'")
    assert built.scene_graph.model_inspector().GetFrameId(person) != built.scene_graph.world_frame_id()
    base = _base(built)
    context = _context(built, tiny_scenario)
    port = built.diagram.GetOutputPort("query_object")
    start = np.asarray(tiny_scenario.start[:2], float)
    for t in (0.0, 3.0):
        context.SetTime(t)
        query = port.Eval(context)
        expected = np.hypot(4.0 - 0.5 * t - start[0], 3.8 - start[1]) - BASE_RADIUS - PERSON_RADIUS
        got = query.ComputeSignedDistancePairClosestPoints(base, person).distance
        assert got == pytest.approx(expected, abs=DISTANCE_TOL), t
        z_late = query.GetPoseInWorld(late).translation()[2]
        assert z_late == pytest.approx(COLLISION_HEIGHT / 2 - PARKED_DEPTH if t < 1.0 else COLLISION_HEIGHT / 2)
        pairs = {frozenset((p.id_A, p.id_B)): p.distance for p in query.ComputeSignedDistancePairwiseClosestPoints(10.0)}
        if mode == "kinematic":  # every query sees the person
            assert pairs[frozenset((base, person))] == pytest.approx(expected, abs=DISTANCE_TOL)
        else:  # filtered out of the plant's contacts (it owns no person), the pair query above still sees them
            assert frozenset((base, person)) not in pairs and len(pairs) > 0
    # The hand value moved: the person walked 1.5 m west, towards the robot.
    assert expected < 3.0


def test_standing_people_stay_anchored(tiny_scenario):
    built = make_station(tiny_scenario, mode="kinematic")
    assert built.people.model.static
    with pytest.raises(RuntimeError):
        built.diagram.GetSubsystemByName("people_geometry")
    (person,) = _ids(built, "person[0] 'standing'")
    inspector = built.scene_graph.model_inspector()
    assert inspector.GetFrameId(person) == built.scene_graph.world_frame_id()
    np.testing.assert_allclose(inspector.GetPoseInFrame(person).translation(), [4.0, 3.8, COLLISION_HEIGHT / 2])


def test_add_environment_can_leave_the_people_out(tiny_scenario):
    from pydrake.multibody.plant import MultibodyPlant

    from drake_social.model.plant import add_environment, environment_names

    names = environment_names(tiny_scenario)
    assert "person[0] 'standing'" in names
    from pydrake.geometry import SceneGraph

    plant, scene_graph = MultibodyPlant(0.0), SceneGraph()  # the plant keeps no reference to the scene graph
    plant.RegisterAsSourceForSceneGraph(scene_graph)
    registered = add_environment(plant, tiny_scenario, people=False)
    assert registered == [n for n in names if not n.startswith("person")]
    assert plant.num_collision_geometries() == len(registered)


def test_the_replay_draws_the_walking_people(tiny_scenario, walking):
    from drake_social.sim.replay import make_meshcat

    meshcat = make_meshcat()
    built = make_station(tiny_scenario, mode="kinematic", meshcat=meshcat)
    context = _context(built, tiny_scenario)
    context.SetTime(2.0)
    built.visualizer.ForcedPublish(built.visualizer.GetMyContextFromRoot(context))
    # The visualizer draws each person's frame (its illustration geometry) under the prefix.
    assert meshcat.HasPath("/drake/illustration/person[0] 'standing'")
    assert meshcat.HasPath("/drake/illustration/person[1] 'late'")
