"""drake_social.viz.tracks: people's tracks and time marks on the map."""

from __future__ import annotations

import dataclasses as dc
import io
import math

import numpy as np
import pytest
from matplotlib.figure import Figure

from drake_social.collision.geometric import GeometricChecker
from drake_social.people import PeopleLog, people_model
from drake_social.planning.algorithms import plan
from drake_social.viz.path import path_figure
from drake_social.viz.show import show_figure
from drake_social.viz.tracks import TRACK_COLORS, draw_people_tracks, mark_times, moving_people


def _log() -> PeopleLog:
    """Person 0 walks +x at 1 m/s from (1, 1) over 0-4 s; person 1 stands at
    (5, 3); person 2 walks -y at 0.5 m/s from (6, 5) and is present only in
    [1, 3) s. Samples every 0.5 s."""
    t = np.arange(0.0, 4.01, 0.5)
    pos = np.zeros((len(t), 3, 2))
    pos[:, 0] = np.c_[1.0 + t, np.full(len(t), 1.0)]
    pos[:, 1] = [5.0, 3.0]
    pos[:, 2] = np.c_[np.full(len(t), 6.0), 5.0 - 0.5 * t]
    head = np.tile([0.0, 1.0, -math.pi / 2], (len(t), 1))
    vel = np.zeros((len(t), 3, 2))
    vel[:, 0, 0], vel[:, 2, 1] = 1.0, -0.5
    present = np.ones((len(t), 3), bool)
    present[:, 2] = (t >= 1.0) & (t < 3.0)
    return PeopleLog(times=t, positions=pos, headings=head, velocities=vel, present=present,
                     radii=[0.25, 0.3, 0.2], names=("ann", "bob", "cy"))


def test_mark_times():
    np.testing.assert_allclose(mark_times(60.0, 5), [0, 15, 30, 45, 60])
    with pytest.raises(ValueError, match="count"):
        mark_times(10.0, 1)
    with pytest.raises(ValueError, match="duration"):
        mark_times(math.nan)


def test_tracks_follow_the_log_and_break_where_absent():
    people = _log()
    np.testing.assert_array_equal(moving_people(people), [True, False, True])
    ax = Figure().add_subplot()
    ax.set_xlim(0, 8), ax.set_ylim(0, 6)
    out = draw_people_tracks(ax, people)
    assert len(out["tracks"]) == 2 and out["marks"] == [] and out["legend"] == []
    np.testing.assert_allclose(out["tracks"][0].get_xydata(), people.positions[:, 0])
    cy = out["tracks"][1].get_xydata()
    np.testing.assert_allclose(cy[2:6], people.positions[2:6, 2])  # t = 1.0 .. 2.5 s
    assert np.isnan(cy[:2]).all() and np.isnan(cy[6:]).all()
    assert out["tracks"][0].get_color() == TRACK_COLORS[0] and out["tracks"][1].get_color() == TRACK_COLORS[1]
    # Start rings at the first present pose, with the body radius.
    rings = [a for a in out["starts"] if hasattr(a, "get_radius")]
    assert [r.center for r in rings] == [pytest.approx((1.0, 1.0)), pytest.approx((6.0, 4.5))]
    assert [r.get_radius() for r in rings] == [0.25, 0.2]
    assert [t.get_text() for t in out["names"]] == ["ann", "cy"]
    # The heading tick of cy points along -y.
    tick = [a for a in out["starts"] if hasattr(a, "get_xydata")][1].get_xydata()
    assert tick[1, 1] < tick[0, 1] and tick[0, 0] == pytest.approx(6.0)


def test_time_marks_put_people_and_robot_at_the_same_instant():
    people = _log()
    times = np.array([0.0, 2.0, 4.0])
    q = np.c_[np.linspace(0.0, 4.0, 3), np.full(3, 2.0), np.zeros(3), np.zeros(3)]  # base at x = t
    ax = Figure().add_subplot()
    out = draw_people_tracks(ax, people, marks=[0.0, 1.25, 3.5], robot=(times, q))
    dots = [a for a in out["marks"] if hasattr(a, "get_xydata")]
    numbers = [a.get_text() for a in out["marks"] if hasattr(a, "get_text")]
    # ann at all three; cy only at 1.25 s (present in [1, 3) s).
    expected = [(1.0, 1.0), (2.25, 1.0), (4.5, 1.0), (6.0, 5.0 - 0.625)]
    np.testing.assert_allclose([d.get_xydata()[0] for d in dots], expected)
    assert numbers == ["1", "2", "3", "2"]
    squares = [a.get_xydata()[0] for a in out["robot_marks"] if hasattr(a, "get_xydata")]
    np.testing.assert_allclose(squares, [[0.0, 2.0], [1.25, 2.0], [3.5, 2.0]])
    assert out["legend"][0].get_label() == "time marks (s) 1: 0, 2: 1.2, 3: 3.5"


def _png(fig) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=40)
    return buffer.getvalue()


def test_figures_with_static_people_are_todays(tiny_scenario):
    state = people_model(tiny_scenario).state_at(0.0)
    static = PeopleLog.from_states([state, dc.replace(state, t=3.0)])
    assert _png(show_figure(tiny_scenario, people=static)) == _png(show_figure(tiny_scenario))
    result = plan(tiny_scenario, GeometricChecker(tiny_scenario), algorithm="social_rrt_star", iterations=60, seed=2)
    assert _png(path_figure(tiny_scenario, result, people=static)) == _png(path_figure(tiny_scenario, result))


def test_path_figure_marks_the_executed_run(tiny_scenario):
    result = plan(tiny_scenario, GeometricChecker(tiny_scenario), algorithm="social_rrt_star", iterations=60, seed=2)
    people = _log()
    times = np.linspace(0.0, 4.0, 9)
    q = np.c_[np.linspace(1.0, 6.0, 9), np.full(9, 2.5), np.zeros(9), np.full(9, 1.57)]
    fig = path_figure(tiny_scenario, result, people=people, executed=(times, q), marks=3)
    labels = [h.get_label() for h in fig.axes[0].get_lines()]
    assert "people's tracks" in labels and "executed base track" in labels
    assert "time marks (s) 1: 0, 2: 2, 3: 4" in labels
    assert _png(fig) != _png(path_figure(tiny_scenario, result))
