"""People absent at t = 0 (a recorded id entering later) are no obstacle for
planning and are not drawn: the geometric, SceneGraph and planar checkers'
rooms, the shape names and the world figure hold the present people only."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

from drake_social.collision.drake_checker import SceneGraphChecker, check_start_goal
from drake_social.collision.geometric import GeometricChecker
from drake_social.model.plant import environment_discs, environment_names, registration_order
from drake_social.scenario import load_scenario
from drake_social.viz import draw_world

TINY = Path(__file__).resolve().parents[2] / "scenarios" / "tiny.yaml"
# Id 1 enters at t = 5 s standing on the robot's start (1.0, 2.5); id 2 stands
# at (6, 4) from t = 0. People order: tiny's 'standing' (0), id 1 (1), id 2 (2).
WALKERS = "t,id,x,y\n5,1,1.0,2.5\n8,1,1.0,2.5\n0,2,6.0,4.0\n8,2,6.0,4.0\n"


@pytest.fixture(scope="module")
def late_scenario(tmp_path_factory):
    folder = tmp_path_factory.mktemp("late")
    (folder / "walkers.csv").write_text(WALKERS)
    path = folder / "s.yaml"
    path.write_text(TINY.read_text() + "people_file: walkers.csv\n")
    return load_scenario(path)


def test_a_start_where_someone_enters_later_is_valid_for_planning(late_scenario):
    start = np.asarray(late_scenario.start, float)
    assert GeometricChecker(late_scenario).is_valid(start)
    check_start_goal(late_scenario)  # raises on a contact with the absent id 1
    # The same spot against id 2 (present at t = 0) is invalid: the checker still sees people.
    on_two = np.array([6.0, 4.0, *start[2:]])
    assert not GeometricChecker(late_scenario).is_valid(on_two)


def test_shape_names_keep_each_persons_index_in_the_full_order(late_scenario):
    names = environment_names(late_scenario)
    assert names == ["obstacle[0]", "person[0] 'standing'", "person[2] '2'",
                     "wall_south", "wall_north", "wall_west", "wall_east"]
    discs = environment_discs(late_scenario)
    assert discs.shape == (len(names), 3)
    np.testing.assert_allclose(discs[1:3], [[4.0, 3.8, 0.25], [6.0, 4.0, 0.25]], atol=1e-12)
    assert sorted(registration_order(late_scenario)) == list(range(len(names)))
    contacts = SceneGraphChecker(late_scenario).contacts(np.array([6.0, 4.0, 0.0, 1.5708]))
    assert "person[2] '2'" in {c.other for c in contacts}


def test_the_figure_does_not_draw_a_person_before_they_enter(late_scenario):
    ax = Figure().add_subplot()
    out = draw_world(ax, late_scenario)
    centres = sorted(tuple(round(v, 9) for v in body.center) for body in out["people"])
    assert centres == [(4.0, 3.8), (6.0, 4.0)]
