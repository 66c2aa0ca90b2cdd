"""Where people will be: the replanner's prediction over a horizon.

A :class:`Prediction` holds the people at the sample times ``t0 + k dt``,
k = 0 .. H - 1 (the last is the horizon's end). Between samples a person's
position is interpolated linearly; heading and presence are those of the
sample at or before the time. Before ``t0`` and after the horizon the first
and the last samples hold: one rule, :mod:`drake_social.people.prediction_kernel`.
The arrays are the layout the compiled kernels read
(:mod:`drake_social.cost.timed_kernel`,
:mod:`drake_social.collision.people_kernel`): they take the prediction's
fields as plain arrays and look them up with the same kernel.

Three predictors:

* :func:`constant_velocity`: every present person goes on at
  the velocity of the state now, facing the way they face now;
* :func:`perfect_prediction`: the open-loop people of a
  :class:`~drake_social.people.compose.ScenarioPeople` (scripted and recorded)
  exactly as they will walk, a crowd (which reacts to the robot) at constant
  velocity. For studies: no deployed robot knows this;
* :func:`drake_social.people.interactive.predict_interactive`: a social-force
  rollout in which the people react to the robot's planned motion.
"""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np

from drake_social.people import prediction_kernel
from drake_social.people.model import PeopleModel, PeopleState

__all__ = ["DEFAULT_PREDICTION_STEP", "Prediction", "constant_velocity", "perfect_prediction", "predict", "sample_times"]

#: Seconds between the samples of a prediction.
DEFAULT_PREDICTION_STEP = 0.1


@dc.dataclass(frozen=True)
class Prediction:
    """People at the times ``t0 + k dt``, k = 0 .. H - 1 (see the module docstring).

    Attributes:
        t0: the time of the first sample (the replan's time), seconds.
        dt: seconds between samples (> 0).
        positions: (H, P, 2) body centres, metres.
        headings: (H, P) facing directions, radians.
        present: (H, P) bool: in the scene at the sample.
        radii: (P,) body radii, metres.
        speeds: (P,) speeds now, m/s (Kirby's speed scaling of the cost).
        max_speeds: (P,) the largest speed of each person's interpolated
            motion over the horizon, m/s (bounds how far they move between
            two times: the safety check's advancement uses it).
        names: P labels.
    """

    t0: float
    dt: float
    positions: np.ndarray
    headings: np.ndarray
    present: np.ndarray
    radii: np.ndarray
    speeds: np.ndarray
    max_speeds: np.ndarray
    names: tuple[str, ...]

    def __post_init__(self) -> None:
        if not (math.isfinite(self.t0) and math.isfinite(self.dt) and self.dt > 0):
            raise ValueError(f"Prediction: t0 must be finite and dt > 0, got t0={self.t0!r}, dt={self.dt!r}")
        p = len(self.names)
        h = np.asarray(self.positions).shape[0] if np.ndim(self.positions) == 3 else -1
        if h < 1:
            raise ValueError(f"Prediction.positions must be (H, P, 2) with H >= 1, got {np.shape(self.positions)}")
        for field, shape, dtype in (("positions", (h, p, 2), float), ("headings", (h, p), float),
                                    ("present", (h, p), bool), ("radii", (p,), float), ("speeds", (p,), float),
                                    ("max_speeds", (p,), float)):
            value = np.ascontiguousarray(getattr(self, field), dtype=dtype)
            if value.shape != shape:
                raise ValueError(f"Prediction.{field} has shape {value.shape}; {p} people over {h} samples need {shape}")
            if dtype is float and not np.all(np.isfinite(value)):
                raise ValueError(f"Prediction.{field} must be finite")
            value = value.copy()
            value.flags.writeable = False
            object.__setattr__(self, field, value)

    @property
    def count(self) -> int:
        """The number of people P."""
        return len(self.names)

    @property
    def samples(self) -> int:
        """The number of sample times H."""
        return self.positions.shape[0]

    @property
    def horizon(self) -> float:
        """The last sample's time, seconds."""
        return self.t0 + (self.samples - 1) * self.dt

    @property
    def static(self) -> bool:
        """True when nobody moves and nobody comes or goes over the horizon."""
        return bool(np.all(self.max_speeds == 0.0) and np.all(self.present == self.present[:1]))

    def until(self, seconds: float) -> "Prediction":
        """The first ``seconds`` of this prediction: its samples up to
        ``t0 + seconds`` (the one at or after it included, so that the
        horizon covers it; all of them when it is longer). Beyond the
        shorter horizon moving people are not safety obstacles, as beyond
        any horizon (:mod:`~drake_social.collision.people_kernel`);
        ``max_speeds`` are kept (they bound the shorter motion too). A time
        within 1e-9 of a step of a sample is that sample's, as the sample
        times of a horizon round."""
        if not seconds > 0:
            raise ValueError(f"Prediction.until: seconds must be > 0, got {seconds!r}")
        k = self.samples if not math.isfinite(seconds) else \
            min(self.samples, int(math.ceil(seconds / self.dt - 1e-9)) + 1)
        if k == self.samples:
            return self
        return Prediction(self.t0, self.dt, self.positions[:k], self.headings[:k], self.present[:k], self.radii,
                          self.speeds, self.max_speeds, self.names)

    def state_at(self, t: float) -> PeopleState:
        """The predicted people at time ``t`` (velocities: those of the
        interpolated motion there; zero past the horizon): the lookup of
        :mod:`~drake_social.people.prediction_kernel`, which the compiled
        kernels run too."""
        k, f = prediction_kernel.slot(float(t), self.t0, self.dt, self.samples)
        pos = prediction_kernel.centres(self.positions, k, f)
        vel = np.zeros_like(pos)
        if k + 1 < self.samples:
            vel = (self.positions[k + 1] - self.positions[k]) / self.dt
        return PeopleState(t=float(t), positions=pos, headings=self.headings[k], velocities=vel,
                           radii=self.radii, names=self.names, present=self.present[k])


