"""Shared fixtures of the test suite and the deterministic Hypothesis profile."""

from __future__ import annotations

import importlib
import importlib.util
import os
import signal
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

# A test run started in the background of a non-interactive shell (`make test &`)
# inherits SIGINT ignored, and so would every command the tests start: the Ctrl-C
# tests need it live. A handled signal is reset to the default in a child.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

#: The repository root (the folder holding ``scenarios/`` and ``drake_social/``).
REPO_ROOT = Path(__file__).resolve().parent.parent
#: The scenario files shipped with the project.
SCENARIO_DIR = REPO_ROOT / "scenarios"
#: Written by ``make install`` once ``pip install -e '.[test,bench]'`` succeeded.
INSTALLED_MARKER = REPO_ROOT / ".venv" / ".installed"


def extras_must_be_installed() -> bool:
    """Whether the optional extras must be importable here: on CI
    (``CI=true``), or in the venv that ``make install`` filled (its marker
    exists and this interpreter is that venv's)."""
    if os.environ.get("CI", "").strip().lower() in ("1", "true", "yes"):
        return True
    venv = INSTALLED_MARKER.parent
    return INSTALLED_MARKER.exists() and Path(sys.prefix).resolve() == venv.resolve()


def import_extra(package: str, module: str | None = None):
    """Imports ``module`` (default: ``package``), which needs the optional
    third-party ``package`` (e.g. ``ompl`` of the ``bench`` extra).

    Skips only when ``package`` itself is not installed, and fails instead
    where it must be (:func:`extras_must_be_installed`). Any error while
    importing ``module`` (say, a broken import inside the project's own
    ``drake_social.experiments.bench.ompl_baseline``) propagates: a test error,
    never a skip.
    """
    if importlib.util.find_spec(package) is None:
        if extras_must_be_installed():
            pytest.fail(f"the {package!r} package is missing, but `make install` installs it here "
                        f"(CI={os.environ.get('CI')!r}, {INSTALLED_MARKER} exists): reinstall with "
                        f"`{sys.executable} -m pip install -e '.[test,bench,docs]'`", pytrace=False)
        pytest.skip(f"the optional {package!r} package is not installed")
    return importlib.import_module(module or package)

# CI must be deterministic: Hypothesis draws from a fixed seed (derandomize),
# and no wall-clock deadline makes a slow machine fail a property. Tests choose
# their own max_examples to stay fast.
settings.register_profile(
    "drake_social",
    derandomize=True,
    deadline=None,
    print_blob=True,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.load_profile("drake_social")


@pytest.fixture(scope="session")
def repo_root() -> Path:
    """The repository root."""
    return REPO_ROOT


@pytest.fixture(scope="session")
def tiny_scenario_path() -> Path:
    """``scenarios/tiny.yaml``: one room, one person, a desk, the 1.5 m bar."""
    return SCENARIO_DIR / "tiny.yaml"


@pytest.fixture(scope="session")
def tiny_scenario(tiny_scenario_path):
    """The tiny scenario, loaded and validated once per session.

    Treat it as read-only; use ``dataclasses.replace`` for variants.
    """
    from drake_social.scenario import load_scenario

    return load_scenario(tiny_scenario_path)


@pytest.fixture(scope="session")
def extra():
    """:func:`import_extra` as a fixture: ``extra("ompl", "drake_social.experiments.bench.ompl_baseline")``."""
    return import_extra


@pytest.fixture
def rng() -> np.random.Generator:
    """A fresh generator with a fixed seed for every test (order-independent)."""
    return np.random.default_rng(20240531)


# ---- markers by rule (registered in pyproject.toml; `make test-fast` leaves them out)


def _code_names(funcs) -> set[str]:
    """The global and attribute names that the code of ``funcs`` uses, with
    those of the functions and classes of their own module that it names
    (and so on); names that resolve to the ``subprocess`` module come back
    as ``"subprocess"``."""
    import subprocess

    names: set[str] = set()
    seen: set = set()
    stack = [(getattr(f, "__code__", None), getattr(f, "__globals__", {})) for f in funcs]
    while stack:
        code, module_globals = stack.pop()
        if code is None or code in seen:
            continue
        seen.add(code)
        names.update(code.co_names)
        stack.extend((c, module_globals) for c in code.co_consts if hasattr(c, "co_names"))
        for name in code.co_names:
            value = module_globals.get(name)
            if value is subprocess:
                names.add("subprocess")
            elif getattr(value, "__module__", None) == module_globals.get("__name__"):
                members = vars(value).values() if isinstance(value, type) else [value]
                stack.extend((getattr(m, "__code__", None), module_globals) for m in members)
    return names


def pytest_collection_modifyitems(config, items):
    """Marks ``browser`` every test that asks for headless Chromium
    (``browser.require_chromium()``), and ``subprocess`` every test that
    starts another process (its code, a fixture it requests or a helper of
    their module uses the ``subprocess`` module)."""
    for item in items:
        func = getattr(item, "function", None)
        if func is None:
            continue
        fixtures = [d.func for defs in item._fixtureinfo.name2fixturedefs.values() for d in defs]
        names = _code_names([func, *fixtures])
        if "require_chromium" in names:
            item.add_marker(pytest.mark.browser)
        if "subprocess" in names:
            item.add_marker(pytest.mark.subprocess)
