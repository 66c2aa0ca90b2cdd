"""The raw planner's paths as hashes: every shipped planning scenario x algorithm x seed.

``tests/data/path_hashes.json`` holds, for K = 2000, seeds 0-2, the five
algorithms, ``office_bar`` and ``generic_L`` with the planar checker and the
paper's planner settings (:data:`PAPER_PLANNER`), the
SHA-256 of each path's waypoints (little-endian float64, row-major) and its
cost. ``tests/planning/test_path_hashes.py`` compares today's planner against
it bit for bit: a refactoring must not change a single path. Regenerate only
for a change that is meant to change paths, and say so in its commit::

    .venv/bin/python tests/planning/path_hashes.py > tests/data/path_hashes.json
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

import numpy as np

SCENARIO_DIR = Path(__file__).resolve().parents[2] / "scenarios"

SCENARIOS = ("office_bar", "generic_L")
SEEDS = (0, 1, 2)
ITERATIONS = 2000
#: The paper's planner (the raw tree path, the fixed r_near, the pure social
#: integral), pinned over the scenario files' defaults (an optimised path, the
#: shrinking radius, a length tie-break).
PAPER_PLANNER = "{planner: {optimize: false, near_radius_mode: fixed}, social: {length_weight: 0.0}}"


def path_hash(waypoints: np.ndarray) -> str:
    """SHA-256 (hex) of ``waypoints`` as little-endian float64, row-major."""
    return hashlib.sha256(np.ascontiguousarray(waypoints, dtype="<f8").tobytes()).hexdigest()


def plan_case(scenario_name: str, algorithm: str, seed: int, checker=None) -> dict:
    """One raw (not optimised) plan's hash, waypoint count and cost."""
    from drake_social.collision.drake_checker import make_checker
    from drake_social.planning.algorithms import plan
    from drake_social.scenario import load_scenario

    scenario = load_scenario(SCENARIO_DIR / f"{scenario_name}.yaml", PAPER_PLANNER)
    checker = checker if checker is not None else make_checker(scenario, "planar")
    result = plan(scenario, checker, algorithm=algorithm, iterations=ITERATIONS, seed=seed)
    return {"scenario": scenario_name, "algorithm": algorithm, "seed": seed, "success": bool(result.success),
            "waypoints": int(len(result.waypoints)), "cost": float(result.cost),
            "sha256": path_hash(result.waypoints)}


def all_cases() -> list[dict]:
    from drake_social.collision.drake_checker import make_checker
    from drake_social.scenario import ALGORITHMS, load_scenario

    rows = []
    for name in SCENARIOS:
        checker = make_checker(load_scenario(SCENARIO_DIR / f"{name}.yaml"), "planar")
        for algorithm in ALGORITHMS:
            for seed in SEEDS:
                rows.append(plan_case(name, algorithm, seed, checker))
    return rows


if __name__ == "__main__":
    json.dump(all_cases(), sys.stdout, indent=1)
    sys.stdout.write("\n")
