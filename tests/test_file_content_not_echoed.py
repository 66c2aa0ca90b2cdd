"""Errors never repeat the text of a file the user (or a file of theirs) named.

A scenario may name any file the process can read as its ``world.map`` or
``people_file``, a map YAML any file as its ``image``, a sweep any file as
one of its ``scenarios``; the command line names a path CSV, a recording, a
map. Each is pointed here at a text file whose first line holds a secret (a
password-file line, a YAML or INI or CSV line, a line YAML or Pillow cannot
parse, ...), named by an absolute path, a ``../`` path and a symbolic link:
the message names the file and the field, stays one line and never holds the
secret (:mod:`drake_social.io.textfile`).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from drake_social.app import run_people_import
from drake_social.cli import main
from drake_social.errors import ScenarioError
from drake_social.experiments.study.sweep import load_sweep
from drake_social.io.paths import parse_path_csv
from drake_social.maps import read_map
from drake_social.scenario import load_scenario
from drake_social.scenario.people_file import read_people_file

from conftest import SCENARIO_DIR

SECRET = "Zq7-s3cr3t-4xW"
#: Files whose first line holds the secret, in the shapes each reader parses
#: or trips on: name -> text.
SECRET_FILES = {
    "passwd": f"root:x:0:0:{SECRET}:/root:/bin/bash\ndaemon:x:1:1::/usr/sbin:/usr/sbin/nologin\n",
    "word": f"{SECRET}\n",
    "yaml_mapping": f"{SECRET}: value\nother: 1\n",
    "yaml_error": f"{SECRET}: a: b\n",
    "ini": f"[{SECRET}]\ntoken = abc\n",
    "csv": f"{SECRET},1,2,3\n4,5,6,7\n",
    "columns": f"{SECRET} 1 2 3\n",
    "tag": f"!{SECRET} x\n",
    "alias": f"*{SECRET}\n",
    "anchor": f"&{SECRET} a: b: c\n",
    "json": f'{{"{SECRET}": 1}}\n',
    "quote": f'"{SECRET}\n',
    "list": f"- {SECRET}\n",
    "tab": f"\t{SECRET}\n",
    "ascii_pgm": f"P2\n{SECRET}\n",
    "url": f"https://user:{SECRET}@example.com\n",
}
MAP_KEYS = "resolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
TINY = (SCENARIO_DIR / "tiny.yaml").read_text()
TINY_BOUNDS = "world:\n  bounds: [0.0, 0.0, 8.0, 5.0]\n"
TINY_PERSON = '  - {x: 4.0, y: 3.8, theta: -1.5708, radius: 0.25, name: "standing"}  # faces south\n'


@pytest.fixture(params=["absolute", "parent", "symlink"])
def named(request, tmp_path, monkeypatch):
    """A factory: ``named(text)`` writes a secret file and returns how the
    files in ``work/`` (the working folder) name it, and the name's last part."""
    work, elsewhere = tmp_path / "work", tmp_path / "elsewhere"
    work.mkdir()
    elsewhere.mkdir()
    monkeypatch.chdir(work)

    def make(text: str) -> tuple[str, str]:
        secret = elsewhere / "secret.txt"
        secret.write_text(text)
        if request.param == "absolute":
            return str(secret), "secret.txt"
        if request.param == "parent":
            return "../elsewhere/secret.txt", "secret.txt"
        (work / "link.txt").symlink_to(secret)
        return "link.txt", "link.txt"

    return make


def _scenario_with(work: Path, *, map_name: str | None = None, people_file: str | None = None) -> Path:
    text = TINY
    if map_name is not None:
        text = text.replace(TINY_BOUNDS, f"world:\n  map: {map_name}\n")
    if people_file is not None:
        text = text.replace("people:\n" + TINY_PERSON, f"people_file: {people_file}\n")
    assert text != TINY
    path = work / "scenario.yaml"
    path.write_text(text)
    return path


def _map_with_image(work: Path, image: str) -> Path:
    path = work / "map.yaml"
    path.write_text(f"image: {image}\n{MAP_KEYS}")
    return path


def _sweep_with(work: Path, scenario: str) -> Path:
    path = work / "sweep.yaml"
    path.write_text(f"runs: 1\niterations: 20\nscenarios: [{scenario}]\n")
    return path


def _refused(call, *words: str) -> str:
    with pytest.raises(ScenarioError) as info:
        call()
    message = str(info.value)
    assert SECRET not in message, message
    assert SECRET[:6] not in message and SECRET[-6:] not in message, message
    assert "\n" not in message, message
    for word in words:
        assert word in message, (word, message)
    return message


#: Reader -> (how it reads the named file from the working folder, the words its message must hold).
READERS = {
    "people_file": (lambda name: load_scenario(_scenario_with(Path.cwd(), people_file=name)),
                    ("scenario.yaml: ", "people_file: ")),
    "world.map": (lambda name: load_scenario(_scenario_with(Path.cwd(), map_name=name)),
                  ("scenario.yaml: ", "world.map: ")),
    "world.map image": (lambda name: load_scenario(_scenario_with(Path.cwd(), map_name=str(_map_with_image(
        Path.cwd(), name)))), ("scenario.yaml: ", "world.map: ", "map.yaml: image: ")),
    "map image": (lambda name: read_map(_map_with_image(Path.cwd(), name)), ("map.yaml: image: ",)),
    "map": (lambda name: read_map(name), ()),
    "people file": (lambda name: read_people_file(name), ()),
    "sweep scenarios": (lambda name: load_sweep(_sweep_with(Path.cwd(), name)), ("sweep.yaml: ", "scenarios[0]: ")),
    "path CSV": (lambda name: parse_path_csv(name), ("(--path)",)),
    "recording": (lambda name: run_people_import(file=name, out=Path.cwd() / "people.csv"), ()),
}


