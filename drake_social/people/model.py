"""The people protocol (:class:`PeopleModel`), its state and the static model."""

from __future__ import annotations

import dataclasses as dc
import math
from typing import Protocol, Sequence, runtime_checkable

import numpy as np

__all__ = ["PeopleModel", "PeopleState", "StaticPeople"]

@dc.dataclass(frozen=True)
class PeopleState:
    """Where everyone is at one time, in the world frame.

    Attributes:
        t: the time of the state, seconds since the start of the run.
        positions: (P, 2) body centres [x, y], metres.
        headings: (P,) facing directions, radians, counter-clockwise from +x.
        velocities: (P, 2) velocities [vx, vy], metres per second.
        radii: (P,) body radii, metres.
        names: P labels for figures and messages ("" where unnamed).
        present: (P,) True for the people in the scene at ``t``; a recorded
            pedestrian is absent before they enter and after they leave.
            Absent people keep their last (or first) pose in the arrays and
            count for nothing: no cost, no collision, no metric. None (the
            default) = everyone present.
    """

    t: float
    positions: np.ndarray
    headings: np.ndarray
    velocities: np.ndarray
    radii: np.ndarray
    names: tuple[str, ...]
    present: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = len(self.names)
        present = np.ones(n, bool) if self.present is None else np.asarray(self.present, dtype=bool)
        if present.shape != (n,):
            raise ValueError(f"PeopleState.present has shape {present.shape}; {n} people need {(n,)}")
        present = present.copy()
        present.flags.writeable = False
        object.__setattr__(self, "present", present)
        for field, shape in (("positions", (n, 2)), ("headings", (n,)), ("velocities", (n, 2)), ("radii", (n,))):
            value = np.asarray(getattr(self, field), dtype=float)
            if value.shape != shape:
                raise ValueError(f"PeopleState.{field} has shape {value.shape}; {n} people need {shape}")
            value = value.copy()
            value.flags.writeable = False
            object.__setattr__(self, field, value)

    @classmethod
    def _trusted(cls, t: float, positions: np.ndarray, headings: np.ndarray, velocities: np.ndarray,
                 radii: np.ndarray, names: tuple[str, ...], present: np.ndarray) -> "PeopleState":
        """A state of arrays the caller owns and vouches for (the models' own
        path, every time step): C-contiguous, of the right dtypes and shapes,
        never written again. They are made read-only and kept, not copied or
        checked (the checks and copies of the constructor cost tens of
        microseconds). ``present`` is required (bool, (P,))."""
        for value in (positions, headings, velocities, radii, present):
            if value.flags.writeable:  # the model's own constants are read-only already (a cheaper test)
                value.flags.writeable = False
        return cls._shared(t, positions, headings, velocities, radii, names, present)

    @classmethod
    def _shared(cls, t, positions, headings, velocities, radii, names, present) -> "PeopleState":
        """:meth:`_trusted` of arrays already read-only (another state's)."""
        state = object.__new__(cls)
        setattr_ = object.__setattr__
        setattr_(state, "t", t)
        setattr_(state, "positions", positions)
        setattr_(state, "headings", headings)
        setattr_(state, "velocities", velocities)
        setattr_(state, "radii", radii)
        setattr_(state, "names", names)
        setattr_(state, "present", present)
        return state

    def at_time(self, t: float) -> "PeopleState":
        """The same people reported at time ``t`` (seconds): the arrays are shared (read-only)."""
        return PeopleState._shared(float(t), self.positions, self.headings, self.velocities, self.radii,
                                   self.names, self.present)

    @property
    def count(self) -> int:
        """The number of people P."""
        return len(self.names)

    def visible(self) -> "PeopleState":
        """The people present at ``t`` only, in the same order (self when all are)."""
        if self.present.all():
            return self
        keep = self.present
        return PeopleState(t=self.t, positions=self.positions[keep], headings=self.headings[keep],
                           velocities=self.velocities[keep], radii=self.radii[keep],
                           names=tuple(n for n, k in zip(self.names, keep) if k))

    def poses(self) -> np.ndarray:
        """(P, 3) rows [x, y, theta]: the layout the social cost reads."""
        return np.column_stack([self.positions, self.headings]).reshape(-1, 3)

    def speeds(self) -> np.ndarray:
        """(P,) speeds, metres per second."""
        return np.hypot(self.velocities[:, 0], self.velocities[:, 1])


@runtime_checkable
class PeopleModel(Protocol):
    """Answers "where is everyone at time t".

    ``count`` people, always the same ones in the same order; ``static`` is
    True when :meth:`state_at` gives the same state at every time.
    """

    @property
    def count(self) -> int: ...

    @property
    def static(self) -> bool: ...

    def state_at(self, t: float) -> PeopleState: ...


class StaticPeople:
    """People who stand still: the same :class:`PeopleState` at every time.

    Args:
        poses: (P, 3) rows [x, y, theta] (metres, radians).
        radii: (P,) body radii, metres.
        names: optional labels, one per person.
    """

    def __init__(self, poses, radii, names: Sequence[str] | None = None) -> None:
        poses = np.asarray(poses, dtype=float).reshape(-1, 3)
        radii = np.asarray(radii, dtype=float).reshape(-1)
        names = tuple(names) if names is not None else ("",) * len(poses)
        if not (len(poses) == len(radii) == len(names)):
            raise ValueError(f"StaticPeople: {len(poses)} poses, {len(radii)} radii and {len(names)} names; "
                             "one of each per person")
        if not (np.isfinite(poses).all() and np.isfinite(radii).all() and (radii > 0).all()):
            raise ValueError("StaticPeople: poses and radii must be finite and the radii > 0")
        self._state = PeopleState(t=0.0, positions=poses[:, :2], headings=poses[:, 2],
                                  velocities=np.zeros((len(poses), 2)), radii=radii, names=names)

    @property
    def count(self) -> int:
        return self._state.count

    @property
    def static(self) -> bool:
        return True

    def state_at(self, t: float) -> PeopleState:
        """The people at time ``t`` (seconds, finite): where they stand."""
        if not math.isfinite(t):
            raise ValueError(f"StaticPeople.state_at: t must be a finite time in seconds, got {t!r}")
        return self._state.at_time(t)
