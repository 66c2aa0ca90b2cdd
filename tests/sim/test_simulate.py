"""Whole runs of the execution diagram on tiny_scenario.yaml, in both modes and both executions.

Each run is checked against independent facts: the executed trajectory is
re-checked for collisions, its end is the goal, speeds respect the limits,
and in synchronized kinematic mode every body point stays on the planned path.
"""

from __future__ import annotations

import copy
import tracemalloc

import numpy as np
import pytest

from drake_social.scenario.geometry import arm_geometry
from drake_social.collision.drake_checker import make_checker
from drake_social.planning.algorithms import plan
from drake_social.sim.analysis import body_points, config_deviation, densify, point_deviation
from drake_social.sim.diagram import build_diagram
from drake_social.sim.results import SimulationDiverged
from drake_social.sim.run import simulate

# Whole executions in Drake's Simulator.
pytestmark = pytest.mark.slow


def _paper_planner(scenario):
    """``scenario`` with the paper's planner and objective (limits.PAPER_PLANNER, PAPER_OBJECTIVE)."""
    paper = copy.deepcopy(scenario)
    paper.planner.optimize, paper.planner.near_radius_mode = False, "fixed"
    paper.social.length_weight = 0.0
    return paper


@pytest.fixture(scope="module")
def tiny_path(tiny_scenario):
    """The paper's raw tree path (14 waypoints), which the paper's execution was
    made for: base and arm move independently between waypoints close together
    and stay clear of the room (min clearance 4 cm). The default, optimised
    path has 13 waypoints farther apart; see
    test_paper_execution_of_far_waypoints_may_touch_and_says_so."""
    paper = _paper_planner(tiny_scenario)
    result = plan(paper, make_checker(paper, "numpy"))
    assert result.success
    return result.waypoints


@pytest.fixture(scope="module")
def runs(tiny_scenario, tiny_path):
    return {
        (mode, ex): simulate(tiny_scenario, mode=mode, execution=ex, waypoints=tiny_path)
        for mode in ("kinematic", "dynamic")
        for ex in ("synchronized", "paper")
    }


@pytest.mark.parametrize("mode", ["kinematic", "dynamic"])
@pytest.mark.parametrize("execution", ["synchronized", "paper"])
def test_run_reaches_the_goal_collision_free(runs, tiny_scenario, tiny_path, mode, execution):
    dut = runs[(mode, execution)]
    assert dut.reached, dut.message
    e = tiny_scenario.execution
    # The sequencer's rule held at its last update, one control period before
    # the run stopped: base and joints within tolerance of the goal, up to
    # what the robot can move in that period.
    q_end = dut.q[-1]
    slack = e.control_period * np.array([e.max_base_speed, *e.arm_max_velocity])
    assert np.hypot(*(q_end[:2] - tiny_scenario.goal[:2])) <= e.base_tolerance + slack[0]
    assert np.all(np.abs(q_end[2:] - np.asarray(tiny_scenario.goal[2:])) <= e.joint_tolerance + slack[1:])
    assert dut.report.collision_free
    assert dut.report.min_clearance > 0
    assert dut.target_index[-1] == len(tiny_path) - 1
    # Time to goal: no faster than the base can cover the path at its top speed.
    base_length = np.hypot(*np.diff(tiny_path[:, :2], axis=0).T).sum()
    assert dut.time_to_goal >= base_length / e.max_base_speed - 2 * e.base_tolerance / e.max_base_speed
    assert dut.time_to_goal <= e.time_limit


@pytest.mark.parametrize("execution", ["synchronized", "paper"])
def test_kinematic_speeds_respect_the_limits(runs, tiny_scenario, execution):
    dut = runs[("kinematic", execution)]
    e = tiny_scenario.execution
    assert np.max(np.hypot(dut.v[:, 0], dut.v[:, 1])) <= e.max_base_speed * (1 + 1e-9)
    assert np.max(np.abs(dut.wheel_speeds)) <= e.max_wheel_speed * (1 + 1e-9)
    # The arm's velocity is the Ruckig reference's, within its limits.
    assert np.all(np.max(np.abs(dut.v[:, 2:]), axis=0) <= np.asarray(e.arm_max_velocity) * (1 + 1e-6))
    # The logged base velocity is what moved the base: the controller is held
    # for each control period, so the base moves in straight pieces and the
    # velocity logged at t_k (published before the update at t_k) is the one
    # applied over [t_k-1, t_k].
    fd = np.diff(dut.q[:, :2], axis=0) / np.diff(dut.times)[:, None]
    np.testing.assert_allclose(fd, dut.v[1:, :2], atol=1e-9)


