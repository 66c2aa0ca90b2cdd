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
        page = f"# `drake_social.{name}`\n\n::: drake_social.{name}\n"
        files.append(File.generated(config, f"api/{name}.md", content=page))
    return files
