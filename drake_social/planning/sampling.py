"""Samplers: uniform over the configuration space, and informed (an XY ellipse).

The informed sampler is the paper's Risk-Informed-RRT*: once a solution
exists, base positions are drawn uniformly inside the ellipse in the XY plane
whose foci are the start and goal base positions and whose transverse
diameter is ``c``; the arm joints stay uniform over their limits. Two ways to
choose ``c`` (see :func:`transverse_diameter`):

* ``"paper"``: the XY length of the current best path's base. Fast to
  converge, but not admissible for a social objective: a longer detour can be
  socially cheaper and is then never sampled.
* ``"admissible"``: ``best_cost / (lambda * min(w_x, w_y))``. Every path's cost
  is at least lambda times its weighted length, which bounds its base's XY
  length, so no path cheaper than the best is excluded. Needs lambda > 0.
"""

from __future__ import annotations

import math

import numpy as np

from drake_social.planning.space import ConfigurationSpace

__all__ = ["EllipseSampler", "transverse_diameter"]


def transverse_diameter(mode: str, best_cost: float, best_xy_length: float, objective) -> float:
    """The ellipse's transverse diameter for an informed mode (inf = no ellipse)."""
    if mode == "paper":
        return float(best_xy_length)
    if mode == "admissible":
        return float(objective.xy_length_bound(best_cost))
    raise ValueError(f"unknown informed mode {mode!r}; allowed: paper, admissible")


class EllipseSampler:
    """Uniform samples with the base inside an XY ellipse and the room.

    Args:
        space: the configuration space (its XY bounds clip the ellipse).
        start_xy, goal_xy: the foci, metres.
        max_attempts: rejection attempts against the room bounds before the
            sampler gives up and raises (only possible for a degenerate room).
    """

    def __init__(self, space: ConfigurationSpace, start_xy, goal_xy, max_attempts: int = 1000):
        self.space = space
        self.f1 = np.asarray(start_xy, float)
        self.f2 = np.asarray(goal_xy, float)
        self.centre = 0.5 * (self.f1 + self.f2)
        d = self.f2 - self.f1
        self.focal_distance = float(np.hypot(*d))
        angle = np.arctan2(d[1], d[0])
        self.rotation = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        self.max_attempts = max_attempts

    def contains(self, xy: np.ndarray, c: float) -> np.ndarray:
        """Whether base positions (..., 2) lie in the ellipse of diameter c."""
        xy = np.asarray(xy, float)
        return np.hypot(*np.moveaxis(xy - self.f1, -1, 0)) + np.hypot(*np.moveaxis(xy - self.f2, -1, 0)) <= c + 1e-9

    def sample(self, rng: np.random.Generator, c: float) -> np.ndarray:
        """One configuration (4,); uniform over the space when c is inf."""
        q = self.space.sample_uniform(rng)
        if not np.isfinite(c):
            return q
        c = max(c, self.focal_distance)
        a = 0.5 * c
        b = 0.5 * math.sqrt(max(c * c - self.focal_distance * self.focal_distance, 0.0))
        lo, hi = self.space.lower[:2], self.space.upper[:2]
        (r00, r01), (r10, r11) = self.rotation
        for _ in range(self.max_attempts):
            # Scalar arithmetic in a fixed order: the compiled loop repeats it bit for bit.
            r, phi = math.sqrt(rng.random()), 2 * math.pi * rng.random()
            u, v = a * r * math.cos(phi), b * r * math.sin(phi)
            xy = np.array([self.centre[0] + (r00 * u + r01 * v), self.centre[1] + (r10 * u + r11 * v)])
            if np.all(xy >= lo) and np.all(xy <= hi):
                q[:2] = xy
                return q
        raise RuntimeError(f"no ellipse sample inside the room bounds after {self.max_attempts} attempts")