def test_synchronized_kinematic_stays_on_the_planned_path(runs):
    dut = runs[("kinematic", "synchronized")]
    assert dut.report.max_point_deviation["max"] < 1e-6  # the target is 0.01 m
    assert dut.report.max_config_deviation < 1e-6
    # Same segments, same cost: the executed integral matches the planned one.
    r = dut.report
    assert r.executed_social_cost == pytest.approx(r.planned_social_cost, rel=0.01, abs=1e-6)


def test_paper_execution_deviation_is_reported(runs):
    sync, paper = runs[("kinematic", "synchronized")], runs[("kinematic", "paper")]
    # Independent base and arm leave the straight segments; the report shows it.
    assert paper.report.max_config_deviation > 10 * sync.report.max_config_deviation
    assert paper.report.max_point_deviation["max"] > 0.05


def test_dynamic_synchronized_tracks_within_a_few_centimetres(runs):
    dut = runs[("dynamic", "synchronized")]
    assert dut.report.max_point_deviation["max"] < 0.05


def test_paper_execution_of_far_waypoints_may_touch_and_says_so(tiny_scenario):
    """The default path's waypoints are far apart: the paper's execution, base
    and arm independent, leaves its segments far enough to touch the room. The
    report's independent re-check finds the contact; in dynamic mode the
    default contact solver (TAMSI) fails in it and the run stops with one
    line that names the setting that solves it, which then reaches the goal."""
    path = plan(tiny_scenario, make_checker(tiny_scenario, "numpy")).waypoints
    kinematic = simulate(tiny_scenario, mode="kinematic", execution="paper", waypoints=path)
    assert kinematic.reached
    assert not kinematic.report.collision_free
    assert kinematic.report.min_clearance < 0
    touch = kinematic.report.first_collision_time
    with pytest.raises(SimulationDiverged, match=r"^the dynamic simulation diverged by t = \d+\.\d\d s \(the "
                       r"plant's tamsi contact solver did not converge\): a hard contact; "
                       r"execution.contact_approximation: lagged or similar \(SAP\) solves it") as failed:
        simulate(tiny_scenario, mode="dynamic", execution="paper", waypoints=path, analyze=False)
    # It fails in the contact, not before the kinematic run's first one.
    assert failed.value.time >= touch - 1.0
    lagged = copy.deepcopy(tiny_scenario)
    lagged.execution.contact_approximation = "lagged"
    dut = simulate(lagged, mode="dynamic", execution="paper", waypoints=path)
    assert dut.reached
    assert not dut.report.collision_free  # it touched, and the contact held it out of the wall
    assert dut.report.min_clearance > -0.01


def test_runs_are_deterministic(tiny_scenario, tiny_path):
    a = simulate(tiny_scenario, mode="kinematic", execution="paper", waypoints=tiny_path, analyze=False)
    b = simulate(tiny_scenario, mode="kinematic", execution="paper", waypoints=tiny_path, analyze=False)
    np.testing.assert_array_equal(a.q, b.q)
    assert a.time_to_goal == b.time_to_goal


def test_time_limit_stops_and_says_so(tiny_scenario, tiny_path):
    dut = simulate(tiny_scenario, waypoints=tiny_path, time_limit=2.0, analyze=False)
    assert not dut.reached
    assert dut.time_to_goal is None
    assert dut.sim_time == pytest.approx(2.0)
    assert "not reached within the time limit of 2 s" in dut.message


