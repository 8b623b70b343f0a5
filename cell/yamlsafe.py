"""YAML from untrusted files, bounded before anything is built.

A job, a parameter file or a Dynamixel configuration comes from a user. YAML's
anchors and aliases let a few hundred bytes expand into gigabytes ("billion
laughs"), and deep nesting exhausts the stack. Here the text is first read as a
stream of parser events, which costs time and memory in proportion to its size:
a file larger than MAX_BYTES, any alias, nesting deeper than MAX_DEPTH or more
than MAX_NODES values is refused before a single node is composed.

The text is parsed by libyaml (`yaml.CSafeLoader`, when PyYAML was built with it) and, only
when libyaml finds an error, again by PyYAML's own Python parser, whose messages (the ones
quoted to the user, e.g. a tab said as such) are the words of the error; a text libyaml
refuses and the Python parser takes is read by the Python parser. A 30,000-item job
(945 kB) parses in about 3 CPU-s this way, 26 with the Python parser alone.
"""

from __future__ import annotations

import copy
import re
import threading
from collections import OrderedDict
from pathlib import Path
from typing import Any

import yaml

from cell.errors import InvalidInput
from cell.infile import check_input_file

__all__ = [
    "MAX_BYTES",
    "MAX_DEPTH",
    "MAX_NODES",
    "check_yaml",
    "compose",
    "read_yaml_text",
    "safe_load",
]

MAX_BYTES = 1_000_000  # [B] a sort job of thousands of lines is ~100 kB
MAX_DEPTH = 32  # nesting of mappings and sequences
MAX_NODES = 200_000  # scalars, mappings and sequences in one file
# the values of the last texts read (each at most _MEMO_BYTES), handed out as copies: the
# same mount and parameter files are read again by every scene, arm and layout
_MEMO: OrderedDict[str, Any] = OrderedDict()
_MEMO_TEXTS = 32
_MEMO_BYTES = 64_000
_MEMO_LOCK = threading.Lock()


# YAML 1.1's octal: a leading 0 and more digits (`010` is 8; `09` is no number at all);
# a job's number field says what to write for one (`cell.yamltree`)
LEADING_ZERO = r"[-+]?0[0-9_]*[0-9][0-9_]*"
_OCTAL = f"(?!{LEADING_ZERO}$)"


def _without_base60(loader: Any) -> Any:
    """`loader` resolving no YAML 1.1 base-60 number: PyYAML reads `1:30` as the integer
    90 and `1:30.5` as 90.5, which no one writing a job means (YAML 1.2 dropped them); so
    a scalar with a colon resolves to text, which a number's field refuses by name. Nor a
    YAML 1.1 octal: `count: 010` is 8 to PyYAML and 10 to a reader (and to YAML 1.2), and
    `facing_half_range_deg: 0120` was 80; written so, it is text, refused by its field
    (a job's says what YAML would read and what to write: `cell.yamltree`)."""
    resolvers = {
        first: [
            (tag, re.compile("(?!.*:)" + _OCTAL * (tag.endswith("int")) + rx.pattern, rx.flags))
            if tag in ("tag:yaml.org,2002:int", "tag:yaml.org,2002:float")
            else (tag, rx)
            for tag, rx in rules
        ]
        for first, rules in loader.yaml_implicit_resolvers.items()
    }
    return type(f"{loader.__name__}NoBase60", (loader,), {"yaml_implicit_resolvers": resolvers})


# PyYAML's Python loader, and libyaml's (None when PyYAML was built without it: the Python
# parser then does all), each without the base-60 numbers
_SLOW: Any = _without_base60(yaml.SafeLoader)
_FAST: Any = _without_base60(yaml.CSafeLoader) if hasattr(yaml, "CSafeLoader") else None


