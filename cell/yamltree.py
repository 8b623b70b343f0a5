"""YAML read for validation: every node keeps its line, and errors name the file,
the line and the field path and say what would be valid.

Loading uses yaml's safe composer only: a tag outside YAML's plain types is an
error, never constructed.
"""

from __future__ import annotations

import math
import re
import unicodedata
from collections.abc import Callable
from typing import Any, TypeVar

import yaml

from cell.errors import JobError

__all__ = ["Checker", "Errors", "Node", "same_text", "shown", "to_tree"]

_T = TypeVar("_T")


class Node:
    """A YAML value with its line, for error messages."""

    def __init__(self, value: Any, line: int) -> None:
        self.value = value
        self.line = line


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
    return Node(value, line)


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
                    f"{k}: write N.{k})"
                    if k.isdigit() and v.value is None
                    else ""
                )
                raise self.fail(
                    v,
                    f"{fp}.{k}" if fp else k,
                    f"unknown key {k!r}{comma}; valid keys here: {', '.join(sorted(allowed))}",
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
        v = node.value
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
            raise self.fail(
                node, fp, f"{shown(v)} must be a whole number from {lo} to {hi}" + _quoted_number(v)
            )
        return int(v)

    def text(self, node: Node, fp: str, choices: tuple[str, ...] | None = None) -> str:
        v = node.value
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            raise self.fail(
                node, fp, f"{shown(v)} is a number; this is a name: write it in quotes, '{v}'"
            )
        if not isinstance(v, str) or not v:
            raise self.fail(node, fp, f"{shown(v)} must be a non-empty text")
        unseen = unseen_problem(v)
        if unseen:
            raise self.fail(node, fp, f"{on_screen(v)!r} {unseen}")
        if choices and v not in choices:
            # the same text in another Unicode form (a decomposed é from another editor)
            same = [ch for ch in choices if same_text(ch, v)]
            if same:
                return same[0]
            alike = [(ch, look_alike(v, ch)) for ch in choices if look_alike(v, ch)]
            hint = f" ({v!r} is not {alike[0][0]!r}: it holds {alike[0][1]})" if alike else ""
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


def _nonfinite(v: Any) -> bool:
    """Is `v` a number that is not finite (.inf, .nan)?"""
    return isinstance(v, float) and not math.isfinite(v)


def _quoted_number(v: Any) -> str:
    """What to say of a text that reads as a number ("" for anything else): in quotes,
    YAML keeps it text."""
    if not isinstance(v, str):
        return ""
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
