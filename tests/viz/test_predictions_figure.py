"""The predictions figure (drake_social.viz.predictions): the replans by
category, one replan's predicted tracks against the real ones, and the
prediction's errors, computed here by hand from a hand-made log, predictions
and people log."""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest
from matplotlib.image import imread

from drake_social.people import PeopleLog
from drake_social.people.predicted import PredictedPeople
from drake_social.scenario import load_scenario
from drake_social.viz import predictions as dut


@dc.dataclass(frozen=True)
class Replan:
    t: float
    status: str
    waypoints: np.ndarray = dc.field(default_factory=lambda: np.array([[1.0, 2.5, 0, 0], [6.5, 2.5, 0, 0]]))
    candidate_cost: float = math.inf
    reason: str = ""


def _log():
    return [Replan(0.0, "initial"), Replan(0.5, "kept"), Replan(1.0, "new", candidate_cost=4.0), Replan(1.5, "kept"),
            Replan(2.0, "wait"), Replan(2.1, "wait"), Replan(2.2, "evade"), Replan(3.0, "new"), Replan(3.5, "kept")]


def _people() -> PeopleLog:
    """ann walks east at 1 m/s from (1, 4); bob stands at (6, 1)."""
    times = np.arange(0.0, 8.01, 0.1)
    pos = np.stack([np.stack([1.0 + times, np.full_like(times, 4.0)], 1), np.tile([6.0, 1.0], (len(times), 1))], 1)
    vel = np.zeros_like(pos)
    vel[:, 0, 0] = 1.0
    return PeopleLog(times, pos, np.zeros((len(times), 2)), vel, np.ones((len(times), 2), bool), [0.25, 0.25],
                     ("ann", "bob"))


def _predicted(replan: int, t: float, culprit: int = -1) -> PredictedPeople:
    """ann predicted standing where she is at t; bob exactly."""
    times = t + 0.6 * np.arange(4)
    pos = np.array([[[1.0 + t, 4.0], [6.0, 1.0]]] * 4)
    return PredictedPeople(replan, t, times, pos, np.ones((4, 2), bool), [0.25, 0.25], [0, 1], ("ann", "bob"), culprit)


PREDICTED = [_predicted(0, 0.0), _predicted(2, 1.0), _predicted(4, 2.0), _predicted(6, 2.2, culprit=0),
             _predicted(7, 3.0)]


def test_prediction_errors_by_hand():
    ahead, error, person = dut.prediction_errors(PREDICTED[1], _people())
    # ann: predicted standing at 2.0, really at 2.0 + 0.6 j at 0.6 j s ahead; bob: 0.
    np.testing.assert_allclose(ahead, np.repeat(0.6 * np.arange(4), 2), atol=1e-12)
    np.testing.assert_allclose(error[person == 0], 0.6 * np.arange(4), atol=1e-9)
    np.testing.assert_allclose(error[person == 1], 0.0, atol=1e-12)


def test_chosen_replan_is_the_first_with_a_culprit_else_the_first_change():
    assert dut.chosen_replan(_log(), PREDICTED).replan == 6
    plain = [dc.replace(p, culprit=-1) for p in PREDICTED]
    assert dut.chosen_replan(_log(), plain).replan == 2
    assert dut.chosen_replan(_log(), plain[:1]).replan == 0
    assert dut.chosen_replan(_log(), []) is None


def test_figure_axes_and_labels(tiny_scenario_path):
    scenario = load_scenario(tiny_scenario_path)
    fig = dut.predictions_figure(scenario, _log(), PREDICTED, _people(), end=4.0)
    ax_dec, ax_map, ax_err = fig.axes
    labels = [t.get_text() for t in ax_dec.get_yticklabels()]
    # Counts: 1 unsafe (3.0 s), 1 cheaper (1.0 s), 1 evasion, 2 waiting replans.
    assert labels == ["wait: nothing safe, or a pause (2)", "evasion: steps aside (1)", "new route: cheaper (1)",
                      "new route: not safe any more (1)"]
    assert ax_dec.get_xlabel() == "simulated time (s)"
    assert ax_map.get_xlabel() == "x (m)" and ax_map.get_ylabel() == "y (m)"
    assert ax_map.get_title() == "replan at t = 2.2 s: evasion: steps aside"
    assert ax_err.get_xlabel() == "time ahead of the replan (s)"
    assert ax_err.get_ylabel() == "predicted - real position (m)"
    # The markers of the top panel at the replans' times, one row per category.
    rows = {int(round(line.get_ydata()[0])): list(line.get_xdata()) for line in ax_dec.lines if len(line.get_xdata())
            and line.get_linestyle() == "None"}
    assert rows == {0: [2.0, 2.1], 1: [2.2], 2: [1.0], 3: [3.0]}
    # The error panel: ann's errors of every kept prediction (bob stood as predicted: left out).
    dots = ax_err.lines[0]
    expected = np.concatenate([0.6 * np.arange(4)] * len(PREDICTED))
    np.testing.assert_allclose(np.sort(dots.get_ydata()), np.sort(expected), atol=1e-9)
    # The map: ann's real track at the kept times of the chosen replan (2.2 s).
    real = [line for line in ax_map.lines if line.get_linestyle() == "-" and len(line.get_xdata()) == 4]
    assert any(np.allclose(line.get_xdata(), 1.0 + 2.2 + 0.6 * np.arange(4)) for line in real)


def test_write_and_refuse(tmp_path, tiny_scenario_path):
    scenario = load_scenario(tiny_scenario_path)

    class Run:
        replans, predicted, people = _log(), PREDICTED, _people()
        times = np.arange(0.0, 4.0, 0.01)
        q = np.tile([1.0, 2.5, 0.0, 0.0], (len(times), 1))
        sim_time = 4.0

    path = dut.write_predictions_figure(Run, scenario, tmp_path, title="t")
    assert path == tmp_path / dut.PREDICTIONS_PNG
    image = imread(path)
    assert image.shape[0] == 1040 and image.shape[1] == 1430  # 11 x 8 in at 130 dpi
    with pytest.raises(ValueError, match="kept predictions"):
        dut.predictions_figure(scenario, _log(), [], _people())