def test_planner_in_the_diagram_plans_the_same_path(tiny_scenario):
    checker = make_checker(tiny_scenario, "numpy")
    dut = simulate(tiny_scenario, checker=checker, analyze=False)
    expected = plan(tiny_scenario, make_checker(tiny_scenario, "numpy"))
    np.testing.assert_array_equal(dut.waypoints, expected.waypoints)
    assert dut.planner is not None and dut.planner.success
    assert dut.reached


def test_no_path_is_reported_without_executing(tiny_scenario):
    scenario = copy.deepcopy(tiny_scenario)
    scenario.planner.iterations = 1
    scenario.planner.goal_bias = 0.0
    dut = simulate(scenario, checker=make_checker(scenario, "numpy"))
    assert not dut.reached and not dut.planner.success
    assert dut.message.startswith("no path to execute")
    assert len(dut.times) == 0


KINEMATIC = {"drive", "hold", "base", "to_pose"}


@pytest.mark.parametrize("mode, execution, autonomy, station", [
    ("kinematic", "synchronized", {"planner", "sequencer", "reference", "controller"}, KINEMATIC),
    ("kinematic", "paper", {"planner", "sequencer", "arm", "controller"}, KINEMATIC),
    ("dynamic", "paper", {"planner", "sequencer", "arm", "controller"}, {"drive", "hold", "plant", "servo"}),
])
def test_subsystems_are_named(tiny_scenario, mode, execution, autonomy, station):
    dut = build_diagram(tiny_scenario, mode=mode, execution=execution, checker=make_checker(tiny_scenario, "numpy"))
    assert autonomy <= {s.get_name() for s in dut.autonomy.diagram.GetSystems()}
    assert station <= {s.get_name() for s in dut.station.diagram.GetSystems()}
    have = {s.get_name() for s in dut.diagram.GetSystems()}
    assert {"station", "autonomy", "q_log", "v_log", "wheel_speeds_log", "target_log", "reference_log",
            "index_log"} <= have


def test_bad_choices_are_refused(tiny_scenario):
    with pytest.raises(ValueError, match="unknown mode 'fast'"):
        build_diagram(tiny_scenario, mode="fast")
    with pytest.raises(ValueError, match=r"build_diagram: waypoints: must be an \(N, 4\) array .* got 0 waypoints"):
        build_diagram(tiny_scenario, waypoints=np.zeros((0, 4)))


# ---- analysis, against hand computations -----------------------------------------


def test_config_deviation_point_to_segment_by_hand():
    planned = np.array([[0, 0, 0, 0], [2, 0, 0, 0], [2, 2, 0, 0]], float)
    executed = np.array([[1, 0.5, 0, 0], [2.3, 1, 0, 0], [3, -1, 0, 0], [1, 0, 0, 0.2]])
    # Distances: 0.5 to the first segment; 0.3 to the second; (3,-1) is sqrt(2) from the corner; 0.2.
    assert config_deviation(planned, executed) == pytest.approx(np.sqrt(2), abs=1e-12)
    assert config_deviation(planned, executed[:2]) == pytest.approx(0.5, abs=1e-12)


def _config_deviation_by_every_pair(planned, executed):
    """The full comparison of every (executed, segment) pair, as a reference."""
    p = np.asarray(planned, float).reshape(-1, 4)
    x = np.asarray(executed, float).reshape(-1, 4)
    if len(p) == 1:
        return float(np.max(np.linalg.norm(x - p[0], axis=1))) if len(x) else 0.0
    a, d = p[:-1], np.diff(p, axis=0)
    dd = np.einsum("sk,sk->s", d, d)
    xc = x[:, None, :]
    t = np.einsum("tsk,sk->ts", xc - a, d) / np.where(dd > 0, dd, 1.0)
    t = np.clip(np.where(dd > 0, t, 0.0), 0.0, 1.0)
    return float(np.linalg.norm(xc - (a + t[..., None] * d), axis=-1).min(axis=1).max())


