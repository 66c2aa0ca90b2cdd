"""MkDocs hook: the pages made from the repository rather than written in docs/.

* ``index.md`` is README.md, its links into ``docs/`` made relative to the site.
* ``api/index.md`` ("Using the library") is the user's API first: the
  functions a script calls (:data:`USER_API`: load a scenario, make a checker,
  plan, build the diagram, simulate, measure the path or the run, the commands
  as ``run_*`` functions, the people and map readers), each one's reference in full.
* ``api/<name>.md`` is one API reference page per package or public top-level
  module of ``drake_social`` (``::: drake_social.<name>``, rendered by
  mkdocstrings from the docstrings), listed under "API reference" in the nav.
  A new package gets its page without editing mkdocs.yml.
* ``api/internals.md`` holds what serves the command line and the library's
  own functions, apart: the modules of :data:`INTERNAL_MODULES` and the
  members of :data:`INTERNAL_MEMBERS` (left out of their module's page).
"""

from __future__ import annotations

import re
from pathlib import Path

from mkdocs.structure.files import File

_ROOT = Path(__file__).resolve().parents[2]
_PACKAGE = _ROOT / "drake_social"

#: The user's API, in the order a script meets it: (section, objects by the
#: module that defines them). Rendered in full on "Using the library"; their
#: modules' pages leave them out (one home each) and link there.
USER_API = (
    ("Scenarios", ("drake_social.scenario.load.load_scenario",)),
    ("Checking and planning", ("drake_social.collision.drake_checker.make_checker",
                               "drake_social.planning.algorithms.plan")),
    ("Executing", ("drake_social.sim.diagram.build_diagram", "drake_social.sim.run.simulate",
                   "drake_social.sim.station.make_station", "drake_social.sim.autonomy.make_autonomy")),
    ("Measuring", ("drake_social.evaluation.metrics.path_metrics",
                   "drake_social.evaluation.nav_metrics.execution_metrics")),
    ("The commands as functions", ("drake_social.app.run_show", "drake_social.app.run_plan",
                                   "drake_social.app.run_simulate", "drake_social.app.run_study",
                                   "drake_social.app.run_crowd_experiment", "drake_social.app.run_recorded_experiment",
                                   "drake_social.app.run_people_import",
                                   "drake_social.map_tools.inspect_map", "drake_social.map_tools.write_map_scenario")),
    ("People", ("drake_social.people.compose.people_model", "drake_social.scenario.people_file.read_people_file",
                "drake_social.people.eth_ucy.parse_eth_ucy", "drake_social.people.eth_ucy.convert")),
    ("Maps", ("drake_social.maps.read.read_map", "drake_social.maps.boxes.map_boxes",
              "drake_social.maps.generate.office_floor_layout", "drake_social.maps.generate.write_map")),
)
#: Top-level modules that serve the command line or the build, not a script:
#: argument checks at the door, the parser, the progress bar, the kernels' warm-up.
INTERNAL_MODULES = ("arguments", "cli", "cli_parser", "cli_progress", "warmup")
#: Public members that only other library functions call (``simulate`` checks
#: and builds through them), by module.
INTERNAL_MEMBERS = {
    "drake_social.sim.diagram": ("build_checked",),
    "drake_social.sim.station": ("station_checked",),
    "drake_social.sim.autonomy": ("autonomy_checked", "check_path_source", "path_source"),
    "drake_social.sim.checks": ("check_diagram_options", "check_diagram_waypoints", "resolve_replan"),
}


def user_api_names() -> list[str]:
    """Every object of :data:`USER_API`, in order."""
    return [name for _, names in USER_API for name in names]


