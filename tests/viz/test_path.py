"""drake_social.viz.path: the path, cost-profile and convergence figures."""

from __future__ import annotations

import dataclasses as dc
import struct
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest

from drake_social.cost import SocialCost
from drake_social.scenario.geometry import arm_geometry
from drake_social.collision.geometric import GeometricChecker
from drake_social.planning.result import PlannerResult
from drake_social.planning.algorithms import plan
from drake_social.viz.path import (
    convergence_figure,
    cost_profile,
    cost_profile_figure,
    draw_path,
    draw_tree,
    path_figure,
    poses_along,
    sample_path,
    write_plan_figures,
)


@pytest.fixture(scope="module")
def planned(tiny_scenario):
    result = plan(tiny_scenario, GeometricChecker(tiny_scenario), algorithm="social_rrt_star", iterations=200, seed=2)
    assert result.success, result.message
    assert result.social_cost_full > 1.0  # the path passes the person: a profile worth checking
    return result


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"
    return struct.unpack(">II", data[16:24])


def _path_by_hand(waypoints: np.ndarray, s: np.ndarray) -> np.ndarray:
    """q at cumulative distances s, by piecewise-linear interpolation (plain norm)."""
    knots = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(waypoints, axis=0), axis=1))])
    return np.stack([np.interp(s, knots, waypoints[:, i]) for i in range(4)], -1)


@pytest.mark.slow
def test_cost_profile_line_is_S_at_the_samples_and_integrates_to_the_social_cost(tiny_scenario, planned):
    cost = SocialCost.from_scenario(tiny_scenario)
    fig = cost_profile_figure(tiny_scenario, {"social": planned.waypoints})
    (dut,) = fig.axes[0].get_lines()
    s, values = np.asarray(dut.get_xdata()), np.asarray(dut.get_ydata())
    assert s[0] == 0.0 and s[-1] == pytest.approx(planned.path_length, rel=1e-12)
    assert np.all(np.diff(s) >= 0)
    # The plotted values are S at the configurations reached after distance s.
    np.testing.assert_allclose(values, cost(_path_by_hand(planned.waypoints, s)), rtol=1e-9, atol=1e-12)
    assert values.max() > 0.2  # the curve is not flat zero
    integral = np.trapezoid(values, s)
    assert integral == pytest.approx(planned.social_cost_full, rel=0.02)
    # The legend reports that integral.
    assert fig.axes[0].get_legend().get_texts()[0].get_text() == f"social: integral {integral:.3g}"


def test_sample_path_respects_the_cost_resolution_and_keeps_the_waypoints(tiny_scenario, planned):
    cost = SocialCost.from_scenario(tiny_scenario)
    s, q = sample_path(planned.waypoints, cost, refine=3)
    step = np.linalg.norm(np.diff(cost.geometry.interest_points(q), axis=0), axis=-1)
    assert step.max() <= cost.resolution / 3 + 1e-9
    # Every waypoint is a sample, in order, at its cumulative distance.
    knots = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(planned.waypoints, axis=0), axis=1))])
    for wp, sk in zip(planned.waypoints, knots):
        k = int(np.argmin(np.abs(s - sk)))
        np.testing.assert_allclose(q[k], wp, atol=1e-12)
    np.testing.assert_array_equal(q[-1], planned.waypoints[-1])
    single_s, single_q = sample_path(planned.waypoints[:1], cost)
    assert single_s.tolist() == [0.0] and np.array_equal(single_q, planned.waypoints[:1])


def test_cost_profile_in_an_empty_room_is_zero_over_the_path_length(tiny_scenario):
    empty = dc.replace(tiny_scenario, people=[])
    wp = np.array([[1.0, 1.0, 0.0, 1.5708], [4.0, 1.5, 0.3, 1.5708], [4.0, 1.5, 0.3, -1.0]])
    s, values = cost_profile(wp, SocialCost.from_scenario(empty))
    assert s[-1] == pytest.approx(np.sqrt(3.0**2 + 0.5**2 + 0.3**2) + 2.5708, rel=1e-12)
    assert np.all(values == 0.0)
    fig = cost_profile_figure(empty, {"empty": wp})
    assert np.trapezoid(fig.axes[0].get_lines()[0].get_ydata(), fig.axes[0].get_lines()[0].get_xdata()) == 0.0


def test_poses_along_are_evenly_spaced_in_configuration_distance():
    # 5 units along x/y (3-4-5), then 5 rad of psi2: 10 units; repeated waypoint ignored.
    wp = np.array([[0.0, 0, 0, 0], [3.0, 4, 0, 0], [3.0, 4, 0, 0], [3.0, 4, 0, 5]])
    dut = poses_along(wp, 5)
    expected = [[0, 0, 0, 0], [1.5, 2, 0, 0], [3, 4, 0, 0], [3, 4, 0, 2.5], [3, 4, 0, 5]]
    np.testing.assert_allclose(dut, expected, atol=1e-12)
    # Weighted norm: psi2 counts double, total 15, so the midpoint is on the arm motion.
    np.testing.assert_allclose(poses_along(wp, 3, [1, 1, 1, 2])[1], [3, 4, 0, 1.25], atol=1e-12)
    with pytest.raises(ValueError, match="count"):
        poses_along(wp, 1)
    with pytest.raises(ValueError, match=r"\(N, 4\)"):
        poses_along(wp[:, :3], 3)


