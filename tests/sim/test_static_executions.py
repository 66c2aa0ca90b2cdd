"""Standing people give the executed trajectories they gave before people could walk.

The hashes were taken at commit 0b6602c (before the walking people of the
people models, the moving SceneGraph bodies, the safety monitor and the hold
were added): sha256 of the executed ``q``, ``v`` and ``times`` bytes of a
default ``simulate`` (the scenario's own planner, seed and execution).
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest

from drake_social.scenario import load_scenario
from drake_social.sim import simulate

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"

PINNED = [
    ("tiny", "kinematic", 3408, "27f2b098df5021b8"),
    ("tiny", "dynamic", 3408, "27d36d72e4ec5d52"),
    ("office_bar", "kinematic", 11986, "29aea01c7eb4836b"),
]


@pytest.mark.slow
@pytest.mark.parametrize("name, mode, samples, digest", PINNED)
def test_a_static_scenario_executes_exactly_as_before(name, mode, samples, digest):
    run = simulate(load_scenario(SCENARIOS / f"{name}.yaml"), mode=mode, analyze=False)
    assert len(run.times) == samples
    data = np.ascontiguousarray(run.q).tobytes() + np.ascontiguousarray(run.v).tobytes() + run.times.tobytes()
    assert hashlib.sha256(data).hexdigest()[:16] == digest
    assert not run.stops and not run.stopped.any()
