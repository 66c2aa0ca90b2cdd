"""Standing people give the same executed trajectories, bit for bit.

sha256 of the executed ``q``, ``v`` and ``times`` bytes of a default
``simulate`` (the scenario's own planner, seed and execution), taken with the
dependency versions of constraints.txt: the walking-people and replanning
machinery must leave a scenario whose people stand exactly as it was. A new
release of drake, numba, numpy or ruckig may move floating-point results; then
constraints.txt and these digests are refreshed together.
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
    ("tiny", "kinematic", 3329, "6c2f4ab49ef1c0b7"),
    ("tiny", "dynamic", 3329, "3b08d8b973ae9b25"),
    ("office_bar", "kinematic", 5828, "b5581bcac446570d"),
]


@pytest.mark.slow
@pytest.mark.parametrize("name, mode, samples, digest", PINNED)
def test_a_static_scenario_executes_exactly_as_before(name, mode, samples, digest):
    run = simulate(load_scenario(SCENARIOS / f"{name}.yaml"), mode=mode, analyze=False)
    assert len(run.times) == samples
    data = np.ascontiguousarray(run.q).tobytes() + np.ascontiguousarray(run.v).tobytes() + run.times.tobytes()
    assert hashlib.sha256(data).hexdigest()[:16] == digest
    assert not run.stops and not run.stopped.any()
