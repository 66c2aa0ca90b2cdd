"""drake-social experiment's execution and outputs under abuse: scheduler
addresses refused before any run, Ctrl-C with the Dask executor (a real
process group, as a terminal interrupts), and finished runs never lost to an
output error."""

from __future__ import annotations

import errno
import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import pytest

from drake_social.cli import main
from drake_social.experiments.study import arena
from drake_social.experiments.study import report
from drake_social.experiments.study.executors import check_scheduler_address, map_tasks
from drake_social.io.outputs import OutputSet, current_set

CLI = Path(sys.executable).with_name("drake-social")
_FORM = "the form is [tcp://|tls://]HOST:PORT with PORT in 1..65535, e.g. tcp://10.0.0.5:8786"


def _sweep(tmp_path: Path, tiny: Path, *, runs: int = 1, iterations: int = 30, algorithms=("social_rrt_star",)) -> Path:
    path = tmp_path / "sweep.yaml"
    path.write_text(f"name: abuse\nruns: {runs}\niterations: {iterations}\nseed: 0\nscenarios: [{tiny}]\n"
                    f"algorithms: [{', '.join(algorithms)}]\nvariants: {{default: {{}}, wide: {{social: {{sigma_h: 1.2}}}}}}\n")
    return path


# ---- the scheduler address ---------------------------------------------------------


@pytest.mark.parametrize("address, problem", [
    ("notanaddress", "has no port"), ("tcp://127.0.0.1", "has no port"), ("", "is empty"),
    ("[::1]", "has no port"), ("tcp://:8786", "is not HOST:PORT"), ("127.0.0.1:port", "is not HOST:PORT"),
    ("tcp://host:8786/path", "is not HOST:PORT"), (" tcp://host:8786", "unknown protocol ' tcp'"),
    ("http://host:8786", "unknown protocol 'http'"), ("tcp://host:0", "port 0 is out of range"),
    ("tcp://host:65536", "port 65536 is out of range"),
])
def test_a_bad_scheduler_address_is_refused_before_anything_runs(tmp_path, tiny_scenario_path, capsys, address,
                                                                   problem):
    sweep = _sweep(tmp_path, tiny_scenario_path)
    out = tmp_path / "out"
    rc = main(["experiment", "sweep", str(sweep), "--executor", "dask", "--scheduler", address, "--out", str(out)])
    captured = capsys.readouterr()
    assert rc == 2
    sep = ":" if problem.startswith(("unknown", "port")) else ""
    assert captured.err == f"drake-social: error: --scheduler: scheduler address {address!r}{sep} {problem}; {_FORM}\n"
    assert captured.out == "" and not out.exists()  # nothing ran, nothing was written
    with pytest.raises(ValueError, match="the form is"):  # the API checks the same before any task
        map_tasks(len, [{}], executor="dask", scheduler=address)


@pytest.fixture
def tls_settings():
    """Dask's TLS settings of a client (the files are read only on connecting)."""
    import dask
    import distributed  # noqa: F401  (its config defaults first, or dask.config.set shadows them)

    with dask.config.set({"distributed.comm.tls.ca-file": "ca.pem", "distributed.comm.tls.client.cert": "me.pem"}):
        yield


@pytest.mark.slow
@pytest.mark.parametrize("address", ["tcp://10.0.0.5:8786", "localhost:8786", "tls://scheduler.example.org:1",
                                     "tcp://[::1]:65535", "127.0.0.1:8786", "dask_scheduler:8786",
                                     "tcp://my_cluster.dask_scheduler_1:8786", "_host_:1"])
def test_good_scheduler_addresses_pass(address, tls_settings):
    assert check_scheduler_address(address) == address


