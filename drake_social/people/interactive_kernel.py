"""The interactive prediction's rollout compiled with numba (see :mod:`drake_social.people.interactive`).

The social force terms of :mod:`drake_social.people.social_force_kernel` (goal,
Moussaid et al.'s interaction, Helbing and Molnar's repulsion of boxes and of
the robot's base disc, links and object), stepped over a prediction's sample
times with the robot at a given configuration at each sample. Two changes
make a rollout cheap enough to run for every judged candidate of a replan:
people react to one another only within ``interaction_range`` metres
(centre to centre), and every person has a single goal (no goal switching).

The kernel calls no other module's compiled function, so numba's own cache
check (this file's source) keeps its on-disk cache fresh.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from drake_social.people.social_force_kernel import box_push

__all__ = ["PARAMS", "rollout"]

#: Layout of the ``params`` vector of :func:`rollout`.
PARAMS = ("time_step", "relaxation_time", "interaction_lambda", "interaction_gamma", "interaction_n",
          "interaction_n_prime", "interaction_strength", "obstacle_strength", "obstacle_range", "standing_speed",
          "heading_speed", "interaction_range", "base_radius", "link1", "link2", "link_radius", "object_radius")


@njit(cache=True)
def _repel(fx, fy, distance, nx, ny, strength, range_):
    w = strength * math.exp(-distance / range_)
    return fx + w * nx, fy + w * ny


@njit(cache=True)
def _capsule(fx, fy, px, py, ax, ay, bx, by, radius, body, strength, range_):
    """The force (fx, fy) plus the repulsion of capsule a-b (radius) on the body at (px, py)."""
    sx, sy = bx - ax, by - ay
    apx, apy = px - ax, py - ay
    dd = sx * sx + sy * sy
    t = (apx * sx + apy * sy) / dd if dd > 0 else 0.0
    t = min(max(t, 0.0), 1.0)
    vx, vy = apx - t * sx, apy - t * sy
    axis = math.hypot(vx, vy)
    if axis > 0:
        return _repel(fx, fy, axis - radius - body, vx / axis, vy / axis, strength, range_)
    return fx, fy


@njit(cache=True)
def rollout(pos0, vel0, heading0, active, radii, speeds, max_speeds, goals, walking, boxes, robot_q, has_robot,
            object_points, params):
    """People over ``robot_q.shape[0]`` samples ``time_step`` apart, from their state at sample 0.

    Args:
        pos0, vel0: (P, 2) positions (metres) and velocities (m/s) now.
        heading0: (P,) headings now, radians.
        active: (P,) bool: present people, who react and are reacted to; the
            others go on at their velocity, seen by nobody.
        radii: (P,) body radii, metres.
        speeds: (P,) preferred speeds v0, m/s (0 for who stands).
        max_speeds: (P,) largest speeds, m/s.
        goals: (P, 2) each person's goal, metres.
        walking: (P,) bool: walks to the goal (else stands: the goal force brakes).
        boxes: (K, 6) rows [cx, cy, half x, half y, cos yaw, sin yaw] (obstacles and walls).
        robot_q: (H, 4) the robot's configuration at each sample (read when ``has_robot``).
        has_robot: the robot is seen.
        object_points: (M, 2) the object's polyline in the gripper frame.
        params: the values of :data:`PARAMS`.

    Returns:
        ``(positions (H, P, 2), velocities (H, P, 2), headings (H, P))``;
        sample k + 1 is one semi-implicit Euler step from sample k with the
        robot at ``robot_q[k]``: ``v' = cap(v + dt F)``, ``x' = x + dt v'``.
    """
    dt, tau = params[0], params[1]
    lam, gamma, n, n_prime, a_int = params[2], params[3], params[4], params[5], params[6]
    a_obs, b_obs, standing_speed, heading_speed, reach = params[7], params[8], params[9], params[10], params[11]
    base_r, l1, l2, link_r, obj_r = params[12], params[13], params[14], params[15], params[16]
    h = robot_q.shape[0]
    p = pos0.shape[0]
    m = object_points.shape[0]
    pos = np.empty((h, p, 2))
    vel = np.empty((h, p, 2))
    head = np.empty((h, p))
    pos[0] = pos0
    vel[0] = vel0
    head[0] = heading0
    force = np.zeros((p, 2))
    verts = np.empty((m, 2))
    reach2 = reach * reach
    for k in range(h - 1):
        if has_robot:
            bx, by = robot_q[k, 0], robot_q[k, 1]
            c1, s1 = math.cos(robot_q[k, 2]), math.sin(robot_q[k, 2])
            c2, s2 = math.cos(robot_q[k, 3]), math.sin(robot_q[k, 3])
            c12, s12 = c1 * c2 - s1 * s2, s1 * c2 + c1 * s2
            ex, ey = bx + l1 * c1, by + l1 * s1
            gx, gy = ex + l2 * c12, ey + l2 * s12
            for j in range(m):
                verts[j, 0] = gx + c12 * object_points[j, 0] - s12 * object_points[j, 1]
                verts[j, 1] = gy + s12 * object_points[j, 0] + c12 * object_points[j, 1]
        for i in range(p):
            px, py = pos[k, i, 0], pos[k, i, 1]
            vx, vy = vel[k, i, 0], vel[k, i, 1]
            if not active[i]:
                continue
            # The goal force (v0 e - v) / tau; a person who stands brakes: -v / tau.
            fx, fy = -vx / tau, -vy / tau
            if walking[i]:
                dx, dy = goals[i, 0] - px, goals[i, 1] - py
                dist = math.hypot(dx, dy)
                if dist > 0:
                    fx += speeds[i] * dx / dist / tau
                    fy += speeds[i] * dy / dist / tau
            for j in range(p):
                if j == i or not active[j]:
                    continue
                rx, ry = px - pos[k, j, 0], py - pos[k, j, 1]
                d2 = rx * rx + ry * ry
                if d2 == 0 or d2 > reach2:
                    continue
                d = math.sqrt(d2)
                ex_, ey_ = rx / d, ry / d
                ddx = lam * (vel[k, j, 0] - vx) + ex_
                ddy = lam * (vel[k, j, 1] - vy) + ey_
                norm = math.hypot(ddx, ddy)
                if norm == 0:
                    continue
                tx, ty = ddx / norm, ddy / norm
                theta = math.atan2(ty, tx) - math.atan2(ey_, ex_)
                theta = (theta + math.pi) % (2 * math.pi) - math.pi
                b = gamma * norm
                along = math.exp(-d / b - (n_prime * b * theta) ** 2)
                sign = 1.0 if theta > 0 else (-1.0 if theta < 0 else 0.0)
                turn = -sign * math.exp(-d / b - (n * b * theta) ** 2)
                fx += a_int * (along * tx - turn * ty)
                fy += a_int * (along * ty + turn * tx)
            body = radii[i]
            for kb in range(boxes.shape[0]):
                distance, nx, ny = box_push(px, py, boxes[kb], body)
                fx, fy = _repel(fx, fy, distance, nx, ny, a_obs, b_obs)
            if has_robot:
                fx, fy = _capsule(fx, fy, px, py, bx, by, bx, by, base_r, body, a_obs, b_obs)
                fx, fy = _capsule(fx, fy, px, py, bx, by, ex, ey, link_r, body, a_obs, b_obs)
                fx, fy = _capsule(fx, fy, px, py, ex, ey, gx, gy, link_r, body, a_obs, b_obs)
                for j in range(m - 1):
                    fx, fy = _capsule(fx, fy, px, py, verts[j, 0], verts[j, 1], verts[j + 1, 0], verts[j + 1, 1],
                                      obj_r, body, a_obs, b_obs)
            force[i, 0], force[i, 1] = fx, fy
        for i in range(p):
            vx, vy = vel[k, i, 0], vel[k, i, 1]
            if active[i]:
                vx, vy = vx + dt * force[i, 0], vy + dt * force[i, 1]
                speed = math.hypot(vx, vy)
                if speed > 0:
                    f = min(1.0, max_speeds[i] / speed)
                    vx, vy = vx * f, vy * f
                    speed = math.hypot(vx, vy)
                if not walking[i] and speed < standing_speed:
                    vx, vy, speed = 0.0, 0.0, 0.0
            else:
                speed = math.hypot(vx, vy)
            vel[k + 1, i, 0], vel[k + 1, i, 1] = vx, vy
            pos[k + 1, i, 0] = pos[k, i, 0] + dt * vx
            pos[k + 1, i, 1] = pos[k, i, 1] + dt * vy
            head[k + 1, i] = math.atan2(vy, vx) if active[i] and speed > heading_speed else head[k, i]
    return pos, vel, head
