"""No function or method of the package is longer than MAX_LINES lines, none
in drake_social/sim/ longer than MAX_SIM_LINES (its ``def`` line to its last
line, docstring included): the code reads as small named steps, the
execution layer most of all (issue 30)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import drake_social

PACKAGE = Path(drake_social.__file__).resolve().parent
SIM = PACKAGE / "sim"
MAX_LINES = 200
MAX_SIM_LINES = 120


def long_functions(folder: Path, most: int) -> list[tuple[int, str, str]]:
    """(lines, file, name) of every function below ``folder`` longer than ``most`` lines, longest first."""
    found = []
    for path in sorted(folder.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = node.end_lineno - node.lineno + 1
                if lines > most:
                    found.append((lines, path.relative_to(folder).as_posix(), node.name))
    return sorted(found, reverse=True)


def test_no_function_of_the_package_is_longer_than_the_bound():
    assert long_functions(PACKAGE, MAX_LINES) == []


def test_no_function_of_sim_is_longer_than_its_bound():
    assert long_functions(SIM, MAX_SIM_LINES) == []


@pytest.mark.parametrize("most", [MAX_LINES, MAX_SIM_LINES])
@pytest.mark.parametrize("delta, long", [(-1, False), (0, False), (1, True)])
def test_the_count_runs_from_the_def_to_the_last_line(tmp_path, most, delta, long):
    lines = most + delta
    body = "".join(f"    x{k} = {k}\n" for k in range(lines - 3))
    (tmp_path / "m.py").write_text(f"class C:\n    @staticmethod\n    def f():\n        '''Doc.'''\n"
                                   + body.replace("    x", "        x") + "        return 0\n")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "m.py").write_text((tmp_path / "m.py").read_text())
    expected = [(lines, "sub/m.py", "f"), (lines, "m.py", "f")] if long else []
    assert long_functions(tmp_path, most) == expected