def test_config_deviation_is_the_full_comparison_bit_for_bit(rng):
    for trial in range(300):
        s, t = int(rng.integers(1, 40)), int(rng.integers(1, 200))
        planned = rng.normal(size=(s, 4)) * rng.choice([0.01, 1.0, 100.0], size=(1, 4))
        if trial % 4 == 0:
            planned[1::2] = planned[::2][: len(planned[1::2])]  # zero-length segments
        # Executed points near the path (the usual case) and far from it.
        executed = planned[rng.integers(0, s, size=t)] + rng.normal(size=(t, 4)) * rng.choice([1e-3, 10.0])
        for block in (1, 5, 1 << 16):
            assert config_deviation(planned, executed, block=block) == _config_deviation_by_every_pair(
                planned, executed), (trial, block)


def test_config_deviation_memory_does_not_grow_with_the_pairs(rng):
    """2000 executed configurations against 2000 segments: the full comparison
    holds 4 x 10^6 pairs x 4 coordinates (128 MB per temporary); the blocked
    search stays within a few megabytes."""
    import tracemalloc

    planned = np.cumsum(rng.normal(size=(2001, 4)) * 0.05, axis=0)
    executed = planned[rng.integers(0, 2001, size=2000)] + rng.normal(size=(2000, 4)) * 0.01
    tracemalloc.start()
    try:
        dut = config_deviation(planned, executed)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 16e6, peak
    assert dut == _config_deviation_by_every_pair(planned, executed)


def test_point_deviation_of_the_path_itself_is_within_half_the_spacing(tiny_scenario, tiny_path):
    geometry = arm_geometry(tiny_scenario)
    on_path = densify(geometry, tiny_path, 0.037)  # other samples of the same segments
    dev = point_deviation(geometry, tiny_path, on_path)
    assert dev["max"] <= 1e-9
    # A base offset of 5 cm perpendicular to a straight path shows as 5 cm at the base.
    straight = np.array([[1.0, 2.5, 0.0, 1.5], [6.0, 2.5, 0.0, 1.5]])
    moved = densify(geometry, straight, 0.05) + [0.0, 0.05, 0.0, 0.0]
    dev = point_deviation(geometry, straight, moved[5:-5])
    assert dev["base"] == pytest.approx(0.05, abs=1e-12)


def test_densify_bounds_the_motion_between_checked_configurations(tiny_scenario, tiny_path):
    geometry = arm_geometry(tiny_scenario)
    dense = densify(geometry, tiny_path, 0.05)
    step = geometry.max_displacement(dense[:-1], dense[1:], include_body=True)
    assert step.max() <= 0.05 + 1e-12
    # Independent: actual body point motion between neighbours is below the bound.
    moved = np.linalg.norm(np.diff(body_points(geometry, dense), axis=0), axis=-1).max()
    assert moved <= 0.05 + 1e-12
    np.testing.assert_array_equal(dense[0], tiny_path[0])
    np.testing.assert_array_equal(dense[-1], tiny_path[-1])


def test_densify_owner_names_the_configuration_each_sample_follows(tiny_scenario, tiny_path):
    geometry = arm_geometry(tiny_scenario)
    dense, owner = densify(geometry, tiny_path, 0.05, return_owner=True)
    assert len(owner) == len(dense) and owner[0] == 0 and owner[-1] == len(tiny_path) - 1
    assert np.all(np.diff(owner) >= 0)
    # Every given configuration stands in the dense list exactly, at its owner's first index.
    for k, q in enumerate(tiny_path):
        first = int(np.argmax(owner == k))
        np.testing.assert_array_equal(dense[first], q)
    # Samples in between lie on the segment from their owner to the next one.
    mid = np.flatnonzero(np.r_[True, np.diff(owner) == 0])[1:]
    a, b = tiny_path[owner[mid]], tiny_path[owner[mid] + 1]
    t = np.einsum("ij,ij->i", dense[mid] - a, b - a) / np.einsum("ij,ij->i", b - a, b - a)
    np.testing.assert_allclose(dense[mid], a + t[:, None] * (b - a), atol=1e-12)
    assert np.all((t > 0) & (t < 1))


def _peak_bytes(function, *args, **kwargs):
    tracemalloc.start()
    try:
        value = function(*args, **kwargs)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return value, peak


