"""drake_social.io.outputs under SIGKILL: a run killed at any step of its commit
leaves the folder holding the complete old set or the complete new one, and
:func:`current_set` says which. Each case is a subprocess that kills itself
(SIGKILL: no handler, no cleanup) just before its k-th file-system change
inside the commit, for every k until the commit runs through."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from drake_social.io.outputs import OutputSet, current_set

#: The set the killed run writes.
NEW = {"path.csv": b"new path", "path.png": b"new png", "extra.png": b"new extra"}
#: The set it replaces (stale.png is not in the new one, extra.png not in the old one).
OLD = {"path.csv": b"old path", "path.png": b"old png", "stale.png": b"old stale"}
#: Files beside the plan set that no plan run may touch: the user's and show's.
OTHERS = {"notes.txt": b"the user's", "scene.png": b"show's scene"}

_KILLED_RUN = textwrap.dedent("""
    import builtins, os, shutil, signal, sys
    from drake_social.io import outputs

    folder, kill_at = sys.argv[1], int(sys.argv[2])
    state = {"committing": False, "changes": 0}

    def step():
        if state["committing"]:
            if state["changes"] == kill_at:
                os.kill(os.getpid(), signal.SIGKILL)
            state["changes"] += 1

    def counted(fn):
        def wrapper(*args, **kwargs):
            step()
            return fn(*args, **kwargs)
        return wrapper

    for name in ("replace", "rename", "symlink", "link", "unlink", "remove", "rmdir", "mkdir", "chmod", "fsync"):
        setattr(os, name, counted(getattr(os, name)))
    real_open = builtins.open

    def open_(file, mode="r", *args, **kwargs):
        if any(c in mode for c in "wax+"):
            step()
        return real_open(file, mode, *args, **kwargs)

    builtins.open = open_
    commit = outputs.OutputSet._commit

    def counted_commit(self):
        state["committing"] = True
        commit(self)

    outputs.OutputSet._commit = counted_commit
    with outputs.OutputSet(folder, "plan") as dut:
        for name, data in %r.items():
            dut.path(name).write_bytes(data)
    print(state["changes"])
""" % (NEW,))


def _visible(folder: Path) -> dict[str, bytes]:
    """What a reader of the folder gets: every non-hidden name that opens
    (a link into a generation that lacks the file reads as missing)."""
    seen = {}
    for p in folder.iterdir():
        if not p.name.startswith("."):
            try:
                seen[p.name] = p.read_bytes()
            except FileNotFoundError:
                pass
    return seen


def _old_folder(root: Path, layout: str) -> Path:
    """A folder with OLD as the plan set, in the generation layout or as the
    plain files and plain manifest of earlier versions, beside OTHERS."""
    folder = root / layout
    if layout == "generations":
        with OutputSet(folder, "plan") as dut:
            for name, data in OLD.items():
                dut.path(name).write_bytes(data)
        with OutputSet(folder, "show") as dut:
            dut.path("scene.png").write_bytes(OTHERS["scene.png"])
    else:
        folder.mkdir(parents=True)
        for name, data in {**OLD, "scene.png": OTHERS["scene.png"]}.items():
            (folder / name).write_bytes(data)
        (folder / ".plan.manifest").write_text("".join(f"{n}\n" for n in sorted(OLD)))
        (folder / ".show.manifest").write_text("scene.png\n")
    (folder / "notes.txt").write_bytes(OTHERS["notes.txt"])
    return folder


def _run(folder: Path, kill_at: int) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", _KILLED_RUN, str(folder), str(kill_at)], capture_output=True,
                          text=True, timeout=120)


@pytest.mark.parametrize("layout", ["generations", "plain files"])
def test_a_kill_at_any_step_of_the_commit_leaves_the_old_or_the_new_set(tmp_path, layout):
    template = _old_folder(tmp_path / "template", layout)
    old_generation = current_set(template, "plan")
    outcomes = []
    kill_at = 0
    while True:
        folder = tmp_path / f"kill_{kill_at}"
        shutil.copytree(template, folder, symlinks=True)
        done = _run(folder, kill_at)
        if done.returncode == 0:  # the commit ran through: every step has been tried
            steps = int(done.stdout)
            assert kill_at == steps
            assert _visible(folder) == {**NEW, **OTHERS}
            break
        assert done.returncode == -signal.SIGKILL, done.stderr
        seen = _visible(folder)
        now = current_set(folder, "plan")
        if seen == {**OLD, **OTHERS}:
            outcomes.append("old")
            # The reader is told the old set: its plain files (no generation
            # yet, or one taken over from them) or its generation.
            assert now is not None and set(now.files) == set(OLD), (kill_at, now)
            if old_generation.generation:
                assert now == old_generation
        else:
            assert seen == {**NEW, **OTHERS}, (kill_at, sorted(seen))  # never a mix
            outcomes.append("new")
            assert now is not None and set(now.files) == set(NEW) and now != old_generation, (kill_at, now)
        # The next run finds the folder as the killed one left it and replaces
        # the set as a whole, leaving nothing of the killed run behind.
        with OutputSet(folder, "plan") as dut:
            dut.write_text("path.csv", "third")
        assert _visible(folder) == {"path.csv": b"third", **OTHERS}
        generation = current_set(folder, "plan").generation
        assert sorted(p.name for p in folder.iterdir() if p.name.startswith(".plan")) == sorted(
            [".plan.current", generation, ".plan.lock", ".plan.manifest"]), kill_at
        kill_at += 1
    # Both outcomes occur: the swap is a step in the middle of the commit.
    assert steps >= 10 and outcomes[0] == "old" and outcomes[-1] == "new"
    assert outcomes == sorted(outcomes, key=["old", "new"].index)  # old until the swap, new after it
