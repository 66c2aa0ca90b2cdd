"""What a replan predicted, kept small (drake_social.people.predicted): the
kept samples are the prediction's own positions at the kept times (checked
against Prediction.state_at), and the bounds on samples and people hold at
their values and either side."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_social.people import PeopleState, constant_velocity
from drake_social.people.predicted import (MAX_PREDICTED_PEOPLE, MAX_PREDICTED_SAMPLES, PREDICTED_STEP,
                                           PredictedPeople, predicted_people, sample_stride)


def _state(count: int, t: float = 2.0) -> PeopleState:
    """``count`` walkers: person i at (i, 0) walking +y at 0.1 (i + 1) m/s, facing pi/4."""
    i = np.arange(count, dtype=float)
    return PeopleState(t=t, positions=np.stack([i, np.zeros(count)], axis=1), headings=np.full(count, math.pi / 4),
                       velocities=np.stack([np.zeros(count), 0.1 * (i + 1)], axis=1), radii=np.full(count, 0.25),
                       names=tuple(f"p{k}" for k in range(count)))


def test_kept_positions_are_the_prediction_at_the_kept_times():
    prediction = constant_velocity(_state(3), horizon=5.0)  # 51 samples, 0.1 s apart
    dut = predicted_people(prediction, replan=7)
    assert dut.replan == 7 and dut.t == 2.0 and dut.culprit == -1 and dut.names == ("p0", "p1", "p2")
    # Every 0.6 s: the smallest multiple of 0.1 s >= 0.5 s that keeps at most 10 of the 51 times.
    np.testing.assert_allclose(dut.times, 2.0 + 0.6 * np.arange(9), rtol=0, atol=1e-12)
    for j, t in enumerate(dut.times):
        np.testing.assert_allclose(dut.positions[j], prediction.state_at(float(t)).positions, rtol=0, atol=1e-12)
        # ... and by hand: x = i, y = 0.1 (i + 1) (t - 2).
        np.testing.assert_allclose(dut.positions[j, :, 1], 0.1 * np.arange(1, 4) * (t - 2.0), atol=1e-12)
    assert dut.present.all() and dut.radii.tolist() == [0.25] * 3 and dut.indices.tolist() == [0, 1, 2]


@pytest.mark.parametrize(("samples", "dt", "kept"), [
    (45, 0.1, 9), (46, 0.1, 10), (47, 0.1, 8),     # stride 5 up to 46 samples (4.5 s), then 6
    (9, 0.5, 9), (10, 0.5, 10), (11, 0.5, 6),      # a 0.5 s step: every sample up to 10 of them
    (5, 0.1, 1), (2, 0.1, 1), (6, 0.1, 2),         # at least PREDICTED_STEP apart
])
def test_at_most_max_samples_at_least_the_step_apart(samples, dt, kept):
    assert MAX_PREDICTED_SAMPLES == 10 and PREDICTED_STEP == 0.5
    stride = sample_stride(samples, dt)
    assert (samples - 1) // stride + 1 == kept
    assert stride * dt >= PREDICTED_STEP - 1e-12
    prediction = constant_velocity(_state(2, t=0.0), horizon=(samples - 1) * dt, dt=dt)
    assert prediction.samples == samples
    dut = predicted_people(prediction, 0)
    assert len(dut.times) == kept
    np.testing.assert_allclose(np.diff(dut.times), stride * dt, atol=1e-12)


def test_never_more_than_max_samples():
    for samples in range(1, 400):
        stride = sample_stride(samples, 0.1)
        assert (samples - 1) // stride + 1 <= MAX_PREDICTED_SAMPLES


@pytest.mark.parametrize("count", [MAX_PREDICTED_PEOPLE - 1, MAX_PREDICTED_PEOPLE, MAX_PREDICTED_PEOPLE + 1])
def test_at_most_max_people_the_nearest_kept(count):
    """People at x = 0 .. count - 1; the robot's path along x = count - 1.5:
    beyond 16 people the one farthest from it (person 0) is left out."""
    assert MAX_PREDICTED_PEOPLE == 16
    prediction = constant_velocity(_state(count), horizon=5.0)
    near = np.array([[count - 1.5, -5.0], [count - 1.5, 5.0]])
    dut = predicted_people(prediction, 3, near=near)
    kept = min(count, MAX_PREDICTED_PEOPLE)
    assert len(dut.names) == kept and dut.positions.shape == (9, kept, 2)
    assert dut.indices.tolist() == list(range(count - kept, count))
    assert dut.nbytes <= 9 * 16 * (2 * 8 + 1) + 9 * 8 + 16 * 16


def test_the_culprit_is_kept_however_far():
    count = MAX_PREDICTED_PEOPLE + 4
    prediction = constant_velocity(_state(count), horizon=5.0)
    near = np.array([[count + 10.0, -5.0], [count + 10.0, 5.0]])  # person 0 is the farthest
    dut = predicted_people(prediction, 1, near=near, culprit=0)
    assert len(dut.names) == MAX_PREDICTED_PEOPLE and dut.indices[0] == 0 and dut.culprit == 0
    assert dut.culprit_name == "p0"
    assert dut.indices[1:].tolist() == list(range(count - MAX_PREDICTED_PEOPLE + 1, count))


def test_refuses_more_than_its_bounds():
    with pytest.raises(ValueError, match="at most 16 people"):
        PredictedPeople(0, 0.0, [0.0], np.zeros((1, 17, 2)), np.ones((1, 17), bool), np.ones(17), np.arange(17),
                        tuple("abcdefghijklmnopq"))
    with pytest.raises(ValueError, match="1 to 10 times"):
        PredictedPeople(0, 0.0, np.arange(11.0), np.zeros((11, 1, 2)), np.ones((11, 1), bool), [0.2], [0], ("a",))


@pytest.mark.parametrize("near", [np.zeros((3, 4)), np.zeros(6), np.array([[0.0, math.nan]])])
def test_refuses_a_near_path_that_is_not_base_positions(near):
    prediction = constant_velocity(_state(MAX_PREDICTED_PEOPLE + 2), horizon=5.0)
    with pytest.raises(ValueError, match=r"near must be \(L, 2\) finite base positions"):
        predicted_people(prediction, 1, near=near)


@pytest.mark.parametrize("dt, step", [(0.0, 0.5), (-0.1, 0.5), (math.nan, 0.5), (0.1, -1e-9), (0.1, math.inf)])
def test_refuses_steps_that_are_not_times(dt, step):
    with pytest.raises(ValueError, match="dt must be > 0 and step >= 0"):
        sample_stride(51, dt, step=step)
    assert sample_stride(51, 0.1, step=0.0) == 6  # step 0: only the bound on samples: ceil(50 / 9)