def test_point_deviation_memory_does_not_grow_with_the_path(tiny_scenario):
    """A long path (review: 10,000 rows of start, goal densified to 11 M
    configurations, 3 GB) is searched in pieces; the figures are those of
    the curves it traces."""
    geometry = arm_geometry(tiny_scenario)
    start, goal = np.array(tiny_scenario.start, float), np.array(tiny_scenario.goal, float)
    executed = densify(geometry, np.array([start, goal]), 0.2) + [0.0, 0.03, 0.01, -0.02]
    # The same segment back and forth: every figure is that of the one segment.
    zigzag = np.tile([start, goal], (1000, 1))
    once = point_deviation(geometry, np.array([start, goal]), executed)
    dut, peak = _peak_bytes(point_deviation, geometry, zigzag, executed)
    assert peak < 40e6, peak
    assert dut == once
    # Distinct segments (each 2 mm off the last): searched piece by piece,
    # within rounding of one search of the whole densified path.
    rng = np.random.default_rng(3)
    wander = np.tile([start, goal], (200, 1)) + [0.0, 1.0, 0.0, 0.0] * rng.uniform(0, 0.002, (400, 1))
    whole = point_deviation(geometry, wander, executed, block=10**9)
    dut, peak = _peak_bytes(point_deviation, geometry, wander, executed)
    assert peak < 40e6, peak
    assert dut == pytest.approx(whole, rel=0, abs=1e-12)


def test_point_deviation_memory_does_not_grow_with_one_long_segment(tiny_scenario):
    """One straight segment longer than a piece (a two-row path 2 km long) is
    cut into parts of at most ``block`` samples: memory is that of a piece,
    not of the whole segment, and the figures are those of searching the
    whole segment at once."""
    geometry = arm_geometry(tiny_scenario)
    start = np.array(tiny_scenario.start, float)
    far = start + [2000.0, 0.0, 0.0, 0.0]
    planned = np.array([start, far])
    executed = start + np.linspace(0, 1, 50)[:, None] * (far - start) + [0.0, 0.03, 0.01, -0.02]
    whole, whole_peak = _peak_bytes(point_deviation, geometry, planned, executed, spacing=0.05, block=10**9)
    dut, peak = _peak_bytes(point_deviation, geometry, planned, executed, spacing=0.05, block=1 << 10)
    assert peak < whole_peak / 4, (peak, whole_peak)
    assert dut == pytest.approx(whole, rel=0, abs=1e-9)


def test_config_deviation_never_measures_more_pairs_than_the_full_comparison(rng, monkeypatch):
    """The worst case: every segment overlaps every other (start, goal, start,
    ... 2000 segments), so every one is a candidate of every configuration.
    Counted, not timed: the point-to-segment distances it measures are at most
    the full comparison's S x T plus one nearest-sample bound per configuration."""
    import drake_social.sim.analysis as analysis

    start, goal = np.array([1.0, 2.5, 0.0, 1.5708]), np.array([6.5, 2.5, 0.0, 1.5708])
    planned = np.tile([start, goal], (1001, 1))[:2001]
    executed = start + rng.uniform(0, 1, (2000, 1)) * (goal - start) + rng.normal(size=(2000, 4)) * 0.01
    measured = []
    original = analysis._segment_distances
    monkeypatch.setattr(analysis, "_segment_distances", lambda x, *rest: measured.append(len(x)) or original(x, *rest))
    dut = config_deviation(planned, executed)
    monkeypatch.setattr(analysis, "_segment_distances", original)
    assert dut == _config_deviation_by_every_pair(planned, executed)
    segments, configurations = len(planned) - 1, len(executed)
    assert sum(measured) <= segments * configurations + configurations


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf, 1e154, -3e200, 1e308])
def test_config_deviation_of_extreme_values_is_the_full_comparison(rng, value):
    planned = rng.normal(size=(30, 4))
    executed = planned[rng.integers(0, 30, size=50)] + rng.normal(size=(50, 4)) * 0.01
    for p, x in ((planned, executed), (executed[:30], planned)):
        x = x.copy()
        x[7, 2] = value
        with np.errstate(all="ignore"):
            np.testing.assert_equal(config_deviation(p, x), _config_deviation_by_every_pair(p, x))
            np.testing.assert_equal(config_deviation(x, p), _config_deviation_by_every_pair(x, p))
