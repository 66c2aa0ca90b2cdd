"""The README's `make demo` block is what the demo prints.

The block lists the Makefile's demo commands as make echoes them, each
followed by the summary line the command prints. The test reads the commands
from the Makefile, checks that the README shows exactly those, runs them (in
a temporary output folder) and compares every README line with the line the
command printed: the same words, and every number within one unit of its last
printed digit. Times and speeds (the machine's) are compared by form only,
and numbers printed below 1e-9 (a deviation at rounding level) only by being
that small.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
COMMAND = "$(VENV)/bin/drake-social"
SHOWN = ".venv/bin/drake-social"

NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?")
#: What depends on the machine: the planner's and the optimiser's seconds, the realtime factor.
MACHINE = re.compile(r"\d+(?:\.\d+)? s \+ \d+(?:\.\d+)? s optimising|\d+(?:\.\d+)?x realtime")
#: Numbers below this are rounding (a planned curve followed to 1e-13 m): only their size is compared.
ROUNDING = 1e-9


def demo_commands() -> list[str]:
    """The demo target's drake-social commands, as make echoes them (VENV = .venv, OUT = out)."""
    text = (ROOT / "Makefile").read_text(encoding="utf-8")
    body = re.search(r"^demo:.*\n((?:\t.*\n)+)", text, re.M).group(1)
    lines = [line.strip() for line in body.splitlines() if line.strip().startswith(COMMAND)]
    return [line.replace("$(VENV)", ".venv").replace("$(OUT)", "out") for line in lines]


def readme_block() -> list[str]:
    """The lines of the README's code block that follows "`make demo` runs"."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return re.search(r"`make demo` runs.*?\n```\n(.*?)\n```", text, re.S).group(1).splitlines()


def _unit(token: str) -> float:
    """One unit of the last printed digit of a number token."""
    mantissa, _, exponent = token.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 10.0 ** (-decimals + (int(exponent) if exponent else 0))


def same_within_printing(shown: str, printed: str) -> list[str]:
    """What differs between a README line and a printed line (empty: the same)."""
    problems = []
    machine_shown, machine_printed = MACHINE.findall(shown), MACHINE.findall(printed)
    if len(machine_shown) != len(machine_printed):
        problems.append(f"machine-dependent parts {machine_shown} against {machine_printed}")
    shown, printed = MACHINE.sub("<machine>", shown), MACHINE.sub("<machine>", printed)
    if NUMBER.sub("#", shown) != NUMBER.sub("#", printed):
        return problems + [f"the words differ: {shown!r} against {printed!r}"]
    for a, b in zip(NUMBER.findall(shown), NUMBER.findall(printed)):
        x, y = float(a), float(b)
        if abs(x) < ROUNDING or abs(y) < ROUNDING:
            if not (abs(x) < ROUNDING and abs(y) < ROUNDING):
                problems.append(f"{a} against {b}: one is rounding, the other not")
        elif abs(x - y) > _unit(a) * (1 + 1e-9):
            problems.append(f"{a} against {b}: more than one unit of the last digit apart")
    return problems


@pytest.mark.parametrize("shown, printed, ok", [
    ("cost 3.972 (raw 5.33), 0.066 s + 0.221 s optimising", "cost 3.973 (raw 5.33), 1.5 s + 0.3 s optimising", True),
    ("cost 3.972 (raw 5.33)", "cost 3.974 (raw 5.33)", False),
    ("cost 3.972 (raw 5.33)", "cost 3.972 (raw 5.34)", True),
    ("cost 3.972 (raw 5.33)", "cost 3.972 (raw 5.35)", False),
    ("91 waypoints", "89 waypoints", False),
    ("91 waypoints", "91 nodes", False),
    ("deviation 8.82e-14 m; 45x realtime", "deviation 9.26e-14 m; 14x realtime", True),
    ("deviation 8.82e-14 m", "deviation 2.1e-06 m", False),
    ("t = 121.36 s", "t = 121.37 s", True),
    ("t = 121.36 s", "t = 119.84 s", False),
    ("collision-free; 45x realtime", "collision-free", False),
])
def test_the_comparison_takes_numbers_to_their_printed_precision(shown, printed, ok):
    assert (not same_within_printing(shown, printed)) is ok


def test_the_readme_shows_the_makefiles_demo_commands():
    commands = demo_commands()
    assert len(commands) == 3
    assert [line for line in readme_block() if line.startswith(SHOWN)] == commands


@pytest.mark.slow
def test_the_readme_demo_lines_are_what_the_demo_prints(tmp_path):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
               MPLBACKEND="Agg")
    block = readme_block()
    starts = [i for i, line in enumerate(block) if line.startswith(SHOWN)]
    for at, end in zip(starts, [*starts[1:], len(block)]):
        argv = block[at][len(SHOWN):].split()
        argv = [a.replace("out/", f"{tmp_path}/", 1) if a.startswith("out/") else a for a in argv]
        run = subprocess.run([sys.executable, "-m", "drake_social.cli", *argv], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600, check=False)
        assert run.returncode == 0, run.stderr[-3000:]
        printed = run.stdout.splitlines()
        for shown in block[at + 1 : end]:
            head = shown.split(":")[0] + ":"
            matches = [line for line in printed if line.startswith(head)]
            assert len(matches) == 1, (shown, printed)
            assert not same_within_printing(shown, matches[0]), (shown, matches[0], same_within_printing(
                shown, matches[0]))
