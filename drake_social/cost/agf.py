"""Kirby's asymmetric Gaussian function (AGF), the paper's Algorithm 1."""

from __future__ import annotations

import dataclasses as dc
import math
from typing import Sequence

import numpy as np

__all__ = ["KIRBY_MIN_SIGMA_H", "KIRBY_SPEED_GAIN", "PersonalSpace", "agf", "agf_algorithm1", "agf_xy",
           "inverse_variances", "person_reaches", "speed_scaled_sigmas"]

#: Kirby 2010's speed scaling: a person walking at v m/s has
#: sigma_h = max(KIRBY_SPEED_GAIN * v, KIRBY_MIN_SIGMA_H) (the formula the
#: paper leaves commented out). Seconds: metres of sigma_h per m/s.
KIRBY_SPEED_GAIN = 2.0
#: The least sigma_h of the speed scaling (a standing person), metres.
KIRBY_MIN_SIGMA_H = 0.5


@dc.dataclass(frozen=True)
class PersonalSpace:
    """Variances of the AGF and the threshold (the paper's values by default).

    Attributes:
        sigma_h: along the facing direction, metres.
        sigma_s: to the sides, metres.
        sigma_r: to the rear, metres.
        threshold: AGF values <= threshold count as 0.
    """

    sigma_h: float = 2.0
    sigma_s: float = 4.0 / 3.0
    sigma_r: float = 1.0
    threshold: float = 0.2

    @classmethod
    def from_options(cls, options) -> "PersonalSpace":
        """From a :class:`drake_social.scenario.SocialCostOptions`."""
        return cls(
            sigma_h=options.sigma_h,
            sigma_s=options.side_ratio * options.sigma_h,
            sigma_r=options.rear_ratio * options.sigma_h,
            threshold=options.threshold,
        )

    @property
    def max_reach(self) -> float:
        """Euclidean distance beyond which the AGF is <= threshold in every direction."""
        return self.reach("front") if self.sigma_h >= max(self.sigma_s, self.sigma_r) else max(
            self.reach("side"), self.reach("rear")
        )

    def reach(self, direction: str = "front") -> float:
        """Distance from the person at which the AGF falls to the threshold.

        Args:
            direction: "front", "side" or "rear".
        """
        sigma = {"front": self.sigma_h, "side": self.sigma_s, "rear": self.sigma_r}[direction]
        if self.threshold <= 0:
            return math.inf
        return sigma * math.sqrt(-2.0 * math.log(self.threshold))


def speed_scaled_sigmas(speeds: np.ndarray, side_ratio: float, rear_ratio: float) -> np.ndarray:
    """Per-person variances of Kirby's speed scaling.

    ``sigma_h = max(2 v, 0.5)`` (:data:`KIRBY_SPEED_GAIN`,
    :data:`KIRBY_MIN_SIGMA_H`) with v the person's speed, then
    ``sigma_s = side_ratio sigma_h`` and ``sigma_r = rear_ratio sigma_h``.

    Args:
        speeds: (H,) speeds, metres per second (finite, >= 0).
        side_ratio, rear_ratio: the scenario's ratios (> 0).

    Returns:
        (H, 3) rows [sigma_h, sigma_s, sigma_r], metres.

    Raises:
        ValueError: a speed is negative or not finite.
    """
    v = np.asarray(speeds, dtype=float).reshape(-1)
    if not (np.all(np.isfinite(v)) and np.all(v >= 0)):
        raise ValueError(f"speed scaling needs finite speeds >= 0 (m/s), got {v}")
    sigma_h = np.maximum(KIRBY_SPEED_GAIN * v, KIRBY_MIN_SIGMA_H)
    return np.column_stack([sigma_h, side_ratio * sigma_h, rear_ratio * sigma_h]).reshape(-1, 3)


def person_reaches(sigmas: np.ndarray, threshold: float) -> np.ndarray:
    """(H,) :attr:`PersonalSpace.max_reach` of each row [sigma_h, sigma_s, sigma_r], metres."""
    return np.array([PersonalSpace(*map(float, row), threshold).max_reach for row in np.reshape(sigmas, (-1, 3))])


