"""Griffe extension: the docstrings' Sphinx roles as Markdown code spans.

The docstrings cite other objects the Sphinx way (``:func:`~drake_social.sim.simulate```);
MkDocs renders Markdown, so each role becomes a code span of the name
(``simulate``; with ``~``, its last component, as Sphinx shows it).
"""

from __future__ import annotations

import re

from griffe import Extension

ROLE = re.compile(r":(?:py:)?(?:class|func|meth|attr|data|mod|exc|obj|const):`(~?)([^`]+)`")


def markdown_roles(text: str) -> str:
    """``text`` with every Sphinx cross-reference role replaced by a code span."""

    def span(match: re.Match) -> str:
        name = match.group(2).strip()
        return f"`{name.rsplit('.', 1)[-1] if match.group(1) else name}`"

    return ROLE.sub(span, text)


class SphinxRoles(Extension):
    """Rewrites each object's docstring as it is loaded."""

    def on_instance(self, *, obj, **kwargs) -> None:
        if obj.docstring is not None:
            obj.docstring.value = markdown_roles(obj.docstring.value)