@pytest.mark.parametrize("settings, missing", [
    ({}, "distributed.comm.tls.ca-file and distributed.comm.tls.client.cert are"),
    ({"distributed.comm.tls.ca-file": "ca.pem"}, "distributed.comm.tls.client.cert is"),
    ({"distributed.comm.tls.client.cert": "me.pem"}, "distributed.comm.tls.ca-file is"),
])
def test_tls_without_dasks_tls_settings_is_refused_before_anything_runs(tmp_path, tiny_scenario_path, capsys,
                                                                         settings, missing):
    import dask
    import distributed  # noqa: F401  (its config defaults first)

    sweep = _sweep(tmp_path, tiny_scenario_path)
    out = tmp_path / "out"
    unset = {"distributed.comm.tls.ca-file": None, "distributed.comm.tls.client.cert": None}
    with dask.config.set({**unset, **settings}):
        rc = main(["experiment", "sweep", str(sweep), "--executor", "dask", "--scheduler", "tls://127.0.0.1:1",
                   "--out", str(out)])
    captured = capsys.readouterr()
    assert rc == 2 and captured.out == "" and not out.exists()
    assert captured.err == ("drake-social: error: --scheduler: scheduler address 'tls://127.0.0.1:1': tls:// needs "
                            f"Dask's TLS settings, and {missing} not set (in the Dask config, or as "
                            "DASK_DISTRIBUTED__COMM__TLS__... variables); or use tcp://\n")


def test_tls_files_dask_cannot_use_are_one_error_line(tmp_path, tiny_scenario_path, capsys):
    """Settings that pass the check but that Dask's client then refuses (a
    key without its certificate, for one): one error line, exit 1, no traceback."""
    import dask
    import distributed  # noqa: F401  (its config defaults first)

    sweep = _sweep(tmp_path, tiny_scenario_path)
    out = tmp_path / "out"
    with dask.config.set({"distributed.comm.tls.ca-file": str(tmp_path / "missing-ca.pem"),
                          "distributed.comm.tls.client.cert": str(tmp_path / "missing-cert.pem")}):
        rc = main(["experiment", "sweep", str(sweep), "--executor", "dask", "--scheduler", "tls://127.0.0.1:1",
                   "--out", str(out)])
    captured = capsys.readouterr()
    assert rc == 1 and "Traceback" not in captured.err
    assert captured.err == ("drake-social: error: cannot connect to the Dask scheduler at tls://127.0.0.1:1: "
                            "[Errno 2] No such file or directory\n")


# ---- Ctrl-C with the Dask executor ------------------------------------------------------