def inverse_variances(sigmas: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``1 / (2 sigma^2)`` of the front, rear and side Gaussians, each (H,),
    1 / m^2, from rows [sigma_h, sigma_s, sigma_r] (the same arithmetic as
    :func:`gaussian`'s scalars)."""
    sigmas = np.reshape(np.asarray(sigmas, dtype=float), (-1, 3))
    return tuple(np.array([1.0 / (2.0 * float(v) ** 2) for v in sigmas[:, k]]) for k in (0, 2, 1))


def agf(points: np.ndarray, people: np.ndarray, space: PersonalSpace, sigmas: np.ndarray | None = None) -> np.ndarray:
    """Thresholded AGF of every point for every person.

    In the person's frame (u along the facing direction, v to the left) the
    AGF of Algorithm 1 is ``exp(-(u^2 / (2 sigma^2) + v^2 / (2 sigma_s^2)))``
    with ``sigma = sigma_h`` in front (u > 0) and ``sigma_r`` behind: the
    quadratic form a, b, c of Algorithm 1 is exactly this rotated ellipse, and
    its normalised angle ``alpha`` is positive precisely when u > 0 (on u = 0
    both branches agree). This form avoids atan2 and angle normalisation.

    Args:
        points: world points (..., 2), metres.
        people: (H, 3) rows [x, y, theta].
        space: variances and threshold.
        sigmas: (H, 3) per-person variances [sigma_h, sigma_s, sigma_r]
            (:func:`speed_scaled_sigmas`) in place of the space's; None =
            the space's for everyone.

    Returns:
        (..., H) values in [0, 1]; values <= threshold are 0; NaN where a
        point or person is NaN.
    """
    points = np.asarray(points, dtype=float)
    return agf_xy(points[..., 0], points[..., 1], people, space, sigmas=sigmas)


def agf_xy(
    x: np.ndarray, y: np.ndarray, people: np.ndarray, space: PersonalSpace, thresholded: bool = True,
    sigmas: np.ndarray | None = None,
) -> np.ndarray:
    """:func:`agf` for world coordinates given as two arrays x, y (...,) -> (..., H).

    Args:
        thresholded: False returns the raw Gaussian, without zeroing values
            <= threshold (the motion integral locates threshold crossings).
        sigmas: per-person variances as in :func:`agf` (None = the space's).
    """
    people = np.asarray(people, dtype=float).reshape(-1, 3)
    dx = np.asarray(x, dtype=float)[..., None] - people[:, 0]
    dy = np.asarray(y, dtype=float)[..., None] - people[:, 1]
    inverse = None
    if sigmas is not None:
        if np.shape(sigmas) != (len(people), 3):
            raise ValueError(f"sigmas must be ({len(people)}, 3) rows [sigma_h, sigma_s, sigma_r], "
                             f"got {np.shape(sigmas)}")
        inverse = inverse_variances(sigmas)
    value = gaussian(dx, dy, np.cos(people[:, 2]), np.sin(people[:, 2]), space, inverse)
    return apply_threshold(value, space) if thresholded else value


def gaussian(dx: np.ndarray, dy: np.ndarray, cos_theta, sin_theta, space: PersonalSpace,
             inverse: tuple | None = None) -> np.ndarray:
    """The raw asymmetric Gaussian at offsets (dx, dy) from people facing
    (cos_theta, sin_theta); all arguments broadcast together.

    Args:
        inverse: per-person ``(inv_front, inv_rear, inv_side)`` arrays
            broadcasting with dx (:func:`inverse_variances`); None = the
            space's variances for everyone.
    """
    if inverse is None:
        inv_front = 1.0 / (2.0 * space.sigma_h**2)
        inv_rear = 1.0 / (2.0 * space.sigma_r**2)
        inv_side = 1.0 / (2.0 * space.sigma_s**2)
    else:
        inv_front, inv_rear, inv_side = inverse
    # Offsets beyond ~1e154 m overflow to inf in u, v or their squares (never
    # to NaN: each is a sum of same-signed overflows); exp(-inf) = 0 is exactly
    # the right value there, so the overflow is not worth a warning.
    with np.errstate(over="ignore"):
        u = cos_theta * dx + sin_theta * dy
        v = cos_theta * dy - sin_theta * dx
        return np.exp(-(u * u * np.where(u > 0, inv_front, inv_rear) + v * v * inv_side))


def apply_threshold(value: np.ndarray, space: PersonalSpace) -> np.ndarray:
    """Values <= threshold count as 0 (NaN stays NaN, never "no discomfort")."""
    return np.where(value <= space.threshold, 0.0, value)


def agf_algorithm1(x: float, y: float, person: Sequence[float], space: PersonalSpace) -> float:
    """Algorithm 1 of the paper, line by line, for one point and one person.

    A scalar reference used by the tests to check :func:`agf`.
    """
    x_i, y_i, theta = person
    alpha = math.atan2(y - y_i, x - x_i) - theta + math.pi / 2
    alpha = math.atan2(math.sin(alpha), math.cos(alpha))  # normalise to (-pi, pi]
    sigma = space.sigma_r if alpha <= 0 else space.sigma_h
    a = math.cos(theta) ** 2 / (2 * sigma**2) + math.sin(theta) ** 2 / (2 * space.sigma_s**2)
    b = math.sin(2 * theta) / (4 * sigma**2) - math.sin(2 * theta) / (4 * space.sigma_s**2)
    c = math.sin(theta) ** 2 / (2 * sigma**2) + math.cos(theta) ** 2 / (2 * space.sigma_s**2)
    dx, dy = x - x_i, y - y_i
    value = math.exp(-(a * dx * dx + 2 * b * dx * dy + c * dy * dy))
    return value if value > space.threshold else 0.0
