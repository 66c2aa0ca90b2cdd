"""The multi-interest-point social cost S(q) and its integral along motions."""

from __future__ import annotations

import numpy as np

from drake_social.cost.agf import PersonalSpace, agf, people_array
from drake_social.kinematics import ArmGeometry, config_distance

__all__ = ["SocialCost", "interpolation_segments"]


def interpolation_segments(max_displacement: np.ndarray, resolution: float) -> np.ndarray:
    """Number of equal steps (>= 1) so that no tracked point moves more than
    ``resolution`` metres per step, given a bound on its total displacement.

    Raises:
        ValueError: a bound is NaN or infinite (a non-finite configuration).
    """
    bound = np.asarray(max_displacement, dtype=float)
    if not np.all(np.isfinite(bound)):
        raise ValueError(f"motions need finite configurations; displacement bounds: {bound[~np.isfinite(bound)]}")
    return np.maximum(1, np.ceil(bound / resolution - 1e-9)).astype(np.int64)


class SocialCost:
    """``S(q) = sum_i sum_j w_j AGF_i(p_j(q))`` and its motion integral (Msc).

    Args:
        geometry: the robot and its object (gives the interest points p_j).
        people: (H, 3) rows [x, y, theta]; may be empty (the cost is then 0).
        space: AGF variances and threshold.
        weights: (3 + P,) weights w_j >= 0, base first (see
            :attr:`ArmGeometry.interest_names`); None = all ones.
        resolution: largest displacement of any weighted interest point
            between two samples of the trapezoid rule, metres.
        distance_weights: per-coordinate scale of the configuration norm used
            as ``ds`` in the integral (None = the plain norm of the paper).
    """

    def __init__(
        self,
        geometry: ArmGeometry,
        people: np.ndarray,
        space: PersonalSpace = PersonalSpace(),
        weights: np.ndarray | None = None,
        resolution: float = 0.05,
        distance_weights: np.ndarray | None = None,
    ):
        n = geometry.num_interest_points
        w = np.ones(n) if weights is None else np.asarray(weights, dtype=float)
        if w.shape != (n,):
            raise ValueError(f"weights must have {n} values ({geometry.interest_names}), got {w.shape}")
        if np.any(~np.isfinite(w)) or np.any(w < 0):
            raise ValueError(f"weights must be finite and >= 0, got {w}")
        if not resolution > 0:
            raise ValueError(f"resolution must be > 0, got {resolution}")
        self.geometry = geometry
        self.people = np.asarray(people, dtype=float).reshape(-1, 3)
        self.space = space
        self.weights = w
        self.resolution = float(resolution)
        self.distance_weights = None if distance_weights is None else np.asarray(distance_weights, float)
        # Only points with a non-zero weight are evaluated (base-only: one point).
        self._active = np.flatnonzero(w > 0)
        self._active_weights = w[self._active]

    @classmethod
    def from_scenario(cls, scenario, weights: np.ndarray | None = None) -> "SocialCost":
        """The scenario's cost; ``weights`` overrides ``scenario.social.weights``."""
        s = scenario.social
        return cls(
            ArmGeometry.from_scenario(scenario),
            people_array(scenario.people),
            PersonalSpace.from_options(s),
            weights=s.weights if weights is None else weights,
            resolution=s.resolution,
            distance_weights=scenario.planner.distance_weights,
        )

    def with_weights(self, weights: np.ndarray) -> "SocialCost":
        """The same cost with other interest-point weights."""
        return SocialCost(self.geometry, self.people, self.space, weights, self.resolution, self.distance_weights)

    # ---- per configuration ----------------------------------------------------

    def point_costs(self, q: np.ndarray) -> np.ndarray:
        """Unweighted ``sum_i AGF_i(p_j(q))`` for every interest point, (..., 3 + P)."""
        return agf(self.geometry.interest_points(q), self.people, self.space).sum(-1)

    def __call__(self, q: np.ndarray) -> np.ndarray:
        """S(q) for q of shape (..., 4); returns shape (...)."""
        q = np.asarray(q, dtype=float)
        if len(self.people) == 0 or len(self._active) == 0:
            return np.zeros(q.shape[:-1])
        pts = self.geometry.interest_points(q)[..., self._active, :]
        return agf(pts, self.people, self.space).sum(-1) @ self._active_weights

    # ---- along motions --------------------------------------------------------

    def segments(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """Trapezoid steps per motion: no weighted point moves > resolution per step."""
        bound = self.geometry.max_displacement(q_a, q_b, active=self._active)
        return interpolation_segments(bound, self.resolution)

    def motion_cost(
        self,
        q_a: np.ndarray,
        q_b: np.ndarray,
        s_a: np.ndarray | None = None,
        s_b: np.ndarray | None = None,
    ) -> np.ndarray:
        """Msc: the trapezoid-rule integral of S along straight motions.

        ``Msc(a, b) = h/2 sum_k [S(q_k) + S(q_{k+1})]`` over N equal steps of
        configuration-space length h, N chosen per motion by :meth:`segments`.

        Args:
            q_a, q_b: motion ends (E, 4) or (4,).
            s_a, s_b: optional known S at the ends (E,), e.g. cached at tree
                nodes; they save two evaluations per motion.

        Returns:
            (E,) costs (a scalar array for single motions).
        """
        q_a = np.asarray(q_a, dtype=float)
        q_b = np.asarray(q_b, dtype=float)
        single = q_a.ndim == 1 and q_b.ndim == 1
        q_a, q_b = np.broadcast_arrays(np.atleast_2d(q_a), np.atleast_2d(q_b))
        length = config_distance(q_a, q_b, self.distance_weights)
        if len(self.people) == 0 or len(self._active) == 0:
            out = np.zeros(len(q_a))
            return out[0] if single else out
        s_a = self(q_a) if s_a is None else np.asarray(s_a, float).reshape(-1)
        s_b = self(q_b) if s_b is None else np.asarray(s_b, float).reshape(-1)
        n = self.segments(q_a, q_b)
        # Interior samples of all motions in one batch: motion e has n[e] - 1.
        inner = n - 1
        total = int(inner.sum())
        interior_sum = np.zeros(len(q_a))
        if total:
            edge = np.repeat(np.arange(len(q_a)), inner)
            start = np.cumsum(inner) - inner
            k = np.arange(total) - np.repeat(start, inner) + 1
            t = (k / n[edge])[:, None]
            s_inner = self(q_a[edge] + t * (q_b[edge] - q_a[edge]))
            interior_sum = np.bincount(edge, weights=s_inner, minlength=len(q_a))
        out = (length / n) * (0.5 * (s_a + s_b) + interior_sum)
        return out[0] if single else out

    # ---- for figures ----------------------------------------------------------

    def field(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``G(x, y) = sum_i AGF_i(x, y)`` (thresholded), broadcast over x and y."""
        x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
        return agf(np.stack([x, y], -1), self.people, self.space).sum(-1)
