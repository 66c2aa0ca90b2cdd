"""Shared fixtures of the test suite and the deterministic Hypothesis profile."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

#: The repository root (the folder holding ``scenarios/`` and ``drake_social/``).
REPO_ROOT = Path(__file__).resolve().parent.parent
#: The scenario files shipped with the project.
SCENARIO_DIR = REPO_ROOT / "scenarios"

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


@pytest.fixture
def rng() -> np.random.Generator:
    """A fresh generator with a fixed seed for every test (order-independent)."""
    return np.random.default_rng(20240531)
