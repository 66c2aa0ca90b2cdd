"""point_deviation's compiled search against its numpy formulation (the
reference), on random paths and executions, and its cost against the numpy one."""

from __future__ import annotations

import time

import numpy as np
import pytest

from drake_social.scenario.geometry import arm_geometry
from drake_social.sim import analysis_kernel
from drake_social.sim.analysis import body_points, densify, point_deviation

pytestmark = pytest.mark.skipif(not analysis_kernel.AVAILABLE, reason="numba is not installed")


def _random_case(rng, scenario, waypoints: int, samples: int, noise: float):
    """A random planned path in the room and an execution near it: the path
    densified, resampled, with a smooth random offset of up to ``noise``."""
    x0, y0, x1, y1 = scenario.world.bounds
    planned = np.column_stack([rng.uniform(x0 + 1, x1 - 1, waypoints), rng.uniform(y0 + 1, y1 - 1, waypoints),
                               rng.uniform(-2.5, 2.5, waypoints), rng.uniform(-2.0, 2.0, waypoints)])
    geometry = arm_geometry(scenario)
    dense = densify(geometry, planned, 0.01)
    executed = dense[np.sort(rng.choice(len(dense), min(samples, len(dense)), replace=False))]
    phase = rng.uniform(0, 2 * np.pi, 4)
    s = np.linspace(0, 6 * np.pi, len(executed))[:, None]
    executed = executed + noise * np.sin(s + phase) * [1.0, 1.0, 0.3, 0.3]
    return geometry, planned, executed


@pytest.mark.parametrize("noise", [0.0, 1e-4, 0.05, 0.4])
def test_compiled_search_gives_the_reference_figures(tiny_scenario, rng, noise):
    for _ in range(3):
        geometry, planned, executed = _random_case(rng, tiny_scenario, 8, 1500, noise)
        reference = point_deviation(geometry, planned, executed, compiled=False)
        dut = point_deviation(geometry, planned, executed, compiled=True)
        assert dut.keys() == reference.keys()
        for name in reference:
            # Both are distances to points of the true curves: the compiled
            # search (Newton on each dense step) is never worse than the golden
            # sections' 30 steps and within their precision of them.
            assert dut[name] <= reference[name] + 1e-12, name
            assert dut[name] == pytest.approx(reference[name], rel=1e-6, abs=1e-8), name


def test_compiled_search_on_the_path_itself_is_zero(tiny_scenario, rng):
    """Executed configurations on the planned segments: every figure is 0 to
    rounding (the golden sections leave up to ~1e-9 m)."""
    geometry, planned, _ = _random_case(rng, tiny_scenario, 6, 10, 0.0)
    t = rng.uniform(0, 1, 2000)
    i = rng.integers(0, len(planned) - 1, 2000)
    on_path = planned[i] + t[:, None] * (planned[i + 1] - planned[i])
    dut = point_deviation(geometry, planned, on_path, compiled=True)
    assert dut["max"] <= 1e-12


def test_compiled_search_measures_a_known_offset(tiny_scenario):
    """A base moved 3 cm sideways off a straight path with the arm fixed: every
    body point is 3 cm off its (straight) curve."""
    geometry = arm_geometry(tiny_scenario)
    planned = np.array([[1.0, 2.5, 0.4, -0.3], [6.0, 2.5, 0.4, -0.3]])
    executed = densify(geometry, planned, 0.05)[3:-3] + [0.0, 0.03, 0.0, 0.0]
    dut = point_deviation(geometry, planned, executed, compiled=True)
    for name, value in dut.items():
        assert value == pytest.approx(0.03, abs=1e-12), name
    np.testing.assert_allclose(body_points(geometry, executed)[:, 0, 1], 2.53)


def test_compiled_search_costs_a_fraction_of_the_numpy_one(tiny_scenario, rng):
    geometry, planned, executed = _random_case(rng, tiny_scenario, 12, 4000, 0.05)
    point_deviation(geometry, planned, executed[:50], compiled=True)  # loads the compiled code
    t0 = time.perf_counter()
    point_deviation(geometry, planned, executed, compiled=True)
    compiled = time.perf_counter() - t0
    t0 = time.perf_counter()
    point_deviation(geometry, planned, executed, compiled=False)
    numpy_time = time.perf_counter() - t0
    assert compiled < numpy_time / 3, (compiled, numpy_time)
