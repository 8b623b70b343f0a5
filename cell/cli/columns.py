"""Columns of text as a terminal shows them: a bin's or an object's name may hold
characters two columns wide (CJK, emoji) or none (combining marks), and may be longer
than its column; a row wider than the terminal is broken between its cells (`fitted`),
not where the terminal wraps it (inside a number: `0.` and `074 m`)."""

from __future__ import annotations

import shutil
import sys
import unicodedata
from collections.abc import Iterable, Sequence

__all__ = ["column_width", "fitted", "pad", "shown_width", "terminal_width"]


def shown_width(text: str) -> int:
    """The columns `text` takes on a terminal: 2 for an East Asian wide or full-width
    character, 0 for a combining mark or a format character, else 1."""
    n = 0
    for ch in text:
        if unicodedata.combining(ch) or unicodedata.category(ch) in ("Mn", "Me", "Cf"):
            continue
        n += 2 if unicodedata.east_asian_width(ch) in ("W", "F") else 1
    return n


def pad(text: str, width: int) -> str:
    """`text` followed by the spaces that make it `width` columns wide (none if wider)."""
    return text + " " * max(0, width - shown_width(text))


def column_width(least: int, texts: Iterable[str]) -> int:
    """The width of a column of `texts`: its widest, at least `least`."""
    return max([least, *(shown_width(t) for t in texts)])


def terminal_width() -> int | None:
    """The columns of the terminal standard output is (`COLUMNS` where set), or None
    where it is no terminal (a file, a pipe: rows are written whole)."""
    try:
        return shutil.get_terminal_size().columns if sys.stdout.isatty() else None
    except (AttributeError, ValueError, OSError):  # a closed or replaced stream
        return None


def fitted(cells: Sequence[str], width: int | None, indent: int) -> str:
    """`cells` joined by a space, one line; where `width` is given and the line is wider,
    broken into lines no wider than `width` where the cells allow: each break before the
    cell that would pass it, the next line indented `indent` columns. A cell is never
    broken (a number stays with its unit); one wider than a line stands alone."""
    line = " ".join(cells)
    if width is None or shown_width(line) <= width:
        return line
    out, cur = [], cells[0]
    for cell in cells[1:]:
        if cur.strip() and shown_width(f"{cur} {cell.rstrip()}") > width:
            out.append(cur.rstrip())
            cur = " " * indent + cell.strip()
        else:
            cur = f"{cur} {cell}"
    return "\n".join([*out, cur.rstrip()])
