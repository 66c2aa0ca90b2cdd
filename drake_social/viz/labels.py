"""User text drawn in figures (descriptions, person names), cut to a bounded size.

Matplotlib lays out and renders every character of a text artist: a
megabyte-long scenario description as a figure title costs about a gigabyte
and minutes. Every text taken from a scenario goes through :func:`fit_text`
before it is drawn, so a figure's text costs the same whatever the input.
"""

from __future__ import annotations

import functools

__all__ = ["MAX_LABEL_CHARS", "MAX_TITLE_CHARS", "MAX_TITLE_LINES", "ELLIPSIS", "fit_text", "fit_width", "text_width"]

#: Longest line of a figure title, characters: a bound on the work, not a
#: layout (:func:`fit_width` fits a title to its figure's width).
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


#: Share of a line's room that a measured text may fill: the width rendered at
#: a figure's dpi differs from the one measured at 72 dpi by a few percent.
_HINTING_MARGIN = 0.95


@functools.lru_cache(maxsize=1)
def _renderer():
    from matplotlib.backends.backend_agg import RendererAgg

    return RendererAgg(1, 1, 72)  # 72 dpi: widths in points


def text_width(text: str, fontsize: float) -> float:
    """Rendered width of one line of ``text`` in the default font, points."""
    from matplotlib.font_manager import FontProperties

    if not text:
        return 0.0
    width, _, _ = _renderer().get_text_width_height_descent(text, FontProperties(size=fontsize), ismath=False)
    return float(width)


def _longest_fitting(text: str, width: float, fontsize: float, suffix: str = "") -> int:
    """The most leading characters of ``text`` that fit ``width`` (points) with ``suffix``."""
    lo, hi = 0, len(text)
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if text_width(text[:mid] + suffix, fontsize) <= width:
            lo = mid
        else:
            hi = mid - 1
    return lo


def fit_width(text: str, width: float, fontsize: float, max_lines: int = MAX_TITLE_LINES) -> str:
    """``text`` wrapped at spaces into lines at most ``width`` inches wide
    when drawn at ``fontsize`` points, at most ``max_lines`` of them.

    A word wider than a line is broken inside it; when the text needs more
    lines, the last one is cut and ends in :data:`ELLIPSIS`. The text is
    first bounded by :func:`fit_text` (``max_lines`` lines of
    :data:`MAX_TITLE_CHARS` characters after wrapping at most: its own lines
    are joined), so the cost does not depend on its length.

    Args:
        text: the text (any length; its line breaks are kept).
        width: the room for one line, inches (> 0).
        fontsize: points.
        max_lines: lines, >= 1.

    Raises:
        ValueError: ``width`` <= 0 or ``max_lines`` < 1.
    """
    if not width > 0 or max_lines < 1:
        raise ValueError(f"width must be > 0 and max_lines >= 1, got {width} and {max_lines}")
    room = 72.0 * width * _HINTING_MARGIN
    bounded = fit_text(text, max_chars=max_lines * MAX_TITLE_CHARS, max_lines=max_lines)
    lines: list[str] = []
    for paragraph in bounded.split("\n"):
        if text_width(paragraph, fontsize) <= room:  # the usual case: one measurement
            lines.append(paragraph)
            continue
        line = ""
        for word in paragraph.split(" "):
            candidate = f"{line} {word}" if line else word
            if text_width(candidate, fontsize) <= room:
                line = candidate
                continue
            if line:
                lines.append(line)
            while text_width(word, fontsize) > room:  # a word wider than a line: broken inside it
                k = max(1, _longest_fitting(word, room, fontsize))
                lines.append(word[:k])
                word = word[k:]
            line = word
        lines.append(line)
    cut = len(lines) > max_lines or bounded.endswith(ELLIPSIS)
    lines = lines[:max_lines]
    if cut:
        last = lines[-1].rstrip(ELLIPSIS).rstrip()
        lines[-1] = last[: _longest_fitting(last, room, fontsize, ELLIPSIS)].rstrip() + ELLIPSIS
    return "\n".join(lines)
