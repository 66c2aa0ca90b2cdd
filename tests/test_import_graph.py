"""drake_social's modules import each other one way, layer by layer.

The graph: a module -> every module its import statements name, wherever they
stand (at the top, inside functions, methods or ``try``, and under ``if
TYPE_CHECKING:``, which never runs but ties the module to what it names for
a type checker: an annotation, string or not, is a dependency too); an import
of ``a.b.c`` runs the packages ``a.b`` and ``a`` too, except the importer's
own packages (already being imported when it runs).

The rules, each checked over the whole graph:

1. no cycle, not even through a function-level import or an annotation's;
2. a module imports only modules of its own layer or a lower one, by this
   table (the longest matching prefix of the module's dotted name decides):

   ===== ==================================================================
   layer modules (prefixes under ``drake_social.``)
   ===== ==================================================================
   0     ``limits``, ``errors``, ``io`` (the package itself),
         ``io.textfile``, ``io.json_numbers``, ``io.records`` (the record
         schema), ``_kernel_cache``, ``interrupts``
   1     ``kinematics`` (pure numpy; it names no schema type),
         ``maps`` (map_server maps: numpy, PyYAML, Pillow)
   2     ``scenario`` (schema, load, validate), ``arguments``
   3     ``people``, ``world``, ``cost``, ``collision`` (the package),
         ``collision.validity``, ``collision.geometric``,
         ``collision.planar_kernel``, ``collision.broadphase``, ``collision.people_kernel``,
         ``collision.people_safety``, ``planning``, ``waypoints``
   4     ``model``, ``collision.planar_checker``, ``collision.drake_checker``
         (Drake: the plant and Drake's checker)
   5     ``control``, ``viz``
   6     ``sim``, ``evaluation`` (the measures of a plan or a run),
         ``io.paths`` (path CSVs, which a run may read)
   7     ``io.outputs``, ``experiments``, ``app``, ``map_tools``
   8     ``cli``, ``cli_parser``, ``cli_progress``
   ===== ==================================================================

   ``drake_social`` itself (the package's ``__init__``) is layer 0, and so is
   a module of ``io`` the table does not name (it may then import only layer
   0); a module the table does not cover fails the test, so a new one is
   placed on purpose;
3. no module imports a private name (``from x import _y``, dunders such as
   ``__version__`` aside) of another module.

The first tests show that each check catches what it is for, on a small
package made here.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path
from typing import NamedTuple

import pytest

import drake_social

ROOT = Path(drake_social.__file__).resolve().parent

#: Module-name prefix -> layer (see the module docstring).
LAYERS: dict[str, int] = {
    "drake_social": 0,
    "drake_social.limits": 0,
    "drake_social.errors": 0,
    "drake_social.io": 0,
    "drake_social.io.textfile": 0,
    "drake_social.io.json_numbers": 0,
    "drake_social.io.records": 0,
    "drake_social._kernel_cache": 0,
    "drake_social.interrupts": 0,
    "drake_social.kinematics": 1,
    "drake_social.maps": 1,
    "drake_social.scenario": 2,
    "drake_social.arguments": 2,
    "drake_social.waypoints": 3,
    "drake_social.people": 3,
    "drake_social.world": 3,
    "drake_social.cost": 3,
    "drake_social.collision": 3,
    "drake_social.collision.validity": 3,
    "drake_social.collision.geometric": 3,
    "drake_social.collision.planar_kernel": 3,
    "drake_social.collision.broadphase": 3,
    "drake_social.collision.people_kernel": 3,
    "drake_social.collision.people_safety": 3,
    "drake_social.planning": 3,
    "drake_social.model": 4,
    "drake_social.collision.planar_checker": 4,
    "drake_social.collision.drake_checker": 4,
    "drake_social.control": 5,
    "drake_social.viz": 5,
    "drake_social.sim": 6,
    "drake_social.evaluation": 6,
    "drake_social.io.outputs": 7,
    "drake_social.io.paths": 6,
    "drake_social.experiments": 7,
    "drake_social.app": 7,
    "drake_social.map_tools": 7,
    "drake_social.warmup": 7,
    "drake_social.cli": 8,
    "drake_social.cli_parser": 8,
    "drake_social.cli_progress": 8,
}


class Import(NamedTuple):
    """One edge of the graph: the statement in ``source`` (its file's line) that runs ``target``."""

    source: str
    target: str
    line: int


def _modules(root: Path = ROOT) -> dict[str, Path]:
    """Module name -> file, for every module and package of the package at ``root``."""
    out = {}
    for path in root.rglob("*.py"):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _import_statements(tree: ast.AST):
    """Every import statement of a module, at any depth (``if TYPE_CHECKING:`` blocks included)."""
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
            continue
        stack.extend(ast.iter_child_nodes(node))


def _imported_module(name: str, is_package: bool, node: ast.ImportFrom) -> str:
    """The module a ``from ... import`` statement of module ``name`` names (relative imports resolved)."""
    if not node.level:
        return node.module
    parts = name.split(".")
    base = parts[: len(parts) + is_package - node.level]
    return ".".join(base + ([node.module] if node.module else []))


def import_edges(modules: dict[str, Path]) -> list[Import]:
    """Every edge of the graph (see the module docstring), with its line."""
    edges = []
    for name, path in modules.items():
        is_package = path.name == "__init__.py"
        own = {".".join(name.split(".")[:k]) for k in range(1, name.count(".") + 1 + is_package)}
        for node in _import_statements(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets = {a.name for a in node.names}
            else:
                module = _imported_module(name, is_package, node)
                targets = {module} | {f"{module}.{a.name}" for a in node.names if f"{module}.{a.name}" in modules}
            for t in targets:
                parts = t.split(".")
                for k in range(1, len(parts) + 1):
                    prefix = ".".join(parts[:k])
                    if prefix in modules and prefix not in own and prefix != name:
                        edges.append(Import(name, prefix, node.lineno))
    return edges


def import_graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    """Module -> the modules its import statements run (:func:`import_edges`)."""
    graph: dict[str, set[str]] = {name: set() for name in modules}
    for edge in import_edges(modules):
        graph[edge.source].add(edge.target)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def layer_of(module: str, layers: dict[str, int]) -> int | None:
    """The layer of ``module``: that of the longest prefix of its dotted name in ``layers``, or None."""
    parts = module.split(".")
    for k in range(len(parts), 0, -1):
        prefix = ".".join(parts[:k])
        if prefix in layers:
            return layers[prefix]
    return None


def layer_violations(edges: list[Import], layers: dict[str, int], modules: dict[str, Path]) -> list[str]:
    """One line per import of a higher layer, or of a module the table does not place."""
    out = []
    for e in sorted(set(edges)):
        source, target = layer_of(e.source, layers), layer_of(e.target, layers)
        where = f"{modules[e.source]}:{e.line}: {e.source}"
        if source is None or target is None:
            unplaced = e.source if source is None else e.target
            out.append(f"{where} imports {e.target}: {unplaced} has no layer in the table")
        elif target > source:
            out.append(f"{where} (layer {source}) imports {e.target} (layer {target}): a module may import "
                       f"only its own layer or lower ones")
    return out


def private_imports(modules: dict[str, Path]) -> list[str]:
    """One line per ``from x import _y`` of a module's private name by another module
    (a private submodule, such as ``drake_social._kernel_cache``, is a module, not a name)."""
    out = []
    for name, path in modules.items():
        is_package = path.name == "__init__.py"
        for node in _import_statements(ast.parse(path.read_text(), str(path))):
            if not isinstance(node, ast.ImportFrom):
                continue
            module = _imported_module(name, is_package, node)
            if module not in modules or module == name:
                continue
            for alias in node.names:
                dunder = alias.name.startswith("__") and alias.name.endswith("__")
                if alias.name.startswith("_") and not dunder and f"{module}.{alias.name}" not in modules:
                    out.append(f"{path}:{node.lineno}: {name} imports the private {alias.name} of {module}")
    return sorted(out)


# ---- the checks catch what they are for -------------------------------------------------


def _package(tmp_path: Path, files: dict[str, str]) -> dict[str, Path]:
    for relative, text in files.items():
        path = tmp_path / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return _modules(tmp_path / "top")


def test_the_graph_sees_function_level_and_annotation_imports_and_cycles_through_a_package(tmp_path):
    modules = _package(tmp_path, {
        "top/__init__.py": "",
        # a -> pkg.sub runs pkg/__init__, which imports b, which imports a.
        "top/a.py": "from top.pkg.sub import X\n",
        "top/b.py": "def f():\n    import top.a  # at call time: still an edge\n",
        "top/pkg/__init__.py": "from top.pkg import sub\nfrom top import b\n",
        "top/pkg/sub.py": "from top.pkg import other  # a sibling: not through its own package\nX = 1\n",
        "top/pkg/other.py": "import os\n",
        "top/e.py": "from .pkg import other\n",
        # c names d only for a type checker (a string annotation): still an edge, so c <-> d is a cycle.
        "top/c.py": "from __future__ import annotations\nfrom typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                    "    from top.d import D\n\n\ndef f(x: 'D') -> D:\n    return x\n",
        "top/d.py": "import top.c\nD = int\n",
    })
    graph = import_graph(modules)
    assert graph["top.a"] == {"top.pkg", "top.pkg.sub"}
    assert graph["top.b"] == {"top.a"}
    assert graph["top.e"] == {"top.pkg", "top.pkg.other"} and graph["top.pkg.other"] == set()
    assert graph["top.c"] == {"top.d"} and graph["top.d"] == {"top.c"}
    assert cycles(graph) == [["top.a", "top.b", "top.pkg"], ["top.c", "top.d"]]


def test_the_layer_check_names_each_import_from_a_higher_layer(tmp_path):
    modules = _package(tmp_path, {
        "top/__init__.py": "",
        "top/low.py": "X = 1\n",
        "top/high/__init__.py": "",
        "top/high/mid.py": "from top.low import X\n",
        "top/high/top_level.py": "import top.high.mid\n",
        "top/stray.py": "import top.low\n",
        "top/bad.py": "def f():\n    from top.high.top_level import Y\n",
    })
    layers = {"top.low": 0, "top.bad": 0, "top.high": 1, "top.high.top_level": 2}
    dut = layer_violations(import_edges(modules), layers, modules)
    assert dut == [
        f"{modules['top.bad']}:2: top.bad (layer 0) imports top.high (layer 1): a module may import only its own "
        "layer or lower ones",
        f"{modules['top.bad']}:2: top.bad (layer 0) imports top.high.top_level (layer 2): a module may import only "
        "its own layer or lower ones",
        f"{modules['top.stray']}:1: top.stray imports top.low: top.stray has no layer in the table",
    ]
    assert layer_of("top.high.mid", layers) == 1 and layer_of("elsewhere", layers) is None


def test_the_private_check_names_each_private_name_imported_from_another_module(tmp_path):
    modules = _package(tmp_path, {
        "top/__init__.py": "",
        "top/_helpers.py": "def _hidden():\n    pass\n\n\ndef shown():\n    pass\n",
        "top/a.py": "from top._helpers import shown  # a private module's public name: fine\n"
                    "from top import _helpers  # a private submodule: a module, fine\n",
        "top/b.py": "def f():\n    from top._helpers import _hidden\n",
        "top/c.py": "from ._helpers import shown, _hidden as h\n",
        "top/d.py": "from top import __version__  # a dunder: public\n",
    })
    assert private_imports(modules) == [
        f"{modules['top.b']}:2: top.b imports the private _hidden of top._helpers",
        f"{modules['top.c']}:1: top.c imports the private _hidden of top._helpers",
    ]


# ---- drake_social -----------------------------------------------------------------


def test_drake_social_has_no_import_cycle():
    graph = import_graph(_modules())
    assert "drake_social.scenario" in graph["drake_social.arguments"]  # the walk sees the package's imports
    assert "drake_social.kinematics" in graph["drake_social.scenario.validate"]
    assert cycles(graph) == []


def _annotation_names(tree: ast.AST) -> set[str]:
    """The identifiers of every annotation of a module (string annotations' too)."""
    notes = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            a = node.args
            notes += [x.annotation for x in (*a.posonlyargs, *a.args, *a.kwonlyargs, a.vararg, a.kwarg) if x]
            notes.append(node.returns)
        elif isinstance(node, ast.AnnAssign):
            notes.append(node.annotation)
    out = set()
    for note in filter(None, notes):
        for node in ast.walk(note):
            if isinstance(node, ast.Name):
                out.add(node.id)
            elif isinstance(node, ast.Attribute):
                out.add(node.attr)
            elif isinstance(node, ast.Constant) and isinstance(node.value, str):
                out.update(re.findall(r"[A-Za-z_]\w*", node.value))
    return out


def test_kinematics_names_no_schema_type():
    """The chain (``kinematics.py``) knows nothing of the scenario: no schema
    type is imported (not even for a type checker), named in its code or in an
    annotation; :mod:`drake_social.scenario.geometry` builds its
    ``ArmGeometry`` from a scenario."""
    from drake_social.scenario import schema

    types = {n for n, v in vars(schema).items() if isinstance(v, type) and v.__module__ == schema.__name__}
    assert {"Scenario", "Bar", "Robot"} <= types
    tree = ast.parse((ROOT / "kinematics.py").read_text())
    code = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)} | \
        {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)} | \
        {(a.asname or a.name).split(".")[-1] for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom))
         for a in n.names}
    assert sorted(types & (code | _annotation_names(tree))) == []
    graph = import_graph(_modules())
    assert not any(t.startswith("drake_social.scenario") for t in graph["drake_social.kinematics"])


