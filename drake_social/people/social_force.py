"""The social force model's terms, vectorised over people (pure numpy).

Each term is an acceleration in m/s^2 acting on every person of the crowd;
:class:`drake_social.people.crowd.SocialForceCrowd` sums them and integrates.

- :func:`goal_force`: Helbing and Molnar 1995, ``(v0 e_goal - v) / tau``.
- :func:`pedestrian_force`: the interaction of Moussaid, Helbing, Garnier,
  Johansson, Combe and Theraulaz 2009 ("Experimental study of the behavioural
  mechanisms underlying self-organization in human crowds", Proc. R. Soc. B),
  written as PySocialForce writes it (``SocialForce._get_force`` in
  ``pysocialforce/forces.py`` of github.com/yuxiang-gao/PySocialForce, whose
  parameters ``lambda_importance, gamma, n, n_prime`` and ``factor`` are our
  ``lam, gamma, n, n_prime`` and ``strength``).
- :func:`obstacle_force`, :func:`capsule_force`: Helbing and Molnar's
  exponential repulsion ``A exp(-d / B)`` along the outward normal of the
  nearest point of each rotated box (obstacles and walls) or capsule (the
  robot's base disc, links and object), with ``d`` the surface-to-surface
  distance (person's radius included).
- :func:`cap_speed`: the largest walking speed.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "box_nearest",
    "cap_speed",
    "capsule_force",
    "capsule_nearest",
    "desired_velocities",
    "exponential_repulsion",
    "goal_force",
    "obstacle_force",
    "pedestrian_force",
]


def desired_velocities(positions: np.ndarray, goals: np.ndarray, speeds: np.ndarray) -> np.ndarray:
    """``v0 e_goal``: each person's preferred velocity towards their goal, (P, 2) m/s.

    Args:
        positions: (P, 2) body centres, metres.
        goals: (P, 2) current goals, metres.
        speeds: (P,) preferred speeds v0, m/s; 0 for a person who stands.

    Returns:
        ``speeds * (goal - position) / |goal - position|``; zero where the
        person stands exactly on the goal (no direction).
    """
    diff = np.asarray(goals, float) - np.asarray(positions, float)
    dist = np.hypot(diff[:, 0], diff[:, 1])
    scale = np.divide(speeds, dist, out=np.zeros_like(dist), where=dist > 0)
    return diff * scale[:, None]


def goal_force(velocities: np.ndarray, desired: np.ndarray, relaxation_time: float) -> np.ndarray:
    """Helbing and Molnar 1995's driving term ``(v0 e_goal - v) / tau``, (P, 2) m/s^2.

    Args:
        velocities: (P, 2) current velocities v, m/s.
        desired: (P, 2) preferred velocities v0 e_goal, m/s
            (:func:`desired_velocities`).
        relaxation_time: tau, seconds (> 0): how fast a person adapts their
            velocity.
    """
    return (np.asarray(desired, float) - np.asarray(velocities, float)) / relaxation_time


def pedestrian_force(positions: np.ndarray, velocities: np.ndarray, other_positions: np.ndarray,
                     other_velocities: np.ndarray, *, lam: float, gamma: float, n: float, n_prime: float,
                     strength: float, self_index: np.ndarray | None = None) -> np.ndarray:
    """The Moussaid et al. 2009 interaction on each person from the others, (P, 2) m/s^2.

    For person i and another j (PySocialForce's equations and signs), with
    centres r and velocities v::

        e     = (r_i - r_j) / |r_i - r_j|          (from j towards i)
        D     = lam (v_j - v_i) + e,   t = D / |D|  (interaction direction)
        theta = angle(t) - angle(e), wrapped to [-pi, pi)
        B     = gamma |D|
        f_ij  = A [exp(-d/B - (n' B theta)^2) t - sign(theta) exp(-d/B - (n B theta)^2) left(t)]

    where ``d = |r_i - r_j|`` is the centre distance (as in PySocialForce),
    ``left(t) = (-t_y, t_x)`` and A = ``strength``. As in PySocialForce,
    ``lam`` (s/m) makes ``lam v`` dimensionless like ``e``, and ``B = gamma
    |D|`` is read as a length in metres (``gamma`` carries the metre). The first term
    slows a person down when someone comes towards them; the second turns
    them aside, away from the side the other passes on. PySocialForce takes
    the raw difference of the two ``arctan2`` angles; it is wrapped here, so
    that a pair in line across the -x axis (angles near +pi and -pi) is not
    seen at theta ~ 2 pi. Pairs at the same centre (no direction) or with
    ``D = 0`` contribute nothing.

    Args:
        positions: (P, 2) centres of the people the force acts on, metres.
        velocities: (P, 2) their velocities, m/s.
        other_positions: (Q, 2) centres of every person they react to
            (themselves included when ``self_index`` says where), metres.
        other_velocities: (Q, 2) their velocities, m/s.
        lam: lambda, weight of the relative velocity, s/m (> 0).
        gamma: gamma, metres (> 0).
        n: n, angular sharpness of the turning term (> 0).
        n_prime: n', angular sharpness of the slowing term (> 0).
        strength: A, m/s^2 (>= 0).
        self_index: (P,) index in the others of each person (their own row,
            left out), or None when none of them is among the others.

    Returns:
        The summed forces, (P, 2) m/s^2.
    """
    pos = np.asarray(positions, float)
    vel = np.asarray(velocities, float)
    opos = np.asarray(other_positions, float)
    ovel = np.asarray(other_velocities, float)
    if len(pos) == 0 or len(opos) == 0:
        return np.zeros((len(pos), 2))
    diff = pos[:, None, :] - opos[None, :, :]  # (P, Q, 2): r_i - r_j
    dist = np.hypot(diff[..., 0], diff[..., 1])
    valid = dist > 0
    if self_index is not None:
        valid[np.arange(len(pos)), np.asarray(self_index)] = False
    safe = np.where(valid, dist, 1.0)
    ex, ey = diff[..., 0] / safe, diff[..., 1] / safe
    dx = lam * (ovel[None, :, 0] - vel[:, None, 0]) + ex
    dy = lam * (ovel[None, :, 1] - vel[:, None, 1]) + ey
    norm = np.hypot(dx, dy)
    valid &= norm > 0
    norm = np.where(valid, norm, 1.0)
    tx, ty = dx / norm, dy / norm
    theta = np.arctan2(ty, tx) - np.arctan2(ey, ex)
    theta = (theta + np.pi) % (2 * np.pi) - np.pi
    b = gamma * norm
    base = -dist / b
    along = np.exp(base - (n_prime * b * theta) ** 2)
    turn = -np.sign(theta) * np.exp(base - (n * b * theta) ** 2)
    fx = np.where(valid, along * tx - turn * ty, 0.0)
    fy = np.where(valid, along * ty + turn * tx, 0.0)
    return strength * np.stack([fx.sum(1), fy.sum(1)], -1)


def box_nearest(points: np.ndarray, centers: np.ndarray, halves: np.ndarray, cos: np.ndarray,
                sin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance and outward normal from each point to each rotated box.

    Args:
        points: (P, 2) points, metres.
        centers: (K, 2) box centres, metres.
        halves: (K, 2) half side lengths along the box's own axes, metres.
        cos, sin: (K,) cosine and sine of the boxes' yaws.

    Returns:
        ``(distance (P, K), normal (P, K, 2))``: the distance from the point
        to the box's boundary, metres, negative inside; and the unit normal
        of the boundary at the nearest point, pointing away from the box (for
        a point outside, from the nearest point to the point; inside, the
        outward normal of the nearest face).
    """
    p = np.asarray(points, float)
    rx = p[:, None, 0] - centers[None, :, 0]
    ry = p[:, None, 1] - centers[None, :, 1]
    lx = cos * rx + sin * ry  # the point in the box's frame
    ly = -sin * rx + cos * ry
    hx, hy = halves[:, 0], halves[:, 1]
    ox = np.abs(lx) - hx  # > 0 outside that pair of faces
    oy = np.abs(ly) - hy
    cx, cy = np.maximum(ox, 0.0), np.maximum(oy, 0.0)
    outside = np.hypot(cx, cy)
    inside = np.minimum(np.maximum(ox, oy), 0.0)
    distance = outside + inside
    sx, sy = np.where(lx >= 0, 1.0, -1.0), np.where(ly >= 0, 1.0, -1.0)
    safe = np.where(outside > 0, outside, 1.0)
    # Outside: along (cx, cy) in the box's quadrant; inside: the nearest face.
    x_face = ox >= oy
    nx_local = np.where(outside > 0, sx * cx / safe, np.where(x_face, sx, 0.0))
    ny_local = np.where(outside > 0, sy * cy / safe, np.where(x_face, 0.0, sy))
    normal = np.stack([cos * nx_local - sin * ny_local, sin * nx_local + cos * ny_local], -1)
    return distance, normal


def capsule_nearest(points: np.ndarray, ends: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed surface distance and outward normal from each point to each capsule.

    A disc is a capsule whose two ends coincide.

    Args:
        points: (P, 2) points, metres.
        ends: (S, 2, 2) capsule axes [[a_x, a_y], [b_x, b_y]], metres.
        radii: (S,) capsule radii, metres.

    Returns:
        ``(distance (P, S), normal (P, S, 2))``: the distance from the point
        to the capsule's surface (axis distance minus radius), metres,
        negative inside; and the unit vector from the nearest axis point to
        the point (zero when the point lies on the axis: no direction).
    """
    p = np.asarray(points, float)
    a, b = ends[:, 0], ends[:, 1]
    d = b - a
    dd = d[:, 0] ** 2 + d[:, 1] ** 2
    apx = p[:, None, 0] - a[None, :, 0]
    apy = p[:, None, 1] - a[None, :, 1]
    t = np.divide(apx * d[:, 0] + apy * d[:, 1], dd, out=np.zeros_like(apx), where=dd > 0)
    t = np.clip(t, 0.0, 1.0)
    vx, vy = apx - t * d[:, 0], apy - t * d[:, 1]
    axis = np.hypot(vx, vy)
    safe = np.where(axis > 0, axis, 1.0)
    normal = np.stack([np.where(axis > 0, vx / safe, 0.0), np.where(axis > 0, vy / safe, 0.0)], -1)
    return axis - radii, normal


def exponential_repulsion(distance: np.ndarray, normal: np.ndarray, strength: float, range_: float) -> np.ndarray:
    """Helbing and Molnar's ``sum_k A exp(-d_k / B) n_k``, (P, 2) m/s^2.

    Args:
        distance: (P, K) surface-to-surface distances d, metres (negative
            when overlapping: the force then exceeds A).
        normal: (P, K, 2) unit directions pointing away from each source.
        strength: A, m/s^2 (>= 0).
        range_: B, metres (> 0).
    """
    w = strength * np.exp(-distance / range_)
    return np.einsum("pk,pkj->pj", w, normal)


def obstacle_force(positions: np.ndarray, radii: np.ndarray, centers: np.ndarray, halves: np.ndarray,
                   cos: np.ndarray, sin: np.ndarray, *, strength: float, range_: float) -> np.ndarray:
    """Repulsion of rotated boxes (obstacles and walls), (P, 2) m/s^2.

    ``sum_k A exp(-d_k / B) n_k`` with ``d_k`` the distance from the body
    centre to box k minus the body radius and ``n_k`` the box's outward
    normal at the nearest point (:func:`box_nearest`).

    Args:
        positions: (P, 2) body centres, metres.
        radii: (P,) body radii, metres.
        centers, halves, cos, sin: the boxes, as in :func:`box_nearest`
            (e.g. :class:`drake_social.world.Boxes`).
        strength: A, m/s^2 (>= 0).
        range_: B, metres (> 0).
    """
    if len(centers) == 0:
        return np.zeros((len(positions), 2))
    distance, normal = box_nearest(positions, centers, halves, cos, sin)
    return exponential_repulsion(distance - np.asarray(radii, float)[:, None], normal, strength, range_)


def capsule_force(positions: np.ndarray, radii: np.ndarray, ends: np.ndarray, capsule_radii: np.ndarray, *,
                  strength: float, range_: float) -> np.ndarray:
    """Repulsion of capsules and discs (the robot's base, links and object), (P, 2) m/s^2.

    ``sum_s A exp(-d_s / B) n_s`` with ``d_s`` the surface-to-surface
    distance between the body disc and capsule s and ``n_s`` the direction
    from the capsule's nearest axis point to the body centre
    (:func:`capsule_nearest`). The force follows the robot's configuration
    at each step, so a person is pushed away from a bar swinging towards them.

    Args:
        positions: (P, 2) body centres, metres.
        radii: (P,) body radii, metres.
        ends: (S, 2, 2) capsule axes, metres (a disc: both ends at its centre).
        capsule_radii: (S,) capsule radii, metres.
        strength: A, m/s^2 (>= 0).
        range_: B, metres (> 0).
    """
    if len(ends) == 0:
        return np.zeros((len(positions), 2))
    distance, normal = capsule_nearest(positions, ends, capsule_radii)
    return exponential_repulsion(distance - np.asarray(radii, float)[:, None], normal, strength, range_)


def cap_speed(velocities: np.ndarray, max_speeds: np.ndarray) -> np.ndarray:
    """The velocities scaled down (direction kept) to at most ``max_speeds``, (P, 2) m/s.

    Args:
        velocities: (P, 2) velocities, m/s.
        max_speeds: (P,) largest speeds, m/s (>= 0).
    """
    v = np.asarray(velocities, float)
    speed = np.hypot(v[:, 0], v[:, 1])
    factor = np.minimum(1.0, np.divide(max_speeds, speed, out=np.ones_like(speed), where=speed > 0))
    return v * factor[:, None]
