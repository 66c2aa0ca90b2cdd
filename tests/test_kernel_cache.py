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
             package / "collision/__pycache__/planar_kernel._pair-99.py311.nbi"]
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
    assert not any(f.exists() for f in files)  # tree_kernel's cache too, though its file did not change
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
