"""Draws the architecture pictures of docs/architecture.md.

* ``docs/layers.png``: the package's layers; imports point downwards only.
* ``docs/diagram_transport.png``, ``docs/diagram_station_<mode>.png`` and
  ``docs/diagram_autonomy_<execution>.png``: the diagrams that
  :func:`drake_social.sim.build_diagram`, :func:`~drake_social.sim.make_station`
  and :func:`~drake_social.sim.make_autonomy` build for ``scenarios/tiny.yaml``
  (its person walking), read from the built diagrams themselves: every
  subsystem by name (the loggers left out), every connection with its output
  and input port names, and each diagram's own input and output ports.

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
#: tiny's person walking east along the north wall (the pictures' people move).
WALKER = "people: [{theta: -1.5708, name: walker, trajectory: [[0.0, 4.0, 4.4], [30.0, 7.5, 4.4]]}]"

# The layers, top to bottom: (title, colour, [(package, what it holds), ...]).
LAYERS = [
    ("front end", "#d9d2e9", [("cli.py", "argparse and printing only")]),
    ("application", "#c9daf8", [("app.py", "run_show, run_plan, run_simulate, run_study; map_tools.py"),
                                ("experiments/", "the runners: bench/, study/ (sweeps, paper, crowd)")]),
    ("execution, measures and figures", "#d0e0e3", [("sim/", "station, autonomy, build_diagram, simulate, replay"),
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


# Where each subsystem is drawn (x, y), per picture; a subsystem not listed
# goes into a row of its own below the others. Each diagram's own input ports
# are drawn on the left, its output ports on the right.
TRANSPORT = {"station": (0, 0), "autonomy": (8, 0), "logged_state": (4, -2.4)}
STATION_KINEMATIC = {
    "hold": (0, 0), "drive": (4, 0), "base": (8, 0), "configuration": (12, 0), "to_pose": (16, 1.6),
    "scene_graph": (20, 1.6), "arm_command_split": (4, -2.6), "velocity": (12, -2.6), "robot_state": (16, -1.3),
    "people": (12, 3.4), "people_geometry": (16, 3.4),
}
STATION_DYNAMIC = {
    "wheel_speeds": (0, 0), "drive": (4, 0), "hold": (8, 0), "arm_command_split": (0, -2.6),
    "desired_state": (12, -1.3), "servo_desired": (16, -1.3), "servo_acceleration": (20, -2.6),
    "servo": (24, -2.6), "servo_state": (16, -3.9), "base_acceleration": (4, -4.6), "desired_acceleration": (8, -4.6),
    "plant": (24, 0.6), "state_split": (20, 2.4), "q_split": (16, 2.4), "scene_graph": (28, 0.6),
    "people": (20, 4.4), "people_geometry": (24, 4.4),
}
AUTONOMY = {
    "robot_state_split": (0, 0), "planner": (4, 2.6), "path": (4, 2.6), "sequencer": (8, 0), "reference": (12, 0),
    "target_split": (12, 0), "reference_feedforward_split": (16, 1.4), "reference_config": (16, 1.4),
    "reference_state_split": (16, -1.4), "arm": (16, -1.4), "controller": (20, 0), "arm_command": (20, -2.6),
    "safety": (4, -2.6), "held": (12, -2.8), "base_position_split": (16, 3.2), "speed_limit": (8, -4.4),
}
BOX_W, BOX_H = 2.9, 0.75
X_SCALE = 1.2  # the positions' x units, stretched so that a label fits between two boxes of a row
GENERIC_PORT = re.compile(r"^(y|u)\d*$|^sum$|^Source_\d+_pose$")


def diagram_graph(diagram):
    """What :func:`draw_diagram` draws of ``diagram``: its subsystems (loggers
    left out), the connections ``(from, output, to, input)`` between them, its
    input ports ``(name, [(to, input), ...])`` and output ports ``(name, from, output)``."""
    from pydrake.systems.framework import InputPortIndex, OutputPortIndex

    names = [s.get_name() for s in diagram.GetSystems() if not s.get_name().endswith("_log")]
    edges = []
    for (in_sys, in_index), (out_sys, out_index) in diagram.connection_map().items():
        if in_sys.get_name() in names and out_sys.get_name() in names:
            edges.append((out_sys.get_name(), out_sys.get_output_port(out_index).get_name(),
                          in_sys.get_name(), in_sys.get_input_port(in_index).get_name()))
    inputs = [(diagram.get_input_port(i).get_name(),
               [(system.get_name(), system.get_input_port(index).get_name())
                for system, index in diagram.GetInputPortLocators(InputPortIndex(i))])
              for i in range(diagram.num_input_ports())]
    outputs = []
    for i in range(diagram.num_output_ports()):
        system, index = diagram.get_output_port_locator(OutputPortIndex(i))
        outputs.append((diagram.get_output_port(i).get_name(), system.get_name(),
                        system.get_output_port(index).get_name()))
    return names, sorted(edges), inputs, outputs


def _border(centre, size, towards):
    """Where the segment from a box's centre towards ``towards`` leaves the box of ``size`` (w, h)."""
    (x, y), (w, h), (tx, ty) = centre, size, towards
    dx, dy = tx - x, ty - y
    scale = min(w / 2 / abs(dx) if dx else float("inf"), h / 2 / abs(dy) if dy else float("inf"))
    return x + dx * scale, y + dy * scale


