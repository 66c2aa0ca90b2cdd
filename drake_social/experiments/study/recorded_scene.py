"""A window of a recorded crowd made a scenario: the flow turned across the
robot's task, the start and the goal outside it, a room around both.

:func:`window_scene` takes a window of an ETH/UCY recording
(:func:`~drake_social.people.windows.cut_windows`) and, in this order:

1. imports its rows as ``people import --start S --end E`` does
   (:func:`~drake_social.people.eth_ucy.convert`: t = 0 at the window's
   start, headings from the motion);
2. turns them about the origin by the rotation that puts the window's flow
   axis (:func:`~drake_social.people.windows.flow_angle` of every step of an
   id inside the window) onto the y axis
   (:func:`~drake_social.people.windows.crossing_rotation`): the robot's task
   runs along +x, across the flow;
3. takes the **flow band**: the people's x between the :data:`FLOW_QUANTILE`
   and ``1 - FLOW_QUANTILE`` quantiles of all their rows, and the **task
   line** (:func:`task_line`): ``y =`` the median of the walking steps'
   midpoints weighted by their lengths (the middle of the flow along it;
   people standing in a group do not pull the line onto themselves);
4. places the robot (carrying the bar, the arm at
   :data:`~drake_social.map_tools.CARRYING_ARM`) on the task line: the start
   with its whole footprint (base disc, links, object) west of the band, the
   goal east of it; each is moved outwards by :data:`PLACEMENT_STEP` until the
   exact surface distance from the robot to every person present at t = 0
   (:func:`~drake_social.people.proximity.part_distances`, the safety
   monitor's measure) is at least :data:`START_CLEARANCE`, at most
   :data:`PLACEMENT_REACH` beyond the band;
5. puts a room around everything: every row's body disc and the robot's
   footprint at the start and at the goal, :data:`ROOM_MARGIN` more on each
   side, rounded outwards to :data:`ROOM_ROUNDING`; then shifts the people,
   the start and the goal so that the room is ``[0, 0, width, height]``.

The scenario has no obstacles (the recordings' scenes are open squares and
pavements; their people are the obstacles), the robot and bar of
``scenarios/office_bar.yaml`` with its planner settings (``planning_range``
2.5, ``near_radius`` 3.0) and ``execution.time_limit`` = the window's
length. :func:`verify_scene` checks the written scenario with the exact planar
checker: the start and the goal at least :data:`START_CLEARANCE` from the
people present at t = 0 and the walls.
"""

from __future__ import annotations

import dataclasses as dc
import functools
import math
from pathlib import Path
from typing import Sequence

import numpy as np

from drake_social.errors import ScenarioError
from drake_social.kinematics import ArmGeometry
from drake_social.scenario.geometry import arm_geometry
from drake_social.map_tools import CARRYING_ARM
from drake_social.people.eth_ucy import Recording, convert, people_csv_text
from drake_social.people.proximity import part_distances
from drake_social.people.windows import Window, crossing_rotation, flow_angle
from drake_social.scenario import load_scenario_text
from drake_social.scenario.people_file import DEFAULT_RADIUS

__all__ = ["FLOW_QUANTILE", "PLACEMENT_REACH", "PLACEMENT_STEP", "ROOM_MARGIN", "ROOM_ROUNDING", "START_CLEARANCE",
           "WindowScene", "footprint", "robot_geometry", "task_line", "verify_scene", "weighted_median", "window_scene",
           "write_scene"]

#: Least exact surface distance from the robot (base, links, object) at its
#: start and at its goal to anyone present at t = 0, metres: outside their
#: personal space's inner part and far beyond the safety monitor's 0.05 m.
START_CLEARANCE = 1.0
#: The flow band holds the people's rows between these quantiles across the task (x after the turn).
FLOW_QUANTILE = 0.05
#: The start and the goal move outwards in steps of this, metres, until clear.
PLACEMENT_STEP = 0.1
#: ... at most this far beyond the band, metres.
PLACEMENT_REACH = 20.0
#: Free room around the people and the robot, metres (the robot may back away from its start).
ROOM_MARGIN = 2.0
#: The room's bounds are rounded outwards to this, metres.
ROOM_ROUNDING = 0.1

#: The robot, its object and its planner settings (those of scenarios/office_bar.yaml).
ROBOT_YAML = ("robot: {base_radius: 0.35, link_lengths: [0.6, 0.5], link_width: 0.08}\n"
              "object: !Bar {length: 1.5, thickness: 0.05}\n")
