"""drake-social's outputs under abuse (issue 9, part 2): Ctrl-C during a real
``plan`` run, and two runs into one folder at once. Real subprocesses."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest

SCENARIO_DIR = Path(__file__).resolve().parent.parent / "scenarios"

TINY = SCENARIO_DIR / "tiny.yaml"
CLI = Path(sys.executable).with_name("drake-social")
#: Files of a plan run.
PLAN_SET = {"path.csv", "result.json", "path.png", "cost_profile.png", "convergence.png"}


def _listing(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in folder.iterdir() if not p.name.startswith(".")}


def _plan(out: Path, iterations: int, *extra: str) -> list[str]:
    return [str(CLI), "plan", str(TINY), "--checker", "numpy", "--iterations", str(iterations), "--out", str(out),
            *extra]


class _Run:
    """A ``drake-social`` subprocess whose stderr is read on a thread, so the
    test can wait for the progress bar to be drawn (planning under way)."""

    def __init__(self, argv: list[str]):
        self.proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     env={**os.environ, "PYTHONUNBUFFERED": "1"})
        self.err = b""
        self.planning = threading.Event()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        while chunk := self.proc.stderr.read1(4096):
            self.err += chunk
            if b"planning [" in self.err and b"/1000000" in self.err:
                self.planning.set()

    def finish(self, timeout: float = 120) -> tuple[int, str, str]:
        out = self.proc.stdout.read()
        rc = self.proc.wait(timeout=timeout)
        self._reader.join(timeout)
        return rc, out.decode(), self.err.decode()


@pytest.fixture(scope="module")
def old_set(tmp_path_factory) -> tuple[Path, dict[str, bytes]]:
    """A folder holding a complete, older ``plan`` set (20 iterations)."""
    out = tmp_path_factory.mktemp("old_set")
    assert subprocess.run(_plan(out, 20), capture_output=True, timeout=300).returncode in (0, 3)
    listing = _listing(out)
    assert set(listing) == PLAN_SET
    return out, listing


def _fresh_copy(old_set, tmp_path: Path) -> Path:
    folder, listing = old_set
    out = tmp_path / "out"
    out.mkdir()
    for name, data in listing.items():
        (out / name).write_bytes(data)
    for hidden in (".plan.manifest",):
        (out / hidden).write_bytes((folder / hidden).read_bytes())
    return out


def _interrupt(run: _Run) -> tuple[int, str, str]:
    assert run.planning.wait(timeout=300), run.err.decode()
    run.proc.send_signal(signal.SIGINT)
    return run.finish()


def test_ctrl_c_while_planning_exits_130_with_one_line_and_keeps_the_old_set(old_set, tmp_path):
    out = _fresh_copy(old_set, tmp_path)
    rc, stdout, stderr = _interrupt(_Run(_plan(out, 1_000_000, "--progress")))
    assert rc == 130, stderr
    assert "Traceback" not in stderr and "KeyboardInterrupt" not in stderr
    # The progress bar ends its line; then exactly one line says what happened.
    lines = stderr.split("\n")
    assert lines[-2:] == ["drake-social: plan interrupted; no output of this run was written", ""]
    assert lines[-3].startswith("\rplanning [") or lines[-3].split("\r")[-1].startswith("planning [")
    assert stdout == ""
    assert _listing(out) == old_set[1]
    assert sorted(p.name for p in out.iterdir() if p.name.startswith(".")) == [".plan.lock", ".plan.manifest"]


def test_a_second_plan_into_the_same_folder_is_refused_and_never_mixes(old_set, tmp_path):
    out = _fresh_copy(old_set, tmp_path)
    first = _Run(_plan(out, 1_000_000, "--progress"))
    assert first.planning.wait(timeout=300), first.err.decode()
    second = subprocess.run(_plan(out, 20), capture_output=True, text=True, timeout=300)
    assert second.returncode == 1, second.stderr
    assert second.stderr == (f"drake-social: error: another drake-social plan run is writing into {out}; "
                             "wait for it or choose another --out\n")
    assert _listing(out) == old_set[1]  # the refused run wrote nothing
    first.proc.send_signal(signal.SIGINT)
    rc, _, stderr = first.finish()
    assert rc == 130, stderr
    assert _listing(out) == old_set[1]
    # Once the folder is free, a run replaces the set as a whole.
    third = subprocess.run(_plan(out, 30), capture_output=True, text=True, timeout=300)
    assert third.returncode in (0, 3), third.stderr
    assert set(_listing(out)) == PLAN_SET
    assert json.loads((out / "result.json").read_text())["iterations"] == 30
