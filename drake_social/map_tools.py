"""``drake-social map``: look at an occupancy-grid map, and start a scenario from one.

* :func:`inspect_map` (``map inspect``): the map's size, extent, cells and
  boxes, and a picture (``map.png``: the cells under the boxes' outlines);
* :func:`write_map_scenario` (``map scenario``): a scenario file around a
  map, with the robot carrying the bar from a start to a goal and planner
  settings sized to the map (:func:`map_planner_settings`); it is loaded
  and validated before it is written, so a start or goal in an occupied or
  unknown cell is refused with the reason, and it says how much room the
  robot with its bar has at the start and at the goal.

From a SLAM map to a first plan, two commands::

    drake-social map scenario lab.yaml --start 1 2 --goal 14 6 --out lab_scenario.yaml
    drake-social plan lab_scenario.yaml
"""

from __future__ import annotations

import dataclasses as dc
import math
import os
import time
from pathlib import Path
from typing import Sequence

import numpy as np

from drake_social.errors import ScenarioError
from drake_social.io.textfile import check_out_file, replace_file
from drake_social.maps import FREE, OCCUPIED, UNKNOWN, map_boxes, read_map
from drake_social.scenario import MAP_UNKNOWN, load_scenario_text

__all__ = ["CARRYING_ARM", "MAP_ITERATIONS_MAX", "MAP_ITERATIONS_MIN", "MAP_ITERATIONS_PER_M2", "MAP_LARGE_SIDE",
           "MAP_RANGE_LARGE", "MAP_RANGE_SMALL", "MAP_TIGHT_ROOM", "MapScenario", "MapSummary", "Room", "inspect_map",
           "map_planner_settings", "map_scenario_text", "write_map_scenario"]

#: The arm's joints ``[psi1, psi2]`` of a scenario written by
#: :func:`write_map_scenario`: link 2 folded back over the base, the bar
#: along x beside it (the carrying pose of ``scenarios/office_bar.yaml``).
CARRYING_ARM = (-1.2292, 2.8)

# The planner's settings for a map (map_planner_settings), from generated office floors
# (drake_social.maps.office_floor_layout, 0.05 m cells) of 20 x 14 to 80 x 50 m, three floors
# each: the bar carried from the foot of the west corridor to the roomiest spot of the farthest
# room, behind its 1.8-2.2 m door; seeds 0-9 (docs/maps.md, "A scenario around a map").
#: Samples per square metre of the map's extent: the planner samples the whole extent, and
#: K = 8 per m2 found the goal in 9 or 10 of 10 seeds on every floor measured.
MAP_ITERATIONS_PER_M2 = 8.0
#: K never below the planner's default, nor above this (a larger map: plan in parts).
MAP_ITERATIONS_MIN = 2000
MAP_ITERATIONS_MAX = 100_000
#: The steer distance: the paper's 1.5 m up to this longer side of the extent (metres),
#: 2.5 m beyond (at 50 x 50 m, 1.5 m needed 2 to 4 times the samples of 2.5 m).
MAP_LARGE_SIDE = 25.0
MAP_RANGE_SMALL = 1.5
MAP_RANGE_LARGE = 2.5
#: Less room than this (metres, robot and bar to the nearest wall or box) at the start or
#: the goal is pointed out: on six of those floors, 179 goals drawn in the three rooms farthest
#: from the start, 5 seeds each at the K above, were found in 79 % of the plans with less room
#: (62 % below 0.05 m) against 93 % with more (97 % from 0.5 m): the tree must arrive with
#: nearly the goal's arm angles.
MAP_TIGHT_ROOM = 0.1


def map_planner_settings(extent: Sequence[float]) -> dict:
    """The planner settings :func:`write_map_scenario` writes for a map of
    ``extent`` ``[x_min, y_min, x_max, y_max]`` (metres): ``iterations`` =
    :data:`MAP_ITERATIONS_PER_M2` per square metre, rounded up to a
    thousand, within [:data:`MAP_ITERATIONS_MIN`, :data:`MAP_ITERATIONS_MAX`];
    ``planning_range`` :data:`MAP_RANGE_SMALL` up to a longer side of
    :data:`MAP_LARGE_SIDE` m, :data:`MAP_RANGE_LARGE` beyond;
    ``near_radius`` the range plus 1 m (as the defaults: 1.5 and 2.5)."""
    x0, y0, x1, y1 = (float(v) for v in extent)
    width, height = x1 - x0, y1 - y0
    k = 1000 * math.ceil(MAP_ITERATIONS_PER_M2 * width * height / 1000 - 1e-9)
    reach = MAP_RANGE_SMALL if max(width, height) <= MAP_LARGE_SIDE else MAP_RANGE_LARGE
    return {"iterations": int(min(max(k, MAP_ITERATIONS_MIN), MAP_ITERATIONS_MAX)), "planning_range": reach,
            "near_radius": reach + 1.0}


