"""What a replan predicted, kept for the replay and the figures: a few samples of a :class:`Prediction`.

A replanning run judges every path against a
:class:`~drake_social.people.prediction.Prediction` (a sample per 0.1 s per
person over ``planner.replan_horizon``). To show later what the robot
expected when it changed its route or waited, the replanning system keeps a
small extract of it, a :class:`PredictedPeople`, for those replans
(:mod:`drake_social.control.replanner_system`):

* the **sample times**: every ``stride`` samples of the prediction from its
  first (the replan's time), ``stride`` the smallest whole number of
  prediction steps that is at least :data:`PREDICTED_STEP` seconds and leaves
  at most :data:`MAX_PREDICTED_SAMPLES` times over the horizon (a 5 s horizon
  at 0.1 s: every 0.6 s, 9 times). The kept positions are the prediction's
  own samples, not interpolated;
* the **people**: at most :data:`MAX_PREDICTED_PEOPLE`, those whose predicted
  track comes nearest to the robot's base path (the path chosen and the one
  replaced), and always the person who made a path unsafe (``culprit``).

One extract holds at most 16 people x 10 samples (positions, presence): about
3 kB. The system keeps at most
:data:`~drake_social.control.replanner_system.MAX_PREDICTED_REPLANS` of them a run.
"""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np

from drake_social.kinematics import polyline_distance
from drake_social.people.prediction import Prediction

__all__ = ["MAX_PREDICTED_PEOPLE", "MAX_PREDICTED_SAMPLES", "PREDICTED_STEP", "PredictedPeople",
           "predicted_people", "sample_stride"]

#: Seconds between the kept samples, at least (a whole number of the prediction's steps).
PREDICTED_STEP = 0.5
#: Kept sample times of one prediction, at most (the first is the replan's time).
MAX_PREDICTED_SAMPLES = 10
#: Kept people of one prediction, at most (the nearest to the robot's base path; the culprit always).
MAX_PREDICTED_PEOPLE = 16


@dc.dataclass(frozen=True, eq=False)
class PredictedPeople:
    """A few samples of the people a replan predicted (see the module docstring).

    Attributes:
        replan: the replan's index in the run's log (``ReplanState.log``).
        t: the replan's time, seconds (the first sample's).
        times: (M,) the sample times, seconds, 1 <= M <= :data:`MAX_PREDICTED_SAMPLES`.
        positions: (M, K, 2) the predicted body centres, metres.
        present: (M, K) bool: predicted in the scene.
        radii: (K,) body radii, metres.
        indices: (K,) each kept person's index among the prediction's people
            (the run's people log has the same order), ascending.
        names: K labels.
        culprit: the index (along K) of the person who made the replaced path
            (or the robot standing) unsafe, -1 when none was named.
    """

    replan: int
    t: float
    times: np.ndarray
    positions: np.ndarray
    present: np.ndarray
    radii: np.ndarray
    indices: np.ndarray
    names: tuple[str, ...]
    culprit: int = -1

    def __post_init__(self) -> None:
        times = np.array(self.times, float).reshape(-1)
        m, k = len(times), len(self.names)
        shapes = {"positions": ((m, k, 2), float), "present": ((m, k), bool), "radii": ((k,), float),
                  "indices": ((k,), np.int64)}
        if not 1 <= m <= MAX_PREDICTED_SAMPLES:
            raise ValueError(f"PredictedPeople.times must hold 1 to {MAX_PREDICTED_SAMPLES} times, got {m}")
        if k > MAX_PREDICTED_PEOPLE:
            raise ValueError(f"PredictedPeople holds at most {MAX_PREDICTED_PEOPLE} people, got {k}")
        if not -1 <= int(self.culprit) < k:
            raise ValueError(f"PredictedPeople.culprit must be -1 or in [0, {k}), got {self.culprit}")
        times.flags.writeable = False
        object.__setattr__(self, "times", times)
        for field, (shape, dtype) in shapes.items():
            value = np.array(getattr(self, field), dtype=dtype)
            if value.shape != shape:
                raise ValueError(f"PredictedPeople.{field} has shape {value.shape}; {m} samples of {k} people "
                                 f"need {shape}")
            value.flags.writeable = False
            object.__setattr__(self, field, value)
        object.__setattr__(self, "names", tuple(self.names))
        object.__setattr__(self, "culprit", int(self.culprit))

    def __eq__(self, other) -> bool:
        """Equal fields, the arrays bit for bit."""
        if not isinstance(other, PredictedPeople):
            return NotImplemented
        return all(np.array_equal(getattr(self, f.name), getattr(other, f.name)) for f in dc.fields(self))

    __hash__ = None  # holds arrays

    @property
    def nbytes(self) -> int:
        """Bytes of the arrays."""
        return sum(getattr(self, f).nbytes for f in ("times", "positions", "present", "radii", "indices"))

    @property
    def culprit_name(self) -> str | None:
        """The culprit's label, None when none was named."""
        return self.names[self.culprit] if self.culprit >= 0 else None


