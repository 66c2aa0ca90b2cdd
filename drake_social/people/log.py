"""A record of where people were: :class:`PeopleLog`, sampled states over a run.

A run's people (scripted, recorded or simulated, the crowd reacting to the
robot) are logged at the control period; the replay, the figures, the metrics
and ``people.csv`` read this log, so they all see where people actually were.
A log is itself a :class:`~drake_social.people.PeopleModel`: :meth:`PeopleLog.state_at`
interpolates linearly between samples (headings along the shorter arc) and
holds the first and last sample outside them.
"""

from __future__ import annotations

import dataclasses as dc
import math
from typing import Iterator, Sequence

import numpy as np

from drake_social.people.model import PeopleModel, PeopleState

__all__ = ["PEOPLE_CSV_FIELDS", "PeopleLog", "person_ids"]

#: Columns of ``people.csv``: time (s), id, position (m), heading (rad), speed (m/s).
PEOPLE_CSV_FIELDS = ("t", "id", "x", "y", "theta", "v")


def person_ids(names: Sequence[str]) -> list[str]:
    """One distinct id per person for files (``people.csv``).

    Person i's id is its name when the name is set, no other person has it,
    and it is not the id of another person; otherwise it is ``str(i)``, the
    person's index. "The id of another person" is applied until nothing
    changes: a name equal to the index of a person who gets their index
    (``["", "0"]`` gives ``["0", "1"]``) gives way, which can make another
    name give way in turn. The ids are then distinct: the kept names are
    distinct, the indices are, and no kept name is another person's index id.

    Args:
        names: the people's names ("" where unnamed), in their order.

    Returns:
        The ids, in the same order.
    """
    counts: dict[str, int] = {}
    for n in names:
        counts[n] = counts.get(n, 0) + 1
    keep = [bool(n) and counts[n] == 1 for n in names]
    while True:
        index_ids = {str(i) for i, k in enumerate(keep) if not k}
        clash = [i for i, (n, k) in enumerate(zip(names, keep)) if k and n in index_ids]
        if not clash:
            return [n if k else str(i) for i, (n, k) in enumerate(zip(names, keep))]
        for i in clash:
            keep[i] = False


@dc.dataclass(frozen=True)
class PeopleLog:
    """People sampled at times ``t_0 < t_1 < ...``.

    Attributes:
        times: (T,) sample times, seconds, strictly increasing (T >= 1).
        positions: (T, P, 2) body centres, metres.
        headings: (T, P) facing directions, radians.
        velocities: (T, P, 2) velocities, metres per second.
        present: (T, P) True where the person is in the scene.
        radii: (P,) body radii, metres.
        names: P labels.
    """

    times: np.ndarray
    positions: np.ndarray
    headings: np.ndarray
    velocities: np.ndarray
    present: np.ndarray
    radii: np.ndarray
    names: tuple[str, ...]

    def __post_init__(self) -> None:
        times = np.asarray(self.times, dtype=float).reshape(-1)
        t, n = len(times), len(self.names)
        if t == 0:
            raise ValueError("PeopleLog: no samples")
        if not (np.isfinite(times).all() and (np.diff(times) > 0).all()):
            raise ValueError("PeopleLog.times must be finite and strictly increasing")
        shapes = {"positions": (t, n, 2), "headings": (t, n), "velocities": (t, n, 2), "present": (t, n),
                  "radii": (n,)}
        object.__setattr__(self, "times", times)
        for field, shape in shapes.items():
            value = np.asarray(getattr(self, field), dtype=bool if field == "present" else float)
            if value.shape != shape:
                raise ValueError(f"PeopleLog.{field} has shape {value.shape}; {t} samples of {n} people need {shape}")
            value = value.copy()
            value.flags.writeable = False
            object.__setattr__(self, field, value)
        object.__setattr__(self, "names", tuple(self.names))

    @classmethod
    def from_states(cls, states: Sequence[PeopleState]) -> "PeopleLog":
        """The log of states taken at increasing times (all of the same people)."""
        if not states:
            raise ValueError("PeopleLog.from_states: no states")
        first = states[0]
        return cls(times=[s.t for s in states], positions=[s.positions for s in states],
                   headings=[s.headings for s in states], velocities=[s.velocities for s in states],
                   present=[s.present for s in states], radii=first.radii, names=first.names)

    @classmethod
    def sample(cls, model: PeopleModel, times: Sequence[float]) -> "PeopleLog":
        """The states of an open-loop ``model`` at ``times`` (seconds, increasing)."""
        return cls.from_states([model.state_at(float(t)) for t in times])

    @property
    def count(self) -> int:
        """The number of people P."""
        return len(self.names)

    @property
    def static(self) -> bool:
        """True when nobody moves, turns, enters or leaves over the log."""
        return bool((self.positions == self.positions[0]).all() and (self.headings == self.headings[0]).all()
                    and (self.present == self.present[0]).all() and not self.velocities.any())

    def state(self, k: int) -> PeopleState:
        """The k-th sample."""
        return PeopleState(t=float(self.times[k]), positions=self.positions[k], headings=self.headings[k],
                           velocities=self.velocities[k], radii=self.radii, names=self.names,
                           present=self.present[k])

    def state_at(self, t: float) -> PeopleState:
        """The people at time ``t`` (seconds): linear between the samples around
        it; present as at the sample at or before ``t``."""
        if not math.isfinite(t):
            raise ValueError(f"PeopleLog.state_at: t must be a finite time in seconds, got {t!r}")
        times = self.times
        if t <= times[0] or len(times) == 1:
            return dc.replace(self.state(0), t=float(t))
        if t >= times[-1]:
            return dc.replace(self.state(len(times) - 1), t=float(t))
        k = int(np.searchsorted(times, t, side="right")) - 1
        w = (t - times[k]) / (times[k + 1] - times[k])
        turn = np.angle(np.exp(1j * (self.headings[k + 1] - self.headings[k])))
        return PeopleState(
            t=float(t),
            positions=(1 - w) * self.positions[k] + w * self.positions[k + 1],
            headings=np.angle(np.exp(1j * (self.headings[k] + w * turn))),
            velocities=(1 - w) * self.velocities[k] + w * self.velocities[k + 1],
            radii=self.radii, names=self.names, present=self.present[k])

    def csv_rows(self) -> Iterator[tuple[float, str, float, float, float, float]]:
        """Rows (t, id, x, y, theta, v) of ``people.csv``: one per present person
        per sample, in time order, then the people's order (ids from :func:`person_ids`),
        one at a time (a long run among many people has millions)."""
        ids = person_ids(self.names)
        speeds = np.hypot(self.velocities[..., 0], self.velocities[..., 1])
        for k, t in enumerate(self.times):
            for i in np.flatnonzero(self.present[k]):
                yield (float(t), ids[i], float(self.positions[k, i, 0]), float(self.positions[k, i, 1]),
                       float(self.headings[k, i]), float(speeds[k, i]))
