"""The wall-clock deadline of one replan, checked by each stage between small chunks of work.

A replan has ``planner.replan_budget`` seconds (docs/replanning.md, "The
anytime budget and the deadline"). The compiled search stops at its own
deadline, earlier (``search``); the work after it (judging the search's
paths, shortening the best one, looking for a way out of a person's path)
checks :meth:`Deadline.passed` before every step whose cost grows with the
people or the candidates, and when the budget is spent keeps the best answer
it has judged (or the documented fallback). :attr:`Deadline.hit` then says
that the budget cut the replan (``deadline_hit`` of ``replans.csv``).

The clock is ``time.perf_counter()``, read through the ``time`` module at
every check (the compiled search reads it the same way), so a test can
replace it.
"""

from __future__ import annotations

import time

__all__ = ["Deadline"]


class Deadline:
    """The ``time.perf_counter()`` values past which a replan stops working.

    Args:
        stop: past it no stage starts another chunk of work (None: no deadline).
        search_stop: the compiled search's deadline, at most ``stop`` (None:
            ``stop``): the rest is kept for the work after the search.

    Attributes:
        hit: a check found ``stop`` passed (sticky: the replan was cut).
    """

    __slots__ = ("stop", "search_stop", "hit")

    def __init__(self, stop: float | None = None, search_stop: float | None = None) -> None:
        self.stop = None if stop is None else float(stop)
        self.search_stop = self.stop if search_stop is None or stop is None else min(float(search_stop), self.stop)
        self.hit = False

    def passed(self) -> bool:
        """Whether the deadline has passed (recorded in :attr:`hit`); always False without one."""
        if not self.hit and self.stop is not None and time.perf_counter() > self.stop:
            self.hit = True
        return self.hit

    def search_passed(self) -> bool:
        """Whether the search's deadline has passed (not recorded: the search records its own)."""
        return self.search_stop is not None and time.perf_counter() > self.search_stop
