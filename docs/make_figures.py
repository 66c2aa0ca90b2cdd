"""Draws the architecture pictures of docs/architecture.md.

* ``docs/layers.png``: the package's layers; imports point downwards only.
* ``docs/diagram_<mode>_<execution>.png``: the execution diagram that
  :func:`drake_social.sim.build_diagram` builds for ``scenarios/tiny.yaml``,
  read from the built diagram itself: every subsystem by name (the loggers
  left out) and every connection with its output and input port names.

Run from the repository root after a change of the layout or the diagram::

    python docs/make_figures.py
"""

from __future__ import annotations

import argparse
import re
import textwrap
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import FancyBboxPatch  # noqa: E402

DOCS = Path(__file__).resolve().parent

# The layers, top to bottom: (title, colour, [(package, what it holds), ...]).
LAYERS = [
    ("front end", "#d9d2e9", [("cli.py", "argparse and printing only")]),
    ("application", "#c9daf8", [("app.py", "run_show, run_plan, run_simulate, run_study; map_tools.py"),
                                ("experiments/", "the runners: bench/, study/ (sweeps, paper, crowd)")]),
    ("execution, measures and figures", "#d0e0e3", [("sim/", "station diagram, simulate, analysis, replay"),
                                                    ("evaluation/", "metrics of a plan or a run: per part, over time"),
                                                    ("viz/", "matplotlib figures")]),
    ("Drake model and systems", "#d9ead3", [("model/", "plant and SceneGraph of a scenario"),
                                            ("control/", "LeafSystems: planner, sequencer, controller, drive, Ruckig"),
                                            ("collision/", "planar_checker, drake_checker")]),
    ("pure numpy core: never imports pydrake", "#fff2cc", [
        ("planning/", "algorithms, rrt_star/, optimize, sampling"),
        ("cost/", "AGF, S(q), motion integral"), ("collision/", "validity, geometric, planar_kernel, broadphase"),
        ("kinematics.py", "batched forward kinematics"), ("people/", "who is where at time t"),
        ("world/", "obstacles: boxes, the map's, walls")]),
    ("foundation", "#f4cccc", [("scenario/", "schema, load, validate"), ("maps/", "map_server maps, cells to boxes"),
                               ("limits.py", "bounds and names"), ("io/", "path CSV, records, output sets, text files")]),
]


def draw_layers(path: Path) -> None:
    """The layer picture: one band per layer, its packages as boxes."""
    fig, ax = plt.subplots(figsize=(13, 8.4))
    band_h, gap, width_all = 1.15, 0.3, 13.0
    for row, (title, colour, boxes) in enumerate(LAYERS):
        y = -row * (band_h + gap)
        ax.add_patch(FancyBboxPatch((0, y), width_all, band_h, boxstyle="round,pad=0.02,rounding_size=0.08",
                                    fc=colour, ec="#555555", lw=1.0))
        ax.text(0.12, y + band_h - 0.08, title, ha="left", va="top", fontsize=10, fontweight="bold")
        width = (width_all - 0.3) / len(boxes)
        for k, (name, what) in enumerate(boxes):
            x = 0.15 + k * width
            ax.add_patch(FancyBboxPatch((x + 0.05, y + 0.08), width - 0.1, band_h - 0.42,
                                        boxstyle="round,pad=0.01,rounding_size=0.05", fc="white", ec="#888888"))
            ax.text(x + width / 2, y + 0.08 + (band_h - 0.42) * 0.68, name, ha="center", va="center",
                    fontsize=9, family="monospace", fontweight="bold")
            wrapped = textwrap.fill(what, width=max(14, int(width * 13)))
            ax.text(x + width / 2, y + 0.08 + (band_h - 0.42) * 0.3, wrapped, ha="center", va="center",
                    fontsize=7.5, linespacing=1.0)
        if row:
            ax.annotate("", xy=(width_all - 0.3, y + band_h + 0.02), xytext=(width_all - 0.3, y + band_h + gap - 0.02),
                        arrowprops=dict(arrowstyle="-|>", color="#333333", lw=1.2))
    ax.text(width_all / 2, band_h + 0.15, "drake_social: each layer imports only the layers below it",
            ha="center", va="bottom", fontsize=11)
    ax.set_xlim(-0.1, width_all + 0.1)
    ax.set_ylim(-len(LAYERS) * (band_h + gap) + gap - 0.1, band_h + 0.6)
    ax.set_axis_off()
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


# Where each subsystem of the execution diagram is drawn (x, y); a subsystem
# not listed here goes into a row of its own below the others.
POSITIONS = {
    "planner": (0, 0), "sequencer": (4, 0), "reference": (8, 0), "target_split": (8, 0), "arm": (8, -2.6),
    "reference_position_split": (12, 2.4), "reference_feedforward_split": (12, 0.8),
    "reference_velocity_split": (12, -0.8), "reference_state_split": (12, -2.4),
    "reference_config": (12, -2.6), "arm_state_split": (12, -4.2),
    "controller": (16, 0), "hold": (20, 0), "drive": (24, 0),
    "base": (24, -4.2), "configuration": (20, -4.2), "velocity": (20, -6.0), "q_split": (16, -4.2),
    "to_pose": (4, -6.0), "scene_graph": (0, -6.0),
    # dynamic mode: the plant under the inverse-dynamics servo
    "state_split": (20, -4.2), "plant": (24, -4.2),
    "desired_state": (12, -6.6), "servo_desired": (16, -6.6), "servo_acceleration": (20, -6.6), "servo": (24, -6.6),
    "base_acceleration": (8, -8.4), "desired_acceleration": (12, -8.4), "servo_state": (16, -8.4),
}
# Where the dynamic mode's diagram differs: the hold follows the drive, and
# the scene graph answers the plant's queries.
DYNAMIC_POSITIONS = {"hold": (24, -2.1), "scene_graph": (28, -4.2)}
BOX_W, BOX_H = 2.5, 0.75
GENERIC_PORT = re.compile(r"^(y|u)\d*$|^sum$|^Source_\d+_pose$")