@dc.dataclass(frozen=True)
class MapSummary:
    """What :func:`inspect_map` found.

    Attributes:
        path: the map's YAML file; image: its image.
        width, height: the grid's size, cells.
        resolution: metres per cell.
        origin: ``(x, y, yaw)`` of the grid's lower-left corner.
        extent: ``[x_min, y_min, x_max, y_max]`` the map covers, metres.
        mode, negate, occupied_thresh, free_thresh: the YAML's settings.
        occupied, free, unknown: cell counts.
        boxes: obstacle boxes with ``unknown`` as given.
        unknown_as: what unknown cells were taken as ("obstacle" or "free").
        seconds: time to read the map and to make its boxes.
        picture: the picture written, or None.
    """

    path: Path
    image: Path
    width: int
    height: int
    resolution: float
    origin: tuple[float, float, float]
    extent: list[float]
    mode: str
    negate: bool
    occupied_thresh: float
    free_thresh: float
    occupied: int
    free: int
    unknown: int
    boxes: int
    unknown_as: str
    seconds: dict
    picture: Path | None

    def lines(self) -> list[str]:
        """The summary as the command prints it."""
        cells = self.width * self.height
        x0, y0, x1, y1 = self.extent

        def share(n: int) -> str:
            return f"{n:,} ({100.0 * n / cells:.1f} %)"

        return [
            f"map {self.path} (image {self.image.name}, mode {self.mode}, negate {int(self.negate)}, "
            f"thresholds free < {self.free_thresh:g}, occupied > {self.occupied_thresh:g})",
            f"  grid      {self.width} x {self.height} cells of {self.resolution:g} m = "
            f"{self.width * self.resolution:g} x {self.height * self.resolution:g} m, "
            f"origin ({self.origin[0]:g}, {self.origin[1]:g}, yaw {self.origin[2]:g})",
            f"  extent    x {x0:g} .. {x1:g}, y {y0:g} .. {y1:g} m (the default world.bounds)",
            f"  cells     {cells:,}: occupied {share(self.occupied)}, free {share(self.free)}, "
            f"unknown {share(self.unknown)}",
            f"  boxes     {self.boxes:,} (unknown cells as {self.unknown_as}; "
            f"read {self.seconds['read']:.2f} s, boxes {self.seconds['boxes']:.2f} s)",
        ] + ([f"  picture   {self.picture}"] if self.picture is not None else [])


def inspect_map(path: str | Path, out: str | Path | None = None, *, unknown: str = "obstacle") -> MapSummary:
    """Reads a map_server map, makes its boxes and (with ``out``) writes
    ``out/map.png``: the cells, the boxes' outlines and the extent.

    Raises:
        ScenarioError: the map or ``unknown`` is invalid (the message names
            the file and the field).
        OSError: the picture could not be written.
    """
    if unknown not in MAP_UNKNOWN:
        raise ScenarioError(f"--unknown: must be one of {', '.join(MAP_UNKNOWN)}, got {unknown!r}")
    t0 = time.perf_counter()
    grid = read_map(path)
    t1 = time.perf_counter()
    boxes = map_boxes(grid, unknown)
    t2 = time.perf_counter()
    picture = None
    if out is not None:
        from drake_social.io.outputs import OutputSet
        from drake_social.viz.map import write_map_picture  # matplotlib: only when drawing

        out = Path(out)
        with OutputSet(out, "map", names=["map.png"]) as outputs:
            write_map_picture(grid, boxes, outputs.folder / "map.png", unknown=unknown)
        picture = out / "map.png"
    classes = grid.classes
    return MapSummary(
        path=grid.path, image=grid.image_path, width=int(grid.shape[1]), height=int(grid.shape[0]),
        resolution=float(grid.resolution), origin=tuple(float(v) for v in grid.origin),
        extent=[float(v) for v in grid.extent()], mode=grid.mode, negate=bool(grid.negate),
        occupied_thresh=float(grid.occupied_thresh), free_thresh=float(grid.free_thresh),
        occupied=int(np.count_nonzero(classes == OCCUPIED)), free=int(np.count_nonzero(classes == FREE)),
        unknown=int(np.count_nonzero(classes == UNKNOWN)), boxes=len(boxes.yaws), unknown_as=unknown,
        seconds={"read": t1 - t0, "boxes": t2 - t1}, picture=picture,
    )


