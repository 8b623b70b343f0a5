"""Columns of text as a terminal shows them: a bin's or an object's name may hold
characters two columns wide (CJK, emoji) or none (combining marks), and may be longer
than its column."""

from __future__ import annotations

import unicodedata
from collections.abc import Iterable

__all__ = ["column_width", "pad", "shown_width"]


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
