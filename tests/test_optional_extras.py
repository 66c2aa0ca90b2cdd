"""Optional extras (``ompl``, the ``bench`` extra) skip only where they may be missing.

:func:`conftest.import_extra` skips a test when the third-party package is not
installed, fails it where ``make install`` installs it (CI, or the
Makefile's venv), and never turns an error inside the project's own module
into a skip.
"""

from __future__ import annotations

import sys

import pytest

MISSING = "drake_social_no_such_package"


@pytest.fixture
def dut(extra, monkeypatch, tmp_path):
    """``import_extra``, outside CI and outside the Makefile's venv."""
    module = sys.modules[extra.__module__]
    monkeypatch.delenv("CI", raising=False)
    monkeypatch.setattr(module, "INSTALLED_MARKER", tmp_path / "venv" / ".installed")
    return extra


def test_a_missing_package_skips_where_it_is_optional(dut):
    with pytest.raises(pytest.skip.Exception, match=f"optional '{MISSING}' package is not installed"):
        dut(MISSING, "drake_social.experiments.bench.ompl_baseline")


@pytest.mark.parametrize("ci", ["true", "1", "True"])
def test_a_missing_package_fails_on_ci(dut, monkeypatch, ci):
    monkeypatch.setenv("CI", ci)
    with pytest.raises(pytest.fail.Exception, match=f"the '{MISSING}' package is missing, but `make install`"):
        dut(MISSING)


def test_a_missing_package_fails_in_the_makefiles_venv(dut, monkeypatch, tmp_path):
    module = sys.modules[dut.__module__]
    marker = tmp_path / "venv" / ".installed"
    marker.parent.mkdir()
    monkeypatch.setattr(sys, "prefix", str(marker.parent))
    assert not module.extras_must_be_installed()  # no marker yet: pip install -e . by hand
    marker.touch()
    assert module.extras_must_be_installed()
    with pytest.raises(pytest.fail.Exception, match="reinstall with"):
        dut(MISSING)
    monkeypatch.setattr(sys, "prefix", str(tmp_path))  # another interpreter: the marker is not its own
    assert not module.extras_must_be_installed()


def test_a_broken_project_module_is_an_error_not_a_skip(dut, monkeypatch, tmp_path):
    """The package is there (numpy), the module importing it is broken."""
    (tmp_path / "broken_baseline.py").write_text(f"import numpy\nimport {MISSING}\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(ModuleNotFoundError, match=MISSING):
        dut("numpy", "broken_baseline")
    sys.modules.pop("broken_baseline", None)


def test_an_installed_package_returns_the_module(dut):
    import drake_social.experiments.bench.planners as expected

    assert dut("numpy", "drake_social.experiments.bench.planners") is expected