def _number(v: float) -> str:
    return repr(float(v))


def map_scenario_text(map_file: str, start: Sequence[float], goal: Sequence[float], *, unknown: str = "obstacle",
                      arm: Sequence[float] = CARRYING_ARM, seed: int = 0, description: str | None = None,
                      planner: dict | None = None) -> str:
    """The YAML of a scenario around a map: the bar carried from ``start``
    to ``goal`` (base positions ``[x, y]``, metres) with the arm at ``arm``,
    no people yet.

    Args:
        map_file: the map's YAML as the scenario names it (relative to the
            scenario file, or absolute).
        planner: ``planner`` fields to write (:func:`map_planner_settings`);
            None = the planner's defaults.
    """
    qs, qg = [*map(float, start), *map(float, arm)], [*map(float, goal), *map(float, arm)]
    desc = description if description is not None else f"a transport through the map {Path(map_file).name}"
    return "\n".join([
        f"# A scenario around the occupancy-grid map {Path(map_file).name}, written by `drake-social map scenario`.",
        "# world.bounds default to the map's extent; add hand-drawn obstacles under world.obstacles.",
        f"description: {_quoted(desc)}",
        "world:",
        f"  map: {_quoted(map_file)}",
        f"  unknown: {unknown}   # unknown cells: obstacle or free",
        "# People stand or walk here, e.g.:",
        "#   - {x: 5.0, y: 3.0, theta: 1.57, radius: 0.25, name: \"reading\"}",
        "people: []",
        "robot: {base_radius: 0.35, link_lengths: [0.6, 0.5], link_width: 0.08}",
        "object: !Bar {length: 1.5, thickness: 0.05}",
        "# [x, y, psi1, psi2]: the arm in the carrying pose (the bar along x beside the base).",
        f"start: [{', '.join(_number(v) for v in qs)}]",
        f"goal: [{', '.join(_number(v) for v in qg)}]",
        *([] if planner is None else [
            "# Sized to the map's extent (drake-social map scenario: docs/maps.md); K = iterations.",
            "planner: {" + ", ".join(f"{k}: {v if isinstance(v, int) else _number(v)}" for k, v in planner.items())
            + "}"]),
        f"random_seed: {int(seed)}",
        "",
    ])


#: The command's option behind each field of the scenario it writes: the
#: scenario file is not written when it is refused, so an error names the option.
OPTION_OF_FIELD = {
    "start": "--start", "start[0]": "--start", "start[1]": "--start", "start[2]": "--arm", "start[3]": "--arm",
    "goal": "--goal", "goal[0]": "--goal", "goal[1]": "--goal", "goal[2]": "--arm", "goal[3]": "--arm",
    "world.unknown": "--unknown", "random_seed": "--seed",
}


def _as_option_error(message: str, out: str) -> str:
    """A refusal of the scenario text (``OUT: field: what``) as the command's:
    the option the field came from (:data:`OPTION_OF_FIELD`); the map's own
    message for ``world.map``; else the field, saying that ``OUT`` was not
    written."""
    prefix = f"{out}: "
    if not message.startswith(prefix):
        return message
    field, sep, rest = message[len(prefix):].partition(": ")
    if not sep:
        return message
    if field in OPTION_OF_FIELD:
        return f"{OPTION_OF_FIELD[field]}: {rest}"
    if field == "world.map":
        return rest
    return f"{out} (not written): {field}: {rest}"


def _quoted(text: str) -> str:
    return '"' + str(text).replace("\\", "\\\\").replace('"', '\\"') + '"'


@dc.dataclass(frozen=True)
class Room:
    """How much room the robot with its object has at a configuration.

    Attributes:
        clearance: the least distance from the robot (base, links, object)
            to a wall or box of the room, metres (exact, planar).
        part: the robot's part nearest to it (``base``, ``link1``,
            ``link2`` or ``object``).
        other: what it is nearest to (a wall, ``obstacle[i]``, or a box of
            the map with its image cells and world coordinates).
    """

    clearance: float
    part: str
    other: str

    def __str__(self) -> str:
        return f"{self.clearance:.2f} m ({self.part} to {self.other})"


