"""Throughput of the validity checkers: configurations and motions per second.

:func:`run_checker_bench` measures, per scenario, the SceneGraph checker
(single-threaded and parallel batched calls, and one call per configuration or
motion as the planners make them) and the pure-numpy checker, the share of the
time spent in Python, and how often the two checkers agree.

The share of Python is measured by comparison with Drake's own batched call
on prepared inputs, single-threaded: per item, ``1 - t_drake / t_adapter``
where ``t_adapter`` is the batched adapter (list conversion, limit checks) or
one adapter call per item (the Python loop, argument conversion, pybind11
dispatch). These use process CPU time, which other load on the machine
barely disturbs; the rates use wall time. Each time is the best of
``repeats`` runs.
"""

from __future__ import annotations

import logging
import os
import time
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
from pydrake.common import Parallelism

from drake_social.kinematics import config_distance
from drake_social.collision.drake_checker import SceneGraphChecker
from drake_social.collision.planar_checker import PlanarChecker
from drake_social.collision.geometric import GeometricChecker
from drake_social.scenario import load_scenario

__all__ = ["random_edges", "raw_distance", "run_checker_bench"]

_log = logging.getLogger(__name__)


def _best_time(fn: Callable[[], object], repeats: int) -> tuple[float, float]:
    """The shortest wall and process-CPU times of ``repeats`` calls, seconds."""
    wall = cpu = np.inf
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall = min(wall, time.perf_counter() - w0)
        cpu = min(cpu, time.process_time() - c0)
    return wall, cpu


def random_edges(
    rng: np.random.Generator, lower: np.ndarray, upper: np.ndarray, length: float, weights: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray]:
    """Random straight motions like the planner's: uniform starts, random directions.

    Each motion has length ``length`` in the weighted distance ``||W dq||``
    (the planner's steer distance) before clipping to the limits.

    Returns:
        ``(q_a, q_b)``, each (n, 4).
    """
    q_a = rng.uniform(lower, upper, size=(n, 4))
    direction = rng.normal(size=(n, 4))
    direction /= config_distance(0.0, direction, weights)[:, None]
    q_b = np.clip(q_a + length * direction, lower, upper)
    return q_a, q_b