PLANNER_YAML = "planner: {planning_range: 2.5, near_radius: 3.0}\n"


@dc.dataclass(frozen=True)
class WindowScene:
    """A window's scenario and what was measured to make it.

    Attributes:
        window: the window of the recording.
        name: the scenario's name (``window_<index>``).
        flow_angle: the flow axis in the recording's frame, radians.
        rotation: the turn applied about the recording's origin, radians.
        offset: the shift applied after the turn, metres.
        band: the flow band ``(x_lo, x_hi)`` in the room, metres.
        task_y: the task line's y in the room, metres.
        bounds: the room ``[0, 0, width, height]``, metres.
        start, goal: the robot's ``[x, y, psi1, psi2]``.
        clearance_start, clearance_goal: the exact distance from the robot
            there to the nearest person present at t = 0, metres (inf: nobody).
        people_end: the last time anyone is present, seconds of the window.
        people_name: the people file's name (beside the scenario).
        scenario_text, people_text: the two files.
    """

    window: Window
    name: str
    flow_angle: float
    rotation: float
    offset: tuple[float, float]
    band: tuple[float, float]
    task_y: float
    bounds: tuple[float, float, float, float]
    start: tuple[float, float, float, float]
    goal: tuple[float, float, float, float]
    clearance_start: float
    clearance_goal: float
    people_end: float
    people_name: str
    scenario_text: str
    people_text: str

    @property
    def task_length(self) -> float:
        """The straight distance from the start's base to the goal's, metres."""
        return math.hypot(self.goal[0] - self.start[0], self.goal[1] - self.start[1])

    def summary(self) -> dict:
        """Plain data of the scene (the window, the turn, the room, the task), for records and the report."""
        return {**self.window.to_json_dict(), "name": self.name, "flow_angle": self.flow_angle,
                "rotation": self.rotation, "offset": list(self.offset), "band": list(self.band),
                "task_y": self.task_y, "bounds": list(self.bounds), "robot_start": list(self.start),
                "robot_goal": list(self.goal), "task_length": self.task_length, "clearance_start": self.clearance_start,
                "clearance_goal": self.clearance_goal, "people_end": self.people_end}


@functools.lru_cache(maxsize=16)
def robot_geometry(sets: tuple[str, ...] = ()) -> ArmGeometry:
    """The robot and object of a window's scenario (with the study's ``--set`` overrides)."""
    text = ("description: \"the robot of a recorded-crowd window\"\nworld: {bounds: [-10.0, -10.0, 10.0, 10.0]}\n"
            + ROBOT_YAML + f"start: [0.0, 0.0, {CARRYING_ARM[0]!r}, {CARRYING_ARM[1]!r}]\n"
            f"goal: [1.0, 0.0, {CARRYING_ARM[0]!r}, {CARRYING_ARM[1]!r}]\n")
    return arm_geometry(load_scenario_text(text, "every window's scenario", list(sets),
                                                        overrides_name="--set"))


def footprint(geometry: ArmGeometry, q: Sequence[float]) -> tuple[float, float, float, float]:
    """``(x_min, y_min, x_max, y_max)`` of the robot at ``q``: base disc, links and object with their radii."""
    q = np.asarray(q, float).reshape(4)
    seg = geometry.segments(q[None])[0]  # (S, 2, 2)
    r = geometry.segment_radii[:, None]
    lo = np.minimum(seg[:, 0], seg[:, 1]) - r
    hi = np.maximum(seg[:, 0], seg[:, 1]) + r
    b = geometry.base_radius
    return (min(float(lo[:, 0].min()), q[0] - b), min(float(lo[:, 1].min()), q[1] - b),
            max(float(hi[:, 0].max()), q[0] + b), max(float(hi[:, 1].max()), q[1] + b))


def _steps(rows: Sequence[tuple]) -> tuple[np.ndarray, np.ndarray]:
    """The walking steps between consecutive rows of each id: their
    displacements (N, 2) and midpoints (N, 2), metres."""
    tracks: dict[str, list] = {}
    for _, person, x, y, _ in rows:  # sorted by time
        tracks.setdefault(person, []).append((x, y))
    paths = [np.asarray(p, float) for p in tracks.values() if len(p) > 1]
    if not paths:
        return np.zeros((0, 2)), np.zeros((0, 2))
    return (np.concatenate([np.diff(p, axis=0) for p in paths]),
            np.concatenate([(p[1:] + p[:-1]) / 2 for p in paths]))


