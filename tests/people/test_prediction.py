"""people.prediction: constant velocity and perfect prediction, sampling, interpolation and clamping, errors."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from drake_social.people.compose import people_model
from drake_social.people.model import PeopleState
from drake_social.people.prediction import Prediction, constant_velocity, perfect_prediction, predict
from drake_social.scenario import load_scenario

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


def _state(t=3.0, present=(True, False)):
    return PeopleState(t=t, positions=np.array([[1.0, 2.0], [-1.0, 0.5]]), headings=np.array([0.0, -1.5]),
                       velocities=np.array([[1.0, 0.0], [0.3, -0.4]]), radii=np.array([0.25, 0.2]),
                       names=("a", "b"), present=np.array(present))


def _by_hand(present_rows):
    """Two people over 4 samples (t0 = 1, dt = 0.5): a walks +x at 1 m/s then
    stops; b stands. Presence per sample as given."""
    pos = np.array([[[0.0, 0.0], [5.0, 5.0]], [[0.5, 0.0], [5.0, 5.0]], [[1.0, 0.0], [5.0, 5.0]],
                    [[1.0, 0.0], [5.0, 5.0]]])
    headings = np.array([[0.0, 1.0], [0.1, 1.0], [0.2, 1.0], [0.3, 1.0]])
    return Prediction(t0=1.0, dt=0.5, positions=pos, headings=headings, present=np.array(present_rows),
                      radii=np.array([0.25, 0.3]), speeds=np.array([1.0, 0.0]), max_speeds=np.array([1.0, 0.0]),
                      names=("a", "b"))


def test_constant_velocity_by_hand():
    pred = constant_velocity(_state(), horizon=1.0, dt=0.25)
    assert pred.samples == 5 and pred.count == 2
    assert pred.t0 == 3.0 and pred.dt == 0.25 and pred.horizon == pytest.approx(4.0, abs=1e-15)
    for k in range(5):
        lag = 0.25 * k
        np.testing.assert_allclose(pred.positions[k], [[1.0 + lag, 2.0], [-1.0 + 0.3 * lag, 0.5 - 0.4 * lag]],
                                   atol=1e-14)
    np.testing.assert_array_equal(pred.headings, np.tile([0.0, -1.5], (5, 1)))
    np.testing.assert_array_equal(pred.present, np.tile([True, False], (5, 1)))
    np.testing.assert_allclose(pred.speeds, [1.0, 0.5], rtol=1e-15)
    np.testing.assert_allclose(pred.max_speeds, [1.0, 0.5], rtol=1e-15)
    np.testing.assert_array_equal(pred.radii, [0.25, 0.2])
    assert pred.names == ("a", "b") and not pred.static
    # A horizon that is not a whole number of steps is covered (rounded up).
    assert constant_velocity(_state(), horizon=0.3, dt=0.25).samples == 3
    assert constant_velocity(_state(), horizon=5.0).samples == 51  # the default step 0.1 s


def test_the_arrays_are_frozen_copies():
    state = _state()
    pred = constant_velocity(state, horizon=1.0, dt=0.5)
    for name in ("positions", "headings", "present", "radii", "speeds", "max_speeds"):
        assert not getattr(pred, name).flags.writeable
        assert getattr(pred, name).flags.c_contiguous


def test_state_at_interpolates_positions_and_holds_heading_and_presence():
    pred = _by_hand([[True, True], [True, False], [False, False], [False, True]])
    assert pred.horizon == 2.5
    s = pred.state_at(1.2)  # between samples 0 and 1 (fraction 0.4)
    np.testing.assert_allclose(s.positions, [[0.2, 0.0], [5.0, 5.0]], atol=1e-15)
    np.testing.assert_allclose(s.velocities, [[1.0, 0.0], [0.0, 0.0]], atol=1e-15)
    np.testing.assert_array_equal(s.headings, [0.0, 1.0])  # sample 0's, not interpolated
    np.testing.assert_array_equal(s.present, [True, True])
    assert s.t == 1.2 and s.names == ("a", "b")
    s = pred.state_at(1.99)  # still sample 1 ... 2: k = 1
    np.testing.assert_array_equal(s.present, [True, False])
    np.testing.assert_allclose(s.positions[0], [0.99, 0.0], atol=1e-14)
    s = pred.state_at(2.0)  # exactly sample 2
    np.testing.assert_array_equal(s.present, [False, False])
    np.testing.assert_allclose(s.positions[0], [1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(s.velocities[0], [0.0, 0.0], atol=1e-15)  # a stopped between 2 and 3
    # Before t0 the first sample holds; after the horizon the last, standing still.
    s = pred.state_at(-10.0)
    np.testing.assert_array_equal(s.positions, pred.positions[0])
    np.testing.assert_array_equal(s.present, [True, True])
    for t in (2.5, 2.6, 1e6):
        s = pred.state_at(t)
        np.testing.assert_array_equal(s.positions, pred.positions[3])
        np.testing.assert_array_equal(s.headings, pred.headings[3])
        np.testing.assert_array_equal(s.present, [False, True])
        np.testing.assert_array_equal(s.velocities, np.zeros((2, 2)))


def test_static():
    assert constant_velocity(PeopleState(t=0.0, positions=np.zeros((1, 2)), headings=np.zeros(1),
                                         velocities=np.zeros((1, 2)), radii=np.array([0.2]), names=("x",)),
                             horizon=2.0).static
    assert not _by_hand([[True, True]] * 4).static  # a walks
    standing = _by_hand([[True, True]] * 4)
    still = Prediction(t0=0.0, dt=0.5, positions=np.repeat(standing.positions[:1], 4, axis=0),
                       headings=standing.headings, present=np.ones((4, 2), bool), radii=standing.radii,
                       speeds=np.zeros(2), max_speeds=np.zeros(2), names=standing.names)
    assert still.static
    leaves = Prediction(t0=0.0, dt=0.5, positions=still.positions, headings=still.headings,
                        present=np.array([[True, True]] * 3 + [[True, False]]), radii=still.radii,
                        speeds=np.zeros(2), max_speeds=np.zeros(2), names=still.names)
    assert not leaves.static


@pytest.fixture(scope="module")
def walkers():
    return people_model(load_scenario(SCENARIOS / "office_walkers.yaml"))


def test_perfect_prediction_equals_the_scripted_peoples_states(walkers):
    t_now = 7.3
    state = walkers.state_at(t_now)
    pred = perfect_prediction(walkers, state, horizon=5.0, dt=0.1)
    assert pred.samples == 51 and pred.count == walkers.count == 10
    for k in range(pred.samples):
        truth = walkers.state_at(t_now + 0.1 * k)
        np.testing.assert_array_equal(pred.positions[k], truth.positions)
        np.testing.assert_array_equal(pred.headings[k], truth.headings)
        np.testing.assert_array_equal(pred.present[k], truth.present)
    step = np.diff(pred.positions, axis=0)
    np.testing.assert_allclose(pred.max_speeds, np.hypot(step[..., 0], step[..., 1]).max(axis=0) / 0.1, rtol=1e-15)
    np.testing.assert_allclose(pred.speeds, state.speeds(), rtol=1e-15)
    assert pred.max_speeds.max() > 0.5  # people walk
    # At the sample times, state_at is the model's state.
    for k in (0, 17, 50):
        t = t_now + 0.1 * k
        np.testing.assert_allclose(pred.state_at(t).positions, walkers.state_at(t).positions, atol=1e-12)
    assert predict("perfect", walkers, state, 5.0, 0.1).positions.tobytes() == pred.positions.tobytes()


def test_perfect_prediction_of_a_crowd_is_constant_velocity_for_it():
    model = people_model(load_scenario(SCENARIOS / "lobby_crowd.yaml"))
    state = model.state_at(2.0)
    n_open = sum(m.count for m in model.open_loop)
    pred = perfect_prediction(model, state, horizon=2.0, dt=0.5)
    cv = constant_velocity(state, horizon=2.0, dt=0.5)
    np.testing.assert_array_equal(pred.positions[:, n_open:], cv.positions[:, n_open:])
    for k in range(pred.samples):
        np.testing.assert_array_equal(pred.positions[k, :n_open], model.open_loop_state(2.0 + 0.5 * k).positions)


def test_predict_dispatches(walkers):
    state = walkers.state_at(1.0)
    a, b = predict("constant_velocity", walkers, state, 2.0, 0.2), constant_velocity(state, 2.0, 0.2)
    assert a.positions.tobytes() == b.positions.tobytes() and a.max_speeds.tobytes() == b.max_speeds.tobytes()
    with pytest.raises(ValueError, match="predict: unknown prediction 'oracle'; allowed: constant_velocity, perfect"):
        predict("oracle", walkers, state, 2.0)


def test_bad_arguments(walkers):
    good = _by_hand([[True, True]] * 4)
    fields = dict(t0=good.t0, dt=good.dt, positions=good.positions, headings=good.headings, present=good.present,
                  radii=good.radii, speeds=good.speeds, max_speeds=good.max_speeds, names=good.names)
    for change, match in ((dict(dt=0.0), "dt > 0"), (dict(t0=math.nan), "t0 must be finite"),
                          (dict(dt=math.inf), "dt > 0"),
                          (dict(positions=np.zeros((4, 2))), r"positions must be \(H, P, 2\)"),
                          (dict(positions=np.zeros((0, 2, 2))), "H >= 1"),
                          (dict(headings=np.zeros((3, 2))), r"headings has shape \(3, 2\); 2 people over 4 samples"),
                          (dict(radii=np.zeros(3)), "radii has shape"),
                          (dict(max_speeds=np.array([1.0, math.nan])), "max_speeds must be finite"),
                          (dict(names=("a",)), "positions has shape")):
        with pytest.raises(ValueError, match=match):
            Prediction(**{**fields, **change})
    for horizon, dt in ((0.0, 0.1), (-1.0, 0.1), (1.0, 0.0), (math.inf, 0.1)):
        with pytest.raises(ValueError, match="a prediction needs horizon > 0 and dt > 0"):
            constant_velocity(_state(), horizon, dt)
    other = _state()
    with pytest.raises(ValueError, match="perfect_prediction: the model has 10 people, the state 2"):
        perfect_prediction(walkers, other, 1.0)


def test_the_lookup_at_the_sample_times_and_the_ends():
    """prediction_kernel.slot at t0, at a sample, between, at the horizon and
    either side of each; centre there equals the samples' own interpolation."""
    from drake_social.people.prediction_kernel import centre, centres, slot

    pred = _by_hand([[True, True]] * 4)  # t0 = 1, dt = 0.5, H = 4: horizon 2.5
    ulp = math.ulp(1.0)
    assert slot(1.0, 1.0, 0.5, 4) == (0, 0.0)
    assert slot(1.0 - ulp, 1.0, 0.5, 4) == (0, 0.0)  # before t0: the first sample holds
    k, f = slot(1.0 + 2 * ulp, 1.0, 0.5, 4)
    assert k == 0 and f == pytest.approx(4 * ulp, rel=1e-12)
    assert slot(2.0, 1.0, 0.5, 4) == (2, 0.0)  # exactly sample 2
    k, f = slot(2.0 - 2 * ulp, 1.0, 0.5, 4)
    assert k == 1 and 1.0 - f == pytest.approx(4 * ulp, rel=1e-12)
    assert slot(2.5, 1.0, 0.5, 4) == (3, 0.0)  # the horizon: the last sample
    k, f = slot(2.5 - 4 * ulp, 1.0, 0.5, 4)
    assert k == 2 and 1.0 - f == pytest.approx(8 * ulp, rel=1e-12)
    assert slot(2.5 + 4 * ulp, 1.0, 0.5, 4) == (3, 0.0)
    assert slot(1.2, 1.0, 0.5, 1) == (0, 0.0)  # one sample: it holds at every time
    assert centre(pred.positions, 0, 0, 0.4) == (0.2, 0.0)
    assert centre(pred.positions, 0, 3, 0.0) == (1.0, 0.0)
    np.testing.assert_array_equal(centres(pred.positions, 1, 0.5), [[0.75, 0.0], [5.0, 5.0]])
    for t in (0.0, 1.0, 1.2, 1.75, 2.0, 2.4999, 2.5, 9.0):
        k, f = slot(t, 1.0, 0.5, 4)
        np.testing.assert_array_equal(pred.state_at(t).positions, centres(pred.positions, k, f))


