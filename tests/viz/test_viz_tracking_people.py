"""drake_social.viz.tracking: the distance-to-people panel of tracking.png."""

from __future__ import annotations

import types

import numpy as np
import pytest

from drake_social.scenario.geometry import arm_geometry
from drake_social.people import PeopleLog
from drake_social.viz.tracking import people_distances, tracking_figure


def _run(people):
    """The base drives along +x at 0.5 m/s for 4 s, the arm folded back (psi1 = pi)."""
    t = np.linspace(0.0, 4.0, 41)
    q = np.c_[0.5 * t, np.zeros_like(t), np.full_like(t, np.pi), np.zeros_like(t)]
    return types.SimpleNamespace(times=t, q=q, reference=q, v=np.c_[np.full_like(t, 0.5), np.zeros((len(t), 3))],
                                 wheel_speeds=np.zeros((len(t), 4)), target_index=np.zeros(len(t), int),
                                 mode="kinematic", execution="p_controller", message="done", people=people)


def _person_ahead(times):
    """One person of radius 0.3 m standing at (4, 0), present until 3 s."""
    n = len(times)
    return PeopleLog(times=times, positions=np.tile([4.0, 0.0], (n, 1, 1)), headings=np.zeros((n, 1)),
                     velocities=np.zeros((n, 1, 2)), present=(times < 3.0)[:, None], radii=[0.3], names=("p",))


def test_base_distance_is_the_gap_between_the_discs(tiny_scenario):
    geometry = arm_geometry(tiny_scenario)
    run = _run(None)
    people = _person_ahead(run.times)
    d = people_distances(geometry, run.times, run.q, people)
    present = run.times < 3.0
    # Base disc at (0.5 t, 0) against the body disc at (4, 0): a hand formula.
    expected = 4.0 - 0.5 * run.times - geometry.base_radius - 0.3
    np.testing.assert_allclose(d["base"][present], expected[present], atol=1e-12)
    assert np.isinf(d["robot"][~present]).all()
    assert (d["robot"] <= d["base"]).all() and (d["robot"] <= d["arm"]).all()
    # The same people given at other times (state_at) give the same distances.
    coarse = _person_ahead(np.linspace(0.0, 4.0, 5))
    again = people_distances(geometry, run.times[:25], run.q[:25], coarse)  # t < 2.5 s: present
    np.testing.assert_allclose(again["base"], d["base"][:25], atol=1e-12)


def test_tracking_figure_gets_a_fifth_panel_only_with_people(tiny_scenario):
    geometry = arm_geometry(tiny_scenario)
    assert len(tracking_figure(_run(None), geometry=geometry).axes) == 4
    run = _run(None)
    run.people = _person_ahead(run.times)
    assert len(tracking_figure(run).axes) == 4  # no geometry: today's figure
    fig = tracking_figure(run, geometry=geometry, safety_distance=0.05)
    assert len(fig.axes) == 5
    lines = {line.get_label(): line for line in fig.axes[4].get_lines()}
    assert set(lines) == {"robot", "base", "arm", "object", "safety distance"}
    robot = lines["robot"].get_ydata()
    assert np.isnan(robot[run.times >= 3.0]).all()
    assert robot[0] == pytest.approx(people_distances(geometry, run.times, run.q, run.people)["robot"][0])
