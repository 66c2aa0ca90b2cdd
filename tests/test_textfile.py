"""Every user file (scenario, sweep, --path CSV) is read by one guarded reader.

Non-regular files are refused by name without being opened for reading (a
FIFO would block, /dev/zero never ends), files over the size limit are
refused with the limit stated, and bytes that are not UTF-8 are named.
"""

from __future__ import annotations

import os
import signal
import socket
import stat
from pathlib import Path

import numpy as np
import pytest

from drake_social.cli import main
from drake_social.experiments.study import load_sweep
from drake_social.scenario import ScenarioError, load_scenario
from drake_social.io.textfile import MAX_PATH_FILE_BYTES, MAX_YAML_FILE_BYTES, read_text_file

TINY = Path(__file__).resolve().parent / ".." / "scenarios" / "tiny.yaml"


@pytest.fixture(autouse=True)
def _deadline():
    """Fails a test that blocks (reading a FIFO with no writer) instead of hanging the suite."""

    def expire(signum, frame):
        raise TimeoutError("blocked for 20 s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.alarm(20)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, previous)


@pytest.fixture
def fifo(tmp_path) -> Path:
    path = tmp_path / "pipe.yaml"
    os.mkfifo(path)
    return path


@pytest.fixture
def unix_socket(tmp_path):
    path = tmp_path / "sock.yaml"
    s = socket.socket(socket.AF_UNIX)
    s.bind(str(path))
    yield path
    s.close()


def _cli(capsys, argv) -> tuple[int, str]:
    code = main(argv)
    return code, capsys.readouterr().err


def _not_regular(path, kind: str, what: str, option: str = "") -> str:
    return f"{path}: not a regular file ({kind}); a {what} file must be a regular file" + (f" ({option})" if option
                                                                                          else "")


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/null", "/dev/urandom"])
def test_a_character_device_is_refused_everywhere(tmp_path, capsys, device):
    code, err = _cli(capsys, ["simulate", str(TINY), "--path", device, "--no-replay", "--out", str(tmp_path / "o")])
    assert (code, err) == (2, f"drake-social: error: {_not_regular(device, 'a character device', 'path', '--path')}\n")
    code, err = _cli(capsys, ["show", device, "--out", str(tmp_path / "o")])
    assert (code, err) == (2, f"drake-social: error: {_not_regular(device, 'a character device', 'scenario')}\n")
    code, err = _cli(capsys, ["experiment", "sweep", device, "--out", str(tmp_path / "o")])
    assert (code, err) == (2, f"drake-social: error: {_not_regular(device, 'a character device', 'sweep')}\n")
    assert not (tmp_path / "o").exists()


def test_a_fifo_is_refused_without_blocking(tmp_path, capsys, fifo):
    code, err = _cli(capsys, ["simulate", str(TINY), "--path", str(fifo), "--no-replay", "--out", str(tmp_path / "o")])
    assert (code, err) == (2, f"drake-social: error: {_not_regular(fifo, 'a FIFO', 'path', '--path')}\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(fifo)
    assert str(info.value) == _not_regular(fifo, "a FIFO", "scenario")
    with pytest.raises(ScenarioError) as info:
        load_sweep(fifo)
    assert str(info.value) == _not_regular(fifo, "a FIFO", "sweep")


def test_a_socket_and_a_directory_are_named(tmp_path, unix_socket):
    with pytest.raises(ScenarioError) as info:
        load_scenario(unix_socket)
    assert str(info.value) == _not_regular(unix_socket, "a socket", "scenario")
    with pytest.raises(ScenarioError) as info:
        load_sweep(tmp_path)
    assert str(info.value) == f"{tmp_path}: is a directory, not a sweep file"


def test_a_fifo_or_device_listed_in_a_sweep_names_the_sweep_and_the_entry(tmp_path, fifo):
    sweep = tmp_path / "s.yaml"
    sweep.write_text(f"scenarios: [{TINY}, {fifo.name}, /dev/zero]\n")
    with pytest.raises(ScenarioError) as info:
        load_sweep(sweep)
    assert str(info.value) == f"{sweep}: line 1: scenarios[1]: {_not_regular(fifo, 'a FIFO', 'scenario')}"
    sweep.write_text(f"scenarios: [{TINY}, /dev/zero]\n")
    with pytest.raises(ScenarioError) as info:
        load_sweep(sweep)
    assert str(info.value) == (f"{sweep}: line 1: scenarios[1]: "
                               f"{_not_regular('/dev/zero', 'a character device', 'scenario')}")


def test_a_symbolic_link_to_a_device_is_refused(tmp_path):
    link = tmp_path / "zero.yaml"
    link.symlink_to("/dev/zero")
    with pytest.raises(ScenarioError) as info:
        load_scenario(link)
    assert str(info.value) == _not_regular(link, "a character device", "scenario")


def test_files_over_the_limit_are_refused_before_reading(tmp_path, capsys):
    big = tmp_path / "big.csv"
    with open(big, "wb") as f:  # sparse: no disk space used
        f.truncate(MAX_PATH_FILE_BYTES + 1)
    code, err = _cli(capsys, ["simulate", str(TINY), "--path", str(big), "--no-replay", "--out", str(tmp_path / "o")])
    assert (code, err) == (2, f"drake-social: error: {big}: {MAX_PATH_FILE_BYTES + 1:,} bytes; a path file may have "
                              f"at most {MAX_PATH_FILE_BYTES:,} bytes (--path)\n")
    scenario = tmp_path / "big.yaml"
    scenario.write_text(TINY.read_text() + "#" * MAX_YAML_FILE_BYTES)
    size = scenario.stat().st_size
    with pytest.raises(ScenarioError) as info:
        load_scenario(scenario)
    assert str(info.value) == f"{scenario}: {size:,} bytes; a scenario file may have at most 4,194,304 bytes"
    with pytest.raises(ScenarioError) as info:
        load_sweep(scenario)
    assert str(info.value) == f"{scenario}: {size:,} bytes; a sweep file may have at most 4,194,304 bytes"


def test_a_file_at_the_limit_is_read_whole(tmp_path):
    path = tmp_path / "exact.txt"
    path.write_bytes(b"a" * 1000)
    assert read_text_file(path, "path", limit=1000) == "a" * 1000
    with pytest.raises(ScenarioError, match="1,001 bytes; a path file may have at most 1,000 bytes"):
        path.write_bytes(b"a" * 1001)
        read_text_file(path, "path", limit=1000)


def test_bytes_that_are_not_utf8_are_named(tmp_path, capsys):
    path = tmp_path / "latin1.csv"
    path.write_bytes(b"x,y,psi1,psi2\n1.0,2.5,0,1.5708\xe9\n")
    code, err = _cli(capsys, ["simulate", str(TINY), "--path", str(path), "--no-replay", "--out", str(tmp_path / "o")])
    assert (code, err) == (2, f"drake-social: error: {path}: not a text (UTF-8) file: byte 30 (b'\\xe9') is not valid "
                              f"UTF-8 (--path)\n")


def test_a_missing_file_and_an_unreadable_one(tmp_path):
    with pytest.raises(ScenarioError) as info:
        load_scenario(tmp_path / "none.yaml")
    assert str(info.value) == f"{tmp_path / 'none.yaml'}: no such scenario file"
    (tmp_path / "plain.txt").write_text("")
    with pytest.raises(ScenarioError) as info:
        load_scenario(tmp_path / "plain.txt" / "below.yaml")  # a parent that is not a folder
    assert str(info.value) == f"{tmp_path / 'plain.txt' / 'below.yaml'}: no such scenario file"
    if os.geteuid() != 0:  # root reads anything
        locked = tmp_path / "locked.yaml"
        locked.write_text(TINY.read_text())
        locked.chmod(0)
        with pytest.raises(ScenarioError, match="cannot be read"):
            load_scenario(locked)
        locked.chmod(stat.S_IRUSR | stat.S_IWUSR)


def test_a_nul_or_empty_file_name_is_refused_by_name():
    from drake_social.scenario import load_scenario

    with pytest.raises(ScenarioError) as info:
        load_scenario("a\0b.yaml")
    assert str(info.value) == "'a\\x00b.yaml': not a valid file name (embedded null byte)"
    with pytest.raises(ScenarioError) as info:
        load_scenario("")
    assert str(info.value) == "'': an empty file name; a scenario file is needed"


def test_replace_file_leaves_the_old_file_or_the_whole_new_one(tmp_path):
    from drake_social.io.textfile import replace_file

    path = tmp_path / "a.txt"
    path.write_text("old")

    def fail(f):
        f.write(b"half")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        replace_file(path, fail)
    assert path.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"]
    assert replace_file(path, lambda f: f.write(b"new")) == path
    assert path.read_text() == "new" and sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"]
    assert path.stat().st_mode & 0o777 == 0o666 & ~_umask()


def _umask() -> int:
    import os

    mask = os.umask(0)
    os.umask(mask)
    return mask


# ---- a single file written is never put in place of a directory, FIFO or device (issue 29, item 10)


def _in_the_way(tmp_path, kind: str):
    """A ``kind`` ("directory", "fifo", "device", "link to fifo") at ``tmp_path / "out.yaml"``, and its description."""
    import os
    import stat

    path = tmp_path / "out.yaml"
    if kind == "directory":
        path.mkdir()
        return path, "a directory", stat.S_ISDIR
    if kind == "device":
        try:
            os.mknod(path, 0o600 | stat.S_IFCHR, os.makedev(1, 3))  # /dev/null's numbers, in the test's folder
        except PermissionError:
            pytest.skip("making a device node needs privileges")
        return path, "a character device", stat.S_ISCHR
    fifo = tmp_path / "fifo" if kind == "link to fifo" else path
    os.mkfifo(fifo)
    if kind == "link to fifo":
        path.symlink_to(fifo)
    return path, "a FIFO", stat.S_ISFIFO


NOT_REGULAR = ["directory", "fifo", "device", "link to fifo"]


@pytest.mark.parametrize("kind", NOT_REGULAR)
def test_replace_file_refuses_what_is_not_a_regular_file(tmp_path, kind):
    import os

    from drake_social.io.textfile import replace_file

    dut, what, is_kind = _in_the_way(tmp_path, kind)
    before = sorted(os.listdir(tmp_path))
    written = []
    with pytest.raises(ScenarioError) as info:
        replace_file(dut, written.append, "--out")
    assert str(info.value) == f"{dut}: --out: must name a regular file (it is replaced) or a new file, got {what}"
    assert written == [] and is_kind(os.stat(dut).st_mode) and sorted(os.listdir(tmp_path)) == before


def test_replace_file_refuses_a_fifo_put_in_place_while_it_writes(tmp_path):
    import os
    import stat

    from drake_social.io.textfile import replace_file

    dut = tmp_path / "a.csv"

    def swap(f):
        f.write(b"new")
        os.mkfifo(dut)

    with pytest.raises(ScenarioError, match="got a FIFO$"):
        replace_file(dut, swap)
    assert stat.S_ISFIFO(os.stat(dut).st_mode) and sorted(os.listdir(tmp_path)) == ["a.csv"]


@pytest.mark.parametrize("kind", NOT_REGULAR)
def test_people_import_and_map_scenario_refuse_an_out_that_is_not_a_regular_file(tmp_path, capsys, kind):
    import os

    from drake_social.cli import main
    from drake_social.maps import write_map

    dut, what, is_kind = _in_the_way(tmp_path, kind)
    recording = tmp_path / "rec.txt"
    recording.write_text("0 1 1.0 1.0\n10 1 2.0 1.0\n")
    grid = np.full((20, 20), 254, np.uint8)  # all free
    (tmp_path / "map").mkdir()
    room = write_map(tmp_path / "map", "room", grid, 0.5, (0.0, 0.0, 0.0))
    before = sorted(os.listdir(tmp_path))
    for argv in (["people", "import", str(recording), "--out", str(dut)],
                 ["map", "scenario", str(room), "--start", "2", "5", "--goal", "8", "5", "--out", str(dut)],
                 ["map", "scenario", str(room), "--start", "2", "5", "--goal", "8", "5", "--out", str(dut), "--force"]):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err == (f"drake-social: error: {dut}: --out: must name a regular file (it is replaced) or a new file, "
                       f"got {what}\n"), argv
        assert is_kind(os.stat(dut).st_mode) and sorted(os.listdir(tmp_path)) == before
