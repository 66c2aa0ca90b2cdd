"""People of the scenario's ``people`` list: standing, or walking timed waypoints.

A person with ``trajectory: [[t, x, y], ...]`` walks straight lines at constant
speed between the waypoints (seconds, metres): before the first time they stand
at the first point, after the last time at the last; with ``loop: true`` the
route repeats every ``t_last - t_first`` seconds (it must be closed); a loop
whose points are all one place (a person pausing there, ``[[0, x, y], [1, x,
y]]``) is a person standing there facing ``theta``. A person without a
trajectory stands at ``(x, y)`` facing ``theta``, exactly as
:class:`~drake_social.people.StaticPeople`.

Velocities are exact: the segment's velocity while walking, 0 while standing.

Heading (see :func:`~drake_social.scenario.heading.heading_knots`): ``theta``
while standing before the first motion. When a segment of motion starts, the
heading turns toward its direction, the shortest way, at
:data:`~drake_social.scenario.heading.TURN_RATE` (pi rad/s: a half turn takes one
second) and holds it; a turn cut short by the next segment continues from where
it got to. While paused between motions and after the end the person keeps the
last walking heading. So the heading is continuous (modulo 2 pi) and never
turns faster than the rate, at corners and stops alike. A looping route's
heading repeats with the route's period once it has settled (after the first
period as soon as one turn of the route completes).
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from drake_social.people.model import PeopleState
from drake_social.people.tracks import TURN_RATE, Tracks, heading_knots

__all__ = ["ScriptedPeople"]


class ScriptedPeople:
    """The ``people`` list of a scenario, standing or walking their trajectories.

    Args:
        people: scenario ``Person`` records (x, y, theta, radius, name,
            trajectory, loop), validated (see
            :func:`drake_social.scenario.validate.validate_scenario`).
        turn_rate: the heading's largest turning rate, rad/s (> 0).

    Raises:
        ValueError: a trajectory is not strictly increasing in time, or a
            looping route's heading never repeats (see
            :func:`~drake_social.scenario.heading.heading_knots`).
    """

    def __init__(self, people: Sequence, turn_rate: float = TURN_RATE) -> None:
        times, points, headings, loops, steady = [], [], [], [], []
        for i, p in enumerate(people):
            if p.trajectory is None:
                t = np.zeros(1)
                x = np.array([[p.x, p.y]], float)
                knots = (np.zeros(1), np.array([float(p.theta)]), math.inf)
            else:
                route = np.asarray(p.trajectory, float).reshape(-1, 3)
                t, x = route[:, 0], route[:, 1:]
                if len(t) < 2 or not (np.diff(t) > 0).all():
                    raise ValueError(f"ScriptedPeople: people[{i}].trajectory needs at least 2 points with strictly "
                                     f"increasing times, got {p.trajectory}")
                try:
                    knots = heading_knots(t, x, float(p.theta), bool(p.loop), turn_rate)
                except ValueError as e:
                    raise ValueError(f"ScriptedPeople: people[{i}].trajectory: {e}") from None
            times.append(t)
            points.append(x)
            headings.append(knots[:2])
            # A loop without motion has no heading period (``steady`` is inf): the person stands.
            loops.append(bool(p.loop) and p.trajectory is not None and math.isfinite(knots[2]))
            steady.append(knots[2])
        self._tracks = Tracks(times, points, headings, loops, steady)
        self._radii = np.array([float(p.radius) for p in people]).reshape(-1)
        self._radii.flags.writeable = False
        self._present = np.ones(len(self._radii), bool)
        self._present.flags.writeable = False
        self._names = tuple(p.name for p in people)
        self._static = all(p.trajectory is None for p in people)

    @property
    def count(self) -> int:
        return self._tracks.count

    @property
    def static(self) -> bool:
        """True when nobody has a trajectory."""
        return self._static

    def state_at(self, t: float) -> PeopleState:
        """The people at time ``t`` (seconds, finite)."""
        if not math.isfinite(t):
            raise ValueError(f"ScriptedPeople.state_at: t must be a finite time in seconds, got {t!r}")
        positions, velocities, headings = self._tracks.evaluate(t)
        # Fresh arrays of the tracks and this model's own read-only ones: no copies.
        return PeopleState._trusted(float(t), positions, headings, velocities, self._radii, self._names,
                                    self._present)
