"""Reading the figures README.md and the guide pages under docs/ quote: each quote is found by
a pattern, and the spans of the numbers it captured are noted, so that
tests/test_readme_figures.py can tell a number with a source from one without."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# the pages whose numbers must each have a source: README.md and every guide page under
# docs/ (a new page is covered as soon as it exists), but for the exemptions below
NOT_CHECKED = (
    "docs/HISTORY.md",  # a dated record of past measurements at named commits
)
PAGES = ("README.md",) + tuple(
    p
    for p in sorted(f"docs/{f.name}" for f in (ROOT / "docs").glob("*.md"))
    if p not in NOT_CHECKED
)
COVERED: dict[str, list[tuple[int, int]]] = {p: [] for p in PAGES}


def page_text(page: str) -> str:
    return (ROOT / page).read_text()


def load_json(rel: str) -> dict:
    path = ROOT / rel
    assert path.is_file(), f"{rel} is missing: run `make figures`"
    return json.loads(path.read_text())


def note(page: str, m: re.Match) -> None:
    COVERED[page].extend(m.span(g) for g in range(1, (m.re.groups or 0) + 1) if m.group(g))


def quoted(page: str, pattern: str) -> tuple[str, ...]:
    """The groups of the first match of `pattern` on `page` (spaces match any whitespace)."""
    m = re.search(pattern.replace(" ", r"\s+"), page_text(page), flags=re.S)
    assert m, f"{page} no longer quotes {pattern!r}"
    note(page, m)
    return m.groups()


def every(page: str, pattern: str) -> list[tuple[str, ...]]:
    """The groups of every match of `pattern` on `page` (at least one)."""
    ms = list(re.finditer(pattern.replace(" ", r"\s+"), page_text(page)))
    assert ms, f"{page} no longer quotes {pattern!r}"
    for m in ms:
        note(page, m)
    return [m.groups() for m in ms]


def num(s: str) -> float:
    return float(s.replace(",", ""))


def close(quoted: str, value: float, digits: int) -> None:
    """`quoted` is `value` as written to `digits` decimals (half a unit of the last one)."""
    assert num(quoted) == pytest.approx(value, abs=0.5 * 10**-digits + 1e-9), (quoted, value)