def weighted_median(values: np.ndarray, weights: np.ndarray) -> float:
    """The smallest value whose weights up to it (sorted) reach half the total (weights >= 0, some > 0)."""
    order = np.argsort(values, kind="stable")
    cumulative = np.cumsum(np.asarray(weights, float)[order])
    return float(np.asarray(values, float)[order][np.searchsorted(cumulative, cumulative[-1] / 2)])


def task_line(xy: np.ndarray, steps: np.ndarray, midpoints: np.ndarray) -> float:
    """The task line's y after the turn: the middle of the flow along it, the
    median of the steps' midpoints weighted by the steps' lengths (each metre
    walked counts once); the median of the rows' y when nobody walks."""
    length = np.hypot(steps[:, 0], steps[:, 1])
    if not np.any(length > 0):
        return float(np.median(xy[:, 1]))
    return weighted_median(midpoints[:, 1], length)


def _place(geometry: ArmGeometry, y: float, x_edge: float, direction: float, centres: np.ndarray,
           where: str) -> tuple[np.ndarray, float]:
    """The first base x from ``x_edge`` outwards (``direction`` -1: west, +1:
    east) whose robot is at least :data:`START_CLEARANCE` from every person at
    ``centres``; its configuration and that distance."""
    arm = list(CARRYING_ARM)
    x_min, _, x_max, _ = footprint(geometry, [0.0, 0.0, *arm])
    x0 = x_edge - x_max if direction < 0 else x_edge - x_min  # the footprint's near side on the band's edge
    k = np.arange(int(round(PLACEMENT_REACH / PLACEMENT_STEP)) + 1)
    qs = np.column_stack([x0 + direction * PLACEMENT_STEP * k, np.full(len(k), y), np.tile(arm, (len(k), 1))])
    d = part_distances(geometry, qs, centres, np.full(len(centres), DEFAULT_RADIUS))["robot"]
    free = np.flatnonzero(d >= START_CLEARANCE)
    if not len(free):
        raise ScenarioError(f"{where}: no place for the robot within {PLACEMENT_REACH:g} m of the flow's "
                            f"{'west' if direction < 0 else 'east'} edge is {START_CLEARANCE:g} m from everyone "
                            "present at t = 0; choose other windows")
    return qs[free[0]], float(d[free[0]])


def _number(v: float) -> str:
    return repr(float(v))


def _scenario_text(stem: str, window: Window, fps: float, angle: float, rotation: float, offset: tuple, band: tuple,
                   bounds: tuple, start: tuple, goal: tuple, people_name: str) -> str:
    """The window's scenario YAML, its making said in its comments."""
    return "\n".join([
        f"# Window {window.index} of the recording {stem}, written by `drake-social experiment crowd --recording`:",
        f"# t = {window.start:g} .. {window.end:g} s of the recording (t = frame / {fps:g}), {window.people_mean:.3g} "
        f"people present on average ({window.people_min} .. {window.people_max}, {window.people_t0} at t = 0).",
        f"# Its people ({people_name}) are turned by {rotation:.6g} rad about the recording's origin and shifted by "
        f"({offset[0]:.6g}, {offset[1]:.6g}) m,",
        f"# so that the flow (axis {angle:.6g} rad in the recording) runs along y, across the robot's task along +x;",
        f"# the start and the goal are outside the flow band x in [{band[0]:.4g}, {band[1]:.4g}] m and at least "
        f"{START_CLEARANCE:g} m from everyone present at t = 0.",
        f"description: \"{stem} window {window.index}: t = {window.start:g} .. {window.end:g} s, "
        f"{window.people_mean:.3g} people present on average, the bar carried across the flow\"",
        f"world: {{bounds: [{', '.join(_number(v) for v in bounds)}]}}",
        f"people_file: {people_name}",
        ROBOT_YAML.rstrip("\n"),
        f"start: [{', '.join(_number(v) for v in start)}]",
        f"goal: [{', '.join(_number(v) for v in goal)}]",
        "random_seed: 0",
        PLANNER_YAML.rstrip("\n"),
        f"execution: {{time_limit: {_number(window.end - window.start)}}}",
        "",
    ])


