"""No function or method in drake_social/sim/ is longer than MAX_LINES lines
(its ``def`` line to its last line, docstring included): the execution layer
reads as small named steps (issue 30)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import drake_social

SIM = Path(drake_social.__file__).resolve().parent / "sim"
MAX_LINES = 120


def long_functions(folder: Path, most: int) -> list[tuple[int, str, str]]:
    """(lines, file, name) of every function below ``folder`` longer than ``most`` lines, longest first."""
    found = []
    for path in sorted(folder.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = node.end_lineno - node.lineno + 1
                if lines > most:
                    found.append((lines, path.name, node.name))
    return sorted(found, reverse=True)


def test_no_function_of_sim_is_longer_than_the_bound():
    assert long_functions(SIM, MAX_LINES) == []


@pytest.mark.parametrize("lines, long", [(MAX_LINES - 1, False), (MAX_LINES, False), (MAX_LINES + 1, True)])
def test_the_count_runs_from_the_def_to_the_last_line(tmp_path, lines, long):
    body = "".join(f"    x{k} = {k}\n" for k in range(lines - 3))
    (tmp_path / "m.py").write_text(f"class C:\n    @staticmethod\n    def f():\n        '''Doc.'''\n"
                                   + body.replace("    x", "        x") + "        return 0\n")
    assert long_functions(tmp_path, MAX_LINES) == ([(lines, "m.py", "f")] if long else [])
