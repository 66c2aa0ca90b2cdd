"""drake_social.io.outputs: a command's files land as one set or not at all."""

from __future__ import annotations

import errno
import os
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import pytest

from drake_social.io import outputs as outputs_module
from drake_social.io.outputs import InterruptedAfterCommit, OutputBusyError, OutputSet, current_set


def _listing(folder: Path) -> dict[str, bytes]:
    """Visible files of ``folder`` and their bytes (hidden lock and manifest left out)."""
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if not p.name.startswith(".")}


def _hidden(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


def _tidy_hidden(folder: Path, command: str = "plan") -> list[str]:
    """The hidden entries of a folder holding one committed set of ``command``:
    its lock, manifest link, current link and the one generation it names."""
    generation = os.readlink(folder / f".{command}.current")
    assert generation.startswith(f".{command}.gen-")
    return sorted([f".{command}.current", generation, f".{command}.lock", f".{command}.manifest"])


def _write_set(folder: Path, files: dict[str, str], command: str = "plan") -> OutputSet:
    with OutputSet(folder, command) as dut:
        for name, text in files.items():
            dut.write_text(name, text)
    return dut


def test_a_new_set_replaces_the_previous_one_as_a_whole(tmp_path):
    _write_set(tmp_path, {"path.csv": "old", "path.png": "old png", "extra.png": "old extra"})
    (tmp_path / "notes.txt").write_text("the user's")  # not in any set: never touched
    dut = _write_set(tmp_path, {"path.csv": "new", "path.png": "new png"})
    assert _listing(tmp_path) == {"notes.txt": b"the user's", "path.csv": b"new", "path.png": b"new png"}
    assert dut.committed == [tmp_path / "path.csv", tmp_path / "path.png"]
    assert _hidden(tmp_path) == _tidy_hidden(tmp_path)  # the staging folder and the old generation are gone
    assert (tmp_path / ".plan.manifest").read_text() == "path.csv\npath.png\n"
    # Every file reads through the one link that a commit swaps.
    for name, target in (("path.csv", "path.csv"), ("path.png", "path.png"), (".plan.manifest", ".manifest")):
        assert os.readlink(tmp_path / name) == f".plan.current/{target}"


def test_sets_of_different_commands_are_independent(tmp_path):
    _write_set(tmp_path, {"scene.png": "show"}, command="show")
    _write_set(tmp_path, {"path.csv": "a"}, command="plan")
    _write_set(tmp_path, {"result.json": "b"}, command="plan")
    assert _listing(tmp_path) == {"result.json": b"b", "scene.png": b"show"}


@pytest.mark.parametrize("error", [RuntimeError("figure failed"), KeyboardInterrupt()])
def test_an_exception_or_ctrl_c_inside_the_block_leaves_the_old_set_untouched(tmp_path, error):
    _write_set(tmp_path, {"path.csv": "old", "path.png": "old png"})
    before = _listing(tmp_path)
    with pytest.raises(type(error)):
        with OutputSet(tmp_path, "plan") as dut:
            dut.write_text("path.csv", "new")
            dut.write_text("result.json", "new")
            raise error
    assert _listing(tmp_path) == before
    assert _hidden(tmp_path) == _tidy_hidden(tmp_path)
    # The lock was released: the next run goes ahead.
    _write_set(tmp_path, {"path.csv": "next"})
    assert _listing(tmp_path) == {"path.csv": b"next"}


def test_committed_files_have_normal_permissions(tmp_path):
    """The staging folder is 0700 and tempfile's files 0600; what lands in
    out_dir has the permissions of a plainly created file (0644 at umask 022)."""
    old = os.umask(0o022)
    try:
        with OutputSet(tmp_path, "simulate") as dut:
            assert stat.S_IMODE(dut.folder.stat().st_mode) == 0o700
            fd, tmp = tempfile.mkstemp(dir=dut.folder)  # as write_replay_html writes
            os.close(fd)
            os.replace(tmp, dut.path("replay.html"))
            assert stat.S_IMODE(dut.path("replay.html").stat().st_mode) == 0o600
            dut.write_text("sim.json", "{}")
    finally:
        os.umask(old)
    for name in ("replay.html", "sim.json", ".simulate.manifest"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == 0o644, name
    assert stat.S_IMODE((tmp_path / ".simulate.current").stat().st_mode) == 0o755  # the generation folder


_HOLDER = textwrap.dedent("""
    import sys
    from drake_social.io.outputs import OutputSet
    with OutputSet(sys.argv[1], "plan") as dut:
        dut.write_text("path.csv", "holder")
        print("ready", flush=True)
        sys.stdin.read()  # until the test closes our stdin
""")


def test_a_concurrent_run_in_another_process_is_refused(tmp_path):
    _write_set(tmp_path, {"path.csv": "old"})
    holder = subprocess.Popen([sys.executable, "-c", _HOLDER, str(tmp_path)], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline() == "ready\n"
        with pytest.raises(OutputBusyError) as info:
            _write_set(tmp_path, {"path.csv": "intruder"})
        assert str(info.value) == (f"another drake-social plan run is writing into {tmp_path}; "
                                   "wait for it or choose another --out")
        _write_set(tmp_path, {"scene.png": "show"}, command="show")  # another command is not blocked
    finally:
        holder.stdin.close()
        assert holder.wait(timeout=60) == 0
    assert _listing(tmp_path) == {"path.csv": b"holder", "scene.png": b"show"}


def test_a_killed_run_leaves_a_staging_folder_that_the_next_run_removes(tmp_path):
    holder = subprocess.Popen([sys.executable, "-c", _HOLDER, str(tmp_path)], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline() == "ready\n"
    holder.kill()  # SIGKILL: no cleanup; the kernel drops the lock
    holder.wait(timeout=60)
    holder.stdin.close()
    assert [n for n in _hidden(tmp_path) if n.startswith(".staging-plan-")]
    _write_set(tmp_path, {"path.csv": "next"})
    assert _hidden(tmp_path) == _tidy_hidden(tmp_path)
    assert _listing(tmp_path) == {"path.csv": b"next"}


def test_ctrl_c_while_moving_the_set_into_place_completes_it_first(tmp_path, monkeypatch):
    """SIGINT arriving between two renames is held back until the set is
    complete, then raised as InterruptedAfterCommit (a KeyboardInterrupt)."""
    _write_set(tmp_path, {"path.csv": "old", "path.png": "old png", "stale.png": "old"})
    replace = os.replace
    calls = []

    def interrupted_replace(src, dst):
        calls.append(Path(dst).name)
        if len(calls) == 1:
            signal.raise_signal(signal.SIGINT)  # as if Ctrl-C were pressed now
        replace(src, dst)

    monkeypatch.setattr(outputs_module.os, "replace", interrupted_replace)
    with pytest.raises(InterruptedAfterCommit) as info:
        _write_set(tmp_path, {"path.csv": "new", "path.png": "new png", "extra.png": "new extra"})
    assert isinstance(info.value, KeyboardInterrupt)
    assert info.value.committed == [tmp_path / "extra.png", tmp_path / "path.csv", tmp_path / "path.png"]
    # The interrupted step links the new name; the swap of the generation still follows.
    assert calls == ["extra.png", ".plan.current"]
    assert _listing(tmp_path) == {"path.csv": b"new", "path.png": b"new png", "extra.png": b"new extra"}
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_names_must_be_plain_and_the_block_must_be_open(tmp_path):
    dut = OutputSet(tmp_path, "plan")
    with pytest.raises(RuntimeError, match="outside its 'with' block"):
        dut.path("a.csv")
    with dut:
        for bad in ("../a.csv", "sub/a.csv", ".hidden"):
            with pytest.raises(ValueError, match="plain file name"):
                dut.path(bad)
    with pytest.raises(RuntimeError, match="not plain files"):
        with OutputSet(tmp_path, "plan") as dut:
            (dut.folder / "sub").mkdir()
    assert _listing(tmp_path) == {}


def test_an_unwritable_out_is_an_oserror(tmp_path):
    (tmp_path / "file").write_text("")
    with pytest.raises(OSError):
        with OutputSet(tmp_path / "file", "plan"):
            pass


def test_without_symbolic_links_the_set_is_moved_file_by_file_with_a_warning(tmp_path, monkeypatch, caplog):
    """FAT and some network shares refuse symbolic links (EPERM): the set
    still lands, as plain files, and the weaker promise is logged."""
    def no_links(*args, **kwargs):
        raise OSError(errno.EPERM, "Operation not permitted")

    monkeypatch.setattr(outputs_module.os, "symlink", no_links)
    _write_set(tmp_path, {"path.csv": "old", "stale.png": "old"})
    caplog.clear()
    with caplog.at_level("WARNING", logger="drake_social.io.outputs"):
        dut = _write_set(tmp_path, {"path.csv": "new", "path.png": "new png"})
    assert _listing(tmp_path) == {"path.csv": b"new", "path.png": b"new png"}
    assert dut.committed == [tmp_path / "path.csv", tmp_path / "path.png"]
    assert not any(p.is_symlink() for p in tmp_path.iterdir())
    assert _hidden(tmp_path) == [".plan.lock", ".plan.manifest"]
    assert (tmp_path / ".plan.manifest").read_text() == "path.csv\npath.png\n"
    assert [r.getMessage() for r in caplog.records] == [
        f"{tmp_path} has no symbolic links: the plan set is moved into place file by file, so a process killed in "
        "those milliseconds can leave a mix of two sets"]
    # Back on a file system with links, that plain set is taken over as a generation.
    monkeypatch.undo()
    _write_set(tmp_path, {"path.csv": "third"})
    assert _listing(tmp_path) == {"path.csv": b"third"}
    assert _hidden(tmp_path) == _tidy_hidden(tmp_path)


def test_a_generation_removed_by_hand_is_replaced_by_the_next_set(tmp_path):
    """`rm -rf out/.plan.gen-*` leaves dangling links: they read as missing
    files, and the next run writes a complete set over them."""
    _write_set(tmp_path, {"path.csv": "old", "path.png": "old png"})
    for generation in tmp_path.glob(".plan.gen-*"):
        shutil.rmtree(generation)
    assert current_set(tmp_path, "plan") is None and _listing_readable(tmp_path) == {}
    _write_set(tmp_path, {"path.csv": "new"})
    assert _listing(tmp_path) == {"path.csv": b"new"}
    assert _hidden(tmp_path) == _tidy_hidden(tmp_path)
    assert current_set(tmp_path, "plan").files == ("path.csv",)


def _listing_readable(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in folder.iterdir() if not p.name.startswith(".") and p.exists()}


@pytest.mark.parametrize("copy", ["cp -rL", "current is a plain file"])
def test_a_dereferenced_copy_is_read_and_written_like_a_plain_set(tmp_path, copy):
    """`cp -rL` turns every link into a file and `.plan.current` into a
    plain folder: the copy reads as its plain files, and a new set replaces
    it as a whole (the plain folder and the copied generations go)."""
    _write_set(tmp_path / "src", {"path.csv": "old", "path.png": "old png", "stale.png": "old stale"})
    copied = tmp_path / "copy"
    subprocess.run(["cp", "-rL", str(tmp_path / "src"), str(copied)], check=True)
    assert (copied / ".plan.current").is_dir() and not (copied / ".plan.current").is_symlink()
    if copy == "current is a plain file":
        shutil.rmtree(copied / ".plan.current")
        (copied / ".plan.current").write_text("not a link")
    shown = current_set(copied, "plan")
    assert shown is not None and shown.generation == "" and shown.files == ("path.csv", "path.png", "stale.png")
    assert _listing(copied) == {"path.csv": b"old", "path.png": b"old png", "stale.png": b"old stale"}
    for text in ("new", "newer"):
        _write_set(copied, {"path.csv": text, "path.png": "new png"})
        assert _listing(copied) == {"path.csv": text.encode(), "path.png": b"new png"}
        assert _hidden(copied) == _tidy_hidden(copied)
        assert current_set(copied, "plan").files == ("path.csv", "path.png")
    assert _listing(tmp_path / "src") == {"path.csv": b"old", "path.png": b"old png", "stale.png": b"old stale"}


def test_a_plain_current_folder_without_a_manifest_is_replaced(tmp_path):
    """A plain `.plan.current` folder with no plain manifest beside it holds no
    set: it reads as none, and the next set takes its place."""
    (tmp_path / ".plan.current").mkdir()
    (tmp_path / ".plan.current" / "path.csv").write_text("orphan")
    assert current_set(tmp_path, "plan") is None
    _write_set(tmp_path, {"path.csv": "new"})
    assert _listing(tmp_path) == {"path.csv": b"new"}
    assert _hidden(tmp_path) == _tidy_hidden(tmp_path)


def test_a_folder_named_like_an_output_is_refused_before_the_work_and_at_commit(tmp_path):
    """A folder has the name of one of the set's files: refused on entering
    the block when the name is declared, at commit otherwise, naming the
    user's path; the old set is left whole either way."""
    _write_set(tmp_path, {"path.csv": "old"})
    (tmp_path / "path.png").mkdir()
    with pytest.raises(outputs_module.OutputInTheWayError) as declared:
        with OutputSet(tmp_path, "plan", names=["path.csv", "path.png"]):
            raise AssertionError("the block must not run")
    assert str(declared.value) == (f"{tmp_path / 'path.png'} is a folder in the way of plan's output path.png; "
                                   "remove or rename it, or choose another --out")
    with pytest.raises(outputs_module.OutputInTheWayError) as at_commit:
        _write_set(tmp_path, {"path.csv": "new", "path.png": "new png"})
    assert str(at_commit.value) == str(declared.value)
    assert (tmp_path / "path.csv").read_text() == "old" and (tmp_path / "path.png").is_dir()
    assert current_set(tmp_path, "plan").files == ("path.csv",)
    assert not [p for p in tmp_path.iterdir() if p.name.startswith((".staging", ".plan.new-"))]
    assert len(list(tmp_path.glob(".plan.gen-*"))) == 1
    # The set's manifest link too.
    (tmp_path / "path.png").rmdir()
    (tmp_path / "fresh" / ".plan.manifest").mkdir(parents=True)
    with pytest.raises(outputs_module.OutputInTheWayError, match=r"fresh/\.plan\.manifest is a folder in the way"):
        _write_set(tmp_path / "fresh", {"path.csv": "new"})
