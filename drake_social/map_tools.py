"""``drake-social map``: look at an occupancy-grid map, and start a scenario from one.

* :func:`inspect_map` (``map inspect``): the map's size, extent, cells and
  boxes, and a picture (``map.png``: the cells under the boxes' outlines);
* :func:`write_map_scenario` (``map scenario``): a scenario file around a
  map, with the robot carrying the bar from a start to a goal; it is loaded
  and validated before it is written, so a start or goal in an occupied or
  unknown cell is refused with the reason.

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
from drake_social.io.textfile import replace_file
from drake_social.maps import FREE, OCCUPIED, UNKNOWN, map_boxes, read_map
from drake_social.scenario import MAP_UNKNOWN, load_scenario_text

__all__ = ["CARRYING_ARM", "MapSummary", "inspect_map", "map_scenario_text", "write_map_scenario"]

#: The arm's joints ``[psi1, psi2]`` of a scenario written by
#: :func:`write_map_scenario`: link 2 folded back over the base, the bar
#: along x beside it (the carrying pose of ``scenarios/office_bar.yaml``).
CARRYING_ARM = (-1.2292, 2.8)


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
                      arm: Sequence[float] = CARRYING_ARM, seed: int = 0, description: str | None = None) -> str:
    """The YAML of a scenario around a map: the bar carried from ``start``
    to ``goal`` (base positions ``[x, y]``, metres) with the arm at ``arm``,
    no people yet, the planner's defaults.

    Args:
        map_file: the map's YAML as the scenario names it (relative to the
            scenario file, or absolute).
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


def write_map_scenario(map_path: str | Path, out: str | Path, start: Sequence[float], goal: Sequence[float], *,
                       unknown: str = "obstacle", arm: Sequence[float] = CARRYING_ARM, seed: int = 0,
                       force: bool = False) -> Path:
    """Writes :func:`map_scenario_text` to ``out`` (a ``.yaml`` file),
    naming the map relative to it, after loading and validating it.

    Raises:
        ScenarioError: the map, ``start``, ``goal`` or ``unknown`` is
            invalid (a base position in an occupied or unknown cell, out of
            the map, ...): the message names the option and the map; or
            ``out`` exists and ``force`` is not set.
        OSError: ``out`` could not be written.
    """
    out = Path(out)
    if out.suffix not in (".yaml", ".yml"):
        raise ScenarioError(f"--out: the scenario file must end in .yaml or .yml, got {out}")
    if out.exists() and not force:
        raise ScenarioError(f"--out: {out} exists; pass --force to replace it")
    for name, xy in (("--start", start), ("--goal", goal), ("--arm", arm)):
        if len(xy) != 2 or not all(math.isfinite(float(v)) for v in xy):
            raise ScenarioError(f"{name}: must be two finite numbers, got {list(xy)}")
    map_path = Path(map_path)
    read_map(map_path)  # the map's own errors first, naming its file
    folder = out.parent.absolute()
    try:
        relative = os.path.relpath(map_path.absolute(), folder)
    except ValueError:  # another drive (Windows)
        relative = str(map_path.absolute())
    text = map_scenario_text(relative, start, goal, unknown=unknown, arm=arm, seed=seed)
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
    folder.mkdir(parents=True, exist_ok=True)
    return replace_file(out, lambda f: f.write(text.encode("utf-8")))
