"""Optimisation objectives: path length (RRT*) and the social integral (Social Risk-RRT*).

Following OMPL's split, an objective gives a *state cost* (S for the social
objectives; the planner does not need it, the OMPL baseline and reports do)
and a *motion cost* for straight motions, batched over motions. Variants
of the paper's planners are configurations of these two classes, not copies
(:data:`drake_social.planning.algorithms.ALGORITHM_SPECS` says which):

* objective ``"length"``: :class:`PathLengthObjective`;
* objective ``"social"``: :class:`SocialObjective` with the scenario's weights,
  or with weight 1 on the base and 0 elsewhere (``weights="base_only"``).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from drake_social.cost.social import SocialCost
from drake_social.kinematics import config_distance

__all__ = ["Objective", "PathLengthObjective", "SocialObjective"]


class Objective:
    """Base class: motion cost ``social(a, b) + length_weight * ||W (b - a)||``."""

    #: Weight of the configuration-space length in the motion cost.
    length_weight: float = 1.0
    #: Per-coordinate scale of the configuration distance.
    distance_weights: np.ndarray = np.ones(4)

    #: Whether :meth:`length_bound` is the motion cost itself (no social term).
    length_is_cost: bool = True

    #: The objective's form in the compiled tree loop
    #: (:mod:`drake_social.planning.rrt_star.tree_kernel`): ``"length"``,
    #: ``"social"``, or None when it has none (the Python loop then plans).
    #: A subclass that overrides :meth:`motion_cost` or :meth:`length_bound`
    #: has none unless it declares one itself (the compiled loop would not run
    #: its code).
    compiled_form: ClassVar[str | None] = None

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        overrides = {"motion_cost", "length_bound"} & set(vars(cls))
        if overrides and "compiled_form" not in vars(cls):
            cls.compiled_form = None

    def state_cost(self, q: np.ndarray) -> np.ndarray:
        """The cost rate at configurations (..., 4) (S for social objectives)."""
        return np.zeros(np.shape(q)[:-1])

    def length_bound(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """``lambda * ||W (b - a)||`` (E,): a lower bound of :meth:`motion_cost`
        computed with the same arithmetic as its length term, so that
        ``motion_cost >= length_bound`` holds exactly in floating point."""
        return Objective.motion_cost(self, q_a, q_b)

    def motion_cost(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """Costs (E,) of straight motions q_a -> q_b, (E, 4) each (or (4,))."""
        return self.length_weight * config_distance(np.atleast_2d(q_a), np.atleast_2d(q_b), self.distance_weights)

    def xy_length_bound(self, cost: float) -> float:
        """An upper bound on the base's XY path length of any path of this cost,
        or inf when the objective does not bound it (length_weight = 0)."""
        scale = self.length_weight * float(min(self.distance_weights[0], self.distance_weights[1]))
        return cost / scale if scale > 0 else np.inf


class PathLengthObjective(Objective):
    """Configuration-space path length, the RRT* baseline of the paper."""

    name = "path_length"
    compiled_form = "length"

    def __init__(self, distance_weights: np.ndarray | None = None):
        self.length_weight = 1.0
        self.distance_weights = np.ones(4) if distance_weights is None else np.asarray(distance_weights, float)


class SocialObjective(Objective):
    """The motion social cost Msc plus an optional length term (lambda).

    Args:
        social: the social cost S (its weights decide multi-point vs base-only).
        length_weight: lambda >= 0 (0 = the paper's pure social integral).
    """

    name = "social"
    compiled_form = "social"

    def __init__(self, social: SocialCost, length_weight: float = 0.0):
        if not length_weight >= 0:
            raise ValueError(f"length_weight must be >= 0, got {length_weight}")
        self.social = social
        self.length_weight = float(length_weight)
        self.length_is_cost = False
        dw = social.distance_weights
        self.distance_weights = np.ones(4) if dw is None else np.asarray(dw, float)

    def state_cost(self, q: np.ndarray) -> np.ndarray:
        return self.social(q)

    def motion_cost(self, q_a, q_b) -> np.ndarray:
        cost = self.social.motion_cost(np.atleast_2d(q_a), np.atleast_2d(q_b))
        if self.length_weight > 0:
            cost = cost + super().motion_cost(q_a, q_b)
        return cost
