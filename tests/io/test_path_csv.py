"""drake_social.io.paths: the path CSV round trip and its errors (and app.read_path_csv's check), the executed CSV."""

from __future__ import annotations

import numpy as np
import pytest

from drake_social.collision.geometric import GeometricChecker
from drake_social.app import read_path_csv
from drake_social.io.paths import EXECUTED_HEADER, PATH_HEADER, parse_path_csv, write_executed_csv, write_path_csv
from drake_social.limits import MAX_WAYPOINTS
from drake_social.scenario import ScenarioError


def _straight(scenario, n: int = 5) -> np.ndarray:
    """n waypoints on the straight line from start to goal (tiny's is free)."""
    start, goal = np.asarray(scenario.start, float), np.asarray(scenario.goal, float)
    return start + np.linspace(0.0, 1.0, n)[:, None] * (goal - start)


def test_a_written_path_reads_back_bit_for_bit(tmp_path, tiny_scenario):
    rng = np.random.default_rng(7)
    wp = _straight(tiny_scenario, 6)
    wp[1:-1] += rng.normal(scale=1e-3, size=(4, 4)) * np.array([1, 1, 0, 0])  # digits a 6-digit format would lose
    checker = GeometricChecker(tiny_scenario)
    assert checker.are_valid(wp).all() and checker.are_motions_valid(wp[:-1], wp[1:]).all()
    dut = tmp_path / "path.csv"
    write_path_csv(dut, wp)
    assert dut.read_text().splitlines()[0] == PATH_HEADER
    assert np.array_equal(read_path_csv(dut, tiny_scenario, checker), wp)
    rows, lines = parse_path_csv(dut)
    assert np.array_equal(rows, wp) and lines == [2, 3, 4, 5, 6, 7]


def test_crlf_a_byte_order_mark_and_blank_lines_are_read(tmp_path, tiny_scenario):
    wp = _straight(tiny_scenario, 3)
    text = "\ufeff" + "x, y, psi1, psi2\r\n" + "".join(",".join(repr(float(v)) for v in row) + "\r\n\r\n" for row in wp)
    dut = tmp_path / "path.csv"
    dut.write_text(text, encoding="utf-8")
    rows, lines = parse_path_csv(dut)
    assert np.array_equal(rows, wp) and lines == [2, 4, 6]


@pytest.mark.parametrize("body, message", [
    ("x,y,psi\n1,2,3\n", "line 1: the header must be 'x,y,psi1,psi2'"),
    ("x,y,psi1,psi2\n1,2,3\n4,5,6,7\n", "line 2: needs 4 numbers x,y,psi1,psi2, got 3 values"),
    ("x,y,psi1,psi2\n1,2,3,4\n1,nan,3,4\n", "line 3: y: must be a finite number, got 'nan'"),
    ("x,y,psi1,psi2\n1,2,3,4\n1,2,3,four\n", "line 3: psi2: must be a finite number, got 'four'"),
    ("x,y,psi1,psi2\n1,2,3,4\n", "needs at least 2 waypoints (start and goal), got 1"),
])
def test_a_malformed_file_is_refused_naming_the_line(tmp_path, body, message):
    dut = tmp_path / "bad.csv"
    dut.write_text(body)
    with pytest.raises(ScenarioError) as e:
        parse_path_csv(dut)
    assert str(e.value).startswith(f"{dut}: ") and message in str(e.value) and str(e.value).endswith("(--path)")


def test_one_row_too_many_is_refused_at_that_row(tmp_path):
    dut = tmp_path / "long.csv"
    dut.write_text(PATH_HEADER + "\n" + "1,2,3,4\n" * (MAX_WAYPOINTS + 1))
    with pytest.raises(ScenarioError, match=rf"line {MAX_WAYPOINTS + 2}: more than {MAX_WAYPOINTS:,} waypoints"):
        parse_path_csv(dut)


def test_a_path_not_from_the_start_is_refused_by_the_waypoint_check(tmp_path, tiny_scenario):
    wp = _straight(tiny_scenario, 3)
    wp[0, 0] += 0.01
    dut = tmp_path / "path.csv"
    write_path_csv(dut, wp)
    with pytest.raises(ScenarioError, match=r"path.csv \(--path\): line 2 \(waypoint 0\): the first waypoint"):
        read_path_csv(dut, tiny_scenario, GeometricChecker(tiny_scenario))


def test_the_executed_csv_holds_time_configuration_and_velocity(tmp_path):
    t = np.array([0.0, 0.1, 0.2])
    q = np.arange(12.0).reshape(3, 4) / 7.0
    v = -np.arange(12.0).reshape(3, 4) / 3.0
    dut = tmp_path / "executed.csv"
    write_executed_csv(dut, t, q, v)
    lines = dut.read_text().splitlines()
    assert lines[0] == EXECUTED_HEADER
    table = np.loadtxt(dut, delimiter=",", skiprows=1)
    assert np.array_equal(table, np.column_stack([t, q, v]))  # 17 digits: exact
    write_executed_csv(dut, [], np.zeros((0, 4)), np.zeros((0, 4)))
    assert dut.read_text() == EXECUTED_HEADER + "\n"