def _label(out_port: str, in_port: str) -> str:
    """An arrow's label: the port names, leaving out the numbered ports of (de)multiplexers."""
    names = [p for p in (out_port, in_port) if not GENERIC_PORT.match(p)]
    if len(names) == 2 and names[0] == names[1]:
        names = names[:1]
    return " > ".join(names)


def _nodes(names, inputs, outputs, positions):
    """Every box: name -> (centre, (w, h), lines). The diagram's own ports are
    grouped by the subsystem they reach (``in:<subsystem>``, ``out:<subsystem>``),
    one box each, on the left and the right beside that subsystem."""
    nodes, extra = {}, 0
    for name in names:
        if name in positions:
            centre = (positions[name][0] * X_SCALE, positions[name][1])
        else:
            centre = (extra % 7 * 4.0 * X_SCALE, min(p[1] for p in positions.values()) - 2.4 - extra // 7 * 1.2)
            extra += 1
        nodes[name] = (centre, (BOX_W, BOX_H), None)
    xs = [c[0] for c, _, _ in nodes.values()]
    groups = {"in": {}, "out": {}}
    for name, targets in inputs:
        for to, _ in targets[:1]:
            groups["in"].setdefault(to, []).append(name)
    for name, source, _ in outputs:
        groups["out"].setdefault(source, []).append(name)
    for side, x in (("in", min(xs) - 4.5), ("out", max(xs) + 4.5)):
        below = float("inf")
        for system, ports in sorted(groups[side].items(), key=lambda item: -nodes[item[0]][0][1]):
            h = 0.32 * len(ports) + 0.3
            y = min(nodes[system][0][1], below - h / 2 - 0.25)
            nodes[f"{side}:{system}"] = ((x, y), (BOX_W + 0.4, h), ports)
            below = y - h / 2
    return nodes


def _arrow(ax, node0, node1, label):
    (p0, size0, _), (p1, size1, _) = node0, node1
    if p0[0] == p1[0]:  # vertical: the upward arrow bends, so a pair both ways stays apart
        rad = 0.3 if p1[1] > p0[1] else 0.0
    elif p1[0] > p0[0]:
        rad = -0.15 if abs(p1[1] - p0[1]) < 0.1 and p1[0] - p0[0] < 6 else 0.0  # next on a row: above; back: below
    else:
        rad = -0.5 if abs(p1[0] - p0[0]) < 5 else -0.25
    a, b = _border(p0, size0, p1), _border(p1, size1, p0)
    ax.annotate("", xy=b, xytext=a, arrowprops=dict(arrowstyle="-|>", color="#4a6fa5", lw=1.0,
                                                    shrinkA=0, shrinkB=0, connectionstyle=f"arc3,rad={rad}"))
    if label:
        dx, dy = b[0] - a[0], b[1] - a[1]
        mx, my = (a[0] + b[0]) / 2 + 0.5 * rad * dy, (a[1] + b[1]) / 2 - 0.5 * rad * dx
        ax.text(mx, my, label, ha="center", va="center", fontsize=7, color="#1f3b63", linespacing=1.1,
                bbox=dict(fc="white", ec="none", alpha=0.85, pad=0.6))


def draw_diagram(diagram, title: str, path: Path, positions: dict) -> None:
    """One diagram, as built: boxes by subsystem name and type, arrows labelled
    by port (parallel connections in one arrow), the diagram's own input and
    output ports in boxes on either side."""
    names, edges, inputs, outputs = diagram_graph(diagram)
    nodes = _nodes(names, inputs, outputs, positions)
    arrows: dict[tuple[str, str], list[str]] = {}
    for out_name, out_port, in_name, in_port in edges:
        arrows.setdefault((out_name, in_name), []).append(_label(out_port, in_port))
    for name, targets in inputs:  # the port boxes name the ports: these arrows need no label
        for to, _ in targets:
            arrows.setdefault((f"in:{targets[0][0]}", to), [])
    for name, source, _ in outputs:
        arrows.setdefault((source, f"out:{source}"), [])
    xs = [c[0] for c, _, _ in nodes.values()]
    ys = [c[1] + sign * size[1] / 2 for c, size, _ in nodes.values() for sign in (-1, 1)]
    fig, ax = plt.subplots(figsize=((max(xs) - min(xs)) * 0.62 + 3, (max(ys) - min(ys)) * 0.62 + 2))
    ax.set_aspect("equal")
    for (start, end), labels in arrows.items():
        _arrow(ax, nodes[start], nodes[end], "\n".join(sorted({label for label in labels if label})))
    for name, ((x, y), (w, h), ports) in nodes.items():
        colour, edge = ("#d9ead3", "#38761d") if ports is not None else ("#fff2cc", "#7f6000")
        ax.add_patch(FancyBboxPatch((x - w / 2, y - h / 2), w, h, boxstyle="round,pad=0.0,rounding_size=0.1",
                                    fc=colour, ec=edge, zorder=3))
        if ports is not None:
            side = "inputs" if name.startswith("in:") else "outputs"
            ax.text(x, y + h / 2 - 0.2, side, ha="center", va="center", fontsize=7, color="#555555", zorder=4)
            ax.text(x, y - 0.1, "\n".join(ports), ha="center", va="center", fontsize=8, fontweight="bold",
                    linespacing=1.25, zorder=4)
            continue
        kind = type(diagram.GetSubsystemByName(name)).__name__.split("_")[0]
        ax.text(x, y + 0.12, name, ha="center", va="center", fontsize=8, fontweight="bold", zorder=4)
        ax.text(x, y - 0.17, kind, ha="center", va="center", fontsize=7, color="#555555", zorder=4)
    ax.set_title(title, fontsize=11)
    ax.set_xlim(min(xs) - BOX_W, max(xs) + BOX_W)
    ax.set_ylim(min(ys) - 0.4, max(ys) + 0.4)
    ax.set_axis_off()
    fig.savefig(path, dpi=100, bbox_inches="tight")
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DOCS, help="folder of the PNG files (default: docs/)")
    args = parser.parse_args()
    draw_layers(args.out / "layers.png")
    from drake_social.scenario import load_scenario
    from drake_social.sim import Replan, build_diagram, make_autonomy, make_station

    # tiny.yaml with its person walking: the people's bodies, the safety monitor and its stop are drawn too.
    scenario = load_scenario(DOCS.parent / "scenarios" / "tiny.yaml", [WALKER])
    built = build_diagram(scenario, mode="kinematic", execution="synchronized")
    draw_diagram(built.diagram, "build_diagram(scenario): the station and the autonomy wired by port name",
                 args.out / "diagram_transport.png", TRANSPORT)
    for mode, positions in (("kinematic", STATION_KINEMATIC), ("dynamic", STATION_DYNAMIC)):
        draw_diagram(make_station(scenario, mode=mode).diagram, f"make_station(scenario, mode={mode!r})",
                     args.out / f"diagram_station_{mode}.png", positions)
    for execution, path, call in (("synchronized", Replan(), "path=Replan()"), ("paper", None, "")):
        autonomy = make_autonomy(scenario, execution=execution, path=path)
        draw_diagram(autonomy.diagram, f"make_autonomy(scenario, execution={execution!r}{', ' + call if call else ''})",
                     args.out / f"diagram_autonomy_{execution}.png", AUTONOMY)


if __name__ == "__main__":
    main()
