"""Valid scenarios of a large room with many people and obstacles, for
memory and scaling checks (``tests/test_memory_bounds.py``) and by hand::

    python tests/crowd_scenarios.py OUT.yaml --size 100 --people 300 --obstacles 2000 \
        [--description-bytes 50000000] [--seed 0]

People and boxes are placed by rejection sampling from a seeded
:class:`numpy.random.Generator`: every person and every box lies inside the
bounds, none overlaps another body or box, and none comes within
``clearance`` metres of the start or the goal base (so the robot and its bar
are free there in any arm pose).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

__all__ = ["crowd_scenario_text", "main"]


def crowd_scenario_text(size: float = 100.0, people: int = 300, obstacles: int = 0, *, seed: int = 0,
                        description: str | None = None, clearance: float = 3.0,
                        iterations: int = 200, walking: bool = False) -> str:
    """YAML text of a ``size`` x ``size`` m room with ``people`` people and
    ``obstacles`` axis-aligned or turned boxes (0.4-1.6 m sides).

    The robot carries a 1.5 m bar from near the south-west corner to near the
    north-east corner; ``planner.iterations`` is ``iterations``. With
    ``walking`` the people are a social-force crowd (``crowd.people``), each
    walking to a point drawn in the room and back, again and again (the
    points are drawn after the placements: the places are those without it).

    Raises:
        ValueError: the room cannot hold that many bodies and boxes (a placement
            failed 1,000 times in a row).
    """
    rng = np.random.default_rng(seed)
    start = (3.0, 3.0)
    goal = (size - 3.0, size - 3.0)
    taken: list[tuple[float, float, float]] = [(start[0], start[1], clearance), (goal[0], goal[1], clearance)]
    # Occupied discs (x, y, radius) hashed on a grid of cells no smaller than
    # the largest gap tested (two box discs of 0.5 * hypot(1.6, 1.6) m and the
    # 0.05 m spacing), so that a clash is always in a neighbouring cell.
    cell = 2.0 * 0.5 * math.hypot(1.6, 1.6) + 0.05
    grid: dict[tuple[int, int], list[tuple[float, float, float]]] = {}

    def add(x: float, y: float, r: float) -> None:
        grid.setdefault((int(x // cell), int(y // cell)), []).append((x, y, r))

    def free(x: float, y: float, r: float) -> bool:
        for sx, sy, sr in taken:
            if math.hypot(x - sx, y - sy) < r + sr:
                return False
        i, j = int(x // cell), int(y // cell)
        for di in (-1, 0, 1):
            for dj in (-1, 0, 1):
                for ox, oy, orad in grid.get((i + di, j + dj), ()):
                    if math.hypot(x - ox, y - oy) < r + orad + 0.05:
                        return False
        return True

    def place(r: float) -> tuple[float, float]:
        for _ in range(1000):
            x, y = rng.uniform(r + 0.05, size - r - 0.05, 2)
            if free(x, y, r):
                add(x, y, r)
                return float(x), float(y)
        raise ValueError(f"no room for another disc of radius {r} m in a {size} m room")

    if description is None:
        description = f"crowd: {size:g} m room, {people} people, {obstacles} boxes"
    lines = [f"description: {_quoted(description)}", "world:", f"  bounds: [0.0, 0.0, {size}, {size}]"]
    if obstacles:
        lines.append("  obstacles:")
    for _ in range(obstacles):
        sx, sy = rng.uniform(0.4, 1.6, 2)
        yaw = float(rng.choice([0.0, rng.uniform(-math.pi, math.pi)]))
        x, y = place(0.5 * math.hypot(sx, sy))  # the box's circumscribed disc
        lines.append(f"    - {{center: [{x:.4f}, {y:.4f}], size: [{sx:.4f}, {sy:.4f}], yaw: {yaw:.4f}}}")
    placed = []
    for k in range(people):
        x, y = place(0.25)
        placed.append((x, y, rng.uniform(-math.pi, math.pi)))
    if walking:
        lines += ["people: []", "crowd:", "  people:" if people else "  people: []"]
        for k, (x, y, _) in enumerate(placed):
            gx, gy = rng.uniform(0.5, size - 0.5, 2)
            lines.append(f"    - {{x: {x:.4f}, y: {y:.4f}, goals: [[{gx:.4f}, {gy:.4f}], [{x:.4f}, {y:.4f}]], "
                         f"cycle: true, name: \"p{k}\"}}")
    else:
        lines.append("people:" if people else "people: []")
        for k, (x, y, theta) in enumerate(placed):
            lines.append(f"  - {{x: {x:.4f}, y: {y:.4f}, theta: {theta:.4f}, radius: 0.25, name: \"p{k}\"}}")
    lines += [
        "robot: {base_radius: 0.35, link_lengths: [0.6, 0.5], link_width: 0.08}",
        "object: !Bar {length: 1.5, thickness: 0.05}",
        f"start: [{start[0]}, {start[1]}, 0.0, 1.5708]",
        f"goal: [{goal[0]}, {goal[1]}, 0.0, 1.5708]",
        f"random_seed: {seed}",
        f"planner: {{iterations: {iterations}}}",
    ]
    return "\n".join(lines) + "\n"


def _quoted(text: str) -> str:
    """A YAML double-quoted scalar of ``text`` (printable ASCII plus escapes)."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--size", type=float, default=100.0, help="room side, metres")
    parser.add_argument("--people", type=int, default=300)
    parser.add_argument("--obstacles", type=int, default=0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--iterations", type=int, default=200)
    parser.add_argument("--description-bytes", type=int, default=None,
                        help="a description of this many bytes (words of lorem ipsum)")
    args = parser.parse_args(argv)
    description = None
    if args.description_bytes is not None:
        words = "lorem ipsum dolor sit amet consectetur adipiscing elit "
        description = (words * (args.description_bytes // len(words) + 1))[: args.description_bytes]
    args.out.write_text(crowd_scenario_text(args.size, args.people, args.obstacles, seed=args.seed,
                                            description=description, iterations=args.iterations))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
