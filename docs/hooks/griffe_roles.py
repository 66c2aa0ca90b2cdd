"""Griffe extension: the docstrings as this project writes them, read as Google style.

* Sphinx roles (``:func:`~drake_social.sim.simulate```) become Markdown code
  spans of the name (with ``~``, its last component, as Sphinx shows it).
* An entry naming several parameters or attributes at once
  (``q_a, q_b: configurations (..., 4).``) becomes one entry per name, each
  with the whole description, so that every name is still checked against
  the signature.
"""

from __future__ import annotations

import re

from griffe import Extension

ROLE = re.compile(r":(?:py:)?(?:class|func|meth|attr|data|mod|exc|obj|const):`(~?)([^`]+)`")
NAMED_SECTION = re.compile(
    r"^(Args|Arguments|Parameters|Params|Attributes|Keyword Args|Keyword Arguments|Other Parameters):\s*$")
COMBINED_ENTRY = re.compile(r"^(\s+)(\w+(?:\s*,\s*\w+)+)(:\s.*|:)$")


def markdown_roles(text: str) -> str:
    """``text`` with every Sphinx cross-reference role replaced by a code span."""

    def span(match: re.Match) -> str:
        name = match.group(2).strip()
        return f"`{name.rsplit('.', 1)[-1] if match.group(1) else name}`"

    return ROLE.sub(span, text)


def split_combined_entries(text: str) -> str:
    """``text`` (a dedented docstring) with each ``a, b: description`` entry of
    an Args or Attributes section repeated once per name."""
    lines = text.splitlines()
    out: list[str] = []
    in_section = False
    i = 0
    while i < len(lines):
        line = lines[i]
        if NAMED_SECTION.match(line):
            in_section = True
        elif line and not line[0].isspace():
            in_section = False
        match = COMBINED_ENTRY.match(line) if in_section else None
        if not match:
            out.append(line)
            i += 1
            continue
        indent, names, rest = match.groups()
        body = [rest]
        i += 1
        while i < len(lines) and lines[i].strip() and len(lines[i]) - len(lines[i].lstrip()) > len(indent):
            body.append("\n" + lines[i])
            i += 1
        for name in (n.strip() for n in names.split(",")):
            out.append(indent + name + "".join(body))
    return "\n".join(out)


class SphinxRoles(Extension):
    """Rewrites each object's docstring as it is loaded."""

    def on_instance(self, *, obj, **kwargs) -> None:
        if obj.docstring is not None:
            obj.docstring.value = split_combined_entries(markdown_roles(obj.docstring.value))