def sample_stride(samples: int, dt: float, *, step: float = PREDICTED_STEP,
                  max_samples: int = MAX_PREDICTED_SAMPLES) -> int:
    """The number of prediction steps between two kept samples: the smallest
    that is at least ``step`` seconds and keeps at most ``max_samples`` of
    the ``samples`` sample times (``(samples - 1) // stride + 1``)."""
    if samples < 1 or max_samples < 1:
        raise ValueError(f"sample_stride: samples and max_samples must be >= 1, got {samples}, {max_samples}")
    if not (math.isfinite(dt) and dt > 0.0 and math.isfinite(step) and step >= 0.0):
        raise ValueError(f"sample_stride: dt must be > 0 and step >= 0 seconds (finite), got {dt!r}, {step!r}")
    at_least = max(1, int(math.ceil(step / dt - 1e-9)))
    fit = int(math.ceil((samples - 1) / (max_samples - 1))) if max_samples > 1 else samples
    return max(at_least, fit, 1)


def predicted_people(prediction: Prediction, replan: int, *, near: np.ndarray | None = None, culprit: int = -1,
                     max_people: int = MAX_PREDICTED_PEOPLE, max_samples: int = MAX_PREDICTED_SAMPLES,
                     step: float = PREDICTED_STEP) -> PredictedPeople:
    """The extract of ``prediction`` kept for replan ``replan`` (see the module docstring).

    Args:
        prediction: what the replan judged its paths against.
        replan: the replan's index in the run's log.
        near: (L, 2) the robot's base path (x, y), metres: with more people
            than ``max_people``, those whose predicted positions (present,
            at the kept times) come nearest to it are kept; None: the first.
        culprit: the index of the person who made a path unsafe among the
            prediction's people (always kept), -1 for none.
        max_people, max_samples, step: the bounds (defaults: the module's).

    Returns:
        A :class:`PredictedPeople`, people in the prediction's order.
    """
    if not -1 <= culprit < prediction.count:
        raise ValueError(f"predicted_people: culprit must be -1 or in [0, {prediction.count}), got {culprit}")
    if not 1 <= max_people <= MAX_PREDICTED_PEOPLE or not 1 <= max_samples <= MAX_PREDICTED_SAMPLES:
        raise ValueError(f"predicted_people: max_people in [1, {MAX_PREDICTED_PEOPLE}] and max_samples in "
                         f"[1, {MAX_PREDICTED_SAMPLES}], got {max_people}, {max_samples}")
    line = None if near is None else np.asarray(near, float)
    if line is not None and (line.ndim != 2 or line.shape[1] != 2 or not np.isfinite(line).all()):
        raise ValueError(f"predicted_people: near must be (L, 2) finite base positions [x, y], got shape "
                         f"{line.shape}")
    stride = sample_stride(prediction.samples, prediction.dt, step=step, max_samples=max_samples)
    rows = np.arange(0, prediction.samples, stride)
    positions, present = prediction.positions[rows], prediction.present[rows]
    order = np.arange(prediction.count)
    if prediction.count > max_people:
        if line is not None and len(line):
            distance = np.where(present, polyline_distance(positions, line), math.inf).min(axis=0)
        else:
            distance = order.astype(float)
        if culprit >= 0:
            distance = distance.copy()
            distance[culprit] = -math.inf
        order = np.sort(np.argsort(distance, kind="stable")[:max_people])
    return PredictedPeople(replan=int(replan), t=float(prediction.t0), times=prediction.t0 + prediction.dt * rows,
                           positions=positions[:, order], present=present[:, order], radii=prediction.radii[order],
                           indices=order, names=tuple(prediction.names[i] for i in order),
                           culprit=int(np.flatnonzero(order == culprit)[0]) if culprit >= 0 else -1)
