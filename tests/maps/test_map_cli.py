"""``drake-social map inspect`` and ``map scenario``: from a map to a first plan."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from drake_social.cli import main
from drake_social.map_tools import CARRYING_ARM, inspect_map, map_scenario_text
from drake_social.maps import write_map
from drake_social.scenario import load_scenario

from maps.test_map_scenario import RESOLUTION, room_image


@pytest.fixture
def room_map(tmp_path):
    return write_map(tmp_path, "room", room_image(), RESOLUTION, (1.0, -2.0, 0.0))


def test_inspect_prints_the_grid_and_counts_and_draws_the_map(room_map, tmp_path, capsys):
    assert main(["map", "inspect", str(room_map), "--out", str(tmp_path / "out")]) == 0
    text = capsys.readouterr().out
    assert "20 x 12 cells of 0.5 m = 10 x 6 m, origin (1, -2, yaw 0)" in text
    assert "extent    x 1 .. 11, y -2 .. 4 m" in text
    # 240 cells: the wall 9 x 2 = 18 occupied, the top row 20 unknown, the rest free.
    assert "occupied 18 (7.5 %), free 202 (84.2 %), unknown 20 (8.3 %)" in text
    assert "boxes     2 (unknown cells as obstacle" in text
    with Image.open(tmp_path / "out" / "map.png") as png:
        assert png.size[0] > 600 and png.size[1] > 300


def test_inspect_counts_boxes_with_unknown_cells_free(room_map):
    summary = inspect_map(room_map, unknown="free")
    assert summary.boxes == 1 and summary.picture is None and summary.unknown == 20


def test_scenario_writes_a_loadable_scenario_naming_the_map_relatively(room_map, tmp_path, capsys):
    out = tmp_path / "scenarios" / "room.yaml"
    assert main(["map", "scenario", str(room_map), "--start", "2.5", "0", "--goal", "9", "0", "--out", str(out)]) == 0
    assert "next: drake-social plan" in capsys.readouterr().out
    scenario = load_scenario(out)
    assert "map: \"../room.yaml\"" in out.read_text()
    assert scenario.world.map == str(room_map)
    assert scenario.world.bounds == [1.0, -2.0, 11.0, 4.0]
    np.testing.assert_array_equal(scenario.start, [2.5, 0.0, *CARRYING_ARM])
    np.testing.assert_array_equal(scenario.goal, [9.0, 0.0, *CARRYING_ARM])
    # A second run does not replace it unless forced.
    assert main(["map", "scenario", str(room_map), "--start", "2.5", "0", "--goal", "9", "0", "--out", str(out)]) == 2
    assert "exists; pass --force" in capsys.readouterr().err
    assert main(["map", "scenario", str(room_map), "--start", "2.5", "1", "--goal", "9", "0", "--out", str(out),
                 "--force"]) == 0
    assert load_scenario(out).start[1] == 1.0


@pytest.mark.parametrize("start, goal, words", [
    (["5.5", "0"], ["9", "0"], ["--start: the base centre (5.5, 0) lies in an occupied cell"]),
    (["2.5", "0"], ["9", "3.8"], ["--goal: the base centre (9, 3.8) lies in an unknown cell"]),
    # The base is free, the bar (x - 0.55 .. x + 0.95) reaches the wall at x = 5 .. 6.
    (["4.3", "0"], ["9", "0"], ["--start: configuration", "is in collision", "map[", "--arm PSI1 PSI2"]),
])
def test_scenario_refuses_a_blocked_start_or_goal(room_map, tmp_path, capsys, start, goal, words):
    out = tmp_path / "s.yaml"
    assert main(["map", "scenario", str(room_map), "--start", *start, "--goal", *goal, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    for word in words:
        assert word in err
    assert not out.exists()


@pytest.mark.parametrize("extra, words", [
    (["--arm", "100", "0"], ["--arm: psi1 = 100.0 is outside the joint range"]),
    (["--arm", "0", "-4"], ["--arm: psi2 = -4.0 is outside the joint range"]),
    (["--goal", "2.5", "0"], ["--goal: must differ from start"]),
    (["--goal", "40", "0"], ["--goal: position (40.0, 0.0) is outside world.bounds"]),
])
def test_scenario_names_the_option_of_a_refused_field(room_map, tmp_path, capsys, extra, words):
    """The scenario file is not written when it is refused: the error names
    the option the field came from, never the file or its field (start[2])."""
    out = tmp_path / "s.yaml"
    argv = ["map", "scenario", str(room_map), "--start", "2.5", "0", "--goal", "9", "0", "--out", str(out), *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("drake-social: error: --")
    for word in words:
        assert word in err
    assert str(out) not in err and "start[" not in err and "goal[" not in err
    assert not out.exists()


def test_a_field_without_an_option_is_named_with_the_file_not_written():
    from drake_social.map_tools import OPTION_OF_FIELD, _as_option_error

    assert _as_option_error("s.yaml: people[0]: too close", "s.yaml") == "s.yaml (not written): people[0]: too close"
    assert _as_option_error("s.yaml: world.map: m.yaml: resolution: bad", "s.yaml") == "m.yaml: resolution: bad"
    assert _as_option_error("s.yaml: start[3]: psi2 = 9", "s.yaml") == "--arm: psi2 = 9"
    assert _as_option_error("other: x: y", "s.yaml") == "other: x: y"
    assert {OPTION_OF_FIELD[f"{end}[{i}]"] for end in ("start", "goal") for i in (2, 3)} == {"--arm"}


def test_scenario_refuses_a_bad_map_naming_its_field(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("image: none.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\n"
                   "free_thresh: 0.2\n")
    assert main(["map", "scenario", str(bad), "--start", "1", "1", "--goal", "2", "2", "--out",
                 str(tmp_path / "s.yaml")]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "image" in err and "none.pgm" in err


def test_scenario_text_quotes_names():
    text = map_scenario_text('my "lab".yaml', (1, 2), (3, 4))
    assert 'map: "my \\"lab\\".yaml"' in text and "start: [1.0, 2.0, -1.2292, 2.8]" in text


@pytest.mark.parametrize("argv, words", [
    (["map", "inspect", "{tmp}/none.yaml"], ["none.yaml", "no such"]),
    (["map", "scenario", "{map}", "--start", "2.5", "0", "--goal", "9", "0", "--out", "{tmp}/s.txt"],
     ["--out: the scenario file must end in .yaml or .yml"]),
    (["map", "scenario", "{map}", "--start", "nan", "0", "--goal", "9", "0", "--out", "{tmp}/s.yaml"],
     ["--start", "nan"]),
    (["map", "inspect", "{map}", "--unknown", "wall"], ["--unknown", "wall"]),
])
def test_bad_map_commands_exit_2_naming_the_input(room_map, tmp_path, capsys, argv, words):
    argv = [a.format(tmp=tmp_path, map=room_map) for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    for word in words:
        assert word in err
    assert not (tmp_path / "s.txt").exists() and not (tmp_path / "s.yaml").exists()
