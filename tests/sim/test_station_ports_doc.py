"""The architecture guide's port tables (docs/architecture.md, "The station's
ports" and "The autonomy's ports") are the built diagrams': in every variant,
the ports of make_station and make_autonomy are exactly the rows of their
table whose condition holds, and build_diagram's exported ports are what the
guide's rule makes of the two tables (every station output, every autonomy
output the station does not take, every autonomy input the station does not
feed)."""

from __future__ import annotations

import dataclasses as dc
import re
from pathlib import Path

import numpy as np
import pytest

from drake_social.scenario import load_scenario
from drake_social.sim.autonomy import ExternalPath, GivenWaypoints, PlanAtInit, Replan, make_autonomy
from drake_social.sim.diagram import build_diagram
from drake_social.sim.station import make_station

ARCHITECTURE = Path(__file__).resolve().parents[2] / "docs" / "architecture.md"
TINY = Path(__file__).resolve().parents[2] / "scenarios" / "tiny.yaml"
WALKER = ["people: [{theta: -1.5708, name: walker, trajectory: [[0.0, 4.0, 4.4], [30.0, 7.5, 4.4]]}]"]
CROWD = ["crowd: {people: [{x: 2.0, y: 4.3, goals: [[6.5, 4.3]]}]}"]


@dc.dataclass(frozen=True)
class Variant:
    """How the station and the autonomy are built."""

    mode: str = "kinematic"
    execution: str = "synchronized"
    path: str = "given"  # given, plan, replan, external
    people: str = "standing"  # standing, walking (a scripted walker), crowd (a walker who also stands)

    @property
    def moving(self) -> bool:
        return self.people != "standing"


#: The conditions a table may state, as predicates of a variant; any other wording fails the test.
CONDITIONS = {
    "with a crowd": lambda v: v.people == "crowd",
    "with synchronized execution": lambda v: v.execution == "synchronized",
    "when people move": lambda v: v.moving,
    "with Replan": lambda v: v.path == "replan",
    "when people move or with Replan": lambda v: v.moving or v.path == "replan",
    "with ExternalPath": lambda v: v.path == "external",
    "with the slow-down": lambda v: v.moving and v.execution == "synchronized",
}

VARIANTS = [
    Variant(),
    Variant(execution="paper"),
    Variant(mode="dynamic"),
    Variant(mode="dynamic", execution="paper"),
    Variant(path="plan"),
    Variant(path="external"),
    Variant(path="external", execution="paper"),
    Variant(people="walking"),
    Variant(people="walking", execution="paper", path="external"),
    Variant(people="crowd"),
    Variant(people="crowd", mode="dynamic", path="plan"),
    Variant(path="replan"),
    Variant(people="walking", path="replan"),
    Variant(people="walking", path="replan", mode="dynamic", execution="paper"),
]


def documented_ports(title: str) -> list[tuple[str, str, str | None]]:
    """(name, "input" or "output", condition or None) of every row of the table under ``## title``."""
    text = ARCHITECTURE.read_text(encoding="utf-8")
    section = text[text.index(f"## {title}\n"):]
    section = section[: section.index("\n## ", 4)]
    rows = [line for line in section.splitlines() if line.startswith("| `")]
    out = []
    for row in rows:
        names, direction = [cell.strip() for cell in row.strip("|").split("|")[:2]]
        kind, _, condition = direction.partition(", only ")
        assert kind in ("input", "output"), row
        condition = condition or None
        assert condition is None or condition in CONDITIONS, f"a condition the test does not know: {row}"
        for name in re.findall(r"`([a-z_]+)`", names):
            out.append((name, kind, condition))
    return out


STATION, AUTONOMY = "The station's ports", "The autonomy's ports"


def expected(title: str, variant: Variant) -> dict[str, list[str]]:
    """The table's ports whose condition holds for ``variant``, sorted, by direction."""
    return {kind: sorted(n for n, k, condition in documented_ports(title)
                         if k == kind and (condition is None or CONDITIONS[condition](variant)))
            for kind in ("input", "output")}


def test_the_tables_are_read_row_by_row():
    station, autonomy = documented_ports(STATION), documented_ports(AUTONOMY)
    assert ("crowd_state", "output", "with a crowd") in station
    assert ("wheel_speeds", "input", None) in station and ("wheel_speeds", "output", None) in station
    assert ("path", "input", "with ExternalPath") in autonomy
    assert ("waiting", "output", "with Replan") in autonomy and ("stop", "output", "when people move") in autonomy
    assert ("done", "output", None) in autonomy and ("index", "output", None) in autonomy
    for rows in (station, autonomy):
        assert len(rows) == len({(n, k) for n, k, _ in rows})  # one row per port and direction


@pytest.fixture(scope="module")
def scenarios():
    """tiny.yaml (its person stands), with the person walking, and with a crowd of one."""
    standing = load_scenario(TINY)
    people = {"standing": standing, "walking": load_scenario(TINY, WALKER), "crowd": load_scenario(TINY, CROWD)}
    path = np.array([standing.start, [3.5, 2.2, 0.0, 1.5708], standing.goal])
    return people, path


def _source(variant: Variant, path: np.ndarray):
    return {"given": lambda: GivenWaypoints(path), "plan": PlanAtInit, "replan": Replan,
            "external": ExternalPath}[variant.path]()


def _ids(variant: Variant) -> str:
    return "-".join(f"{k}={getattr(variant, k)}" for k in ("mode", "execution", "path", "people")
                    if getattr(variant, k) != getattr(Variant(), k)) or "default"


@pytest.mark.parametrize("variant", VARIANTS, ids=_ids)
def test_the_station_and_the_autonomy_have_the_documented_ports(scenarios, variant):
    people, path = scenarios
    scenario = people[variant.people]
    station = make_station(scenario, mode=variant.mode)
    autonomy = make_autonomy(scenario, execution=variant.execution, path=_source(variant, path))
    for dut, title in ((station, STATION), (autonomy, AUTONOMY)):
        table = expected(title, variant)
        assert sorted(dut.input_port_names()) == table["input"], title
        assert sorted(dut.output_port_names()) == table["output"], title


@pytest.mark.parametrize("variant", VARIANTS, ids=_ids)
def test_the_composed_diagram_exports_what_the_rule_makes_of_the_tables(scenarios, variant):
    people, path = scenarios
    dut = build_diagram(people[variant.people], mode=variant.mode, execution=variant.execution,
                        path=_source(variant, path))
    station, autonomy = expected(STATION, variant), expected(AUTONOMY, variant)
    outputs = set(station["output"]) | (set(autonomy["output"]) - set(station["input"]))
    inputs = set(autonomy["input"]) - set(station["output"])
    assert sorted(dut.output_port_names()) == sorted(outputs)
    assert sorted(dut.input_port_names()) == sorted(inputs)
    # The parts' subsystem names are unique across the three diagrams (TransportDiagram.subsystem finds each).
    names = [[s.get_name() for s in d.GetSystems()] for d in (dut.diagram, dut.station.diagram, dut.autonomy.diagram)]
    flat = [n for group in names for n in group]
    assert len(flat) == len(set(flat))
