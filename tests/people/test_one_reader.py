"""People come from the people model and obstacles from the world model.

Outside ``scenario/`` (which defines them) and ``people/`` no module of the
package reads a scenario's ``people``; outside ``scenario/`` and ``world/``
none reads ``world.obstacles``. Walking people or a map then change one
package, not every consumer.
"""

from __future__ import annotations

import ast
from pathlib import Path

import drake_social

ROOT = Path(drake_social.__file__).resolve().parent

#: ``.people`` reads that are a SocialCost's own (P, 3) array [x, y, theta],
#: not a scenario's list: (module path under the package, expression).
COST_PEOPLE = {
    ("cost/social.py", "self.people"),
    ("planning/rrt_star/compiled.py", "sc.people"),
    # The compiled loop's SocialParams: the standing people's array that compiled.py packed from sc.people.
    ("planning/rrt_star/tree_kernel.py", "s.people"),
    # A SimulationResult's people log (a PeopleLog over the run), not a scenario's list.
    ("sim/run.py", "result.people"),
    # The station's people source (a PeopleSource, which answers from the people model).
    ("sim/run.py", "built.station.people"),
    ("app.py", "run.people"),
    ("experiments/study/runs.py", "run.people"),
    ("experiments/study/crowd_episode.py", "run.people"),
    ("viz/predictions.py", "run.people"),
}


def attribute_reads(source: str, attribute: str) -> list[tuple[int, str]]:
    """(line, expression) of every ``<expr>.<attribute>`` in ``source``."""
    return sorted((node.lineno, ast.unparse(node)) for node in ast.walk(ast.parse(source))
                  if isinstance(node, ast.Attribute) and node.attr == attribute)


def reads_outside(attribute: str, owners: set[str], allowed: set[tuple[str, str]] = frozenset()) -> list[str]:
    """``file:line: expression`` of the reads of ``attribute`` in modules outside the packages ``owners``."""
    out = []
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        if rel.split("/")[0] in owners:
            continue
        for line, expr in attribute_reads(path.read_text(), attribute):
            if (rel, expr) not in allowed:
                out.append(f"{rel}:{line}: {expr}")
    return out


def test_the_detector_finds_reads_in_any_expression():
    source = "n = len(scenario.people)\nfor p in s.people: pass\nx = f(a.b.world.obstacles)\ny = people\n"
    assert attribute_reads(source, "people") == [(1, "scenario.people"), (2, "s.people")]
    assert attribute_reads(source, "obstacles") == [(3, "a.b.world.obstacles")]
    # It sees the scenario package's own reads (which it is allowed to make).
    assert attribute_reads((ROOT / "people" / "compose.py").read_text(), "people")


def test_only_the_people_model_reads_the_scenarios_people():
    assert reads_outside("people", {"scenario", "people"}, COST_PEOPLE) == []


def test_the_cost_people_allowance_is_used():
    # Each allowed expression still occurs in its module: the list stays exact.
    for rel, expr in COST_PEOPLE:
        assert expr in {e for _, e in attribute_reads((ROOT / rel).read_text(), "people")}, (rel, expr)


def test_only_the_world_model_reads_the_obstacles():
    assert reads_outside("obstacles", {"scenario", "world"}) == []
