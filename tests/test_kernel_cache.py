"""The numba cache guard: cached kernels are dropped when any kernel source changes."""

from __future__ import annotations

import shutil

import pytest

from drake_social import _kernel_cache as dut


@pytest.fixture
def package(tmp_path, monkeypatch):
    """A copy of the kernel sources with cached files beside them."""
    for name in dut.KERNEL_SOURCES:
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(dut._PACKAGE / name, tmp_path / name)
    monkeypatch.setattr(dut, "_PACKAGE", tmp_path)
    monkeypatch.setattr(dut, "_done", False)
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))  # not the user's own cache
    return tmp_path


def _cached(package):
    files = [package / "cost/__pycache__/kernel.msc_sums-101.py311.nbi",
             package / "planning/rrt_star/__pycache__/tree_kernel.grow-70.py311.1.nbc",
             package / "collision/__pycache__/planar_kernel._pair-99.py311.nbi",
             package / "cost/__pycache__/timed_kernel.msc_sums_timed-58.py311.2.nbc",
             package / "collision/__pycache__/people_kernel._probe-120.py311.nbi"]
    for f in files:
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_bytes(b"x")
    other = package / "planning/rrt_star/__pycache__/__init__.cpython-311.pyc"
    other.write_bytes(b"y")
    return files, other


def test_caches_survive_while_the_sources_stay_and_go_when_one_changes(package, monkeypatch):
    dut.ensure_fresh()  # first run: no stamp yet, nothing cached
    files, other = _cached(package)
    monkeypatch.setattr(dut, "_done", False)
    dut.ensure_fresh()
    assert all(f.exists() for f in files)  # same sources: kept
    stamp = dut.sources_hash()
    with open(package / "collision/planar_kernel.py", "a") as f:
        f.write("\n# edited\n")
    assert dut.sources_hash() != stamp
    monkeypatch.setattr(dut, "_done", False)
    dut.ensure_fresh()
    # tree_kernel's cache too, though its file did not change, and every other kernel module's
    assert [f.name for f in files if f.exists()] == []
    assert other.exists()  # only numba's kernel caches are touched
    assert (package / "collision/__pycache__" / dut._STAMP).read_text() == dut.sources_hash()


def test_once_per_process(package, monkeypatch):
    dut.ensure_fresh()
    files, _ = _cached(package)
    with open(package / "cost/kernel.py", "a") as f:
        f.write("\n# edited\n")
    dut.ensure_fresh()  # already done in this process
    assert all(f.exists() for f in files)


def test_numbas_other_cache_folders_are_kept_fresh_too(package, monkeypatch, tmp_path_factory):
    """With NUMBA_CACHE_DIR (or numba's user-wide folder), the cached kernels
    below a drake_social folder there go when a source changes; other
    packages' files called kernel.* stay."""
    cache = tmp_path_factory.mktemp("numba_cache")
    ours = cache / "work_main_drake_social_planning" / "tree_kernel.grow-70.py311.nbi"
    theirs = cache / "other_pkg" / "kernel.run-3.py311.nbi"
    for f in (ours, theirs):
        f.parent.mkdir(parents=True)
        f.write_bytes(b"x")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.mktemp("xdg")))
    dut.ensure_fresh()
    assert not ours.exists() and theirs.exists()
    assert (cache / dut._STAMP).read_text() == dut.sources_hash()
    ours.write_bytes(b"x")  # cached again under the current sources
    monkeypatch.setattr(dut, "_done", False)
    dut.ensure_fresh()
    assert ours.exists()  # stamp current: kept


# ---- the warm-up: make install fills the cache ------------------------------

_PLAN_AND_COUNT = """
import json, sys
from drake_social.cli import main
from drake_social.collision.drake_checker import make_checker
from drake_social.planning.algorithms import ALGORITHM_SPECS, plan
from drake_social.planning.rrt_star.compiled import kernel_dispatchers
from drake_social.scenario import load_scenario
tiny, out = sys.argv[1], sys.argv[2]
assert main(["plan", tiny, "--out", out]) == 0
scenario = load_scenario(tiny)
checker = make_checker(scenario, "planar")
for name in ALGORITHM_SPECS:
    plan(scenario, checker, algorithm=name, seed=3)
stats = {name: d.stats for name, d in kernel_dispatchers().items()}
print(json.dumps({"misses": {n: sum(s.cache_misses.values()) for n, s in stats.items() if s.cache_misses},
                  "hits": {n: sum(s.cache_hits.values()) for n, s in stats.items() if s.cache_hits}}))
"""


def test_after_the_warm_up_a_plan_in_a_fresh_process_compiles_nothing(tmp_path, repo_root):
    """``python -m drake_social.warmup`` (what make install runs), then the CLI's
    plan and every algorithm in a new process: numba's statistics show every
    kernel loaded from the cache (hits) and none compiled (no misses), and
    stderr has no cold-cache line."""
    import json
    import subprocess
    import sys

    warm = subprocess.run([sys.executable, "-m", "drake_social.warmup"], capture_output=True, text=True,
                          timeout=1800, cwd=tmp_path)
    assert warm.returncode == 0, warm.stderr
    assert warm.stdout.startswith("drake_social kernels ready: ")
    run = subprocess.run([sys.executable, "-c", _PLAN_AND_COUNT, str(repo_root / "scenarios/tiny.yaml"),
                          str(tmp_path / "out")], capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    counts = json.loads(run.stdout.splitlines()[-1])
    assert counts["misses"] == {}
    assert counts["hits"].get("drake_social.planning.rrt_star.tree_kernel.grow", 0) >= 1
    assert counts["hits"].get("drake_social.collision.planar_kernel.valid", 0) >= 1
    assert "cold" not in run.stderr


def test_a_cold_cache_is_said_once_with_the_compile_time(monkeypatch, caplog):
    """When loading the kernels had to compile (numba's cache misses grew), one
    warning says so with the time it took; the next run says nothing."""
    import logging
    import types

    import numpy as np

    from drake_social.planning.rrt_star import compiled

    misses = iter([0, 7, 7, 7])
    monkeypatch.setattr(compiled, "cache_misses", lambda: next(misses))
    monkeypatch.setattr(compiled, "_cold_cache_reported", False)
    monkeypatch.setattr(compiled, "grow_params", lambda *args: "params")
    calls = []

    def grow(rng, it_start, it_stop, params, state):  # the throwaway load: the start's goal connection
        calls.append((it_start, it_stop, params, state))

    grow.signatures = []  # not loaded in this process
    fake = types.SimpleNamespace(grow=grow, init_state=lambda start, iterations, params: ("state", iterations),
                                 seed_chain=lambda seed, params, state: state)  # a one-row seed: the tree unchanged
    monkeypatch.setattr(compiled, "tree_kernel", fake)
    options = types.SimpleNamespace(iterations=5)
    with caplog.at_level(logging.INFO, logger=compiled.__name__):
        run = compiled.prepare(None, None, None, options, 1.0, np.zeros(4), np.ones(4))
        compiled.prepare(None, None, None, options, 1.0, np.zeros(4), np.ones(4))
    assert run.params == "params" and run.iterations == 5
    assert calls == [(-1, 0, "params", ("state", 1))] * 2
    assert len(caplog.records) == 1 and caplog.records[0].levelno == logging.WARNING
    message = caplog.records[0].getMessage()
    assert message.startswith("numba's cache of the planning kernels was cold: compiled them once in ")
    assert "python -m drake_social.warmup" in message
