"""MkDocs hook: the pages made from the repository rather than written in docs/.

* ``index.md`` is README.md, its links into ``docs/`` made relative to the site.
* ``api/<name>.md`` is one API reference page per package or public top-level
  module of ``drake_social`` (``::: drake_social.<name>``, rendered by
  mkdocstrings from the docstrings), listed under "API reference" in the nav.
  A new package gets its page without editing mkdocs.yml.
"""

from __future__ import annotations

import re
from pathlib import Path

from mkdocs.structure.files import File

_ROOT = Path(__file__).resolve().parents[2]
_PACKAGE = _ROOT / "drake_social"


def api_modules() -> list[str]:
    """The documented names below ``drake_social``: its packages and public modules, sorted."""
    names = [p.name for p in _PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").is_file()]
    names += [p.stem for p in _PACKAGE.glob("*.py") if not p.stem.startswith("_")]
    return sorted(names)


def api_page(name: str) -> str:
    """The Markdown of ``name``'s API page: for a package of several modules,
    its docstring, then each of its modules (subpackages' included) in turn,
    so that an object re-exported by the package appears once, under its own
    module; for a module or a package of one file, all of it."""
    lines = [f"# `drake_social.{name}`", ""]
    path = _PACKAGE / name
    if not path.is_dir() or not [m for m in path.rglob("*.py") if m.name != "__init__.py"]:
        return "\n".join([*lines, f"::: drake_social.{name}", ""])
    lines += [f"::: drake_social.{name}", "    options:", "      members: false", "      show_root_heading: false", ""]
    for module in sorted(path.rglob("*.py")):
        parts = module.relative_to(_PACKAGE.parent).with_suffix("").parts
        if any(p.startswith("_") for p in parts[2:-1]) or (parts[-1].startswith("_") and parts[-1] != "__init__"):
            continue
        if parts[-1] == "__init__":
            if module.parent == path:
                continue
            parts = parts[:-1]
        lines += [f"::: {'.'.join(parts)}", ""]
    return "\n".join(lines)


def readme_as_index(text: str) -> str:
    """README.md with its ``docs/...`` links and images pointing inside the site."""
    return re.sub(r"\]\(docs/", "](", text)


def on_config(config, **kwargs):
    nav = config["nav"]
    if not any(isinstance(entry, dict) and "API reference" in entry for entry in nav):
        nav.append({"API reference": [{name: f"api/{name}.md"} for name in api_modules()]})
    return config


def on_files(files, config, **kwargs):
    readme = (_ROOT / "README.md").read_text(encoding="utf-8")
    files.append(File.generated(config, "index.md", content=readme_as_index(readme)))
    for name in api_modules():
        files.append(File.generated(config, f"api/{name}.md", content=api_page(name)))
    return files