@dc.dataclass(frozen=True)
class MapScenario:
    """What :func:`write_map_scenario` wrote.

    Attributes:
        path: the scenario file.
        planner: the planner settings written (:func:`map_planner_settings`).
        extent: ``[x_min, y_min, x_max, y_max]`` of the map (the scenario's bounds).
        start, goal: the room at the start and at the goal (:class:`Room`).
    """

    path: Path
    planner: dict
    extent: list[float]
    start: Room
    goal: Room

    def lines(self) -> list[str]:
        """What the command prints after its first line."""
        x0, y0, x1, y1 = self.extent
        p = self.planner
        def room(r: Room) -> str:
            tight = (f"; less than {MAP_TIGHT_ROOM:g} m: the planner arrives less often (more --iterations, or "
                     f"move it or turn the bar with --arm)") if r.clearance < MAP_TIGHT_ROOM else ""
            return f"{r}{tight}"

        return [f"  planner   K = {p['iterations']:,}, planning range {p['planning_range']:g} m, near radius "
                f"{p['near_radius']:g} m: sized to the map's {x1 - x0:g} x {y1 - y0:g} m (docs/maps.md)",
                f"  room      at the start {room(self.start)}", f"            at the goal  {room(self.goal)}"]


def _room(checker, q) -> Room:
    """The :class:`Room` of configuration ``q`` from the planar checker's exact pair distances."""
    from drake_social.collision import planar_kernel
    from drake_social.model.plant import shape_label

    d = planar_kernel.pair_distances(np.asarray(q, float), checker.bodies, checker.robot, checker.env)
    j, k = np.unravel_index(int(np.argmin(d)), d.shape)
    return Room(float(d[j, k]), checker.capsule_names[j][0], shape_label(checker.scenario, checker.env_names[k]))


def write_map_scenario(map_path: str | Path, out: str | Path, start: Sequence[float], goal: Sequence[float], *,
                       unknown: str = "obstacle", arm: Sequence[float] = CARRYING_ARM, seed: int = 0,
                       force: bool = False) -> MapScenario:
    """Writes :func:`map_scenario_text` to ``out`` (a ``.yaml`` file),
    naming the map relative to it, with planner settings sized to the map's
    extent (:func:`map_planner_settings`), after loading and validating it.

    Returns:
        The file, the settings and the room at the start and the goal.

    Raises:
        ScenarioError: the map, ``start``, ``goal`` or ``unknown`` is
            invalid (a base position in an occupied or unknown cell, out of
            the map, ...): the message names the option and the map; or
            ``out`` exists and ``force`` is not set, or is not a regular
            file (a directory, FIFO, device: never replaced).
        OSError: ``out`` could not be written.
    """
    out = Path(out)
    if out.suffix not in (".yaml", ".yml"):
        raise ScenarioError(f"--out: the scenario file must end in .yaml or .yml, got {out}")
    check_out_file(out, "--out")  # a directory, FIFO or device there is never replaced, even with --force
    if out.exists() and not force:
        raise ScenarioError(f"--out: {out} exists; pass --force to replace it")
    for name, xy in (("--start", start), ("--goal", goal), ("--arm", arm)):
        if len(xy) != 2 or not all(math.isfinite(float(v)) for v in xy):
            raise ScenarioError(f"{name}: must be two finite numbers, got {list(xy)}")
    map_path = Path(map_path)
    extent = [float(v) for v in read_map(map_path).extent()]  # the map's own errors first, naming its file
    folder = out.parent.absolute()
    try:
        relative = os.path.relpath(map_path.absolute(), folder)
    except ValueError:  # another drive (Windows)
        relative = str(map_path.absolute())
    planner = map_planner_settings(extent)
    text = map_scenario_text(relative, start, goal, unknown=unknown, arm=arm, seed=seed, planner=planner)
    try:
        scenario = load_scenario_text(text, str(out), base_dir=folder)
        # The whole robot (arm and bar too) clear of the map's boxes at both ends.
        from drake_social.collision.drake_checker import check_start_goal

        check_start_goal(scenario, None, str(out))
    except ScenarioError as e:
        message = _as_option_error(str(e), str(out))
        if "in collision" in message:
            message += " (move it, or turn the bar with --arm PSI1 PSI2)"
        raise ScenarioError(message) from None
    from drake_social.collision.planar_checker import PlanarChecker

    checker = PlanarChecker(scenario)
    rooms = [_room(checker, q) for q in (scenario.start, scenario.goal)]
    folder.mkdir(parents=True, exist_ok=True)
    path = replace_file(out, lambda f: f.write(text.encode("utf-8")), "--out")
    return MapScenario(path=path, planner=planner, extent=extent, start=rooms[0], goal=rooms[1])
