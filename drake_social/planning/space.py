"""The configuration space: bounds, uniform sampling, distance and steering."""

from __future__ import annotations

import dataclasses as dc

import numpy as np

from drake_social.arguments import require_scenario
from drake_social.kinematics import config_distance

__all__ = ["ConfigurationSpace"]


@dc.dataclass(frozen=True)
class ConfigurationSpace:
    """Box-bounded configurations ``q = [x, y, psi1, psi2]``.

    Attributes:
        lower: (4,) lower bounds (metres, radians).
        upper: (4,) upper bounds.
        weights: (4,) per-coordinate scale of the distance ``||W dq||``.
    """

    lower: np.ndarray
    upper: np.ndarray
    weights: np.ndarray = dc.field(default_factory=lambda: np.ones(4))

    def __post_init__(self):
        lo, hi = np.asarray(self.lower, float), np.asarray(self.upper, float)
        if lo.shape != (4,) or hi.shape != (4,) or not np.all(hi > lo):
            raise ValueError(f"bounds must be (4,) with upper > lower, got {lo}, {hi}")
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)
        object.__setattr__(self, "weights", np.asarray(self.weights, float))

    @classmethod
    def from_scenario(cls, scenario) -> "ConfigurationSpace":
        """Base positions keep the base disc inside the room; joints in their limits."""
        require_scenario(scenario, "ConfigurationSpace.from_scenario")
        x0, y0, x1, y1 = scenario.world.bounds
        r = scenario.robot.base_radius
        lower = [x0 + r, y0 + r, *scenario.robot.joint_lower]
        upper = [x1 - r, y1 - r, *scenario.robot.joint_upper]
        return cls(np.array(lower), np.array(upper), np.array(scenario.planner.distance_weights, float))

    def contains(self, q: np.ndarray) -> np.ndarray:
        """Whether q (..., 4) lies within the bounds."""
        q = np.asarray(q, float)
        return np.all((q >= self.lower) & (q <= self.upper), axis=-1)

    def sample_uniform(self, rng: np.random.Generator, n: int | None = None) -> np.ndarray:
        """Uniform samples, (4,) or (n, 4)."""
        size = (4,) if n is None else (n, 4)
        return self.lower + rng.random(size) * (self.upper - self.lower)

    def distance(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """``||W (q_b - q_a)||``, broadcast over leading dimensions."""
        return config_distance(q_a, q_b, self.weights)

    def steer(self, q_from: np.ndarray, q_to: np.ndarray, step: float, distance: float | None = None) -> np.ndarray:
        """The paper's Steer: q_to if within ``step`` of q_from, else the point
        at distance ``step`` from q_from towards q_to.

        Args:
            distance: ``self.distance(q_from, q_to)`` when already known.
        """
        d = float(self.distance(q_from, q_to)) if distance is None else distance
        if d <= step:
            return np.array(q_to, dtype=float)
        return q_from + (q_to - q_from) * (step / d)
