"""The architecture guide's table of the station's ports (docs/architecture.md,
"The station's ports") is the built diagram's: in every variant, the exported
input and output ports are exactly the table's rows whose condition holds."""

from __future__ import annotations

import dataclasses as dc
import re
from pathlib import Path

import numpy as np
import pytest

from drake_social.scenario import load_scenario
from drake_social.sim.diagram import build_diagram

ARCHITECTURE = Path(__file__).resolve().parents[2] / "docs" / "architecture.md"
TINY = Path(__file__).resolve().parents[2] / "scenarios" / "tiny.yaml"


@dc.dataclass(frozen=True)
class Variant:
    """How the diagram is built."""

    mode: str = "kinematic"
    execution: str = "synchronized"
    waypoints: bool = True  # given (else planned)
    planner: bool = True
    controller: bool = True
    walking: bool = False  # the person walks (else stands)
    replan: bool = False


#: The conditions the table may state, as predicates of a variant; any other wording fails the test.
CONDITIONS = {
    "`planner=False` and no `waypoints`": lambda v: not v.planner and not v.waypoints,
    "`controller=False`": lambda v: not v.controller,
    "synchronized execution": lambda v: v.execution == "synchronized",
    "when people move": lambda v: v.walking,
    "replanning": lambda v: v.replan,
}

VARIANTS = [
    Variant(),
    Variant(execution="paper"),
    Variant(mode="dynamic"),
    Variant(mode="dynamic", execution="paper"),
    Variant(waypoints=False),
    Variant(waypoints=False, planner=False),
    Variant(controller=False),
    Variant(waypoints=False, planner=False, controller=False, execution="paper"),
    Variant(walking=True),
    Variant(walking=True, execution="paper", controller=False),
    Variant(walking=True, waypoints=False, replan=True),
    Variant(walking=True, waypoints=False, replan=True, mode="dynamic", execution="paper"),
]


def documented_ports() -> list[tuple[str, str, str | None]]:
    """(name, "input" or "output", condition or None) of every row of the table."""
    text = ARCHITECTURE.read_text(encoding="utf-8")
    section = text[text.index("## The station's ports"):]
    section = section[: section.index("\n## ", 4)]
    rows = [line for line in section.splitlines() if line.startswith("| `")]
    out = []
    for row in rows:
        names, direction = [cell.strip() for cell in row.strip("|").split("|")[:2]]
        kind, _, condition = direction.partition(", only ")
        assert kind in ("input", "output"), row
        condition = condition.removeprefix("with ") if condition else None
        assert condition is None or condition in CONDITIONS, f"a condition the test does not know: {row}"
        for name in re.findall(r"`([a-z_]+)`", names):
            out.append((name, kind, condition))
    return out


def test_the_table_is_read_row_by_row():
    rows = documented_ports()
    assert ("waiting", "output", "replanning") in rows and ("path_version", "output", "replanning") in rows
    assert ("done", "output", None) in rows and ("index", "output", None) in rows
    assert ("path", "input", "`planner=False` and no `waypoints`") in rows
    assert ("stop", "output", "when people move") in rows
    assert len(rows) == len({(n, k) for n, k, _ in rows})  # one row per port and direction


@pytest.fixture(scope="module")
def scenarios():
    """tiny.yaml (its person stands), and the same with the person walking across the room."""
    standing = load_scenario(TINY)
    walking = load_scenario(TINY, ["people: [{theta: -1.5708, name: walker, "
                                   "trajectory: [[0.0, 4.0, 4.4], [30.0, 7.5, 4.4]]}]"])
    path = np.array([standing.start, [3.5, 2.2, 0.0, 1.5708], standing.goal])
    return standing, walking, path


@pytest.mark.parametrize("variant", VARIANTS, ids=lambda v: "-".join(
    f"{k}={getattr(v, k)}" for k in ("mode", "execution", "waypoints", "planner", "controller", "walking", "replan")
    if getattr(v, k) != getattr(Variant(), k)) or "default")
def test_the_built_diagram_exports_the_documented_ports(scenarios, variant):
    standing, walking, path = scenarios
    dut = build_diagram(walking if variant.walking else standing, mode=variant.mode, execution=variant.execution,
                        waypoints=path if variant.waypoints else None, planner=variant.planner,
                        controller=variant.controller, replan=variant.replan)
    expected = {kind: sorted(n for n, k, condition in documented_ports()
                             if k == kind and (condition is None or CONDITIONS[condition](variant)))
                for kind in ("input", "output")}
    assert sorted(dut.input_port_names()) == expected["input"]
    assert sorted(dut.output_port_names()) == expected["output"]
