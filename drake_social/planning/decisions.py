"""What a replan decided, in a few categories, for the figures and the replay.

A :class:`~drake_social.planning.replan.ReplanResult` says what it did in
its ``status`` and why in its ``reason`` (words). The figures and the replay
group the replans by :func:`decision`, from the structured fields alone
(not the words):

* ``"initial"``: the first plan;
* ``"unsafe"``: a new route because the current one was not safe any more
  (status ``"new"`` with no safe candidate: ``candidate_cost`` infinite,
  which includes having no current path);
* ``"cheaper"``: a new route because it was cheaper by the margin (status
  ``"new"``, the candidate safe);
* ``"evade"``: a way out of a person's path (status ``"evade"``);
* ``"wait"``: the robot holds (status ``"wait"``): nothing is safe, or
  the current path is safe after a pause that costs less than a new route
  (:mod:`~drake_social.planning.replan_commit`);
* ``"kept"``: the current path stays.
"""

from __future__ import annotations

import math

__all__ = ["DECISIONS", "DECISION_LABELS", "decision"]

#: The categories, in the order the figures list them.
DECISIONS = ("initial", "unsafe", "cheaper", "evade", "wait", "kept")
#: A short label of each category.
DECISION_LABELS = {"initial": "first plan", "unsafe": "new route: not safe any more",
                   "cheaper": "new route: cheaper", "evade": "evasion: steps aside",
                   "wait": "wait: nothing safe, or a pause", "kept": "path kept"}


def decision(result) -> str:
    """The category of a ReplanResult-like record (``status``, and
    ``candidate_cost`` for a new route: absent counts as not safe)."""
    status = result.status
    if status == "new":
        return "cheaper" if math.isfinite(getattr(result, "candidate_cost", math.inf)) else "unsafe"
    if status in ("initial", "evade", "wait", "kept"):
        return status
    raise ValueError(f"decision: unknown status {status!r}")
