"""Ctrl-C stops ``simulate --replan`` and ``experiment crowd`` while they
replan: SIGINT to the process or to its group ends the run with exit 130 and
one line, the folder keeps the previous run's set byte for byte, and no
process of the run is left. Real subprocesses.

The replanning runs at 100 Hz with a search at every replan (the setting
under which a Ctrl-C crashed in numba's argument passing:
:mod:`drake_social.interrupts`), so the signal lands in the compiled
search most of the time.
"""

from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from drake_social.io.outputs import current_set

from experiments.test_crowd_study import TINY_WALKER

CLI = Path(sys.executable).with_name("drake-social")

#: The crowd study's tiny room with a walker crossing the route again and again, replanned at 100 Hz.
_PLANNING = "planner: {iterations: 300}\nexecution: {time_limit: 20.0}\n"
assert _PLANNING in TINY_WALKER
SCENARIO = TINY_WALKER.replace(_PLANNING, "planner: {iterations: 300, replan_search_period: 0, replan_rate: 100}\n"
                                          "execution: {time_limit: %s}\n")

#: Seconds from the signal to the exit: far above the second a Ctrl-C takes, far below a run's length.
WITHIN = 10.0


def _scenario(folder: Path, time_limit: float) -> Path:
    path = folder / f"walker_{time_limit:g}.yaml"
    path.write_text(SCENARIO % time_limit)
    return path


def _simulate(scenario: Path, out: Path) -> list[str]:
    return [str(CLI), "simulate", str(scenario), "--replan", "--no-replay", "--progress", "--out", str(out)]


def _crowd(scenario: Path, out: Path, workers: int) -> list[str]:
    return [str(CLI), "experiment", "crowd", "--scenarios", str(scenario), "--variants", "replan_multi",
            "--episodes", "2", "--jitter", "0", "--workers", str(workers), "--out", str(out)]


def _hashes(folder: Path) -> dict[str, str]:
    """SHA-256 of every visible file of ``folder`` (through the set's links)."""
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.iterdir() if not p.name.startswith(".")}


def _session(sid: int) -> list[int]:
    """The processes of session ``sid`` (the run's, started with ``start_new_session``), zombies left out."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[3]) == sid and fields[0] != "Z":
                found.append(int(entry.name))
    return found


def _cpu_seconds(sid: int) -> float:
    """User and system CPU seconds of the processes of session ``sid`` (the run and its workers)."""
    total = 0.0
    for pid in _session(sid):
        try:
            fields = (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        total += sum(int(v) for v in fields[11:13]) / os.sysconf("SC_CLK_TCK")
    return total


def _interrupt(argv: list[str], out: Path, command: str, group: bool, busy: float) -> tuple[int, str, str, float]:
    """Runs ``argv`` in a session of its own, sends SIGINT (to the process or its group) once its
    set is staged in ``out`` and its processes have used ``busy`` CPU seconds since (a loaded
    machine makes the wait longer, not the run less far); returns the exit code,
    stdout, stderr and the seconds from the signal to the exit."""
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"})
    err = bytearray()
    reader = threading.Thread(target=lambda: [err.extend(c) for c in iter(lambda: proc.stderr.read1(4096), b"")],
                              daemon=True)
    reader.start()
    try:
        deadline = time.monotonic() + 300
        while not any(p.name.startswith(f".staging-{command}-") for p in out.iterdir()):
            assert proc.poll() is None and time.monotonic() < deadline, err.decode()
            time.sleep(0.05)
        staged = _cpu_seconds(proc.pid)
        while _cpu_seconds(proc.pid) < staged + busy:
            assert proc.poll() is None and time.monotonic() < deadline, err.decode()
            time.sleep(0.05)
        (os.killpg if group else os.kill)(proc.pid, signal.SIGINT)
        sent = time.monotonic()
        stdout = proc.stdout.read()
        rc = proc.wait(timeout=120)
        took = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    reader.join(30)
    # Nothing of the run outlives it (workers, their fork server).
    deadline = time.monotonic() + 30
    while _session(proc.pid):
        assert time.monotonic() < deadline, f"processes {_session(proc.pid)} of the run are left"
        time.sleep(0.05)
    return rc, stdout.decode(), err.decode(), took


def _one_line(stderr: str, command: str) -> None:
    lines = [line.split("\r")[-1] for line in stderr.split("\n")]  # a progress bar ends its line first
    assert lines[-2:] == [f"drake-social: {command} interrupted; no output of this run was written", ""], stderr
    assert "Traceback" not in stderr and "Error" not in stderr and "leaked" not in stderr, stderr


@pytest.fixture(scope="module")
def old_simulate(tmp_path_factory) -> tuple[Path, dict[str, str]]:
    """A folder holding a complete ``simulate --replan`` set of a 1 s run."""
    folder = tmp_path_factory.mktemp("old_simulate")
    done = subprocess.run(_simulate(_scenario(folder, 1.0), folder / "out"), capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 5, done.stderr  # not reached in 1 s
    return folder / "out", _hashes(folder / "out")


@pytest.mark.parametrize("group", [False, True], ids=["process", "group"])
def test_ctrl_c_stops_simulate_replan(tmp_path, old_simulate, group):
    out, before = old_simulate
    assert set(before) == {"executed.csv", "people.csv", "path.png", "predictions.png", "replans.csv", "replans.png",
                           "sim.json", "tracking.png", "motion.png"}
    rc, stdout, stderr, took = _interrupt(_simulate(_scenario(tmp_path, 120.0), out), out, "simulate", group,
                                          busy=3.0)
    assert rc == 130, stderr
    _one_line(stderr, "simulate")
    assert "simulating [" in stderr  # interrupted while it simulated (and replanned)
    assert stdout == ""
    assert took < WITHIN, f"exited {took:.1f} s after the signal"
    assert _hashes(out) == before
    assert not [p.name for p in out.iterdir() if p.name.startswith(".staging-")]


@pytest.fixture(scope="module")
def old_crowd(tmp_path_factory) -> tuple[Path, dict[str, str]]:
    """A folder holding a complete ``experiment crowd`` set (two episodes of 0.5 s)."""
    folder = tmp_path_factory.mktemp("old_crowd")
    argv = _crowd(_scenario(folder, 0.5), folder / "out", 1)
    done = subprocess.run(argv, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return folder / "out", _hashes(folder / "out")


@pytest.mark.parametrize("workers, group", [(1, False), (2, True)], ids=["in-process", "workers-group"])
def test_ctrl_c_stops_experiment_crowd(tmp_path, old_crowd, workers, group):
    out, before = old_crowd
    assert "records.json" in before and current_set(out, "experiment") is not None
    rc, stdout, stderr, took = _interrupt(_crowd(_scenario(tmp_path, 120.0), out, workers), out, "experiment",
                                          group, busy=4.0)
    assert rc == 130, stderr
    _one_line(stderr, "experiment")
    assert stdout == ""
    assert took < WITHIN, f"exited {took:.1f} s after the signal"
    assert _hashes(out) == before
    assert not [p.name for p in out.iterdir() if p.name.startswith(".staging-")]
