"""``people.csv`` (the project's writer) reads back as a ``people_file``:
quoted ids with commas, distinct ids, the same positions at the sample times."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drake_social.io.paths import write_people_csv
from drake_social.people import PeopleLog, people_model
from drake_social.people.log import person_ids
from drake_social.people.recorded import RecordedPeople
from drake_social.scenario import ScenarioError, load_scenario
from drake_social.scenario.people_file import DEFAULT_RADIUS, read_people_file

OFFICE = Path(__file__).resolve().parents[2] / "scenarios" / "office_walkers.yaml"


@pytest.mark.parametrize("names, ids", [
    (["", "0"], ["0", "1"]),             # the name "0" is person 0's index id
    (["", "0", "1"], ["0", "1", "2"]),   # giving way cascades: "1" is then person 1's id
    (["a", "a", "b"], ["0", "1", "b"]),  # a shared name gives way on both
    (["1", "0"], ["1", "0"]),            # names that are indices, but nobody takes an index
    (["2", "", "x"], ["2", "1", "x"]),
    (["x, y", 'say "hi"'], ["x, y", 'say "hi"']),
])
def test_person_ids_hand_cases(names, ids):
    assert person_ids(names) == ids


def test_person_ids_are_distinct_for_random_names(rng):
    pool = ["", "0", "1", "2", "3", "a", "b"]
    for _ in range(300):
        names = [pool[k] for k in rng.integers(0, len(pool), rng.integers(1, 7))]
        ids = person_ids(names)
        assert len(set(ids)) == len(ids), names
        assert all(i == n or i == str(k) for k, (i, n) in enumerate(zip(ids, names)))


def test_office_walkers_people_csv_reads_back_at_the_sample_times(tmp_path):
    model = people_model(load_scenario(OFFICE))
    times = np.arange(0.0, 30.0, 0.25)
    log = PeopleLog.sample(model, times)
    assert any("," in n for n in log.names)  # the file holds quoted ids
    path = tmp_path / "people.csv"
    write_people_csv(path, log)
    ids = person_ids(log.names)
    recording = read_people_file(path)
    assert sorted(recording.tracks) == sorted(ids)
    back = RecordedPeople(recording, ids)  # in the log's order
    assert back.count == log.count
    for k, t in enumerate(times):
        s = back.state_at(float(t))
        np.testing.assert_array_equal(s.present, log.present[k])
        np.testing.assert_allclose(s.positions, log.positions[k], rtol=0, atol=1e-12)
        turn = np.angle(np.exp(1j * (s.headings - log.headings[k])))
        np.testing.assert_allclose(turn, 0.0, atol=1e-12)
    # people.csv has no radius column: the recorded people read back with the default radius.
    np.testing.assert_array_equal(s.radii, DEFAULT_RADIUS)


def test_quoted_fields_keep_the_line_numbers_in_errors(tmp_path):
    path = tmp_path / "p.csv"
    path.write_text('t,id,x,y\n0,"a, b",1,2\n\n1,"a, b",x,2\n')
    with pytest.raises(ScenarioError, match=r"p\.csv: line 4: x: must be a number, got 'x'"):
        read_people_file(path)
    path.write_text('t,id,x,y\n0,"a, b",1,2\n1,"a, b,1,2\n')
    with pytest.raises(ScenarioError, match=r"p\.csv: line 3: not CSV"):
        read_people_file(path)
    path.write_text('t,id,x,y\n0,"a, b",1,2\n1,"a, b",2,2\n')
    track = read_people_file(path).tracks["a, b"]
    np.testing.assert_array_equal(track.positions, [[1, 2], [2, 2]])
    assert track.first_line == 2
