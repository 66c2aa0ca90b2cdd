"""The documentation: the README stays a ten-minute read, every link in it and
in docs/ reaches a file, its Python examples run, and the MkDocs site builds
with --strict (any warning, such as a docstring MkDocs cannot read, fails)."""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = ROOT / "docs"
MAX_README_LINES = 400

# [text](target) and ![alt](target); the target ends at whitespace or ")".
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
PYTHON_BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def _pages() -> list[Path]:
    return [README, *sorted(DOCS.glob("*.md"))]


def _local_links(page: Path) -> list[str]:
    """The links of ``page`` to files of the repository (not URLs, not anchors within the page)."""
    text = page.read_text(encoding="utf-8")
    text = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)  # code blocks hold no links
    targets = [m.group(1) for m in LINK.finditer(text)]
    return [t for t in targets if not re.match(r"^[a-z]+:", t) and not t.startswith("#")]


def _hooks(extra):
    extra("mkdocs")  # the docs extra: skipped where it may be missing, required where make install ran
    spec = importlib.util.spec_from_file_location("docs_hooks_pages", DOCS / "hooks" / "pages.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_readme_is_a_ten_minute_read():
    lines = README.read_text(encoding="utf-8").splitlines()
    assert 100 < len(lines) <= MAX_README_LINES, f"README.md has {len(lines)} lines"


def test_the_link_finder_sees_links_and_leaves_out_urls_and_code(tmp_path):
    dut = tmp_path / "probe.md"
    dut.write_text("[a](x.md) ![b](pics/y.png) [c](https://e.org) [d](#top) [e](cli.md#exit-codes)\n"
                   "```\n[f](inside_code.md)\n```\n", encoding="utf-8")
    assert _local_links(dut) == ["x.md", "pics/y.png", "cli.md#exit-codes"]


@pytest.mark.parametrize("page", _pages(), ids=lambda p: p.name)
def test_every_link_reaches_a_file(page):
    links = _local_links(page)
    missing = [t for t in links if not (page.parent / t.split("#")[0]).is_file()]
    assert not missing, f"{page.relative_to(ROOT)} links to missing files: {missing}"


def test_readme_links_into_docs_become_site_links(extra):
    dut = _hooks(extra)
    text = "![a](docs/office_bar.png) see [the limits](docs/limits.md) and `docs/make_figures.py`"
    assert dut.readme_as_index(text) == "![a](office_bar.png) see [the limits](limits.md) and `docs/make_figures.py`"


def test_every_package_gets_an_api_page(extra):
    dut = _hooks(extra)
    names = dut.api_modules()
    packages = {p.name for p in (ROOT / "drake_social").iterdir() if (p / "__init__.py").is_file()}
    assert packages <= set(names)
    assert {"kinematics", "limits", "map_tools", "app"} <= set(names)
    assert not [n for n in names if n.startswith("_")]
    assert names == sorted(names)


def test_the_api_reference_puts_the_users_api_first_and_the_internals_apart(extra):
    import importlib

    dut = _hooks(extra)
    nav = dut.api_nav()
    assert [next(iter(entry)) for entry in nav] == ["Using the library", "Packages and modules", "Internals"]
    names = dut.user_api_names()
    # The list: the entry points a script meets, in order, then every run_* of the app layer.
    short = [n.rpartition(".")[2] for n in names]
    assert short[:5] == ["load_scenario", "make_checker", "plan", "build_diagram", "simulate"]
    import drake_social.app as app

    assert {n for n in app.__all__ if n.startswith("run_") and n != "run_bench"} <= set(short)
    assert {"read_people_file", "parse_eth_ucy", "read_map", "map_boxes", "inspect_map",
            "write_map_scenario"} <= set(short)
    for name in names:  # each named by the module that defines it (its one home in the site)
        module, _, attr = name.rpartition(".")
        assert getattr(importlib.import_module(module), attr).__module__ == module, name
    page = dut.user_api_page()
    assert [line[4:] for line in page.splitlines() if line.startswith("::: ")] == names
    # Internals: not among the packages' pages, but on their own page, members left out of their module's.
    listed = [next(iter(e)) for e in nav[1]["Packages and modules"]]
    assert not {"arguments", "warmup", "cli_parser", "cli", "cli_progress"} & set(listed)
    assert {"scenario", "planning", "sim", "people", "maps", "app", "map_tools"} <= set(listed)
    assert dut.INTERNAL_MEMBERS["drake_social.sim.diagram"] == ("build_checked",)
    assert {"check_diagram_options", "check_diagram_waypoints", "resolve_replan"} <= set(
        dut.INTERNAL_MEMBERS["drake_social.sim.checks"])
    sim = dut.api_page("sim")
    for module, public in (("diagram", "build_diagram"), ("station", "make_station"), ("autonomy", "make_autonomy")):
        block = sim[sim.index(f"::: drake_social.sim.{module}\n"):].split("\n\n")[0]
        for member in [*dut.INTERNAL_MEMBERS[f"drake_social.sim.{module}"], public]:
            assert f'"!^{member}$"' in block, member
    assert '"!^simulate$"' in sim[sim.index("::: drake_social.sim.run\n"):].split("\n\n")[0]
    internals = dut.internals_page()
    assert "::: drake_social.sim.diagram.build_checked" in internals and "::: drake_social.warmup" in internals
    assert "::: drake_social.sim.diagram.build_checked" not in sim


def _griffe_extension(extra):
    extra("griffe")
    spec = importlib.util.spec_from_file_location("docs_hooks_roles", DOCS / "hooks" / "griffe_roles.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_sphinx_roles_become_code_spans(extra):
    dut = _griffe_extension(extra)
    text = "See :func:`~drake_social.sim.simulate`, :class:`Scenario` and :py:meth:`a.B.c`; ``kept``."
    assert dut.markdown_roles(text) == "See `simulate`, `Scenario` and `a.B.c`; ``kept``."


def test_an_entry_of_several_names_becomes_one_per_name(extra):
    dut = _griffe_extension(extra)
    text = ("Runs it.\n\nArgs:\n    scenario: a scenario.\n    mode, execution: see\n        build_diagram.\n"
            "    q_a, q_b: ends.\n\nReturns:\n    a, b: left alone outside Args and Attributes.\n")
    assert dut.split_combined_entries(text) == (
        "Runs it.\n\nArgs:\n    scenario: a scenario.\n    mode: see\n        build_diagram.\n"
        "    execution: see\n        build_diagram.\n    q_a: ends.\n    q_b: ends.\n\nReturns:\n"
        "    a, b: left alone outside Args and Attributes.")


def test_a_package_page_lists_each_module_once(extra):
    dut = _hooks(extra)
    page = dut.api_page("planning")
    directives = [line for line in page.splitlines() if line.startswith(":::")]
    assert directives[0] == "::: drake_social.planning"
    assert "::: drake_social.planning.rrt_star" in directives
    assert "::: drake_social.planning.rrt_star.tree_kernel" in directives
    assert len(directives) == len(set(directives))
    assert dut.api_page("kinematics").splitlines()[-1] == "::: drake_social.kinematics"


def _readme_examples() -> list[str]:
    return PYTHON_BLOCK.findall(README.read_text(encoding="utf-8"))


def test_readme_has_a_python_example():
    assert len(_readme_examples()) >= 1


@pytest.mark.slow
@pytest.mark.parametrize("index", range(len(_readme_examples())))
def test_readme_python_example_runs(index, tmp_path):
    code = _readme_examples()[index]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
               MPLBACKEND="Agg")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True,
                         timeout=600, check=False)
    assert out.returncode == 0, out.stderr[-3000:]
    printed = out.stdout
    # The example plans, executes and reads the diagram's outputs.
    assert re.search(r"social_rrt_star: \d+ waypoints, cost [0-9.]+", printed), printed
    assert "goal reached" in printed and "collision-free" in printed, printed
    assert not list(ROOT.glob("*.png")), "the example wrote files into the repository"


