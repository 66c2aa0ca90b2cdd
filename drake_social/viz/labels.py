"""User text drawn in figures (descriptions, person names), cut to a bounded size.

Matplotlib lays out and renders every character of a text artist: a
megabyte-long scenario description as a figure title costs about a gigabyte
and minutes. Every text taken from a scenario goes through :func:`fit_text`
before it is drawn, so a figure's text costs the same whatever the input.
"""

from __future__ import annotations

__all__ = ["MAX_LABEL_CHARS", "MAX_TITLE_CHARS", "MAX_TITLE_LINES", "ELLIPSIS", "fit_text"]

#: Longest line of a figure title, characters (the narrowest figure with a
#: title, a square map's 10.4 inches, holds about 110 at the title's 12 pt).
MAX_TITLE_CHARS = 100
#: Most lines of a figure title (the map figures have room for one, the
#: tracking figure for two).
MAX_TITLE_LINES = 2
#: Longest label next to a person on the map, characters.
MAX_LABEL_CHARS = 40
#: Marks where a text was cut.
ELLIPSIS = "\u2026"


def fit_text(text: str, max_chars: int = MAX_TITLE_CHARS, max_lines: int = MAX_TITLE_LINES) -> str:
    """The first ``max_lines`` lines of ``text``, each cut to ``max_chars``
    characters; a cut line, or the last line when lines were left out, ends
    in :data:`ELLIPSIS`. Lines are not wrapped: the figures' layouts are
    fixed, with room for a known number of title lines.

    Only the first ``max_lines * (max_chars + 1) + 1`` characters are
    looked at, so the cost does not depend on the length of ``text``.

    Args:
        text: the text (any length).
        max_chars: characters per line, >= 1 (the ellipsis included).
        max_lines: lines, >= 1.

    Raises:
        ValueError: ``max_chars`` or ``max_lines`` < 1.
    """
    if max_chars < 1 or max_lines < 1:
        raise ValueError(f"max_chars and max_lines must be >= 1, got {max_chars} and {max_lines}")
    head = text[: max_lines * (max_chars + 1) + 1]
    cut = len(head) < len(text)
    if not cut:
        head = head.rstrip("\n")
    lines = head.split("\n")
    more = len(lines) > max_lines or cut
    lines = lines[:max_lines]
    out = []
    for k, line in enumerate(lines):
        if len(line) > max_chars or (k == len(lines) - 1 and more):
            line = line[: max_chars - 1] + ELLIPSIS
        out.append(line)
    return "\n".join(out)