def api_modules() -> list[str]:
    """The documented names below ``drake_social``: its packages and public
    modules, sorted, without :data:`INTERNAL_MODULES`."""
    names = [p.name for p in _PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").is_file()]
    names += [p.stem for p in _PACKAGE.glob("*.py") if not p.stem.startswith("_")]
    return sorted(n for n in names if n not in INTERNAL_MODULES)


def _left_out(module: str) -> list[str]:
    """The members of ``module`` rendered elsewhere: the user's API and the internals."""
    return sorted({n.rpartition(".")[2] for n in user_api_names() if n.rpartition(".")[0] == module}
                  | set(INTERNAL_MEMBERS.get(module, ())))


def _directive(module: str) -> list[str]:
    """``::: module``, with a filter leaving out :func:`_left_out`'s members."""
    names = _left_out(module)
    if not names:
        return [f"::: {module}", ""]
    filters = ", ".join(['"!^_"', *(f'"!^{re.escape(n)}$"' for n in names)])
    return [f"::: {module}", "    options:", f"      filters: [{filters}]", ""]


def user_api_page() -> str:
    """The Markdown of "Using the library": each object of :data:`USER_API` in full, by section."""
    lines = ["# Using the library", "",
             "The functions a script calls, in the order it meets them; every other public name is on its "
             "package's page, and what serves the command line is under [internals](internals.md).", ""]
    for section, names in USER_API:
        lines += [f"## {section}", ""]
        for name in names:
            lines += [f"::: {name}", "    options:", "      heading_level: 3", ""]
    return "\n".join(lines)


def internals_page() -> str:
    """The Markdown of the internals page: :data:`INTERNAL_MEMBERS`, then :data:`INTERNAL_MODULES`."""
    lines = ["# Internals", "",
             "What serves the command line and the library's own functions; a script does not need it.", ""]
    for module, names in INTERNAL_MEMBERS.items():
        lines += [f"## `{module}`", ""]
        for name in names:
            lines += [f"::: {module}.{name}", "    options:", "      heading_level: 3", ""]
    for name in INTERNAL_MODULES:
        lines += [f"::: drake_social.{name}", ""]
    return "\n".join(lines)


def api_page(name: str) -> str:
    """The Markdown of ``name``'s API page: for a package of several modules,
    its docstring, then each of its modules (subpackages' included) in turn,
    so that an object re-exported by the package appears once, under its own
    module; for a module or a package of one file, all of it."""
    lines = [f"# `drake_social.{name}`", ""]
    path = _PACKAGE / name
    here = [n.rpartition(".")[2] for n in user_api_names() if n.startswith(f"drake_social.{name}.")]
    if here:
        lines += ["Its functions of the user's API are on [Using the library](index.md): "
                  + ", ".join(f"`{n}`" for n in here) + ".", ""]
    if not path.is_dir() or not [m for m in path.rglob("*.py") if m.name != "__init__.py"]:
        return "\n".join([*lines, *_directive(f"drake_social.{name}")])
    lines += [f"::: drake_social.{name}", "    options:", "      members: false", "      show_root_heading: false", ""]
    for module in sorted(path.rglob("*.py")):
        parts = module.relative_to(_PACKAGE.parent).with_suffix("").parts
        if any(p.startswith("_") for p in parts[2:-1]) or (parts[-1].startswith("_") and parts[-1] != "__init__"):
            continue
        if parts[-1] == "__init__":
            if module.parent == path:
                continue
            parts = parts[:-1]
        lines += _directive(".".join(parts))
    return "\n".join(lines)


def readme_as_index(text: str) -> str:
    """README.md with its ``docs/...`` links and images pointing inside the site."""
    return re.sub(r"\]\(docs/", "](", text)


def api_nav() -> list:
    """The "API reference" section of the nav: the user's API first, then
    the packages, then the internals."""
    return [{"Using the library": "api/index.md"},
            {"Packages and modules": [{name: f"api/{name}.md"} for name in api_modules()]},
            {"Internals": "api/internals.md"}]


def on_config(config, **kwargs):
    nav = config["nav"]
    if not any(isinstance(entry, dict) and "API reference" in entry for entry in nav):
        nav.append({"API reference": api_nav()})
    return config


def on_files(files, config, **kwargs):
    readme = (_ROOT / "README.md").read_text(encoding="utf-8")
    files.append(File.generated(config, "index.md", content=readme_as_index(readme)))
    files.append(File.generated(config, "api/index.md", content=user_api_page()))
    files.append(File.generated(config, "api/internals.md", content=internals_page()))
    for name in api_modules():
        files.append(File.generated(config, f"api/{name}.md", content=api_page(name)))
    return files