def test_drake_social_imports_only_its_own_layer_or_lower_ones():
    modules = _modules()
    dut = layer_violations(import_edges(modules), LAYERS, modules)
    assert dut == [], "\n".join(dut)


def test_no_module_imports_another_modules_private_name():
    dut = private_imports(_modules())
    assert dut == [], "\n".join(dut)


def test_the_layer_table_places_every_module():
    unplaced = [name for name in _modules() if layer_of(name, LAYERS) is None]
    assert unplaced == []


@pytest.mark.parametrize("module", ["drake_social.kinematics", "drake_social.io.textfile",
                                    "drake_social.scenario.schema", "drake_social.arguments"])
def test_each_low_module_imports_first_in_a_fresh_interpreter(module):
    """Imported before anything else (no other module has set up the order),
    a module low in the graph loads: the graph's edges are the ones that run."""
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True, text=True, timeout=120,
                         check=False)
    assert out.returncode == 0, out.stderr


def test_the_command_line_parser_does_not_import_the_studies():
    """``import drake_social.cli`` and building its parser (every subcommand's
    arguments, ``experiment``'s bounds included) read their constants from
    :mod:`drake_social.limits`, not from :mod:`drake_social.experiments.study`
    (which imports the report, the figures and the records)."""
    import subprocess
    import sys

    code = ("import sys, drake_social.cli; from drake_social.cli_parser import build_parser; build_parser(); "
            "print(sorted(m for m in sys.modules if m.startswith('drake_social.experiments')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


#: Runs ``plan`` and ``simulate`` (planned, and replanned among a walker with
#: its people log, path figure and replans) through :mod:`drake_social.app`,
#: then prints every ``drake_social`` module loaded.
_PLAN_AND_SIMULATE = """
import json, sys
from drake_social import app
tiny, walker, out = sys.argv[1:4]
app.run_plan(scenario=tiny, out=out + "/plan", iterations=100)
app.run_simulate(scenario=tiny, out=out + "/simulate", iterations=100, replay=False)
app.run_simulate(scenario=walker, out=out + "/walker", iterations=100, replay=False, replan=True,
                 overrides=["execution: {time_limit: 2.0}"])
print(json.dumps(sorted(m for m in sys.modules if m.startswith("drake_social"))))
"""


def test_plan_and_simulate_load_nothing_from_the_experiments(tmp_path, tiny_scenario_path):
    """``plan`` and ``simulate`` (app.py's run_plan and run_simulate, and all
    they import: sim/, viz/, the metrics of :mod:`drake_social.evaluation`)
    run in a fresh interpreter without loading :mod:`drake_social.experiments`."""
    import json
    import subprocess
    import sys

    from experiments.test_crowd_study import TINY_WALKER

    walker = tmp_path / "tiny_walker.yaml"
    walker.write_text(TINY_WALKER)
    out = subprocess.run([sys.executable, "-c", _PLAN_AND_SIMULATE, str(tiny_scenario_path), str(walker),
                          str(tmp_path / "out")], capture_output=True, text=True, timeout=600, check=False)
    assert out.returncode == 0, out.stderr
    loaded = json.loads(out.stdout.strip().splitlines()[-1])
    assert [m for m in loaded if m == "drake_social.experiments" or m.startswith("drake_social.experiments.")] == []
    # The code paths ran: the records, the metrics over time, the replanning figure.
    assert {"drake_social.evaluation.records", "drake_social.evaluation.nav_metrics", "drake_social.sim.run",
            "drake_social.viz.replans"} <= set(loaded)
    assert {"result.json", "path.csv"} <= {p.name for p in (tmp_path / "out" / "plan").iterdir()}
    assert {"sim.json", "people.csv", "replans.csv"} <= {p.name for p in (tmp_path / "out" / "walker").iterdir()}


def test_arguments_checks_the_checker_protocol_by_its_methods():
    from drake_social.arguments import CHECKER_METHODS
    from drake_social.collision.validity import ValidityChecker

    protocol = {k for k, v in vars(ValidityChecker).items() if callable(v) and not k.startswith("_")}
    assert set(CHECKER_METHODS) == protocol


def test_each_shared_constant_has_one_home():
    """Each constant of :mod:`drake_social.limits` is assigned there and nowhere else."""
    limits = ast.parse((ROOT / "limits.py").read_text())
    constants = {t.id for node in limits.body if isinstance(node, ast.Assign) for t in node.targets
                 if isinstance(t, ast.Name) and t.id.isupper()}
    assert {"ALGORITHMS", "CHECKERS", "MAX_ITERATIONS", "MAX_TIME_LIMIT"} <= constants
    homes = {}
    for name, path in _modules().items():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.Assign, ast.AnnAssign)):
                for t in (node.targets if isinstance(node, ast.Assign) else [node.target]):
                    if isinstance(t, ast.Name) and t.id in constants:
                        homes.setdefault(t.id, []).append(name)
    assert {c: h for c, h in homes.items() if h != ["drake_social.limits"]} == {}


def package_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """The graph between the package's parts: its top-level modules and
    subpackages (``drake_social.planning.rrt_star`` is ``drake_social.planning``)."""
    def part(name: str) -> str:
        return ".".join(name.split(".")[:2])

    out: dict[str, set[str]] = {}
    for name, targets in graph.items():
        out.setdefault(part(name), set()).update(part(t) for t in targets if part(t) != part(name) and "." in t)
    return out


def test_drake_social_parts_import_each_other_one_way():
    parts = package_graph(import_graph(_modules()))
    assert "drake_social.arguments" in parts["drake_social.planning"]
    assert cycles(parts) == []