def _workers(pid: int) -> list[int]:
    """The worker processes of the study run by ``pid``: the processes forked
    by its multiprocessing fork server (a child of ``pid``), or spawned by
    ``pid`` itself."""
    parents, commands = {}, {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
                commands[int(entry.name)] = (entry / "cmdline").read_bytes()
            except OSError:
                continue
            parents[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    servers = {p for p, parent in parents.items() if parent == pid and b"forkserver" in commands.get(p, b"")}
    return sorted(p for p, parent in parents.items()
                  if parent in servers or (parent == pid and b"spawn_main" in commands.get(p, b"")))


def _cpu_seconds(pid: int) -> float:
    """CPU time (user + system) of process ``pid`` so far, seconds (0: gone)."""
    try:
        fields = (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _wait_for(condition, deadline_s: float, what: str) -> None:
    """Polls ``condition()`` until true; fails naming ``what`` after ``deadline_s`` seconds."""
    deadline = time.monotonic() + deadline_s
    while not condition():
        assert time.monotonic() < deadline, f"not within {deadline_s} s: {what}"
        time.sleep(0.05)


#: CPU seconds after which a study's worker, Drake loaded, is taken to be
#: planning: measured here, a worker has Drake mapped at about 0.8 s of CPU
#: and 3.5-4 s of CPU 8 s after it appears (the fixed wait this replaces).
#: Counted in CPU time, so a loaded machine only makes the wait longer.
_PLANNING_CPU = 4.0


def _planning(pid: int) -> bool:
    """Whether worker ``pid`` has Drake loaded and :data:`_PLANNING_CPU` of CPU."""
    try:
        loaded = "libdrake" in (Path("/proc") / str(pid) / "maps").read_text()
    except OSError:
        return False
    return loaded and _cpu_seconds(pid) >= _PLANNING_CPU


def _alive(pid: int) -> bool:
    try:
        return (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.parametrize("executor, when", [("dask", "running"), ("dask", "starting"), ("process", "starting")])
def test_ctrl_c_during_a_study_exits_130_with_one_line(tmp_path, tiny_scenario_path, executor, when):
    """SIGINT to the whole process group, as a terminal's Ctrl-C, while the
    workers plan or while they start: no worker may print a traceback, nor
    distributed its shutdown log."""
    sweep = _sweep(tmp_path, tiny_scenario_path, runs=4, iterations=1_000_000)
    out = tmp_path / "out"
    proc = subprocess.Popen([str(CLI), "experiment", "sweep", str(sweep), "--executor", executor, "--workers", "2",
                             "--out", str(out), "--progress"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})
    err = bytearray()

    def read() -> None:
        while chunk := proc.stderr.read1(4096):
            err.extend(chunk)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        deadline = time.monotonic() + 120
        while len(workers := _workers(proc.pid)) < (2 if when == "running" else 1):
            assert proc.poll() is None and time.monotonic() < deadline, err.decode()
            time.sleep(0.05)
        if when == "running":  # the workers have the tasks, planning
            _wait_for(lambda: len(_workers(proc.pid)) >= 2 and all(_planning(w) for w in _workers(proc.pid))
                      or proc.poll() is not None, 300, f"two workers with Drake and {_PLANNING_CPU} s of CPU each")
            assert proc.poll() is None, err.decode()
            workers = _workers(proc.pid)
        os.killpg(proc.pid, signal.SIGINT)
        stdout = proc.stdout.read()
        rc = proc.wait(timeout=120)  # a hang fails here
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    reader.join(30)
    stderr = err.decode()
    assert rc == 130, stderr
    assert "Traceback" not in stderr and "KeyboardInterrupt" not in stderr and "Error" not in stderr, stderr
    assert "distributed" not in stderr, stderr
    lines = [line.split("\r")[-1] for line in stderr.split("\n")]
    assert lines[-2:] == ["drake-social: experiment interrupted; no output of this run was written", ""], stderr
    assert all(line.startswith("experiment abuse:") for line in lines[:-2]), stderr  # the bar, nothing else
    assert stdout == b"" and current_set(out, "experiment") is None
    # No worker left behind (they may take a moment to be reaped).
    _wait_for(lambda: not [w for w in workers if _alive(w)], 30, f"workers {workers} gone")


# ---- an output error after the runs -----------------------------------------------------


def _no_space(*args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device")


def _script_failed(*args, **kwargs):
    raise RuntimeError("ompl_benchmark_statistics.py failed on the logs")

def _assert_the_records_alone(out):
    """The set committed in ``out`` is the two runs' records alone, complete."""
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == ["results.csv", "results.json"]
    assert current_set(out, "experiment").files == ("results.csv", "results.json")
    records = json.loads((out / "results.json").read_text())["runs"]
    assert [(r["group"], r["run"]) for r in records] == [("tiny-default", 0), ("tiny-wide", 0)]
    assert all(r["success"] and len(r["waypoints"]) >= 2 for r in records)
    assert len((out / "results.csv").read_text().splitlines()) == 3



@pytest.mark.slow
@pytest.mark.parametrize("where, failure, message", [
    (report, ("write_figures", _no_space), "[Errno 28] No space left on device"),
    (arena, ("build_database", _script_failed), "ompl_benchmark_statistics.py failed on the logs"),
])
def test_an_output_error_after_the_runs_keeps_their_records_in_out(tmp_path, tiny_scenario_path, monkeypatch, capsys,
                                                                   where, failure, message):
    sweep = _sweep(tmp_path, tiny_scenario_path)
    out = tmp_path / "out"
    monkeypatch.setattr(where, *failure)
    rc = main(["experiment", "sweep", str(sweep), "--out", str(out)])
    captured = capsys.readouterr()
    assert rc == 1
    assert captured.err == (f"drake-social: error: writing the study's outputs into {out} failed: {message}; the "
                            f"records of its 2 runs are in {out / 'results.json'} and {out / 'results.csv'} (the "
                            "figures, REPORT.md and the arena files were not written)\n")
    _assert_the_records_alone(out)


@pytest.mark.slow
def test_records_that_out_cannot_take_are_saved_in_the_temporary_directory(tmp_path, tiny_scenario_path, monkeypatch,
                                                                           capsys):
    sweep = _sweep(tmp_path, tiny_scenario_path)
    out = tmp_path / "out"
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))
    monkeypatch.setattr(OutputSet, "_commit", _no_space)  # even the records cannot land in out
    rc = main(["experiment", "sweep", str(sweep), "--out", str(out)])
    captured = capsys.readouterr()
    assert rc == 1
    (rescued,) = temporary.iterdir()
    assert rescued.name.startswith("drake-social-records-")
    assert captured.err == (f"drake-social: error: writing the study's outputs into {out} failed: [Errno 28] No space "
                            f"left on device; the records of its 2 runs were saved to {rescued / 'results.json'} and "
                            f"{rescued / 'results.csv'} instead\n")
    records = json.loads((rescued / "results.json").read_text())["runs"]
    assert [(r["group"], r["success"]) for r in records] == [("tiny-default", True), ("tiny-wide", True)]
    assert current_set(out, "experiment") is None  # out holds nothing of the run
    # Nowhere to save them: the message says so, still without a traceback.
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "missing"))
    rc = main(["experiment", "sweep", str(sweep), "--out", str(out)])
    captured = capsys.readouterr()
    assert rc == 1
    assert captured.err.startswith(f"drake-social: error: writing the study's outputs into {out} failed: [Errno 28] "
                                   "No space left on device; saving the records of its 2 runs into the temporary "
                                   "directory failed too: [Errno 2] No such file or directory: ")
    assert "Traceback" not in captured.err


def test_a_figure_error_and_then_a_failed_commit_name_both_and_save_the_records(tmp_path, tiny_scenario_path,
                                                                                monkeypatch, capsys):
    sweep = _sweep(tmp_path, tiny_scenario_path)
    out = tmp_path / "out"
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))
    monkeypatch.setattr(report, "write_figures", _script_failed)
    monkeypatch.setattr(OutputSet, "_commit", _no_space)
    assert main(["experiment", "sweep", str(sweep), "--out", str(out)]) == 1
    (rescued,) = temporary.iterdir()
    assert capsys.readouterr().err == (
        f"drake-social: error: writing the study's outputs into {out} failed: ompl_benchmark_statistics.py failed on "
        "the logs; then committing the records alone failed: [Errno 28] No space left on device; the records of its "
        f"2 runs were saved to {rescued / 'results.json'} and {rescued / 'results.csv'} instead\n")
    assert len(json.loads((rescued / "results.json").read_text())["runs"]) == 2


