"""Recorded tracks are checked between samples: the body disc swept along each
segment against the walls (world.bounds) and the obstacles, as scripted
trajectories are, naming the file and the line of the segment's end row."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from drake_social.people import people_model
from drake_social.scenario import ScenarioError, load_scenario
from drake_social.scenario.people_rules import segment_box_distance, segments_box_distances

TINY = Path(__file__).resolve().parents[2] / "scenarios" / "tiny.yaml"  # desk: x 3.2..4.8, y 0.2..1.0


def _load(tmp_path: Path, csv: str):
    (tmp_path / "walkers.csv").write_text(csv)
    path = tmp_path / "s.yaml"
    path.write_text(TINY.read_text() + "people_file: walkers.csv\n")
    return load_scenario(path)


def test_a_segment_through_the_desk_names_the_line_of_its_end_row(tmp_path):
    # id 1: every sample clear of the desk; the leg (6, 0.6) -> (2, 0.6) crosses it. Rows of ids interleaved.
    csv = "t,id,x,y\n0,1,6.0,1.5\n0,2,7.0,4.0\n2,1,6.0,0.6\n3,2,7.0,3.0\n6,1,2.0,0.6\n"
    with pytest.raises(ScenarioError, match=r"walkers\.csv, line 6, id '1'\): the segment from t = 2 s at "
                                            r"\(6, 0\.6\) \(line 4\) to t = 6 s at \(2, 0\.6\) passes through "
                                            r"world\.obstacles\[0\] \(the body's centre comes 0 m from it"):
        _load(tmp_path, csv)


@pytest.mark.parametrize("rows, line", [
    ("0,2,7.0,4.0\n3,2,7.9,4.0\n", 3),  # the body's edge reaches x = 8.15 > 8
    ("5,3,0.1,2.5\n", 2),               # a lone sample, half in the west wall
])
def test_a_segment_or_lone_sample_into_the_walls(tmp_path, rows, line):
    with pytest.raises(ScenarioError, match=rf"walkers\.csv, line {line}, id '\d'\): the (segment|sample).* takes "
                                            r"the body \(radius 0\.25 m\) out of world\.bounds \[0\.0, 0\.0, 8\.0, "
                                            r"5\.0\] into the walls"):
        _load(tmp_path, "t,id,x,y\n" + rows)


def test_a_track_passing_the_desk_at_more_than_its_radius_loads(tmp_path):
    # (2, 1.3) -> (6, 1.3): 0.3 m above the desk's top edge (y = 1.0), radius 0.25.
    scenario = _load(tmp_path, "t,id,x,y\n0,1,6.0,1.3\n4,1,2.0,1.3\n")
    np.testing.assert_allclose(people_model(scenario).state_at(2.0).positions[-1], [4.0, 1.3], atol=1e-12)


def test_many_segments_equal_one_at_a_time(rng):
    a, b = rng.uniform(-3, 3, (200, 2)), rng.uniform(-3, 3, (200, 2))
    b[:20] = a[:20]  # points
    centres, sizes, yaws = rng.uniform(-2, 2, (7, 2)), rng.uniform(0.2, 1.5, (7, 2)), rng.uniform(-3, 3, 7)
    many = segments_box_distances(a, b, centres, sizes, yaws)
    one = np.array([segment_box_distance(a[n], b[n], centres, sizes, yaws) for n in range(len(a))])
    np.testing.assert_allclose(many, one, rtol=0, atol=1e-15)


def test_a_ten_thousand_row_file_is_checked_quickly(tmp_path):
    # 100 ids x 100 samples walking east and west along y = 2.0 .. 4.5, clear of the desk and the walls.
    rows = ["t,id,x,y"]
    for i in range(100):
        y = 1.6 + 0.03 * i
        for k in range(100):
            rows.append(f"{10 + 0.4 * k:g},{i},{1.0 + 6.0 * abs((k % 20) - 10) / 10:g},{y:g}")
    csv = "\n".join(rows) + "\n"
    t0 = time.perf_counter()
    scenario = _load(tmp_path, csv)
    elapsed = time.perf_counter() - t0
    assert people_model(scenario).count == 101
    assert elapsed < 5.0, f"loading a 10,000-row people file took {elapsed:.2f} s"
