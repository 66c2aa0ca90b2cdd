"""One RRT* core for the whole family (the paper's Algorithm 2).

Per iteration: draw one sample (the goal with probability ``goal_bias``),
find the nearest node, Steer by ``planning_range``, check the new
configuration, gather the near set within the near radius, then choose the
parent: motions are checked in order of ``F(near) + Msc(near, new)`` and the
first collision-free one wins (the paper's choose-parent loop visits the same
candidates in any order and keeps the same minimum). The new node then
rewires its near set: a node whose cost drops through the new node is
re-parented, and the change is propagated to all its descendants. Motion
costs are symmetric (the trapezoid rule is), so the rewiring reuses the costs
computed for the parent choice.

Motion costs are lazy (``RrtStarOptions.lazy_costs``): every motion cost is
at least ``lambda * length`` (the social integral is >= 0), so a candidate
parent whose ``F(near) + lambda * length`` already exceeds the best checked
candidate, or a near node that the new node cannot improve even at that
bound, is never integrated. The parent, the rewiring and the motion checks
are exactly those of the eager reference (``lazy_costs=False``), in the same
order, bit for bit.

The near radius is ``near_radius`` (``near_radius_mode="fixed"``, the paper)
or the standard RRT* radius ``min(near_radius, gamma (log n / n)^(1/d))``
(``"shrinking"``, n the tree's size with the new node, d = 4), which keeps
the near set of a large tree small. The goal-connection radius is always
``near_radius``. Nearest and near queries use a KD-tree over the weighted
coordinates once the tree is large (rebuilt as it grows, recent nodes
scanned directly); its candidates are re-measured with the same arithmetic
as the direct scan, so the neighbours are the same bit for bit.

Iteration k draws exactly one sample, valid or not, as in the paper.

The package holds the two loops side by side: :mod:`.reference` (the
planner :class:`RrtStar` and the Python loop, the reference), and the
compiled loop, :mod:`.tree_kernel` (numba, typed by the NamedTuples
:class:`~.tree_kernel.GrowParams` and :class:`~.tree_kernel.TreeState`)
with its glue :mod:`.compiled` (:func:`~.compiled.compiled_support`, the
capability check that decides which loop runs); :mod:`.options` holds
:class:`RrtStarOptions`.
"""

from __future__ import annotations

from drake_social.limits import MAX_ITERATIONS
from drake_social.planning.rrt_star.compiled import CHUNK, PROGRESS_CHUNK, compiled_support
from drake_social.planning.rrt_star.options import NEAR_RADIUS_MODES, RrtStarOptions, default_gamma
from drake_social.planning.rrt_star.reference import KD_TREE_MIN_NODES, RrtStar

__all__ = ["CHUNK", "KD_TREE_MIN_NODES", "MAX_ITERATIONS", "NEAR_RADIUS_MODES", "PROGRESS_CHUNK", "RrtStar",
           "RrtStarOptions", "compiled_support", "default_gamma"]
