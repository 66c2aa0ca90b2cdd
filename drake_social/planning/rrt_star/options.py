"""The options of :class:`~drake_social.planning.rrt_star.RrtStar` and the
shrinking radius's default constant."""

from __future__ import annotations

import dataclasses as dc
import math

import numpy as np

from drake_social.limits import NEAR_RADIUS_MODES  # the allowed near_radius_mode values
from drake_social.planning.space import ConfigurationSpace

__all__ = ["NEAR_RADIUS_MODES", "RrtStarOptions", "default_gamma"]


def default_gamma(space: ConfigurationSpace) -> float:
    """OMPL's RRT* radius constant for ``space`` (its default rewire factor
    1.1, ``RRTstar::calculateRewiringLowerBounds``):
    ``1.1 (2 (1 + 1/d) V / zeta_d)^(1/d)`` with V the volume of the weighted
    configuration box and zeta_d the unit d-ball's volume, d = 4."""
    d = 4
    volume = float(np.prod(space.weights * (space.upper - space.lower)))
    zeta = np.pi ** (d / 2) / math.gamma(d / 2 + 1)
    return 1.1 * (2.0 * (1.0 + 1.0 / d) * volume / zeta) ** (1.0 / d)


@dc.dataclass
class RrtStarOptions:
    """Options of :class:`RrtStar` (configuration-space units).

    The defaults are the paper's Algorithm 2: the fixed near radius and the
    raw path (``near_radius_mode="fixed"``, ``optimize=False``). A scenario's
    :class:`~drake_social.scenario.PlannerOptions` carries the user-facing
    defaults (the shrinking radius and the optimised path) and
    :meth:`from_scenario` copies them, so a plan of a scenario runs those;
    only code that builds these options itself gets the paper's.

    Attributes:
        iterations: samples drawn, K (1 .. MAX_ITERATIONS).
        planning_range: Steer distance delta.
        near_radius: near-set radius r_near (also the goal-connection radius);
            the cap of the shrinking radius.
        goal_bias: probability of sampling the goal.
        informed: sample base positions in an XY ellipse after the first solution.
        informed_mode: "paper" or "admissible" (see ``planning.sampling``).
        near_radius_mode: "fixed" (r_near) or "shrinking" (see the module docstring).
        near_radius_gamma: gamma of the shrinking radius; 0 = :func:`default_gamma`.
        optimize: optimise the returned path (:mod:`drake_social.planning.optimize`).
        lazy_costs: skip motion costs that their lower bound shows cannot
            matter (same result; False is the eager reference).
        kd_tree: use a KD-tree for neighbours from ``KD_TREE_MIN_NODES`` on
            (same neighbours; False scans every node, the reference).
        compiled: run the tree loop compiled (:mod:`~drake_social.planning.rrt_star.tree_kernel`,
            the default) when :func:`~drake_social.planning.rrt_star.compiled.compiled_support`
            says it can (a checker with a compiled scene, an objective with a
            compiled form); same tree bit for bit. The Python loop
            (:mod:`~drake_social.planning.rrt_star.reference`) stays the
            reference and serves every other case.
    """

    iterations: int = 2000
    planning_range: float = 1.5
    near_radius: float = 2.5
    goal_bias: float = 0.05
    informed: bool = False
    informed_mode: str = "paper"
    near_radius_mode: str = "fixed"
    near_radius_gamma: float = 0.0
    optimize: bool = False
    lazy_costs: bool = True
    kd_tree: bool = True
    compiled: bool = True

    @classmethod
    def from_scenario(cls, planner_options, informed: bool = False) -> "RrtStarOptions":
        p = planner_options
        return cls(
            p.iterations, p.planning_range, p.near_radius, p.goal_bias, informed, p.informed_mode,
            near_radius_mode=p.near_radius_mode, near_radius_gamma=p.near_radius_gamma, optimize=p.optimize,
        )
