"""Shared fixtures of the test suite and the deterministic Hypothesis profile."""

from __future__ import annotations

import importlib
import importlib.util
import os
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

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
                        f"`{sys.executable} -m pip install -e '.[test,bench]'`", pytrace=False)
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