@pytest.mark.slow
def test_site_builds_strictly(tmp_path, extra):
    extra("mkdocs")
    extra("material")  # mkdocs-material
    extra("mkdocstrings_handlers", "mkdocstrings_handlers.python")
    site = tmp_path / "site"
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    out = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(site)], cwd=ROOT,
                         env=env, capture_output=True, text=True, timeout=900, check=False)
    assert out.returncode == 0, out.stderr[-5000:]
    index = (site / "index.html").read_text(encoding="utf-8")
    assert "Two commands" in index and 'src="office_bar.png"' in index
    for page in ("scenario", "people", "cli", "architecture", "performance", "testing", "limits", "memory"):
        assert (site / page / "index.html").is_file(), page
    # The API pages carry the docstrings: load_scenario's summary line is on the user's API page, which the
    # scenario page links to; build_checked is on the internals page only.
    api = (site / "api" / "index.html").read_text(encoding="utf-8")
    assert 'id="drake_social.scenario.load.load_scenario"' in api and "Loads and validates a scenario file" in api
    scenario_page = (site / "api" / "scenario" / "index.html").read_text(encoding="utf-8")
    assert "Using the library" in scenario_page and 'id="drake_social.scenario.load.load_scenario"' not in scenario_page
    assert 'id="drake_social.sim.diagram.build_checked"' in (site / "api" / "internals" / "index.html").read_text(
        encoding="utf-8")
    assert 'id="drake_social.sim.diagram.build_checked"' not in (site / "api" / "sim" / "index.html").read_text(
        encoding="utf-8")


FAST = "not slow and not browser and not subprocess"


@pytest.mark.slow
def test_the_documented_test_counts_are_the_collected_ones():
    """docs/testing.md and the Makefile say how many tests make test and make
    test-fast run: within 15 % of what pytest collects (tests are added all
    the time; a figure that far off has drifted)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    out = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider", "-m", FAST,
                          "tests"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600, check=False)
    found = re.search(r"(\d+)/(\d+) tests collected", out.stdout)
    assert found, out.stdout[-2000:] + out.stderr[-2000:]
    fast, total = int(found.group(1)), int(found.group(2))
    testing = (DOCS / "testing.md").read_text(encoding="utf-8")
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    documented = {
        "testing.md, make test": re.search(r"`make test` ran ([\d,]+) tests", testing),
        "testing.md, make test-fast": re.search(r"`make test-fast` ([\d,]+) in", testing),
        "Makefile, make test": re.search(r"make test runs them all \(([\d,]+) tests", makefile),
        "Makefile, make test-fast": re.search(r"three out \(([\d,]+) tests", makefile),
    }
    for where, match in documented.items():
        assert match, f"{where}: no count found"
        count = int(match.group(1).replace(",", ""))
        actual = total if where.endswith("make test") else fast
        assert abs(count - actual) <= 0.15 * actual, f"{where} says {count}, pytest collects {actual}"
