"""The people as a Drake system: where everyone is at the context's time.

:class:`PeopleSource` wraps a :class:`~drake_social.people.PeopleModel` and
answers, at the context's time ``t``, with ``model.state_at(t)``. It has no
state: the model is a fixed description of the people (a static crowd, a
script of walks), so a cloned or reset context gives the same answers.

Ports (outputs only):

* ``people_state``: abstract, the :class:`~drake_social.people.PeopleState`
  (positions, headings, velocities, radii, names).
* ``people_vector``: ``6 P`` numbers, per person ``[x, y, theta, vx, vy,
  radius]`` (metres, radians, metres per second), for vector consumers and
  loggers. With no people it has size 0.

Both outputs depend on the time only (the state records its time ``t``).

Example::

    from drake_social.control import PeopleSource
    from drake_social.people import StaticPeople

    source = PeopleSource(StaticPeople([[2.0, 1.0, 0.5]], [0.3], ["ann"]))
    context = source.CreateDefaultContext()
    print(source.GetOutputPort("people_vector").Eval(context))  # [2.  1.  0.5 0.  0.  0.3]
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, Context, LeafSystem

from drake_social.people import PeopleModel, PeopleState

__all__ = ["PEOPLE_VECTOR_FIELDS", "PeopleSource", "people_vector"]

#: The layout of one person in the ``people_vector`` output.
PEOPLE_VECTOR_FIELDS = ("x", "y", "theta", "vx", "vy", "radius")


def people_vector(state: PeopleState) -> np.ndarray:
    """The ``(6 P,)`` vector of a people state, per person ``[x, y, theta, vx, vy, radius]``."""
    rows = np.column_stack([state.positions, state.headings, state.velocities, state.radii])
    return rows.reshape(-1)


class PeopleSource(LeafSystem):
    """Outputs a people model's state at the context's time.

    Args:
        model: the people (any :class:`~drake_social.people.PeopleModel`,
            e.g. :func:`drake_social.people.people_model` of a scenario).

    Raises:
        TypeError: ``model`` is not a PeopleModel.
    """

    def __init__(self, model: PeopleModel):
        super().__init__()
        if not isinstance(model, PeopleModel):
            raise TypeError(f"PeopleSource: model must be a drake_social.people.PeopleModel "
                            f"(count, static, state_at(t)), got {type(model).__name__}")
        self._model = model
        count = int(model.count)
        prereqs = {self.time_ticket()}
        self.DeclareAbstractOutputPort(
            "people_state", lambda: AbstractValue.Make(model.state_at(0.0)), self._CalcState,
            prerequisites_of_calc=prereqs)
        self.DeclareVectorOutputPort("people_vector", 6 * count, self._CalcVector, prerequisites_of_calc=prereqs)

    @property
    def model(self) -> PeopleModel:
        """The people model this source answers from."""
        return self._model

    def _CalcState(self, context: Context, output: AbstractValue) -> None:
        output.set_value(self._model.state_at(context.get_time()))

    def _CalcVector(self, context: Context, output: BasicVector) -> None:
        output.SetFromVector(people_vector(self._model.state_at(context.get_time())))