def window_scene(recording: Recording, window: Window, *, fps: float, sets: tuple[str, ...] = ()) -> WindowScene:
    """The scenario of ``window`` (see the module docstring).

    Args:
        recording: the parsed recording.
        window: one of its windows.
        fps: frames per second (t = frame / fps).
        sets: the study's ``--set`` overrides (the robot and its object may change with them).

    Raises:
        ScenarioError: no place for the start or the goal (naming the recording and the window).
    """
    where = f"{recording.source}: window {window.index} (t = {window.start:g} .. {window.end:g} s)"
    plain = convert(recording, fps=fps, start=window.start, end=window.end)
    angle = flow_angle(_steps(plain)[0])
    rotation = crossing_rotation(angle)
    turned = convert(recording, fps=fps, start=window.start, end=window.end, rotate=rotation)
    xy = np.array([(r[2], r[3]) for r in turned], float)
    x_lo, x_hi = (float(v) for v in np.quantile(xy[:, 0], [FLOW_QUANTILE, 1 - FLOW_QUANTILE]))
    task_y = task_line(xy, *_steps(turned))
    at_start = np.array([(r[2], r[3]) for r in turned if r[0] == 0.0], float).reshape(-1, 2)
    geometry = robot_geometry(tuple(sets))
    q_start, c_start = _place(geometry, task_y, x_lo, -1.0, at_start, where)
    q_goal, c_goal = _place(geometry, task_y, x_hi, +1.0, at_start, where)
    boxes = [footprint(geometry, q_start), footprint(geometry, q_goal)]
    lo = np.minimum.reduce([xy.min(axis=0) - DEFAULT_RADIUS, *(np.array(b[:2]) for b in boxes)]) - ROOM_MARGIN
    hi = np.maximum.reduce([xy.max(axis=0) + DEFAULT_RADIUS, *(np.array(b[2:]) for b in boxes)]) + ROOM_MARGIN
    lo = np.floor(lo / ROOM_ROUNDING) * ROOM_ROUNDING
    size = np.round(np.ceil((hi - lo) / ROOM_ROUNDING) * ROOM_ROUNDING, 6)
    offset = (float(-lo[0]), float(-lo[1]))
    rows = convert(recording, fps=fps, start=window.start, end=window.end, rotate=rotation, offset=offset)
    start = (float(q_start[0] + offset[0]), float(q_start[1] + offset[1]), *map(float, CARRYING_ARM))
    goal = (float(q_goal[0] + offset[0]), float(q_goal[1] + offset[1]), *map(float, CARRYING_ARM))
    bounds = (0.0, 0.0, float(size[0]), float(size[1]))
    name = f"window_{window.index}"
    people_name = f"{name}_people.csv"
    band = (x_lo + offset[0], x_hi + offset[0])
    text = _scenario_text(Path(recording.source).name, window, fps, angle, rotation, offset, band, bounds, start,
                          goal, people_name)
    return WindowScene(window=window, name=name, flow_angle=angle, rotation=rotation, offset=offset,
                       band=band, task_y=task_y + offset[1], bounds=bounds,
                       start=start, goal=goal, clearance_start=c_start, clearance_goal=c_goal,
                       people_end=float(max(r[0] for r in rows)), people_name=people_name, scenario_text=text,
                       people_text=people_csv_text(rows))


def write_scene(scene: WindowScene, folder: str | Path) -> Path:
    """Writes the scene's scenario (``<name>.yaml``) and people file into ``folder``; returns the scenario's path."""
    folder = Path(folder)
    (folder / scene.people_name).write_text(scene.people_text)
    path = folder / f"{scene.name}.yaml"
    path.write_text(scene.scenario_text)
    return path


def verify_scene(scenario, source: str) -> None:
    """Checks a window's loaded scenario with the exact planar checker: its
    start and goal at least :data:`START_CLEARANCE` from the people present
    at t = 0 and from the walls.

    Raises:
        RuntimeError: one is closer (the placement above keeps them clear: a bug).
    """
    from drake_social.collision.drake_checker import make_checker

    checker = make_checker(scenario, "planar", parallelism=1)
    for what, q in (("start", scenario.start), ("goal", scenario.goal)):
        clearance = checker.clearance(np.asarray(q, float))
        if not clearance >= START_CLEARANCE * (1 - 1e-9):
            raise RuntimeError(f"{source}: the {what} is {clearance:.6g} m from the nearest person or wall, less than "
                               f"the {START_CLEARANCE:g} m it was placed to keep")
