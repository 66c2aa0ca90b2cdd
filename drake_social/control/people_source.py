"""The people as a Drake system: where everyone is at the context's time.

:class:`PeopleSource` wraps a scenario's people model
(:func:`drake_social.people.people_model`, a
:class:`~drake_social.people.ScenarioPeople`) or any
:class:`~drake_social.people.PeopleModel`.

Without a crowd it has no state: the model is a fixed description of the
people (a static group, a script of walks, a recording), and the outputs are
``model.state_at(t)`` at the context's time ``t``, so a cloned or reset
context gives the same answers.

With a crowd (``model.crowd`` is a :class:`~drake_social.people.CrowdModel`)
the crowd is a discrete-time system fed back the robot: a periodic update
every ``crowd.time_step`` seconds (the first at t = 0) computes
``crowd.step(x_k, t_k, model.open_loop_state(t_k), robot_q(t_k))``. The
crowd's vector ``x_k`` holds over ``[t_k, t_k + time_step)``, as in
:meth:`~drake_social.people.ScenarioPeople.crowd_state_open_loop`; so that
the outputs need nothing but the state and the time (no algebraic loop
through ``robot_q``), the discrete state keeps the step just computed beside
the one in force: ``[t_k, x_k, x_{k+1}]`` (``1 + 2 n`` numbers for a crowd
vector of ``n``), and an output at ``t >= t_k + time_step`` (the instant of
the next update, before it runs) answers from ``x_{k+1}``.

Ports:

* input ``robot_q`` (with a crowd only): the robot's configuration
  ``[x, y, psi1, psi2]`` (metres, radians), read at the updates.
* ``people_state``: abstract, the :class:`~drake_social.people.PeopleState`
  (the open-loop people at ``t``, then the crowd's).
* ``people_vector``: ``6 P`` numbers, per person ``[x, y, theta, vx, vy,
  radius]`` (metres, radians, metres per second), for vector consumers and
  loggers; computed from ``people_state`` (one model evaluation per time).
  With no people it has size 0.
* ``crowd_state`` (with a crowd only): the discrete state ``[t_k, x_k,
  x_{k+1}]`` itself, a C++ state output (no Python call), which a run logs
  to rebuild the people afterwards (:meth:`PeopleSource.people_log`).

Example::

    from drake_social.control import PeopleSource
    from drake_social.people import StaticPeople

    source = PeopleSource(StaticPeople([[2.0, 1.0, 0.5]], [0.3], ["ann"]))
    context = source.CreateDefaultContext()
    print(source.GetOutputPort("people_vector").Eval(context))  # [2.  1.  0.5 0.  0.  0.3]
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, Context, DiscreteValues, LeafSystem

from drake_social.people import CrowdModel, PeopleLog, PeopleModel, PeopleState
from drake_social.people.compose import concat_states

__all__ = ["PEOPLE_VECTOR_FIELDS", "PeopleSource", "people_vector"]

#: The layout of one person in the ``people_vector`` output.
PEOPLE_VECTOR_FIELDS = ("x", "y", "theta", "vx", "vy", "radius")

#: The fields of a PeopleState that a join concatenates (see PeopleSource.people_at).
_JOINED = ("positions", "headings", "velocities", "radii", "present", "names")

#: Slack (seconds) when comparing the context's time with the next update's:
#: Drake computes periodic event times as offset + k * period.
_TIME_SLACK = 1e-9


def people_vector(state: PeopleState) -> np.ndarray:
    """The ``(6 P,)`` vector of a people state, per person ``[x, y, theta, vx, vy, radius]``."""
    rows = np.column_stack([state.positions, state.headings, state.velocities, state.radii])
    return rows.reshape(-1)


class PeopleSource(LeafSystem):
    """Outputs a people model's state at the context's time; steps its crowd.

    Args:
        model: the people (any :class:`~drake_social.people.PeopleModel`,
            e.g. :func:`drake_social.people.people_model` of a scenario).
            When it has a ``crowd`` (a :class:`~drake_social.people.CrowdModel`,
            not None) and an ``open_loop_state(t)``, the crowd is simulated
            here with the robot fed back (see the module docstring).

    Raises:
        TypeError: ``model`` is not a PeopleModel, or its crowd not a CrowdModel.
    """

    def __init__(self, model: PeopleModel):
        super().__init__()
        if not isinstance(model, PeopleModel):
            raise TypeError(f"PeopleSource: model must be a drake_social.people.PeopleModel "
                            f"(count, static, state_at(t)), got {type(model).__name__}")
        crowd = getattr(model, "crowd", None)
        if crowd is not None and not isinstance(crowd, CrowdModel):
            raise TypeError(f"PeopleSource: model.crowd must be a drake_social.people.CrowdModel, "
                            f"got {type(crowd).__name__}")
        self._model = model
        self._crowd: CrowdModel | None = crowd
        self._last_join: tuple[tuple, PeopleState] | None = None  # see people_at
        count = int(model.count)
        prereqs = {self.time_ticket()}
        if crowd is not None:
            self._n = len(np.asarray(crowd.initial_state(), float).reshape(-1))
            self._dt = float(crowd.time_step)
            self._open_count = count - int(crowd.count)
            self._robot_q = self.DeclareVectorInputPort("robot_q", 4)
            self._xd = self.DeclareDiscreteState(self.initial_crowd_state())
            self.DeclarePeriodicDiscreteUpdateEvent(self._dt, 0.0, self._Step)
            prereqs.add(self.discrete_state_ticket(self._xd))
        self._state_port = self.DeclareAbstractOutputPort(
            "people_state", lambda: AbstractValue.Make(model.state_at(0.0)), self._CalcState,
            prerequisites_of_calc=prereqs)
        self.DeclareVectorOutputPort("people_vector", 6 * count, self._CalcVector, prerequisites_of_calc=prereqs)
        if crowd is not None:
            self.DeclareStateOutputPort("crowd_state", self._xd)

    @property
    def model(self) -> PeopleModel:
        """The people model this source answers from."""
        return self._model

    @property
    def crowd(self) -> CrowdModel | None:
        """The simulated crowd, or None."""
        return self._crowd

    def initial_crowd_state(self) -> np.ndarray:
        """The discrete state at t = 0: ``[-time_step, x_0, x_0]`` (an update
        "before" t = 0 whose result x_0 is in force from t = 0)."""
        if self._crowd is None:
            raise ValueError("PeopleSource.initial_crowd_state: the model has no crowd")
        x0 = np.asarray(self._crowd.initial_state(), float).reshape(-1)
        return np.concatenate([[-self._dt], x0, x0])

    def people_at(self, t: float, crowd_state: np.ndarray | None = None) -> PeopleState:
        """The people at time ``t`` (seconds) given the discrete state
        ``crowd_state`` (``[t_k, x_k, x_{k+1}]``, a row of the ``crowd_state``
        output; None and ignored without a crowd)."""
        t = float(t)
        if self._crowd is None:
            return self._model.state_at(t)
        row = np.asarray(crowd_state, float).reshape(-1)
        n = self._n
        x = row[1 + n:] if t >= row[0] + self._dt - _TIME_SLACK else row[1:1 + n]
        crowd = self._crowd.people_state(x, t)
        if not self._open_count:  # a crowd alone: no open-loop state to build and join
            return crowd
        parts = [self._model.open_loop_state(t), crowd]
        # Standing people and a crowd between its steps keep their arrays while
        # the time moves on: the last join is reused when its parts' arrays are
        # the very same (read-only) objects.
        arrays = tuple(getattr(s, f) for s in parts for f in _JOINED)  # held: their ids stay theirs
        last = self._last_join
        if last is not None and all(a is b for a, b in zip(arrays, last[0])):
            return last[1].at_time(t)
        joined = concat_states(parts, t)
        self._last_join = (arrays, joined)
        return joined

    def people_log(self, times: Sequence[float], crowd_states: np.ndarray | None = None) -> PeopleLog:
        """The people at ``times`` (T,), seconds, increasing, T >= 1; with a crowd,
        ``crowd_states`` (T, 1 + 2 n) are the ``crowd_state`` output at those times."""
        times = np.asarray(times, float).reshape(-1)
        if self._crowd is None:
            return PeopleLog.sample(self._model, times)
        rows = np.asarray(crowd_states, float).reshape(len(times), -1)
        return PeopleLog.from_states([self.people_at(t, row) for t, row in zip(times, rows)])

    def _people(self, context: Context) -> PeopleState:
        if self._crowd is None:
            return self._model.state_at(context.get_time())
        return self.people_at(context.get_time(), context.get_discrete_state(self._xd).value())

    def _Step(self, context: Context, discrete: DiscreteValues) -> None:
        crowd, n, t = self._crowd, self._n, context.get_time()
        row = context.get_discrete_state(self._xd).value()
        # The update at t_k: x_k (computed at the last update) comes into force.
        x = row[1 + n:].copy()
        q = self._robot_q.Eval(context)
        following = np.asarray(crowd.step(x, t, self._model.open_loop_state(t), q), float).reshape(-1)
        if following.shape != (n,):
            raise ValueError(f"PeopleSource: the crowd's step returned {following.shape} numbers; "
                             f"its state has {n}")
        discrete.get_mutable_vector(self._xd).SetFromVector(np.concatenate([[t], x, following]))

    def _CalcState(self, context: Context, output: AbstractValue) -> None:
        output.set_value(self._people(context))

    def _CalcVector(self, context: Context, output: BasicVector) -> None:
        output.SetFromVector(people_vector(self._state_port.Eval(context)))