@pytest.mark.parametrize("reader", list(READERS))
@pytest.mark.parametrize("shape", list(SECRET_FILES))
def test_a_named_file_is_refused_without_repeating_its_text(named, reader, shape):
    name, last = named(SECRET_FILES[shape])
    read, words = READERS[reader]
    _refused(lambda: read(name), last, *words)
    assert not (Path.cwd() / "people.csv").exists()


def _cli_refused(capsys, argv: list[str], *words: str) -> None:
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert SECRET not in captured.out + captured.err, captured
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("drake-social: error: "), captured.err
    for word in words:
        assert word in lines[0], (word, lines[0])


@pytest.mark.parametrize("shape", ["passwd", "yaml_mapping", "csv", "ascii_pgm"])
def test_the_command_line_never_prints_a_named_files_text(named, capsys, shape):
    name, last = named(SECRET_FILES[shape])
    work = Path.cwd()
    out = ["--out", str(work / "out")]
    _cli_refused(capsys, ["show", str(_scenario_with(work, people_file=name)), *out], last, "people_file: ")
    _cli_refused(capsys, ["show", str(_scenario_with(work, map_name=name)), *out], last, "world.map: ")
    _cli_refused(capsys, ["plan", str(_scenario_with(work, map_name=str(_map_with_image(work, name)))), *out],
                 last, "world.map: ", "image: ")
    _cli_refused(capsys, ["simulate", str(SCENARIO_DIR / "tiny.yaml"), "--path", name, *out], last, "(--path)")
    _cli_refused(capsys, ["people", "import", name, "--out", str(work / "people.csv")], last)
    _cli_refused(capsys, ["map", "inspect", name, *out], last)
    _cli_refused(capsys, ["map", "inspect", str(_map_with_image(work, name)), *out], last, "image: ")
    _cli_refused(capsys, ["map", "scenario", name, "--start", "1", "1", "--goal", "2", "2", "--out",
                          str(work / "s.yaml")], last)
    _cli_refused(capsys, ["experiment", "sweep", str(_sweep_with(work, name)), *out], last, "scenarios[0]: ")
    _cli_refused(capsys, ["experiment", "crowd", "--scenarios", name, *out], last)
    assert sorted(os.listdir(work)) == sorted(n for n in ("map.yaml", "scenario.yaml", "sweep.yaml", "link.txt")
                                              if (work / n).exists())


def test_a_file_of_its_kind_still_has_its_mistakes_quoted(tmp_path):
    """Once a file shows it is of its kind, a mistake in it is quoted as before."""
    scenario = tmp_path / "s.yaml"
    scenario.write_text(TINY + "plannr: {}\n")
    assert "plannr: unknown field at the top level" in _refused(lambda: load_scenario(scenario))
    people = tmp_path / "p.csv"
    people.write_text("t,id,x,y,speed\n0,a,1,1,0\n")
    assert "unknown column 'speed'" in _refused(lambda: read_people_file(people))
    people.write_text("t,id,x,y\nsoon,a,1,1\n")
    assert "t: must be a number, got 'soon'" in _refused(lambda: read_people_file(people))
    path = tmp_path / "p2.csv"
    path.write_text("x,y,psi1,psi2\n1,2,3,four\n")
    assert "psi2: must be a finite number, got 'four'" in _refused(lambda: parse_path_csv(path))
    grid = tmp_path / "m.yaml"
    grid.write_text(f"image: m.pgm\n{MAP_KEYS}colour: 1\n")
    assert "unknown key 'colour'" in _refused(lambda: read_map(grid))


@pytest.mark.parametrize("text, message", [
    ("- a\n", "line 1: not a scenario file: a scenario is a mapping (description, world, "),
    ("a\n", "got text"),
    ("3\n", "got a number"),
    ("!Foo {a: 1}\n", "got a mapping with a tag"),
    ("x: 1\ny: 2\n", "line 1: not a scenario file: none of its 2 top-level keys is a field of a scenario "
                     "(description, world, "),
])
def test_a_file_that_is_not_a_scenario_is_described(tmp_path, text, message):
    dut = tmp_path / "s.yaml"
    dut.write_text(text)
    assert message in _refused(lambda: load_scenario(dut), f"{dut}: ")


@pytest.mark.parametrize("text, message", [
    ("a: b: c\n", "not valid YAML: line 1, column 5: mapping values are not allowed here"),
    ('description: "abc\n', "not valid YAML: line 2, column 1: found unexpected end of stream (while scanning a "
                           "quoted scalar at line 1, column 14)"),
    ("description: *name\n", "not valid YAML: line 1, column 14: found undefined alias"),
    ("\tdescription: x\n", "not valid YAML: line 1, column 1: found character '\\t' that cannot start any token"),
])
def test_a_yaml_error_names_line_and_column_without_the_text(tmp_path, text, message):
    dut = tmp_path / "s.yaml"
    dut.write_text(text)
    assert message in _refused(lambda: load_scenario(dut), f"{dut}: ")
