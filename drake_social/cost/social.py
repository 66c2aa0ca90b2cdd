"""The multi-interest-point social cost S(q) and its integral along motions."""

from __future__ import annotations

import numpy as np

from drake_social.cost.agf import PersonalSpace, agf, agf_xy, people_array
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
        x, y = self.geometry.interest_xy(q, self._active)
        return agf_xy(x, y, self.people, self.space).sum(-1) @ self._active_weights

    # ---- along motions --------------------------------------------------------

    def segments(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """Trapezoid steps per motion: no weighted point moves > resolution per step."""
        bound = self.geometry.max_displacement(q_a, q_b, active=self._active)
        return interpolation_segments(bound, self.resolution)

    def may_cost(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """False for motions (E,) whose cost is exactly 0 by a distance bound.

        A weighted point moves at most D (:meth:`ArmGeometry.max_displacement`)
        along the motion, so at every instant it is at least ``(A + B - D) / 2``
        from a person it starts A and ends B away. Beyond the AGF's reach
        (where it is <= threshold in every direction) its term is 0 throughout.
        """
        reach = self.space.max_reach
        if not np.isfinite(reach):
            return np.ones(len(q_a), dtype=bool)
        xa, ya = self.geometry.interest_xy(q_a, self._active)
        xb, yb = self.geometry.interest_xy(q_b, self._active)
        px, py = self.people[:, 0], self.people[:, 1]
        dist_a = np.hypot(xa[..., None] - px, ya[..., None] - py)
        dist_b = np.hypot(xb[..., None] - px, yb[..., None] - py)
        slack = self.geometry.max_displacement(q_a, q_b, active=self._active)[:, None, None]
        return np.any(dist_a + dist_b - slack <= 2.0 * reach, axis=(1, 2))

    def motion_cost(self, q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
        """Msc: the integral of S along straight motions, by the trapezoid rule.

        Each motion is cut into N equal steps of configuration length h
        (N from :meth:`segments`). The trapezoid rule is applied to every
        (point, person) term ``w_j AGF_i`` on its own, and where a term crosses
        the threshold inside a step (it jumps between 0 and > threshold there)
        the crossing is located by linear interpolation of the raw Gaussian
        and only the part above the threshold is integrated. Without crossings
        this is exactly the paper's ``h/2 sum [S(q_k) + S(q_k+1)]``; with them
        the error stays second order instead of a first-order jump error.
        Motions that :meth:`may_cost` rules out are not sampled at all.

        Args:
            q_a, q_b: motion ends (E, 4) or (4,), broadcastable.

        Returns:
            (E,) costs (a 0-d value for a single motion).
        """
        q_a = np.asarray(q_a, dtype=float)
        q_b = np.asarray(q_b, dtype=float)
        single = q_a.ndim == 1 and q_b.ndim == 1
        q_a, q_b = np.broadcast_arrays(np.atleast_2d(q_a), np.atleast_2d(q_b))
        out = np.zeros(len(q_a))
        if len(self.people) == 0 or len(self._active) == 0 or len(q_a) == 0:
            return out[0] if single else out
        length = config_distance(q_a, q_b, self.distance_weights)
        live = np.flatnonzero((length > 0) & self.may_cost(q_a, q_b))
        if live.size:
            out[live] = self._integrate(q_a[live], q_b[live], length[live])
        return out[0] if single else out

    def _integrate(self, q_a: np.ndarray, q_b: np.ndarray, length: np.ndarray) -> np.ndarray:
        """The threshold-aware trapezoid rule for motions (E, 4) in one batch."""
        n = self.segments(q_a, q_b)
        count = n + 1  # samples per motion, ends included
        edge = np.repeat(np.arange(len(q_a)), count)
        k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
        t = (k / n[edge])[:, None]
        q = q_a[edge] + t * (q_b[edge] - q_a[edge])
        x, y = self.geometry.interest_xy(q, self._active)
        g = agf_xy(x, y, self.people, self.space, thresholded=False)  # (samples, K, H)
        step = np.flatnonzero(k[:-1] < n[edge[:-1]])  # sample pairs inside one motion
        g0, g1 = g[step], g[step + 1]
        tau = self.space.threshold
        up0, up1 = g0 > tau, g1 > tau
        hi, lo = np.maximum(g0, g1), np.minimum(g0, g1)
        with np.errstate(divide="ignore", invalid="ignore"):
            crossing = 0.5 * (hi + tau) * (hi - tau) / (hi - lo)
        area = np.where(up0 & up1, 0.5 * (g0 + g1), np.where(up0 ^ up1, crossing, 0.0))
        per_step = area.sum(-1) @ self._active_weights
        return np.bincount(edge[step], weights=per_step, minlength=len(q_a)) * (length / n)

    # ---- for figures ----------------------------------------------------------

    def field(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``G(x, y) = sum_i AGF_i(x, y)`` (thresholded), broadcast over x and y."""
        x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
        return agf(np.stack([x, y], -1), self.people, self.space).sum(-1)
