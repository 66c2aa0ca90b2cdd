"""A scenario's people as one model: the open-loop people, then the crowd.

:class:`ScenarioPeople` joins models into one :class:`~drake_social.people.PeopleModel`:
first the open-loop ones in order (the scenario's ``people`` list: standing or
scripted; then the recorded ``people_file``), then the simulated crowd. The
open-loop people go where their description says whatever happens; the crowd
(a :class:`CrowdModel`) is a discrete-time system that reacts to the others and
to the robot. :meth:`ScenarioPeople.state_at` runs the crowd open loop,
without the robot (what the planner sees at t = 0 and what a prediction
without the robot gives); the simulation diagram steps it with the robot's
configuration fed back (:class:`drake_social.control.PeopleSource`).
"""

from __future__ import annotations

import math
from typing import Protocol, Sequence, TypeVar, runtime_checkable

import numpy as np

from drake_social.people.model import PeopleModel, PeopleState, StaticPeople
from drake_social.people.recorded import recorded_model
from drake_social.people.scripted import ScriptedPeople

__all__ = ["CrowdModel", "ScenarioPeople", "concat_states", "people_model", "with_people", "without_people"]

_S = TypeVar("_S")


@runtime_checkable
class CrowdModel(Protocol):
    """People whose motion depends on the others and on the robot.

    The crowd's state is a flat vector (a Drake discrete state), advanced by
    :meth:`step` every ``time_step`` seconds; between steps it holds.
    """

    @property
    def count(self) -> int: ...

    @property
    def time_step(self) -> float: ...

    def initial_state(self) -> np.ndarray:
        """The state vector at t = 0."""

    def step(self, state: np.ndarray, t: float, others: PeopleState, robot_q: np.ndarray | None) -> np.ndarray:
        """The state one ``time_step`` after ``state`` (taken at time ``t``),
        with the open-loop people ``others`` at ``t`` and the robot at
        configuration ``robot_q`` (4,) (None: no robot)."""

    def people_state(self, state: np.ndarray, t: float) -> PeopleState:
        """The crowd's people in ``state``, reported at time ``t``."""


def concat_states(states: Sequence[PeopleState], t: float) -> PeopleState:
    """One state of the people of ``states`` in turn, at time ``t``."""
    if len(states) == 1:
        return states[0]
    # Fresh arrays of states already checked: no copies, no checks again.
    return PeopleState._trusted(
        float(t),
        np.concatenate([s.positions for s in states]).reshape(-1, 2),
        np.concatenate([s.headings for s in states]),
        np.concatenate([s.velocities for s in states]).reshape(-1, 2),
        np.concatenate([s.radii for s in states]),
        tuple(n for s in states for n in s.names),
        np.concatenate([s.present for s in states]),
    )


class ScenarioPeople:
    """The open-loop models' people, then the crowd's (see the module docstring).

    Args:
        open_loop: models that ignore the robot, in order.
        crowd: the simulated crowd, or None.
    """

    def __init__(self, open_loop: Sequence[PeopleModel], crowd: CrowdModel | None = None) -> None:
        self._open = tuple(open_loop)
        self._crowd = crowd
        self._crowd_states: list[np.ndarray] = [] if crowd is None else [np.asarray(crowd.initial_state(), float)]
        # The last open-loop state asked for: the simulation asks twice per
        # time (the crowd's step and the people output). The models answer
        # the same for the same time, and a state is immutable.
        self._last_open: PeopleState | None = None

    @property
    def open_loop(self) -> tuple[PeopleModel, ...]:
        """The open-loop models."""
        return self._open

    @property
    def crowd(self) -> CrowdModel | None:
        """The simulated crowd, or None."""
        return self._crowd

    @property
    def count(self) -> int:
        return sum(m.count for m in self._open) + (self._crowd.count if self._crowd is not None else 0)

    @property
    def static(self) -> bool:
        return self._crowd is None and all(m.static for m in self._open)

    def open_loop_state(self, t: float) -> PeopleState:
        """The open-loop people at time ``t`` (all of them when there is no crowd)."""
        last = self._last_open
        if last is not None and last.t == t:
            return last
        states = [m.state_at(t) for m in self._open]
        if not states:
            state = PeopleState(t=float(t), positions=np.zeros((0, 2)), headings=np.zeros(0),
                                velocities=np.zeros((0, 2)), radii=np.zeros(0), names=())
        else:
            state = concat_states(states, t)
        self._last_open = state
        return state

    def crowd_state_open_loop(self, t: float) -> np.ndarray:
        """The crowd's state vector at time ``t`` simulated without the robot:
        the state after floor(t / time_step) steps from t = 0 (held between steps)."""
        crowd = self._crowd
        if crowd is None:
            raise ValueError("ScenarioPeople.crowd_state_open_loop: there is no crowd")
        k = max(0, int(math.floor(t / crowd.time_step + 1e-9)))
        while len(self._crowd_states) <= k:
            j = len(self._crowd_states) - 1
            tj = j * crowd.time_step
            self._crowd_states.append(np.asarray(
                crowd.step(self._crowd_states[j], tj, self.open_loop_state(tj), None), float))
        return self._crowd_states[k]

    def state_at(self, t: float) -> PeopleState:
        """Everyone at time ``t`` (seconds, finite), the crowd open loop (no robot)."""
        if not math.isfinite(t):
            raise ValueError(f"ScenarioPeople.state_at: t must be a finite time in seconds, got {t!r}")
        open_state = self.open_loop_state(t)
        if self._crowd is None:
            return open_state
        return concat_states([open_state, self._crowd.people_state(self.crowd_state_open_loop(t), t)], t)


def people_model(scenario) -> PeopleModel:
    """The people model of a (validated) scenario: a :class:`ScenarioPeople` of
    its ``people`` list (a :class:`StaticPeople` when nobody has a trajectory,
    else a :class:`~drake_social.people.scripted.ScriptedPeople`), then its
    recorded ``people_file`` (:class:`~drake_social.people.recorded.RecordedPeople`),
    then its simulated ``crowd``."""
    people = scenario.people
    if all(p.trajectory is None for p in people):
        listed = StaticPeople([[p.x, p.y, p.theta] for p in people], [p.radius for p in people],
                              [p.name for p in people])
    else:
        listed = ScriptedPeople(people)
    recorded = recorded_model(scenario)
    open_loop = [listed] + ([] if recorded is None else [recorded])
    if scenario.crowd is None:
        crowd = None
    else:
        from drake_social.people.crowd import crowd_model
        crowd = crowd_model(scenario)
    return ScenarioPeople(open_loop, crowd)


def with_people(scenario: _S, extra: Sequence) -> _S:
    """A deep copy of ``scenario`` whose people are its own followed by ``extra``.

    Args:
        scenario: a scenario (not modified).
        extra: scenario ``Person`` records to append (the records themselves,
            not copies).

    Returns:
        The new scenario; it is not validated again.
    """
    import copy

    out = copy.deepcopy(scenario)
    out.people = list(out.people) + list(extra)
    return out


def without_people(scenario: _S) -> _S:
    """A deep copy of ``scenario`` with nobody in it (no people list, no
    people file, no crowd): the room alone, e.g. to check a run against the
    obstacles and walls while the people move. It is not validated again."""
    import copy

    out = copy.copy(scenario)  # the people's fields are replaced below, the rest deep-copied
    out.people, out.people_file, out.people_file_ids, out.crowd = [], None, None, None
    return copy.deepcopy(out)
