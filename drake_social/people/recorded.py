"""Recorded pedestrians: the scenario's ``people_file`` replayed.

Each id of the file (see :mod:`drake_social.scenario.people_file`) is one
person, present from their first sample's time to their last
(:attr:`PeopleState.present`; before and after they keep their first and
last pose and count for nothing). Between samples the position is
interpolated linearly and the velocity is the segment's (from the samples;
a ``v`` column is ignored). The heading is the ``theta`` column
interpolated linearly (the shorter way round between samples) when the file
has one; otherwise the direction of motion, smoothed as the scripted people's
(:func:`~drake_social.scenario.heading.heading_knots`: turning at a bounded rate,
holding the last walking heading while standing), starting from the direction
of the id's first motion (0 for an id that never moves).
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from drake_social.people.model import PeopleState
from drake_social.people.tracks import TURN_RATE, Tracks, heading_knots
from drake_social.scenario.people_file import PeopleRecording, read_people_file

__all__ = ["RecordedPeople", "recorded_model"]


class RecordedPeople:
    """The people of a recording, in the order of ``ids``.

    Args:
        recording: a people file read by
            :func:`~drake_social.scenario.people_file.read_people_file`.
        ids: the ids to keep, in this order; None = all, in the recording's order.
        turn_rate: the heading's largest turning rate without a ``theta`` column, rad/s (> 0).

    Raises:
        ValueError: an id is not in the recording.
    """

    def __init__(self, recording: PeopleRecording, ids: Sequence[str] | None = None,
                 turn_rate: float = TURN_RATE) -> None:
        ids = list(recording.tracks) if ids is None else [str(i) for i in ids]
        unknown = [i for i in ids if i not in recording.tracks]
        if unknown:
            raise ValueError(f"RecordedPeople: ids {unknown} are not in {recording.path}")
        tracks = [recording.tracks[i] for i in ids]
        headings = []
        for tr in tracks:
            if tr.thetas is not None:
                headings.append((tr.times, np.unwrap(tr.thetas)))
                continue
            d = np.diff(tr.positions, axis=0)
            moving = np.flatnonzero(d.any(axis=1))
            theta = math.atan2(d[moving[0], 1], d[moving[0], 0]) if len(moving) else 0.0
            headings.append(heading_knots(tr.times, tr.positions, theta, False, turn_rate)[:2])
        n = len(tracks)
        self._tracks = Tracks([tr.times for tr in tracks], [tr.positions for tr in tracks], headings,
                              [False] * n, [math.inf] * n)
        self._first = np.array([tr.times[0] for tr in tracks]).reshape(n)
        self._last = np.array([tr.times[-1] for tr in tracks]).reshape(n)
        self._radii = np.array([tr.radius for tr in tracks], float).reshape(n)
        self._radii.flags.writeable = False  # shared by every state
        self._names = tuple(ids)

    @property
    def count(self) -> int:
        return self._tracks.count

    @property
    def static(self) -> bool:
        """False: people come and go."""
        return False

    def state_at(self, t: float) -> PeopleState:
        """The recorded people at time ``t`` (seconds, finite), ``present`` where
        ``t`` lies within an id's first and last sample times."""
        if not math.isfinite(t):
            raise ValueError(f"RecordedPeople.state_at: t must be a finite time in seconds, got {t!r}")
        positions, velocities, headings = self._tracks.evaluate(t)
        # Fresh arrays of the tracks and this model's own read-only ones: no copies.
        return PeopleState._trusted(float(t), positions, headings, velocities, self._radii, self._names,
                                    (self._first <= t) & (t <= self._last))


def recorded_model(scenario) -> RecordedPeople | None:
    """The recorded people of a validated scenario (its ``people_file``, an
    absolute path once loaded, and ``people_file_ids``), or None without a file."""
    if scenario.people_file is None:
        return None
    return RecordedPeople(read_people_file(scenario.people_file), scenario.people_file_ids)
