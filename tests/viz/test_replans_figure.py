"""The replanning figure (drake_social.viz.replans): it plots the log's own numbers.

The log is hand-made: records with the documented fields of a ReplanResult
(drake_social.planning.replan).
"""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest
from matplotlib.image import imread

from drake_social.viz import replans as dut


@dc.dataclass(frozen=True)
class Replan:
    t: float
    plan_time: float
    cost: float
    changed: bool
    status: str
    deadline_hit: bool = False
    iterations: int = 500
    waypoints: np.ndarray = dc.field(default_factory=lambda: np.zeros((2, 4)))


def log() -> list[Replan]:
    rng = np.random.default_rng(7)
    out = [Replan(0.0, 0.4, 10.0, True, "initial", iterations=2000)]
    cost = 10.0
    for k in range(1, 60):
        t = 0.1 * k
        if 20 <= k < 25:
            out.append(Replan(t, 0.08 + 0.001 * k, math.inf, k == 20, "wait", deadline_hit=True, iterations=300))
            continue
        changed = k in (10, 25, 40)
        cost = cost * 0.8 if changed else cost + 0.01
        out.append(Replan(t, float(rng.uniform(0.01, 0.07)), cost, changed, "new" if changed else "kept",
                          deadline_hit=k == 33, iterations=int(rng.integers(100, 500))))
    return out


class Run:
    """What write_replan_figure reads of a SimulationResult."""

    def __init__(self, replans):
        self.replans, self.sim_time = replans, 7.0


def test_series_are_the_log():
    replans = log()
    s = dut.replan_series(replans)
    for name in ("t", "plan_time", "cost", "changed", "deadline_hit", "iterations"):
        np.testing.assert_array_equal(s[name], [getattr(r, name) for r in replans])
    np.testing.assert_array_equal(s["wait"], [r.status == "wait" for r in replans])
    np.testing.assert_array_equal(np.flatnonzero(s["initial"]), [0])
    assert s["iterations"].dtype == np.int64 and s["changed"].dtype == bool


def test_wait_intervals():
    t = np.array([0.0, 0.1, 0.2, 0.3, 0.4, 0.5])
    assert dut.wait_intervals(t, [0, 1, 1, 0, 1, 1]) == [(0.1, 0.3), (0.4, 0.5)]
    assert dut.wait_intervals(t, [0, 1, 1, 0, 1, 1], end=2.0) == [(0.1, 0.3), (0.4, 2.0)]
    assert dut.wait_intervals(t, [0] * 6) == []


def test_figure_plots_the_log():
    replans = log()
    s = dut.replan_series(replans)
    fig = dut.replan_figure(replans, budget=0.08)
    ax_time, ax_cost = fig.axes
    lines = {line.get_label(): line for line in ax_time.lines}
    later_ok = ~s["initial"] & ~s["deadline_hit"]
    np.testing.assert_array_equal(lines["replan"].get_xdata(), s["t"][later_ok])
    np.testing.assert_allclose(lines["replan"].get_ydata(), 1e3 * s["plan_time"][later_ok], rtol=1e-15)
    hit = ~s["initial"] & s["deadline_hit"]
    np.testing.assert_array_equal(lines["deadline hit"].get_xdata(), s["t"][hit])
    assert hit.sum() == 6
    assert list(lines["budget 80 ms"].get_ydata()) == [80.0, 80.0]
    assert "first plan 0.4 s (not shown)" in lines
    cost = {line.get_label(): line for line in ax_cost.lines}
    finite = np.isfinite(s["cost"])
    np.testing.assert_array_equal(cost["cost of the plan"].get_xdata(), s["t"])
    # The plans' costs, broken (NaN) while waiting.
    np.testing.assert_array_equal(cost["cost of the plan"].get_ydata(), np.where(finite, s["cost"], np.nan))
    assert np.isnan(cost["cost of the plan"].get_ydata()).sum() == 5
    # Changed: the initial plan and k = 10, 25, 40 (the wait that changed has no cost).
    np.testing.assert_allclose(cost["path changed"].get_xdata(), [0.0, 1.0, 2.5, 4.0])
    np.testing.assert_allclose(cost["waited"].get_xdata(), [2.0, 2.1, 2.2, 2.3, 2.4])
    # One wait shaded on each panel, 2.0 s to 2.5 s.
    for ax in (ax_time, ax_cost):
        (span,) = ax.patches
        assert span.get_x() == pytest.approx(2.0) and span.get_x() + span.get_width() == pytest.approx(2.5)
    assert fig._suptitle.get_text() == "60 replans: 4 path changes, 5 waiting, 6 over the deadline"


def test_write_replan_figure(tmp_path):
    replans = log()
    for source in (replans, Run(replans)):
        path = dut.write_replan_figure(source, tmp_path, budget=0.08)
        assert path == tmp_path / "replans.png"
        image = imread(path)
        assert image.shape[0] > 500 and image.shape[1] > 1000
    with pytest.raises(ValueError, match="replans is empty"):
        dut.write_replan_figure([], tmp_path)
    with pytest.raises(ValueError, match="budget"):
        dut.replan_figure(replans, budget=0.0)
    with pytest.raises(ValueError, match="replans is None"):
        dut.write_replan_figure(Run(None), tmp_path)