def test_the_lookup_is_written_once():
    """``(t - t0) / dt`` of a prediction's sample times is computed in
    prediction_kernel.slot alone: the Prediction and the compiled kernels call
    it (the time-indexed cost's numpy reference keeps its own, batched: it is
    the independent check of the kernel)."""
    import ast

    import drake_social

    root = Path(drake_social.__file__).resolve().parent

    def name(node):
        return node.id if isinstance(node, ast.Name) else node.attr if isinstance(node, ast.Attribute) else ""

    homes = set()
    for path in root.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if (isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div) and name(node.right) == "dt"
                    and isinstance(node.left, ast.BinOp) and isinstance(node.left.op, ast.Sub)
                    and name(node.left.right) == "t0"):
                homes.add(str(path.relative_to(root)))
    assert homes == {"people/prediction_kernel.py", "cost/social.py"}


@pytest.mark.parametrize("seconds, samples", [
    # one step, and either side of it: within 1e-9 of a step is that step, as the sample times round
    (0.5, 2), (math.nextafter(0.5, 1.0), 2), (0.5 + 1e-6, 3), (math.nextafter(0.5, 0.0), 2),
    (1.0, 3), (1.5, 4), (1.6, 4), (math.inf, 4), (0.1, 2)])
def test_until_keeps_the_samples_up_to_the_one_covering_its_time(seconds, samples):
    """The first ``seconds``: the samples at t0 + k dt for k dt < seconds and the
    first at or after it (4 samples at t0 = 1, dt = 0.5 over 1.5 s)."""
    full = _by_hand([[True, True]] * 4)
    dut = full.until(seconds)
    assert dut.samples == samples
    np.testing.assert_array_equal(dut.positions, full.positions[:samples])
    np.testing.assert_array_equal(dut.present, full.present[:samples])
    np.testing.assert_array_equal(dut.headings, full.headings[:samples])
    np.testing.assert_array_equal(dut.max_speeds, full.max_speeds)  # a bound on the shorter motion too
    assert dut.t0 == full.t0 and dut.dt == full.dt and dut.names == full.names
    assert dut.horizon >= min(full.t0 + seconds, full.horizon) - 1e-12
    if samples == full.samples:
        assert dut is full


@pytest.mark.parametrize("seconds", [0.0, -1.0, math.nan])
def test_until_needs_a_positive_time(seconds):
    with pytest.raises(ValueError, match="Prediction.until: seconds must be > 0"):
        _by_hand([[True, True]] * 4).until(seconds)