@pytest.mark.slow
def test_draw_path_draws_robots_at_the_even_poses_with_opaque_ends(tiny_scenario, planned):
    from matplotlib.figure import Figure

    ax = Figure().add_subplot()
    geometry = arm_geometry(tiny_scenario)
    dut = draw_path(ax, geometry, planned.waypoints, poses=6)
    expected = poses_along(planned.waypoints, 6)
    centres = np.array([r["base"][0].center for r in dut["robots"]])
    np.testing.assert_allclose(centres, expected[:, :2], atol=1e-12)
    alphas = [r["base"][0].get_alpha() for r in dut["robots"]]
    assert alphas[0] == alphas[-1] == 1.0 and all(a < 1.0 for a in alphas[1:-1])
    # The base track passes through every waypoint's base position.
    track = np.column_stack(dut["base_track"][0].get_data())
    for xy in planned.waypoints[:, :2]:
        assert np.min(np.linalg.norm(track - xy, axis=1)) < 1e-9


def test_draw_tree_draws_one_edge_per_non_root_node(planned):
    from matplotlib.figure import Figure

    ax = Figure().add_subplot()
    (dut,) = draw_tree(ax, planned.tree_nodes, planned.tree_parents)
    xs = np.asarray(dut.get_xdata())
    assert np.isnan(xs).sum() == planned.tree_size - 1
    assert draw_tree(ax, planned.tree_nodes[:1], np.array([-1])) == []


def test_convergence_line_is_the_finite_part_of_the_history(planned):
    fig = convergence_figure({"run": planned.cost_history})
    dut = fig.axes[0].get_lines()[0]
    first = planned.first_solution_iteration
    assert dut.get_xdata()[0] == first
    np.testing.assert_array_equal(dut.get_ydata(), planned.cost_history[first - 1:])
    assert np.all(np.diff(dut.get_ydata()) <= 0)  # anytime: never worse
    empty = convergence_figure({"failed": np.full(10, np.inf)})
    assert "no solution: failed" in [t.get_text() for t in empty.axes[0].texts]


def test_several_paths_share_one_cost_axes(tiny_scenario, planned):
    straight = np.array([tiny_scenario.start, tiny_scenario.goal], float)
    fig = cost_profile_figure(tiny_scenario, {"planned": planned.waypoints, "straight": straight, "none": np.zeros((0, 4))})
    ax = fig.axes[0]
    assert len(ax.get_lines()) == 2
    assert ax.get_lines()[0].get_color() != ax.get_lines()[1].get_color()
    assert "no path: none" in [t.get_text() for t in ax.texts]
    # The straight line passes in front of the person: its profile peaks above the threshold.
    assert max(ax.get_lines()[1].get_ydata()) > tiny_scenario.social.threshold


@pytest.mark.slow
def test_write_plan_figures_writes_three_non_empty_pngs(tiny_scenario, planned, tmp_path):
    dut = write_plan_figures(tiny_scenario, planned, tmp_path / "new")
    assert sorted(dut) == ["convergence", "cost_profile", "path"]
    for name, path in dut.items():
        assert path == tmp_path / "new" / f"{name}.png"
        width, height = _png_size(path)
        assert width >= 900 and height >= 500
        rgb = matplotlib.image.imread(path)[..., :3]
        assert rgb.std() > 0.05  # not a blank canvas
    # The map shows the path's robots: many more dark-blue base pixels than start and goal alone.
    rgb = matplotlib.image.imread(dut["path"])[..., :3]
    base_blue = (np.abs(rgb - np.array([0x1F, 0x3B, 0x73]) / 255).max(-1) < 0.06).mean()
    assert base_blue > 0.003


def test_path_figure_without_a_path_says_so_and_draws_the_tree(tiny_scenario, planned):
    failed = dc.replace(planned, success=False, waypoints=np.zeros((0, 4)), cost=np.inf, message="no path")
    dut = path_figure(tiny_scenario, failed)
    ax = dut.axes[0]
    assert "no path found" in ax.get_title()
    labels = {t.get_text() for t in dut.legends[0].get_texts()}
    assert "tree (base)" in labels and "base track" not in labels
    ok = path_figure(tiny_scenario, planned)
    assert "social cost" in ok.axes[0].get_title()
    assert isinstance(planned, PlannerResult)


def test_intermediate_poses_are_numbered_in_order_along_the_path(tiny_scenario, planned):
    from matplotlib.figure import Figure

    ax = Figure().add_subplot()
    dut = draw_path(ax, arm_geometry(tiny_scenario), planned.waypoints, poses=5)
    assert [t.get_text() for t in dut["numbers"]] == ["2", "3", "4"]
    expected = poses_along(planned.waypoints, 5)[1:-1, :2]
    np.testing.assert_allclose([t.get_position() for t in dut["numbers"]], expected, atol=1e-12)
