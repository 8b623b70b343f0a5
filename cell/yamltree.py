"""YAML read for validation: every node keeps its line, and errors name the file,
the line and the field path and say what would be valid.

Loading uses yaml's safe composer only: a tag outside YAML's plain types is an
error, never constructed.
"""

from __future__ import annotations

import datetime
import difflib
import math
import re
import unicodedata
from collections.abc import Callable, Iterable
from typing import Any, TypeVar

import yaml

from cell.errors import JobError
from cell.yamlsafe import LEADING_ZERO

__all__ = ["Checker", "Errors", "Node", "nearest", "same_text", "shown", "to_tree"]

_T = TypeVar("_T")


class Node:
    """A YAML value with its line, for error messages; `source`, a plain (unquoted)
    scalar's text as written (`010`, `yes`, `~`), which YAML 1.1 may read as another
    value (8, True, None): a name's message quotes what the user wrote."""

    def __init__(self, value: Any, line: int, source: str | None = None) -> None:
        self.value = value
        self.line = line
        self.source = source


_WITH_UNIT = re.compile(r"\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*[^\W\d_]+[/^²³\w]*\s*")
_SCIENTIFIC = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)[eE][-+]?\d+")
_SAFE_TAGS = frozenset(t for t in yaml.SafeLoader.yaml_constructors if t)


def to_tree(node: yaml.Node, path: str) -> Node:
    line = node.start_mark.line + 1
    if node.tag not in _SAFE_TAGS:
        raise JobError(
            f"{path}, line {line}: YAML tag {node.tag} is not allowed in a job file "
            "(plain mappings, lists, text and numbers only)"
        )
    if isinstance(node, yaml.MappingNode):
        out: dict[str, Node] = {}
        for k, v in node.value:
            key = (
                yaml.safe_load(yaml.serialize(k)) if not isinstance(k, yaml.ScalarNode) else k.value
            )
            if str(key) in out:
                raise JobError(f"{path}, line {k.start_mark.line + 1}: key {key!r} appears twice")
            out[str(key)] = to_tree(v, path)
        return Node(out, line)
    if isinstance(node, yaml.SequenceNode):
        return Node([to_tree(v, path) for v in node.value], line)
    # resolve the scalar with the safe constructor alone (no reader nor parser built for it)
    value = yaml.constructor.SafeConstructor().construct_object(node, deep=True)  # type: ignore[no-untyped-call]
    plain = isinstance(node, yaml.ScalarNode) and not node.style  # libyaml: "", PyYAML: None
    return Node(value, line, node.value if plain else None)


def same_text(a: str, b: str) -> bool:
    """`a` and `b` are the same text, written in the same or another Unicode normal form
    (an `é` composed, or `e` and a combining accent: one name on screen)."""
    return a == b or unicodedata.normalize("NFC", a) == unicodedata.normalize("NFC", b)


# Characters that show nothing on screen: controls, format characters (a zero-width
# space, a byte-order mark, a direction mark), private-use and unassigned code points,
# line and paragraph separators
_UNSEEN = frozenset(("Cc", "Cf", "Co", "Cn", "Zl", "Zp"))


def unseen_problem(text: str) -> str:
    """What makes `text` look like another text on screen ("" if nothing): a character
    that shows nothing (named by its code point), or a space at either end."""
    for i, ch in enumerate(text):
        if unicodedata.category(ch) in _UNSEEN:
            name = unicodedata.name(ch, "a control or unassigned character")
            return (
                f"holds an invisible character, U+{ord(ch):04X} {name}, at position {i + 1}: "
                "write it without (pasted from a web page or a spreadsheet?)"
            )
    if not text.strip():
        return "is blank; give a name"
    if text != text.strip():
        return "begins or ends with a space: write it without"
    return ""


def look_alike(a: str, b: str) -> str:
    """How `a` differs from `b` where the two are one text to the eye but not the same
    (not `same_text`): written with compatibility characters (full-width letters, a
    ligature, a superscript: equal under NFKC), each named by code point; "" otherwise."""
    if same_text(a, b) or unicodedata.normalize("NFKC", a) != unicodedata.normalize("NFKC", b):
        return ""
    odd = [ch for ch in dict.fromkeys(a + b) if unicodedata.normalize("NFKC", ch) != ch]
    return ", ".join(f"U+{ord(ch):04X} {unicodedata.name(ch, '?')}" for ch in odd)


def on_screen(text: str) -> str:
    """`text` with every character that shows nothing written as its code point."""
    return "".join(
        f"<U+{ord(ch):04X}>" if unicodedata.category(ch) in _UNSEEN else ch for ch in text
    )


