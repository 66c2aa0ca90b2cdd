"""drake_social's modules import each other one way: no cycle among their
module-level imports, and each shared limit has one home."""

from __future__ import annotations

import ast
from pathlib import Path

import drake_social

ROOT = Path(drake_social.__file__).resolve().parent


def _modules(root: Path = ROOT) -> dict[str, Path]:
    """Module name -> file, for every module and package of the package at ``root``."""
    out = {}
    for path in root.rglob("*.py"):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _runtime_body(body: list[ast.stmt]):
    """The statements run when the module is imported: its top level, with
    the branches of ``if`` and ``try`` but not ``if TYPE_CHECKING:``."""
    for node in body:
        if isinstance(node, ast.If):
            test = node.test
            name = test.id if isinstance(test, ast.Name) else test.attr if isinstance(test, ast.Attribute) else ""
            if name != "TYPE_CHECKING":
                yield from _runtime_body(node.body)
            yield from _runtime_body(node.orelse)
        elif isinstance(node, ast.Try):
            for block in (node.body, node.orelse, node.finalbody, *(h.body for h in node.handlers)):
                yield from _runtime_body(block)
        else:
            yield node


def import_graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    """Module -> the modules its module-level imports run. Importing
    ``a.b.c`` runs the packages ``a.b`` and ``a`` too, except the importer's
    own packages (already being imported when it runs)."""
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        is_package = path.name == "__init__.py"
        own = {".".join(name.split(".")[:k]) for k in range(1, name.count(".") + 1 + is_package)}
        targets = set()
        for node in _runtime_body(ast.parse(path.read_text(), str(path)).body):
            if isinstance(node, ast.Import):
                targets |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = name.split(".")[: len(name.split(".")) + is_package - node.level]
                    module = ".".join(base + ([node.module] if node.module else []))
                else:
                    module = node.module
                targets.add(module)
                targets |= {f"{module}.{a.name}" for a in node.names if f"{module}.{a.name}" in modules}
        edges = set()
        for t in targets:
            parts = t.split(".")
            for k in range(1, len(parts) + 1):
                prefix = ".".join(parts[:k])
                if prefix in modules and prefix not in own and prefix != name:
                    edges.add(prefix)
        graph[name] = edges
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


def test_the_detector_finds_a_cycle_through_a_package(tmp_path):
    # a -> pkg.sub runs pkg/__init__, which imports b, which imports a.
    pkg = tmp_path / "top"
    (pkg / "pkg").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from top.pkg.sub import X\n")
    (pkg / "b.py").write_text("import top.a\n")
    (pkg / "pkg" / "__init__.py").write_text("from top.pkg import sub\nfrom top import b\n")
    (pkg / "pkg" / "sub.py").write_text("from top.pkg import other  # a sibling: not a cycle\nX = 1\n")
    (pkg / "pkg" / "other.py").write_text("import os\n\ndef f():\n    import top.a  # at call time: not counted\n")
    (pkg / "e.py").write_text("from .pkg import other\n")
    (pkg / "c.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import top.d\n")
    (pkg / "d.py").write_text("import top.c\n")
    graph = import_graph(_modules(pkg))
    assert graph["top.a"] == {"top.pkg", "top.pkg.sub"}
    assert graph["top.e"] == {"top.pkg", "top.pkg.other"} and graph["top.pkg.other"] == set()
    assert cycles(graph) == [["top.a", "top.b", "top.pkg"]]


def test_drake_social_has_no_import_cycle():
    graph = import_graph(_modules())
    assert "drake_social.scenario" in graph["drake_social.arguments"]  # the walk sees the package's imports
    assert cycles(graph) == []


def test_arguments_checks_the_checker_protocol_by_its_methods():
    from drake_social.arguments import CHECKER_METHODS
    from drake_social.collision.validity import ValidityChecker

    protocol = {k for k, v in vars(ValidityChecker).items() if callable(v) and not k.startswith("_")}
    assert set(CHECKER_METHODS) == protocol


def test_max_iterations_has_one_home():
    homes = [name for name, path in _modules().items()
             if any(isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "MAX_ITERATIONS" for t in node.targets)
                    for node in ast.parse(path.read_text()).body)]
    assert homes == ["drake_social.limits"]


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
