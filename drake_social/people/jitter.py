"""Seeded start delays of a scenario's scripted walkers (the crowd study's
episodes, :mod:`drake_social.experiments.study.crowd`).

Walker ``i`` (a :class:`~drake_social.scenario.schema.Person` with a
``trajectory``, ``i`` its index in the scenario's people) starts late by
``d_i = jitter * u``, ``u`` the first ``random()`` of
``numpy.random.default_rng(SeedSequence([seed, JITTER_TAG, i]))``. Every time
of its trajectory is shifted by ``d_i``: the walker stands at its first point
``d_i`` seconds longer (where it is at t = 0 does not change, nor a loop's
period). The tag keeps these draws apart from the planner's
``default_rng([seed, replan_index])``.
"""

from __future__ import annotations

import dataclasses as dc

import numpy as np

__all__ = ["JITTER_TAG", "delay_walkers", "has_people", "walker_delays"]

#: The SeedSequence tag of the walkers' delays ("JITT").
JITTER_TAG = 0x4A495454


def has_people(scenario) -> bool:
    """Whether ``scenario`` has any person: listed, recorded (``people_file``) or a simulated crowd."""
    return bool(scenario.people or scenario.people_file or scenario.crowd is not None)


def walker_delays(scenario, seed: int, jitter: float) -> dict[int, float]:
    """The start delay of every scripted walker of ``scenario`` for ``seed``:
    person index -> seconds in [0, jitter] (module docstring)."""
    delays = {}
    for i, person in enumerate(scenario.people):
        if person.trajectory is None:
            continue
        u = np.random.default_rng(np.random.SeedSequence([int(seed), JITTER_TAG, i])).random()
        delays[i] = float(jitter * u)
    return delays


def delay_walkers(scenario, seed: int, jitter: float) -> tuple[list, dict[int, float]]:
    """The people of ``scenario`` with every scripted walker's trajectory times
    shifted by its :func:`walker_delays` (copies; ``scenario`` is not changed).

    Returns:
        ``(the delayed people list, the delays)``.
    """
    delays = walker_delays(scenario, seed, jitter)
    people = [dc.replace(p, trajectory=[[t + delays[i], x, y] for t, x, y in p.trajectory]) if i in delays else p
              for i, p in enumerate(scenario.people)]
    return people, delays