def nearest(v: str, choices: Iterable[str]) -> str:
    """`; did you mean 'cube50'?` for a name written in another case or width (`Cube50`,
    `ｃube50`, a key `Bins`), else of a near spelling (`cube-50`); "" where none is near."""
    names = list(choices)
    folded = unicodedata.normalize("NFKC", v).casefold()
    near = [ch for ch in names if unicodedata.normalize("NFKC", ch).casefold() == folded]
    near = near or difflib.get_close_matches(v, names, n=1, cutoff=0.75)
    return f"; did you mean {' or '.join(map(repr, near))}?" if near else ""


def shown(value: Any, limit: int = 60) -> str:
    """A value as an error message quotes it: lists and mappings with their plain values
    (not the tree's nodes), cut to `limit` characters."""

    def plain(v: Any) -> Any:
        v = v.value if isinstance(v, Node) else v
        if isinstance(v, list):
            return [plain(x) for x in v]
        if isinstance(v, dict):
            return {k: plain(x) for k, x in v.items()}
        return v

    text = repr(plain(value))
    return text if len(text) <= limit else text[: limit - 1] + "…"


class Checker:
    def __init__(self, path: str) -> None:
        self.path = path

    def fail(self, node: Node, field_path: str, msg: str) -> JobError:
        where = f", {field_path}" if field_path else " (the whole file)"
        return JobError(f"{self.path}, line {node.line}{where}: {msg}")

    def mapping(self, node: Node, fp: str, allowed: dict[str, str]) -> dict[str, Node]:
        if not isinstance(node.value, dict):
            raise self.fail(node, fp, f"must be a mapping with keys {sorted(allowed)}")
        for k, v in node.value.items():
            if k not in allowed:
                # `{mass_kg: 0,05}` is two entries, mass_kg 0 and a key 05 of no value
                comma = (
                    f" (a decimal comma? in {{…}} YAML reads `N,{k}` as the number N and a key "
                    f"{k}: write N.{k}; a thousands separator: write N{k})"
                    if k.isdigit() and v.value is None
                    else ""
                )
                raise self.fail(
                    v,
                    f"{fp}.{k}" if fp else k,
                    f"unknown key {k!r}{comma}{nearest(k, allowed)}; valid keys here: "
                    + ", ".join(sorted(allowed)),
                )
        return node.value

    def number(
        self,
        node: Node,
        fp: str,
        *,
        lo: float | None = None,
        hi: float | None = None,
        strict_lo: bool = False,
    ) -> float:
        if said := _misread(node, "a number"):
            raise self.fail(node, fp, said)
        v = node.value
        if isinstance(v, str) and _SCIENTIFIC.fullmatch(v.strip()):
            v = float(v)  # YAML 1.1 reads 5e-2 (no dot) as text; the parameter loader does not
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(float(v)):
            raise self.fail(node, fp, f"{shown(v)} must be a {'finite ' * _nonfinite(v)}number"
                            + _quoted_number(v))  # fmt: skip
        v = float(v)
        if lo is not None and (v <= lo if strict_lo else v < lo):
            raise self.fail(node, fp, f"{v} must be {'>' if strict_lo else '≥'} {lo}")
        if hi is not None and v > hi:
            raise self.fail(node, fp, f"{v} must be ≤ {hi}")
        return v

    def integer(self, node: Node, fp: str, lo: int, hi: int) -> int:
        if said := _misread(node, f"a whole number from {lo} to {hi}"):
            raise self.fail(node, fp, said)
        v = node.value
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
            raise self.fail(
                node, fp, f"{shown(v)} must be a whole number from {lo} to {hi}" + _quoted_number(v)
            )
        return int(v)

    def text(self, node: Node, fp: str, choices: tuple[str, ...] | None = None) -> str:
        v = node.value
        if not isinstance(v, str) or not v:
            raise self.fail(node, fp, not_text(v, node.source, choices))
        unseen = unseen_problem(v)
        if unseen:
            raise self.fail(node, fp, f"{on_screen(v)!r} {unseen}")
        if choices and v not in choices:
            # the same text in another Unicode form (a decomposed é from another editor)
            same = [ch for ch in choices if same_text(ch, v)]
            if same:
                return same[0]
            alike = [(ch, look_alike(v, ch)) for ch in choices if look_alike(v, ch)]
            hint = (
                f" ({v!r} is not {alike[0][0]!r}: it holds {alike[0][1]})"
                if alike
                else nearest(v, choices)
            )
            raise self.fail(
                node,
                fp,
                f"{v!r} is not valid; choose one of {', '.join(map(on_screen, choices))}{hint}",
            )
        return v

    def vector(
        self, node: Node, fp: str, n: int, *, positive: bool = False, hint: str = ""
    ) -> tuple[float, ...]:
        """A list of `n` finite numbers (`positive`: each > 0); `hint` says what they are
        where the list has another length."""
        if not isinstance(node.value, list) or len(node.value) != n:
            said = f" ({hint})" if hint and isinstance(node.value, list) else ""
            raise self.fail(node, fp, f"must be a list of {n} numbers{said}")
        return tuple(
            self.number(x, f"{fp}[{i}]", lo=0.0 if positive else None, strict_lo=positive)
            for i, x in enumerate(node.value)
        )


