"""One crowd step compiled with numba: the loops of :mod:`drake_social.people.social_force`.

:meth:`drake_social.people.crowd.SocialForceCrowd.step` calls :func:`crowd_step`;
its numpy path (:meth:`~drake_social.people.crowd.SocialForceCrowd.step_reference`,
built from the documented terms) is the reference the tests compare it with.
The same equations, term by term, written as loops over people, boxes and
capsules: a step of 10 people then costs microseconds instead of the numpy
path's hundreds (many small arrays).

The kernel calls no other module's compiled function, so numba's own cache
check (this file's source) keeps its on-disk cache fresh.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["PARAMS", "PEOPLE_COLUMNS", "crowd_step"]


@njit(cache=True)
def _repel(out, i, distance, nx, ny, strength, range_):
    w = strength * math.exp(-distance / range_)
    out[i, 0] += w * nx
    out[i, 1] += w * ny


#: Layout of the ``params`` vector of :func:`crowd_step`.
PARAMS = ("time_step", "relaxation_time", "goal_radius", "interaction_lambda", "interaction_gamma",
          "interaction_n", "interaction_n_prime", "interaction_strength", "obstacle_strength", "obstacle_range",
          "standing_speed", "heading_speed", "has_robot", "base_radius", "link1", "link2", "link_radius",
          "object_radius")
#: Columns of the ``people`` table of :func:`crowd_step`.
PEOPLE_COLUMNS = ("radius", "speed", "max_speed", "goal_count", "cycle")


@njit(cache=True)
def _capsule(out, i, px, py, ax, ay, bx, by, radius, body, strength, range_):
    """Adds the repulsion of capsule a-b (radius) on the body at (px, py) to ``out[i]``."""
    sx, sy = bx - ax, by - ay
    apx, apy = px - ax, py - ay
    dd = sx * sx + sy * sy
    t = (apx * sx + apy * sy) / dd if dd > 0 else 0.0
    t = min(max(t, 0.0), 1.0)
    vx, vy = apx - t * sx, apy - t * sy
    axis = math.hypot(vx, vy)
    if axis > 0:
        _repel(out, i, axis - radius - body, vx / axis, vy / axis, strength, range_)


@njit(cache=True)
def box_push(px, py, box, body):
    """The surface distance of a body disc (centre (px, py), radius ``body``)
    from the oriented box ``box`` ([cx, cy, half_x, half_y, cos, sin]) and
    the world unit normal pointing from the box to the disc, as ``(distance,
    nx, ny)`` (negative distance: overlapping; inside: the nearest face's
    normal)."""
    co, si = box[4], box[5]
    rx, ry = px - box[0], py - box[1]
    lx, ly = co * rx + si * ry, -si * rx + co * ry
    ox, oy = abs(lx) - box[2], abs(ly) - box[3]
    cx, cy = max(ox, 0.0), max(oy, 0.0)
    outside = math.hypot(cx, cy)
    sx = 1.0 if lx >= 0 else -1.0
    sy = 1.0 if ly >= 0 else -1.0
    if outside > 0:
        nlx, nly = sx * cx / outside, sy * cy / outside
    elif ox >= oy:
        nlx, nly = sx, 0.0
    else:
        nlx, nly = 0.0, sy
    return outside + min(max(ox, oy), 0.0) - body, co * nlx - si * nly, si * nlx + co * nly


@njit(cache=True)
def crowd_step(state, goal_table, people, others, boxes, robot_q, object_points, params):
    """The crowd's state one step later (see ``SocialForceCrowd.step``).

    Args:
        state: (6 P,) [x, y, vx, vy, heading, goal index].
        goal_table: (P, G, 2) goals, padded.
        people: (P, 5) rows of :data:`PEOPLE_COLUMNS` (goal_count: how many
            goals of the row are real; cycle: 1.0 or 0.0).
        others: (O, 4) rows [x, y, vx, vy] of the open-loop people present.
        boxes: (K, 6) rows [cx, cy, half x, half y, cos yaw, sin yaw] (obstacles, then walls).
        robot_q: (4,) the robot's configuration (read when params' has_robot is 1).
        object_points: (M, 2) the object's polyline in the gripper frame.
        params: the values of :data:`PARAMS`.
    """
    dt, tau, goal_radius = params[0], params[1], params[2]
    lam, gamma, n, n_prime, a_int = params[3], params[4], params[5], params[6], params[7]
    a_obs, b_obs = params[8], params[9]
    standing_speed, heading_speed = params[10], params[11]
    p = people.shape[0]
    pos = np.empty((p, 2))
    vel = np.empty((p, 2))
    goal = np.empty(p, np.int64)
    for i in range(p):
        pos[i, 0], pos[i, 1] = state[i], state[p + i]
        vel[i, 0], vel[i, 1] = state[2 * p + i], state[3 * p + i]
        goal[i] = int(state[5 * p + i])
    force = np.zeros((p, 2))
    walking = np.empty(p, np.bool_)
    for i in range(p):
        g = goal[i]
        count = int(people[i, 3])
        if g < count:
            if math.hypot(goal_table[i, g, 0] - pos[i, 0], goal_table[i, g, 1] - pos[i, 1]) <= goal_radius:
                g += 1
                if g >= count:
                    if people[i, 4] != 0.0:
                        g = 0
                    else:
                        vel[i, 0] = 0.0
                        vel[i, 1] = 0.0
                goal[i] = g
        walking[i] = g < count
        # The goal force (v0 e - v) / tau; a person who stands brakes: -v / tau.
        dx, dy, v0 = 0.0, 0.0, 0.0
        if walking[i]:
            dx, dy = goal_table[i, g, 0] - pos[i, 0], goal_table[i, g, 1] - pos[i, 1]
            dist = math.hypot(dx, dy)
            v0 = people[i, 1] / dist if dist > 0 else 0.0
        force[i, 0] = (v0 * dx - vel[i, 0]) / tau
        force[i, 1] = (v0 * dy - vel[i, 1]) / tau
    n_other = others.shape[0]
    has_robot = params[12] != 0.0
    if has_robot:
        # The robot's capsules, as ArmGeometry.segments computes them.
        l1, l2 = params[14], params[15]
        bx, by = robot_q[0], robot_q[1]
        c1, s1 = math.cos(robot_q[2]), math.sin(robot_q[2])
        c2, s2 = math.cos(robot_q[3]), math.sin(robot_q[3])
        c12, s12 = c1 * c2 - s1 * s2, s1 * c2 + c1 * s2
        ex, ey = bx + l1 * c1, by + l1 * s1
        gx, gy = ex + l2 * c12, ey + l2 * s12
        m = object_points.shape[0]
        verts = np.empty((m, 2))
        for k in range(m):
            verts[k, 0] = gx + c12 * object_points[k, 0] - s12 * object_points[k, 1]
            verts[k, 1] = gy + s12 * object_points[k, 0] + c12 * object_points[k, 1]
    for i in range(p):
        for j in range(p + n_other):
            if j == i:
                continue
            if j < p:
                xj, yj, vxj, vyj = pos[j, 0], pos[j, 1], vel[j, 0], vel[j, 1]
            else:
                k = j - p
                xj, yj, vxj, vyj = others[k, 0], others[k, 1], others[k, 2], others[k, 3]
            rx, ry = pos[i, 0] - xj, pos[i, 1] - yj
            d = math.hypot(rx, ry)
            if d == 0:
                continue
            ex_, ey_ = rx / d, ry / d
            dx = lam * (vxj - vel[i, 0]) + ex_
            dy = lam * (vyj - vel[i, 1]) + ey_
            norm = math.hypot(dx, dy)
            if norm == 0:
                continue
            tx, ty = dx / norm, dy / norm
            theta = math.atan2(ty, tx) - math.atan2(ey_, ex_)
            theta = (theta + math.pi) % (2 * math.pi) - math.pi
            b = gamma * norm
            along = math.exp(-d / b - (n_prime * b * theta) ** 2)
            sign = 1.0 if theta > 0 else (-1.0 if theta < 0 else 0.0)
            turn = -sign * math.exp(-d / b - (n * b * theta) ** 2)
            force[i, 0] += a_int * (along * tx - turn * ty)
            force[i, 1] += a_int * (along * ty + turn * tx)
        body = people[i, 0]
        for k in range(boxes.shape[0]):
            distance, nx, ny = box_push(pos[i, 0], pos[i, 1], boxes[k], body)
            _repel(force, i, distance, nx, ny, a_obs, b_obs)
        if has_robot:
            px, py = pos[i, 0], pos[i, 1]
            _capsule(force, i, px, py, bx, by, bx, by, params[13], body, a_obs, b_obs)
            _capsule(force, i, px, py, bx, by, ex, ey, params[16], body, a_obs, b_obs)
            _capsule(force, i, px, py, ex, ey, gx, gy, params[16], body, a_obs, b_obs)
            for k in range(m - 1):
                _capsule(force, i, px, py, verts[k, 0], verts[k, 1], verts[k + 1, 0], verts[k + 1, 1],
                         params[17], body, a_obs, b_obs)
    out = np.empty(6 * p)
    for i in range(p):
        vx, vy = vel[i, 0] + dt * force[i, 0], vel[i, 1] + dt * force[i, 1]
        speed = math.hypot(vx, vy)
        if speed > 0:
            f = min(1.0, people[i, 2] / speed)
            vx, vy = vx * f, vy * f
            speed = math.hypot(vx, vy)
        if not walking[i] and speed < standing_speed:
            vx, vy, speed = 0.0, 0.0, 0.0
        out[i] = pos[i, 0] + dt * vx
        out[p + i] = pos[i, 1] + dt * vy
        out[2 * p + i] = vx
        out[3 * p + i] = vy
        out[4 * p + i] = math.atan2(vy, vx) if speed > heading_speed else state[4 * p + i]
        out[5 * p + i] = goal[i]
    return out