def _interrupt(*args, **kwargs):
    raise KeyboardInterrupt


@pytest.mark.slow
@pytest.mark.parametrize("where, name", [(report, "write_figures"), (arena, "write_logs"),
                                         (report, "report_markdown")])
def test_ctrl_c_after_the_runs_keeps_their_records_in_out(tmp_path, tiny_scenario_path, monkeypatch, capsys, where,
                                                           name):
    """A Ctrl-C while the figures, logs or report are written, after every
    run finished: the records are committed alone, the message says so, exit 130."""
    sweep = _sweep(tmp_path, tiny_scenario_path)
    out = tmp_path / "out"
    monkeypatch.setattr(where, name, _interrupt)
    rc = main(["experiment", "sweep", str(sweep), "--out", str(out)])
    captured = capsys.readouterr()
    assert rc == 130
    assert captured.err == (f"drake-social: experiment interrupted after its 2 runs: their records were written to "
                            f"{out / 'results.json'} and {out / 'results.csv'} (the figures, REPORT.md and the arena "
                            "files were not written)\n")
    _assert_the_records_alone(out)


@pytest.mark.parametrize("first", ["ctrl-c", "error"])
def test_a_second_ctrl_c_while_the_records_are_written_alone_keeps_them(tmp_path, tiny_scenario_path, monkeypatch,
                                                                        capsys, first):
    """A Ctrl-C (a real SIGINT) that arrives while the records are rewritten
    alone, after a first Ctrl-C or an output error: they are still committed,
    the message says so, exit 130."""
    from drake_social.experiments import study

    sweep = _sweep(tmp_path, tiny_scenario_path)
    out = tmp_path / "out"
    monkeypatch.setattr(report, "write_figures", _interrupt if first == "ctrl-c" else _no_space)
    original = study.write_records
    calls = []

    def write_records(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:  # the records alone, after the figures failed
            signal.raise_signal(signal.SIGINT)
        return original(*args, **kwargs)

    for owner in (study, study.framework):  # the command's own call and write_study's
        monkeypatch.setattr(owner, "write_records", write_records)
    rc = main(["experiment", "sweep", str(sweep), "--out", str(out)])
    captured = capsys.readouterr()
    assert len(calls) == 2
    assert rc == 130
    assert captured.err == (f"drake-social: experiment interrupted after its 2 runs: their records were written to "
                            f"{out / 'results.json'} and {out / 'results.csv'} (the figures, REPORT.md and the arena "
                            "files were not written)\n")
    _assert_the_records_alone(out)


@pytest.mark.parametrize("name", ["results.json", "arena_tiny-wide.log", "paths_single_algorithm_groups.png",
                                  "REPORT.md", "arena.db"])
def test_a_folder_in_the_way_of_any_output_is_refused_before_the_runs(tmp_path, tiny_scenario_path, capsys, name):
    """A folder named like any file of the study (the records, a figure, a
    group's arena log: all known from the sweep) is refused before any run,
    naming the user's path."""
    sweep = _sweep(tmp_path, tiny_scenario_path)
    out = tmp_path / "out"
    (out / name).mkdir(parents=True)
    assert main(["experiment", "sweep", str(sweep), "--out", str(out)]) == 1
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err == (f"drake-social: error: {out / name} is a folder in the way of experiment's "
                            f"output {name}; remove or rename it, or choose another --out\n")
    assert current_set(out, "experiment") is None


@pytest.mark.slow
@pytest.mark.parametrize("algorithms", [("social_rrt_star",), ("rrt_star", "social_rrt_star")])
def test_the_names_refused_up_front_are_the_files_a_study_writes(tmp_path, tiny_scenario_path, algorithms):
    """output_names(study) lists every file write_study writes (arena.db only
    when OMPL's script is there), for groups of one and of several algorithms."""
    from drake_social.experiments.study import load_sweep, output_names

    sweep = _sweep(tmp_path, tiny_scenario_path, iterations=20, algorithms=algorithms)
    out = tmp_path / "out"
    assert main(["experiment", "sweep", str(sweep), "--out", str(out)]) == 0
    written = set(current_set(out, "experiment").files)
    expected = set(output_names(load_sweep(sweep)))
    assert written - {"arena.db"} == expected - {"arena.db"}
    assert written <= expected


@pytest.mark.slow
def test_a_study_on_a_scheduler_says_so_not_the_workers_default(tmp_path, tiny_scenario_path, capsys):
    distributed = pytest.importorskip("distributed")
    sweep = _sweep(tmp_path, tiny_scenario_path)
    with distributed.LocalCluster(n_workers=2, processes=False, protocol="tcp://", dashboard_address=None) as cluster:
        address = cluster.scheduler_address
        rc = main(["experiment", "sweep", str(sweep), "--executor", "dask", "--scheduler", address,
                   "--out", str(tmp_path / "out")])
    captured = capsys.readouterr()
    assert rc == 0, captured.err
    first = captured.out.splitlines()[0]
    assert first.startswith("2 runs in ") and first.endswith(f" s (on the Dask scheduler at {address})"), first
