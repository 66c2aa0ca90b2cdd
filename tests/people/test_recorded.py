"""Recorded people (``people_file``) against hand values, and the file's errors."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from drake_social.people import people_model
from drake_social.people.recorded import RecordedPeople
from drake_social.people.tracks import TURN_RATE
from drake_social.scenario import ScenarioError, load_scenario
from drake_social.scenario.people_file import MAX_PEOPLE_FILE_BYTES, read_people_file

TINY = Path(__file__).resolve().parents[2] / "scenarios" / "tiny.yaml"

# Rows in any order; id 7 walks east then north between t = 1 and t = 5, id 3 stands
# from t = 0 to t = 2; the v column is ignored.
MOVING = """t,id,x,y,v
3,7,4,1,9
0,3,6,3,9
1,7,2,1,9
5,7,4,3,9
2,3,6,3,9
"""


# MOVING 1 m further north, for tiny's room: MOVING's leg (2, 1) -> (4, 1) of id 7
# passes through tiny's desk (x 3.2..4.8, y 0.2..1.0), which a scenario refuses.
IN_ROOM = """t,id,x,y,v
3,7,4,2,9
0,3,6,4,9
1,7,2,2,9
5,7,4,4,9
2,3,6,4,9
"""


def _write(tmp_path: Path, text: str, name: str = "people.csv") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _model(tmp_path: Path, text: str, ids=None) -> RecordedPeople:
    return RecordedPeople(read_people_file(_write(tmp_path, text)), ids)


@pytest.mark.parametrize("t, present, p7, v7", [
    (0.5, (True, False), (2, 1), (0, 0)),     # 7 has not entered: first pose, absent
    (1.0, (True, True), (2, 1), (1, 0)),
    (2.0, (True, True), (3, 1), (1, 0)),
    (2.5, (False, True), (3.5, 1), (1, 0)),   # 3 has left at t = 2
    (4.0, (False, True), (4, 2), (0, 1)),
    (5.0, (False, True), (4, 3), (0, 0)),
    (5.5, (False, False), (4, 3), (0, 0)),
])
def test_positions_velocities_and_presence_at_hand_chosen_times(tmp_path, t, present, p7, v7):
    model = _model(tmp_path, MOVING)
    s = model.state_at(t)
    assert s.names == ("3", "7") and tuple(s.present) == present
    np.testing.assert_allclose(s.positions, [[6, 3], p7], atol=1e-12)
    np.testing.assert_allclose(s.velocities[1], v7, atol=1e-12)
    assert not s.velocities[0].any() and (s.radii == 0.25).all()
    assert s.visible().names == tuple(n for n, k in zip(("3", "7"), present) if k)


def test_heading_without_theta_follows_the_motion_at_the_bounded_rate(tmp_path):
    model = _model(tmp_path, MOVING)
    # 7 starts facing its first motion (east, 0); at the corner (t = 3) it turns north at pi rad/s.
    for t, h in ((0.0, 0.0), (2.0, 0.0), (3.0, 0.0), (3.25, math.pi / 4), (3.5, math.pi / 2), (9.0, math.pi / 2)):
        assert model.state_at(t).headings[1] == pytest.approx(h, abs=1e-12)
    assert model.state_at(1.0).headings[0] == 0.0  # 3 never moves
    h = np.array([model.state_at(k * 1e-3).headings[1] for k in range(6000)])
    assert np.abs(np.diff(h)).max() <= TURN_RATE * 1e-3 + 1e-9


def test_theta_is_interpolated_the_shorter_way_and_ids_are_chosen(tmp_path):
    text = "id,t,x,y,theta,radius\na,0,1,1,3.0,0.3\na,1,2,1,-3.0,0.3\nb,0,5,5,0,0.2\nb,4,5,1,1,0.2\n"
    model = _model(tmp_path, text, ids=["b", "a"])
    s = model.state_at(0.5)
    assert s.names == ("b", "a") and list(s.radii) == [0.2, 0.3]
    # From 3.0 to -3.0 the shorter way passes pi: halfway is 3.0 + (2 pi - 6) / 2.
    assert s.headings[1] == pytest.approx(3.0 + (2 * math.pi - 6.0) / 2, abs=1e-12)
    assert s.headings[0] == pytest.approx(0.125, abs=1e-12)
    np.testing.assert_allclose(s.velocities, [[0, -1], [1, 0]], atol=1e-12)
    with pytest.raises(ValueError, match="not in"):
        _model(tmp_path, text, ids=["c"])


def _error(tmp_path: Path, text: str) -> str:
    path = _write(tmp_path, text)
    with pytest.raises(ScenarioError) as info:
        read_people_file(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ")
    return message[len(str(path)) + 2:]


@pytest.mark.parametrize("text, message", [
    ("", "empty; a people file needs a header (t,id,x,y (required) and theta, radius, v (optional), in any order) "
         "and a row per person and time"),
    ("\n\n", "empty; a people file needs a header (t,id,x,y (required) and theta, radius, v (optional), in any "
             "order) and a row per person and time"),
    ("0,1,2,3\n1,1,2,3\n", "line 1: no header; the first line must name the columns: t,id,x,y (required) and "
                           "theta, radius, v (optional), in any order"),
    ("t,id,x,y,speed\n", "line 1: unknown column 'speed'; allowed: t,id,x,y (required) and theta, radius, v "
                         "(optional), in any order"),
    ("t,id,x,x\n", "line 1: column 'x' twice; each column once: t,id,x,y (required) and theta, radius, v "
                   "(optional), in any order"),
    ("t,id,x\n0,a,1\n", "line 1: no column y; the header needs t,id,x,y (required) and theta, radius, v "
                        "(optional), in any order"),
    ("t,id,x,y\n", "no rows after the header; a people file needs a row per person and time"),
    ("t,id,x,y\n0,a,1,2\n1,a,1\n", "line 3: 3 fields; every row needs 4, one per column of the header (t,id,x,y)"),
    ("t,id,x,y\n0,a,1,2\n1,a,1,2,5\n", "line 3: 5 fields; every row needs 4, one per column of the header "
                                       "(t,id,x,y)"),
    ("t,id,x,y\n0,a,one,2\n", "line 2: x: must be a number, got 'one'"),
    ("t,id,x,y\n0,a,1,nan\n", "line 2: y: must be a finite number, got nan"),
    ("t,id,x,y\ninf,a,1,2\n", "line 2: t: must be a finite number, got inf"),
    ("t,id,x,y,theta\n0,a,1,2,\n", "line 2: theta: must be a number, got ''"),
    ("t,id,x,y\n0,,1,2\n", "line 2: empty id; every row needs the id of its person"),
    ("t,id,x,y\n0,a,1,2\n1,b,1,2\n0.0,a,3,2\n", "line 4: id 'a' at t = 0 s again (first at line 2); one row per id "
                                                "and time"),
    ("t,id,x,y,radius\n0,a,1,2,0\n", "line 2: radius: must be > 0 metres, got 0"),
    ("t,id,x,y,radius\n0,a,1,2,0.25\n1,a,1,2,0.3\n", "line 3: radius: id 'a' has radius 0.3 here and 0.25 at "
                                                     "line 2; one radius per id"),
])
def test_each_bad_file_names_the_file_the_line_and_what_is_allowed(tmp_path, text, message):
    assert _error(tmp_path, text) == message


def test_a_missing_or_oversized_file_is_refused(tmp_path):
    with pytest.raises(ScenarioError, match="no such people file"):
        read_people_file(tmp_path / "none.csv")
    big = tmp_path / "big.csv"
    with open(big, "wb") as f:
        f.truncate(MAX_PEOPLE_FILE_BYTES + 1)
    with pytest.raises(ScenarioError, match=f"a people file may have at most {MAX_PEOPLE_FILE_BYTES:,} bytes"):
        read_people_file(big)


def _scenario(tmp_path: Path, extra: str, csv: str | None = IN_ROOM) -> Path:
    folder = tmp_path / "room"
    folder.mkdir(exist_ok=True)
    if csv is not None:
        _write(folder, csv, "walkers.csv")
    path = folder / "s.yaml"
    path.write_text(TINY.read_text() + extra)
    return path


def test_the_file_is_resolved_against_the_scenarios_folder_and_read_by_people_model(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # not the scenario's folder
    scenario = load_scenario(_scenario(tmp_path, "people_file: walkers.csv\npeople_file_ids: ['7']\n"))
    assert scenario.people_file == str(tmp_path / "room" / "walkers.csv")
    s = people_model(scenario).state_at(4.0)
    # The tiny scenario's standing person, then id 7.
    assert s.names == ("standing", "7") and tuple(s.present) == (True, True)
    np.testing.assert_allclose(s.positions, [[4.0, 3.8], [4, 3]], atol=1e-12)


@pytest.mark.parametrize("extra, csv, message", [
    ("people_file: missing.csv\n", None, "people_file: {folder}/missing.csv: no such people file"),
    ("people_file: walkers.csv\n", "t,id,x,y\n0,a,1\n",
     "people_file: {folder}/walkers.csv: line 2: 3 fields; every row needs 4, one per column of the header "
     "(t,id,x,y)"),
    ("people_file: walkers.csv\npeople_file_ids: ['7', '8']\n", MOVING,
     "people_file_ids[1]: id '8' is not in {folder}/walkers.csv; its ids: 3, 7"),
    ("people_file_ids: ['7']\n", None, "people_file_ids: needs a people_file to choose from"),
    ("people_file: walkers.csv\n", "t,id,x,y\n0,a,4,0.6\n1,a,4,2\n",
     "people_file ({folder}/walkers.csv, line 2, id 'a'): the first sample (t = 0 s) at (4, 0.6) puts the body "
     "(radius 0.25 m) inside world.obstacles[0] (its centre is 0 m from the box); a person must start clear of "
     "the obstacles"),
    ("people_file: walkers.csv\n", "t,id,x,y\n-1,a,1,3.5\n1,a,1,1.5\n",
     "people_file ({folder}/walkers.csv, line 2, id 'a'): the position at t = 0 (1, 2.5) puts the body (radius "
     "0.25 m) into the robot's base at its start configuration [1.0, 2.5, 0.0, 1.5708] (overlap 0.6 m); a person "
     "must start clear of the robot"),
])
def test_a_bad_recording_fails_at_load_naming_the_field(tmp_path, extra, csv, message):
    path = _scenario(tmp_path, extra, csv)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(info.value) == f"{path}: " + message.format(folder=tmp_path / "room")


def test_text_resolves_against_the_working_directory_and_overrides_against_the_file(tmp_path, monkeypatch):
    from drake_social.scenario import load_scenario_text

    _write(tmp_path, IN_ROOM, "walkers.csv")
    monkeypatch.chdir(tmp_path)
    scenario = load_scenario_text(TINY.read_text() + "people_file: walkers.csv\n", "<text>")
    assert scenario.people_file == str(tmp_path / "walkers.csv")
    path = _scenario(tmp_path, "")  # room/s.yaml next to room/walkers.csv
    monkeypatch.chdir(tmp_path.parent)
    scenario = load_scenario(path, "people_file: walkers.csv")
    assert scenario.people_file == str(tmp_path / "room" / "walkers.csv")
    assert people_model(scenario).count == 3


def test_numeric_ids_sort_as_numbers_and_a_single_sample_is_present_only_then(tmp_path):
    model = _model(tmp_path, "t,id,x,y\n2,10,1,1\n0,9,3,3\n4,9,3,1\n")
    assert model.state_at(0.0).names == ("9", "10")  # numbers: 9 before 10
    for t, present in ((1.999, False), (2.0, True), (2.001, False)):
        s = model.state_at(t)
        assert bool(s.present[1]) is present
        np.testing.assert_allclose(s.positions[1], (1, 1), atol=0)
        assert not s.velocities[1].any()
    np.testing.assert_allclose(model.state_at(3.0).velocities[0], (0, -0.5), atol=1e-12)
    assert model.state_at(3.0).headings[0] == pytest.approx(-math.pi / 2, abs=1e-12)  # its first motion, south
    assert _model(tmp_path, "t,id,x,y\n0,b,0,0\n0,a10,0,0\n0,a9,0,0\n").state_at(0).names == ("a10", "a9", "b")
