"""Every shipped planning scenario x algorithm x seed gives the same raw path,
bit for bit, as the table made before the package's reorganisation
(``tests/data/path_hashes.json``, written by ``tests/planning/path_hashes.py``)."""

from __future__ import annotations

import json

import pytest

from drake_social.scenario import ALGORITHMS
from path_hashes import SCENARIO_DIR, SCENARIOS, SEEDS, plan_case  # tests/planning/path_hashes.py

# Thirty plans of K = 2000 against the committed table: minutes.
pytestmark = pytest.mark.slow

TABLE = json.loads((SCENARIO_DIR.parent / "tests" / "data" / "path_hashes.json").read_text())


def test_the_table_covers_every_case():
    keys = {(r["scenario"], r["algorithm"], r["seed"]) for r in TABLE}
    assert keys == {(s, a, k) for s in SCENARIOS for a in ALGORITHMS for k in SEEDS}
    assert all(r["success"] and r["waypoints"] >= 2 for r in TABLE)


@pytest.mark.parametrize("row", TABLE, ids=lambda r: f"{r['scenario']}-{r['algorithm']}-{r['seed']}")
def test_the_raw_path_is_unchanged(row):
    dut = plan_case(row["scenario"], row["algorithm"], row["seed"])
    assert (dut["waypoints"], dut["sha256"]) == (row["waypoints"], row["sha256"])
    # The waypoints are bit for bit; the cost is a sum the compiled kernels
    # may order or fuse (FMA) differently on another processor: a few ulp.
    assert dut["cost"] == pytest.approx(row["cost"], rel=1e-12, abs=0.0)