def raw_distance(checker: SceneGraphChecker, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
    """Drake's configuration distance (E,) of each motion (its edge-step metric)."""
    return np.array([checker.drake.ComputeConfigurationDistance(a, b) for a, b in zip(q_a, q_b)])


def _bench_scenario(path: Path, num_configs: int, num_edges: int, rng: np.random.Generator, repeats: int) -> dict:
    scenario = load_scenario(path)
    drake = SceneGraphChecker(scenario)
    numpy_ = GeometricChecker(scenario)
    planar = PlanarChecker(scenario, model=drake.model)
    qs = rng.uniform(drake.lower, drake.upper, size=(num_configs, 4))
    q_a, q_b = random_edges(
        rng, drake.lower, drake.upper, scenario.planner.planning_range,
        np.asarray(scenario.planner.distance_weights, float), num_edges,
    )
    single, parallel = Parallelism(1), Parallelism.Max()
    q_list, edge_list = list(qs), list(zip(q_a, q_b))
    # One call per item is slow for numpy; time it on a fifth of the items.
    few_q, few_e = q_list[: max(1, num_configs // 5)], edge_list[: max(1, num_edges // 5)]

    def threads(n: Parallelism, fn: Callable[[], object]) -> Callable[[], object]:
        def run():
            drake.parallelism = n
            return fn()

        return run

    # label -> (function, number of items it checks)
    cases = {
        "drake_configs_single": (threads(single, lambda: drake.are_valid(qs)), num_configs),
        "drake_configs_parallel": (threads(parallel, lambda: drake.are_valid(qs)), num_configs),
        "drake_configs_raw_single": (lambda: drake.drake.CheckConfigsCollisionFree(q_list, single), num_configs),
        # Fresh clearance cache per run: repeats must not read what the last one cached.
        "drake_configs_per_call": (lambda: (drake.clear_cache(), [drake.is_valid(q) for q in few_q]), len(few_q)),
        # What is_valid asks Drake for, without our Python around it.
        "drake_configs_raw_per_call": (
            lambda: [drake.drake.CalcRobotClearance(q, drake.influence) for q in few_q],
            len(few_q),
        ),
        "numpy_configs_batched": (lambda: numpy_.are_valid(qs), num_configs),
        "numpy_configs_per_call": (lambda: [numpy_.is_valid(q) for q in few_q], len(few_q)),
        "drake_edges_single": (threads(single, lambda: drake.are_motions_valid(q_a, q_b)), num_edges),
        "drake_edges_parallel": (threads(parallel, lambda: drake.are_motions_valid(q_a, q_b)), num_edges),
        "drake_edges_raw_single": (lambda: drake.drake.CheckEdgesCollisionFree(edge_list, single), num_edges),
        "drake_edges_per_call": (
            lambda: (drake.clear_cache(), [drake.is_motion_valid(a, b) for a, b in few_e]),
            len(few_e),
        ),
        "numpy_edges_batched": (lambda: numpy_.are_motions_valid(q_a, q_b), num_edges),
        # The compiled planar checker, one call per item as the planners make them.
        "planar_clearance_per_call": (lambda: [planar.clearance(q) for q in q_list], num_configs),
        "planar_configs_per_call": (lambda: [planar.is_valid(q) for q in q_list], num_configs),
        "planar_edges_per_call": (lambda: [planar.is_motion_valid(a, b) for a, b in edge_list], num_edges),
        "numpy_edges_per_call": (lambda: [numpy_.is_motion_valid(a, b) for a, b in few_e], len(few_e)),
    }
    seconds, rate, cpu_rate = {}, {}, {}
    # Every planar kernel timed below compiled (or loaded from numba's cache) before timing.
    planar.is_motion_valid(q_a[0], q_b[0])
    planar.clearance(q_a[0])
    planar.is_valid(q_a[0])
    for label, (fn, count) in cases.items():
        wall, cpu = _best_time(fn, repeats)
        seconds[label] = {"wall": wall, "cpu": cpu, "items": count}
        rate[label], cpu_rate[label] = count / wall, count / cpu
    drake.parallelism = parallel

    valid_d, valid_n = drake.are_valid(qs), numpy_.are_valid(qs)
    edges_d, edges_n = drake.are_motions_valid(q_a, q_b), numpy_.are_motions_valid(q_a, q_b)
    disagree = np.flatnonzero(valid_d != valid_n)
    # Steps per motion (a valid motion checks steps + 1 configurations).
    drake_steps = np.maximum(1, np.ceil(raw_distance(drake, q_a, q_b) / drake.edge_step_size))
    numpy_samples, _ = numpy_.motion_samples(q_a, q_b)

    def python_share(raw: str, adapter: str) -> float:
        # Per item: C++ work (Drake's batched call, one thread) vs the adapter's CPU time.
        return 1.0 - cpu_rate[adapter] / cpu_rate[raw]

    def pick(kind: str) -> dict:
        return {
            "drake_single": rate[f"drake_{kind}_single"],
            "drake_parallel": rate[f"drake_{kind}_parallel"],
            "drake_per_call": rate[f"drake_{kind}_per_call"],
            "numpy_batched": rate[f"numpy_{kind}_batched"],
            "numpy_per_call": rate[f"numpy_{kind}_per_call"],
        }

    result = {
        "configs_per_s": pick("configs"),
        "edges_per_s": pick("edges"),
        "parallel_speedup": {
            "configs": rate["drake_configs_parallel"] / rate["drake_configs_single"],
            "edges": rate["drake_edges_parallel"] / rate["drake_edges_single"],
        },
        "python_fraction": {
            "configs_batched": python_share("drake_configs_raw_single", "drake_configs_single"),
            "configs_per_call": python_share("drake_configs_raw_per_call", "drake_configs_per_call"),
            "edges_batched": python_share("drake_edges_raw_single", "drake_edges_single"),
            # is_motion_valid runs its own search over clearance queries: there
            # is no single Drake call doing the same work to compare with.
            "edges_per_call": None,
        },
        "agreement": {
            "configs": int(num_configs - len(disagree)),
            "configs_total": int(num_configs),
            "configs_max_margin_m": float(np.abs(numpy_.clearances(qs[disagree])).max()) if len(disagree) else 0.0,
            "edges": int(np.sum(edges_d == edges_n)),
            "edges_total": int(num_edges),
        },
        "valid_fraction": {"configs": float(valid_d.mean()), "edges": float(edges_d.mean())},
        "steps_per_edge": {"drake": float(drake_steps.mean()), "numpy": (len(numpy_samples) - num_edges) / num_edges},
        # Microseconds per call, planar beside Drake (CPU time, best of the repeats).
        "per_call_us": {
            "planar_clearance": 1e6 / cpu_rate["planar_clearance_per_call"],
            "drake_clearance": 1e6 / cpu_rate["drake_configs_raw_per_call"],
            "planar_is_valid": 1e6 / cpu_rate["planar_configs_per_call"],
            "drake_is_valid": 1e6 / cpu_rate["drake_configs_per_call"],
            "planar_motion": 1e6 / cpu_rate["planar_edges_per_call"],
            "drake_motion": 1e6 / cpu_rate["drake_edges_per_call"],
        },
        "agreement_planar": {
            "configs": int(np.sum(planar.are_valid(qs) == valid_d)),
            "edges": int(np.sum(planar.are_motions_valid(q_a, q_b) == edges_d)),
        },
        "seconds": seconds,
    }
    _log.info("%s: %s", path.name, result["configs_per_s"])
    return result


def run_checker_bench(
    *, scenario_paths: Sequence[str | Path], num_configs: int = 10_000, num_edges: int = 1_000, seed: int = 0,
    repeats: int = 3,
) -> dict:
    """Measures both validity checkers on each scenario.

    Args:
        scenario_paths: scenario YAML files.
        num_configs: random configurations (uniform within the limits) per scenario.
        num_edges: random motions per scenario, of the scenario's
            ``planner.planning_range`` in its ``planner.distance_weights``
            (clipped to the limits).
        seed: seeds one independent stream per scenario
            (``SeedSequence(seed).spawn``).
        repeats: runs per measurement; the fastest counts.

    Returns:
        ``{"machine": {...}, "scenarios": {file name: {...}}}``; per scenario
        ``configs_per_s`` and ``edges_per_s`` (keys ``drake_single``,
        ``drake_parallel``, ``drake_per_call``, ``numpy_batched``,
        ``numpy_per_call``), ``parallel_speedup`` (Drake, parallel over
        single-threaded), ``python_fraction`` (``configs_batched``,
        ``configs_per_call``, ``edges_batched``, ``edges_per_call``; see the
        module docstring), ``per_call_us`` (CPU microseconds per call:
        ``planar_clearance`` / ``drake_clearance`` (Drake's
        ``CalcRobotClearance``), ``planar_is_valid`` / ``drake_is_valid``,
        ``planar_motion`` / ``drake_motion``), ``agreement`` counts between
        the checkers (``agreement_planar``: planar against Drake),
        ``valid_fraction``, mean ``steps_per_edge`` (Drake's, numpy's; a
        valid motion checks steps + 1 configurations) and the raw ``seconds``
        (wall, CPU, items) of every measurement.
    """
    if num_configs < 1 or num_edges < 1 or repeats < 1:
        raise ValueError(f"num_configs, num_edges and repeats must be >= 1, got {num_configs}, {num_edges}, {repeats}")
    paths = [Path(p) for p in scenario_paths]
    streams = np.random.SeedSequence(seed).spawn(len(paths))
    return {
        "machine": {"cpu_count": os.cpu_count(), "drake_max_threads": Parallelism.Max().num_threads()},
        "scenarios": {
            p.name: _bench_scenario(p, num_configs, num_edges, np.random.default_rng(s), repeats)
            for p, s in zip(paths, streams)
        },
    }