def sample_times(t0: float, horizon: float, dt: float) -> np.ndarray:
    """The sample times ``t0 + k dt`` of a prediction over ``horizon`` seconds (the last at or past it)."""
    if not (math.isfinite(horizon) and horizon > 0 and math.isfinite(dt) and dt > 0):
        raise ValueError(f"a prediction needs horizon > 0 and dt > 0 seconds, got horizon={horizon!r}, dt={dt!r}")
    return float(t0) + dt * np.arange(int(math.ceil(horizon / dt - 1e-9)) + 1)


def _max_speeds(positions: np.ndarray, dt: float) -> np.ndarray:
    if positions.shape[0] < 2:
        return np.zeros(positions.shape[1])
    step = np.diff(positions, axis=0)
    return np.hypot(step[..., 0], step[..., 1]).max(axis=0) / dt


def constant_velocity(state: PeopleState, horizon: float, dt: float = DEFAULT_PREDICTION_STEP) -> Prediction:
    """Everyone in ``state`` going on at their velocity for ``horizon``
    seconds from ``state.t``, facing and present as now."""
    times = sample_times(state.t, horizon, dt)
    lag = (times - state.t)[:, None, None]
    positions = state.positions[None] + lag * state.velocities[None]
    h = len(times)
    speeds = state.speeds()
    return Prediction(t0=float(state.t), dt=float(dt), positions=positions,
                      headings=np.broadcast_to(state.headings, (h, state.count)),
                      present=np.broadcast_to(state.present, (h, state.count)), radii=state.radii,
                      speeds=speeds, max_speeds=speeds, names=state.names)


def perfect_prediction(model: PeopleModel, state: PeopleState, horizon: float,
                       dt: float = DEFAULT_PREDICTION_STEP) -> Prediction:
    """The open-loop people of ``model`` as they will walk (their model at
    each sample time) and a crowd at constant velocity from ``state`` (the
    people now, in the model's order: open-loop people first, then the
    crowd, as :class:`~drake_social.people.compose.ScenarioPeople` orders them).
    A model without ``open_loop_state`` is open loop as a whole."""
    if model.count != state.count:
        raise ValueError(f"perfect_prediction: the model has {model.count} people, the state {state.count}")
    times = sample_times(state.t, horizon, dt)
    cv = constant_velocity(state, horizon, dt)
    positions, headings, present = cv.positions.copy(), cv.headings.copy(), cv.present.copy()
    crowd = getattr(model, "crowd", None)
    open_state = getattr(model, "open_loop_state", None) if crowd is not None else None
    for k, t in enumerate(times):
        s = open_state(float(t)) if open_state is not None else model.state_at(float(t))
        n = s.count
        positions[k, :n], headings[k, :n], present[k, :n] = s.positions, s.headings, s.present
    return Prediction(t0=float(state.t), dt=float(dt), positions=positions, headings=headings, present=present,
                      radii=state.radii, speeds=state.speeds(), max_speeds=_max_speeds(positions, dt),
                      names=state.names)


def predict(kind: str, model: PeopleModel, state: PeopleState, horizon: float,
            dt: float = DEFAULT_PREDICTION_STEP, interactive=None) -> Prediction:
    """The prediction ``kind`` (``planner.prediction``: "constant_velocity",
    "perfect" or "interactive"). "interactive" needs ``interactive``, an
    :class:`~drake_social.people.interactive.InteractiveModel`, and gives its
    rollout without the robot (the reference the replanner measures the
    people's effort against; each judged path is judged against the
    rollout it induces, :mod:`drake_social.planning.replan_interactive`)."""
    if kind == "constant_velocity":
        return constant_velocity(state, horizon, dt)
    if kind == "perfect":
        return perfect_prediction(model, state, horizon, dt)
    if kind == "interactive":
        if interactive is None:
            raise ValueError("predict: the interactive prediction needs interactive= (an InteractiveModel)")
        return interactive.predict(state, horizon, dt)
    raise ValueError(f"predict: unknown prediction {kind!r}; allowed: constant_velocity, perfect, interactive")