def diagram_edges(built) -> tuple[list[str], list[tuple[str, str, str, str]]]:
    """The subsystems (loggers left out) and the connections ``(from, output, to, input)``."""
    diagram = built.diagram
    names = [s.get_name() for s in diagram.GetSystems() if not s.get_name().endswith("_log")]
    edges = []
    for (in_sys, in_index), (out_sys, out_index) in diagram.connection_map().items():
        if in_sys.get_name() in names and out_sys.get_name() in names:
            edges.append((out_sys.get_name(), out_sys.get_output_port(out_index).get_name(),
                          in_sys.get_name(), in_sys.get_input_port(in_index).get_name()))
    return names, sorted(edges)


def _border(centre, towards):
    """Where the segment from a box's centre towards ``towards`` leaves the box."""
    (x, y), (tx, ty) = centre, towards
    dx, dy = tx - x, ty - y
    scale = min(BOX_W / 2 / abs(dx) if dx else float("inf"), BOX_H / 2 / abs(dy) if dy else float("inf"))
    return x + dx * scale, y + dy * scale


def _label(out_port: str, in_port: str) -> str:
    """An arrow's label: the port names, leaving out the numbered ports of (de)multiplexers."""
    names = [p for p in (out_port, in_port) if not GENERIC_PORT.match(p)]
    if len(names) == 2 and names[0] == names[1]:
        names = names[:1]
    return " > ".join(names)


def draw_diagram(built, title: str, path: Path) -> None:
    """One execution diagram, as built: boxes by subsystem name, arrows labelled by port."""
    names, edges = diagram_edges(built)
    positions = {**POSITIONS, **(DYNAMIC_POSITIONS if built.mode == "dynamic" else {})}
    pos, extra = {}, 0
    for name in names:
        if name in positions:
            pos[name] = positions[name]
        else:
            pos[name] = (extra % 7 * 4.0, -7.6 - extra // 7 * 1.2)
            extra += 1
    fig, ax = plt.subplots(figsize=(20, 8.5))
    ax.set_aspect("equal")
    for out_name, out_port, in_name, in_port in edges:
        p0, p1 = pos[out_name], pos[in_name]
        if p0[0] == p1[0]:  # vertical: the upward arrow bends, so a pair both ways stays apart
            rad = 0.3 if p1[1] > p0[1] else 0.0
        elif p1[0] > p0[0]:
            rad = 0.0
        else:
            rad = -0.5 if abs(p1[0] - p0[0]) < 5 else -0.25
        a, b = _border(p0, p1), _border(p1, p0)
        ax.annotate("", xy=b, xytext=a, arrowprops=dict(arrowstyle="-|>", color="#4a6fa5", lw=1.0,
                                                        shrinkA=0, shrinkB=0, connectionstyle=f"arc3,rad={rad}"))
        label = _label(out_port, in_port)
        if label:
            dx, dy = b[0] - a[0], b[1] - a[1]
            mx, my = (a[0] + b[0]) / 2 + 0.5 * rad * dy, (a[1] + b[1]) / 2 - 0.5 * rad * dx
            ax.text(mx, my, label, ha="center", va="center", fontsize=7, color="#1f3b63",
                    bbox=dict(fc="white", ec="none", alpha=0.85, pad=0.6))
    for name, (x, y) in pos.items():
        kind = type(built.diagram.GetSubsystemByName(name)).__name__.split("_")[0]
        ax.add_patch(FancyBboxPatch((x - BOX_W / 2, y - BOX_H / 2), BOX_W, BOX_H,
                                    boxstyle="round,pad=0.0,rounding_size=0.1", fc="#fff2cc", ec="#7f6000",
                                    zorder=3))
        ax.text(x, y + 0.12, name, ha="center", va="center", fontsize=8, fontweight="bold", zorder=4)
        ax.text(x, y - 0.17, kind, ha="center", va="center", fontsize=7, color="#555555", zorder=4)
    exported_in = [built.diagram.get_input_port(i).get_name() for i in range(built.diagram.num_input_ports())]
    exported_out = [built.diagram.get_output_port(i).get_name() for i in range(built.diagram.num_output_ports())]
    ports = f"exported inputs: {', '.join(exported_in) or 'none'};  outputs: {', '.join(exported_out) or 'none'}"
    ax.set_title(f"{title}\n{ports}", fontsize=11)
    xs = [p[0] for p in pos.values()]
    ys = [p[1] for p in pos.values()]
    ax.set_xlim(min(xs) - BOX_W, max(xs) + BOX_W)
    ax.set_ylim(min(ys) - 1.0, max(ys) + 1.0)
    ax.set_axis_off()
    fig.savefig(path, dpi=100, bbox_inches="tight")
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DOCS, help="folder of the PNG files (default: docs/)")
    args = parser.parse_args()
    draw_layers(args.out / "layers.png")
    from drake_social.scenario import load_scenario
    from drake_social.sim import build_diagram

    scenario = load_scenario(DOCS.parent / "scenarios" / "tiny.yaml")
    for mode, execution in (("kinematic", "synchronized"), ("kinematic", "paper"), ("dynamic", "synchronized")):
        built = build_diagram(scenario, mode=mode, execution=execution)
        draw_diagram(built, f"build_diagram(scenario, mode={mode!r}, execution={execution!r})",
                     args.out / f"diagram_{mode}_{execution}.png")


if __name__ == "__main__":
    main()