def not_text(v: Any, source: str | None, choices: tuple[str, ...] | None = None) -> str:
    """What to say of a name's value `v` that is not text, written `source` (None: in
    quotes, or not a scalar): YAML 1.1 reads a plain `yes`, `off` or `~` as a boolean or no
    value, `010` as the number 8, `2026-12-01` as a date; the message quotes the text
    written and what YAML made of it, and says to quote it (or, where the name is one of
    `choices`, which are valid)."""
    what = _read_as(v, source)
    if v is None and not source:
        return "has no value: give a name" if not choices else (
            f"has no value; choose one of {', '.join(map(on_screen, choices))}"
        )  # fmt: skip
    if not what or source is None:
        return f"{shown(v)} must be a non-empty text"
    number = isinstance(v, (int, float)) and not isinstance(v, bool)  # a name, as before
    if choices and not number and not any(same_text(source, ch) for ch in choices):
        return f"{source} is {what}; choose one of {', '.join(map(on_screen, choices))}"
    return f"{source} is {what}; this is a name: write it in quotes, '{source}'"


def _read_as(v: Any, source: str | None) -> str:
    """What YAML 1.1 made of the plain scalar `source` ("" where it is text, or `source`
    is None): a boolean, no value, a number (said where it reads otherwise), a date."""
    if source is None:
        return ""
    if isinstance(v, bool):
        return "a boolean to YAML (yes, no, on, off, true and false are)"
    if isinstance(v, (int, float)):
        return "a number" + (f" to YAML ({v})" if source != str(v) else "")
    if v is None and source:
        return "no value to YAML (null; ~ and null are)"
    if isinstance(v, (datetime.date, datetime.datetime)):
        return "a date to YAML"
    return ""


_LEADING_ZERO = re.compile(LEADING_ZERO)


def _misread(node: Node, want: str) -> str:
    """What to say of a number field's plain value that YAML 1.1 read as another: written
    with a leading zero (`_leading_zero`), or a boolean or no value (`_read_as`; `want`,
    what to give instead); "" for any other value."""
    if said := _leading_zero(node.source):
        return said
    v = node.value
    if (isinstance(v, bool) or v is None) and (what := _read_as(v, node.source)):
        return f"{node.source} is {what}; give {want}"
    return ""


def _leading_zero(source: str | None) -> str:
    """What to say of a plain number written with a leading zero (`010`, `0010`, `09`; ""
    for anything else): YAML 1.1 reads `010` as the octal 8 (a count of 10 would be 8
    items) and `09`, no octal, as text; written in quotes, it is text (the field says so)."""
    if source is None or not _LEADING_ZERO.fullmatch(source):
        return ""
    digits = source.replace("_", "")
    try:
        read = f"the octal number {int(digits, 8)}"
    except ValueError:
        read = "text (a leading 0 marks an octal number, whose digits are 0-7)"
    return f"{source} has a leading 0, which YAML reads as {read}: write {int(digits, 10)}"


def _nonfinite(v: Any) -> bool:
    """Is `v` a number that is not finite (.inf, .nan)?"""
    return isinstance(v, float) and not math.isfinite(v)


def _quoted_number(v: Any) -> str:
    """What to say of a text that reads as a number ("" for anything else): in quotes,
    YAML keeps it text."""
    if not isinstance(v, str):
        return ""
    if _SCIENTIFIC.fullmatch(v.strip()):  # `count: 1e3`: YAML 1.1 needs a dot, so text
        f = float(v)
        whole = f"{f:.0f}" if math.isfinite(f) and f.is_integer() else ""
        return f" (written with an exponent{': write ' + whole if whole else ''})"
    if _WITH_UNIT.fullmatch(v):
        return (
            " (a number with a unit: the unit is the key's, _m metres, _kg kilograms, _s "
            "seconds, _mps m/s; write the number alone, in that unit)"
        )
    try:
        if not math.isfinite(float(v.strip())):
            return ""
    except ValueError:
        return ""
    return " (it is in quotes, so YAML reads it as text: write it without the quotes)"


class Errors:
    """The errors of a job, collected so that one report names them all."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.messages: list[str] = []

    def add(self, exc: JobError) -> None:
        self.messages.append(str(exc))

    def run(self, fn: Callable[..., _T], *args: Any) -> _T | None:
        """fn(*args), or None with its JobError kept."""
        try:
            return fn(*args)
        except JobError as exc:
            self.add(exc)
            return None

    def raise_all(self) -> None:
        """JobError with every message, one a line (none: nothing)."""
        if len(self.messages) == 1:
            raise JobError(self.messages[0])
        if self.messages:
            raise JobError(
                f"{self.path}: {len(self.messages)} errors:\n" + "\n".join(self.messages)
            )