def check_yaml(text: str, path: str) -> None:
    """Refuse YAML text that is too large, uses aliases, or nests too deep or too wide.

    Args:
        text: the file's text.
        path: the file, for the message.

    Raises:
        InvalidInput: naming the file, the line and the bound; also for YAML syntax errors.
    """
    if len(text) > MAX_BYTES:
        raise InvalidInput(f"{path}: {len(text)} characters; at most {MAX_BYTES} are read")
    if _FAST is not None:
        try:
            _check_events(yaml.parse(text, Loader=_FAST), path)
            return
        except yaml.YAMLError:
            pass  # worded by the Python parser, below
    try:
        _check_events(yaml.parse(text, Loader=_SLOW), path)
    except yaml.YAMLError as exc:
        raise InvalidInput(yaml_error(path, exc)) from None


def _check_events(events: Any, path: str) -> None:
    """Refuse an alias, a merge key (`<<`), a second document, nesting deeper than
    MAX_DEPTH or more than MAX_NODES values in a stream of parser events (InvalidInput
    naming the line); a YAMLError passes through."""
    depth = nodes = documents = 0
    for ev in events:
        line = ev.start_mark.line + 1 if ev.start_mark is not None else 0
        if isinstance(ev, yaml.DocumentStartEvent):
            documents += 1
            if documents > 1:
                raise InvalidInput(
                    f"{path}, line {line}: a second YAML document starts here (after a "
                    "`---` or `...`); the file is read as one document: put the second in "
                    "a file of its own (or delete the `---` where nothing follows it)"
                )
        if _merge_key(ev):
            raise InvalidInput(
                f"{path}, line {line}: a YAML merge key (<<, unquoted) is not accepted: "
                "mappings are not merged here; write each key out where it is used (as "
                "text, quote it: '<<')"
            )
        if isinstance(ev, yaml.AliasEvent):
            raise InvalidInput(
                f"{path}, line {line}: YAML aliases (*{ev.anchor}) are not "
                "accepted; write the value out where it is used"
            )
        if isinstance(ev, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
            depth += 1
            if depth > MAX_DEPTH:
                raise InvalidInput(
                    f"{path}, line {line}: nested deeper than {MAX_DEPTH} "
                    "levels; a valid file nests a few"
                )
        elif isinstance(ev, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
            depth -= 1
        if isinstance(ev, (yaml.ScalarEvent, yaml.MappingStartEvent, yaml.SequenceStartEvent)):
            nodes += 1
            if nodes > MAX_NODES:
                raise InvalidInput(f"{path}: more than {MAX_NODES} values; too large to read")


def _merge_key(ev: Any) -> bool:
    """Is this YAML's merge key: `<<` unquoted (a key, or a value, which YAML reads as
    the same merge tag), or tagged `!!merge`?"""
    if not isinstance(ev, yaml.ScalarEvent) or ev.value != "<<":
        return False
    return ev.tag == "tag:yaml.org,2002:merge" or (not ev.style and ev.implicit[0])


def compose(text: str) -> yaml.Node | None:
    """The node tree of a text that passed `check_yaml` (libyaml's, or the Python
    parser's when libyaml refuses it). Raises yaml.YAMLError as the Python parser words it."""
    if _FAST is not None:
        try:
            return yaml.compose(text, Loader=_FAST)  # type: ignore[no-any-return]
        except yaml.YAMLError:
            pass
    return yaml.compose(text, Loader=_SLOW)  # type: ignore[no-any-return]


def yaml_error(path: str, exc: yaml.YAMLError) -> str:
    """The parser's error as one line naming the file, line and column (a tab, which
    YAML never takes for indentation, said as such)."""
    mark = getattr(exc, "problem_mark", None)
    problem = getattr(exc, "problem", None)
    if mark is None or not problem:
        return f"{path}: not valid YAML ({exc})"
    where = f"{path}, line {mark.line + 1}, column {mark.column + 1}"
    if "'\\t'" in problem:
        return f"{where}: not valid YAML: a tab; YAML indents with spaces, never tabs"
    context = getattr(exc, "context", None)
    return f"{where}: not valid YAML: {problem}" + (f" ({context})" if context else "")


def read_yaml_text(path: str | Path, what: str) -> str:
    """The text of a user's YAML file, with its size bounded before it is read.

    Args:
        path: the file.
        what: what it should be, for the messages ("parameter file").

    Raises:
        InvalidInput: missing, a folder, a device or FIFO, unreadable, too large or not
            UTF-8 text.
    """
    p = check_input_file(path, what, MAX_BYTES)
    try:
        with open(p, "rb") as fh:
            raw = fh.read(MAX_BYTES + 1)  # a file that grew since it was checked stays bounded
    except OSError as exc:
        raise InvalidInput(f"{p}: cannot read it ({exc.strerror})") from None
    if len(raw) > MAX_BYTES:
        raise InvalidInput(f"{p}: more than {MAX_BYTES} bytes; a {what} is at most {MAX_BYTES}")
    try:
        if b"\x00" in raw:  # valid UTF-8, but no text holds a NUL: UTF-16 without its mark
            raise UnicodeDecodeError("utf-8", raw, raw.index(b"\x00"), len(raw), "NUL")
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        why = _not_utf8(raw, exc.start)
        save = "" if why.startswith("not a text") else " in UTF-8: save it as UTF-8"
        raise InvalidInput(f"{p}: {why}; a {what} is YAML text{save}") from None


def _not_utf8(raw: bytes, at: int) -> str:
    """Why `raw` is not UTF-8 text, its first bad byte at `at`: UTF-32 or UTF-16 by its
    byte-order mark; binary data by a control byte no text holds (NUL, ...) or by more
    bytes outside ASCII than ASCII ones; else text in another encoding (the byte and
    where it is: a Latin-1 or Windows-1252 editor's `é`)."""
    if raw[:4] in (b"\xff\xfe\x00\x00", b"\x00\x00\xfe\xff"):
        return "saved as UTF-32"
    if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
        return "saved as UTF-16 (a Windows editor's 'Unicode')"
    # ASCII text in UTF-16 without its byte-order mark: every other byte NUL (UTF-32: three
    # of four), as `cell.log.csvio` tells a log
    start = raw[:8192]
    for width, name in ((4, "UTF-32"), (2, "UTF-16")):
        for first, order in ((0, "big"), (width - 1, "little")):
            zeros = [start[i::width] for i in range(width) if i != width - 1 - first]
            if len(start) >= 2 * width and all(set(z) == {0} for z in zeros):
                return f"saved as {name} ({order}-endian, without a byte-order mark)"
    controls = bytes(range(9)) + bytes(range(14, 32))
    ascii_only = raw.translate(None, bytes(range(128, 256)))
    if len(raw.translate(None, controls)) < len(raw) or 2 * len(ascii_only) < len(raw):
        return "not a text file"
    line = raw.count(b"\n", 0, at) + 1
    column = at - (raw.rfind(b"\n", 0, at) + 1) + 1  # in bytes, 1-based
    return (
        f"not UTF-8 (byte 0x{raw[at]:02x} on line {line}, column {column}: Latin-1 or "
        "Windows-1252?)"
    )


def safe_load(text: str, path: str) -> Any:
    """`yaml.safe_load` of text that passed `check_yaml`. A text read before gives a copy
    of what it gave then (the same value: YAML's safe loader depends on the text alone);
    one that failed is checked again, so its error names this `path`.

    Raises:
        InvalidInput: as `check_yaml`.
    """
    with _MEMO_LOCK:
        known = _MEMO.get(text, _MEMO)
        if known is not _MEMO:
            _MEMO.move_to_end(text)
    if known is not _MEMO:
        return copy.deepcopy(known)
    check_yaml(text, path)
    try:
        value = _load(text)
    except (yaml.YAMLError, RecursionError, OverflowError) as exc:
        raise InvalidInput(f"{path}: not valid YAML ({exc})") from None
    if len(text) <= _MEMO_BYTES:
        kept = copy.deepcopy(value)
        with _MEMO_LOCK:
            _MEMO[text] = kept
            if len(_MEMO) > _MEMO_TEXTS:
                _MEMO.popitem(last=False)
    return value


def _load(text: str) -> Any:
    """`yaml.safe_load` of the text, by libyaml when it takes it (the same constructor)."""
    if _FAST is not None:
        try:
            return yaml.load(text, Loader=_FAST)  # noqa: S506 - CSafeLoader is the safe loader
        except yaml.YAMLError:
            pass
    return yaml.load(text, Loader=_SLOW)  # noqa: S506 - SafeLoader without base 60
