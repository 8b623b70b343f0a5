"""The `cell` command line: one module per subcommand in this package.

Each subcommand module defines `register(subparsers)`, adding its parser with
`set_defaults(func=...)`; `func(args) -> int` is the exit status. The CLI owns
logging configuration and progress bars; the library does neither.
"""

from __future__ import annotations

import argparse
import difflib
import importlib
import logging
import os
import re
import signal
import sys
import threading
from typing import Any, NoReturn

import numpy as np

from cell.errors import CellError

__all__ = ["main", "COMMANDS"]

# Subcommand modules, in the order `cell --help` lists them.
COMMANDS = (
    "run",
    "throw",
    "plan",
    "predict",
    "reach",
    "identify",
    "learn",
    "gap",
    "synth",
    "calibrate",
    "log",
    "ee",
    "study",
    "bench",
    "job",
)


class Parser(argparse.ArgumentParser):
    """argparse's parser, with its refusals said as `cell: error:` lines (exit 2), and
    `-inf`, `-nan` and `-1e300` read as the values they are (argparse's own pattern of a
    negative number takes only `-1` and `-1.5`, and `--at 0 -inf 0` would end the option
    there, with a message that does not name it). An option is taken only as written:
    argparse's prefix matching (`--no-lo` for `--no-log`) is off, so an abbreviation is
    refused naming the option it abbreviates, and a later option cannot change what it
    means (the subcommands' parsers are of this class too)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(
            r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$", re.IGNORECASE
        )

    # names `json_spelling` read as no path of --json's (set by `main`): an argument
    # refused as unrecognized among them is said to be one
    json_not_paths: tuple[str, ...] = ()

    def parse_args(self, args: Any = None, namespace: Any = None) -> Any:  # type: ignore[override]
        """argparse's, but an unrecognized argument is refused by the subcommand's parser
        (its usage, `cell run --help`), with the option nearest a misspelt one."""
        ns, extras = self.parse_known_args(args, namespace)
        if extras:
            owner = subcommand_parser(self, getattr(ns, "command", None)) or self
            if isinstance(owner, Parser):
                owner.json_not_paths = self.json_not_paths
            owner.error(
                f"unrecognized arguments: {' '.join(extras)}{nearest_option(owner, extras)}"
            )
        return ns

    def error(self, message: str) -> NoReturn:
        self.print_usage(sys.stderr)
        message += nearest_choice(message)
        head = "unrecognized arguments: "
        extra = message[len(head) :] if message.startswith(head) else ""
        for name in (n for n in self.json_not_paths if n and n in extra):
            message += (
                f"; --json {name}: a path for --json must end in .json, so --json was read "
                f"as the bare flag and {name} as another argument (the bare --json prints "
                "the JSON on standard output)"
            )
            break
        self.exit(2, f"cell: error: {message} (see `{self.prog} --help`)\n")


def subcommand_parser(parser: argparse.ArgumentParser, name: str | None) -> Any:
    """The parser of the subcommand `name` (`cell run`'s), or None."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction) and name in action.choices:
            return action.choices[name]
    return None


def nearest_option(parser: argparse.ArgumentParser, extras: list[str]) -> str:
    """`; did you mean --json?` for the first unrecognized option near one of `parser`'s:
    the options it is a prefix of (an abbreviation, `--lay` of `--layouts`), else the
    nearest spelling."""
    options = [o for a in parser._actions for o in a.option_strings]
    for extra in extras:
        if extra.startswith("--"):
            longer = [o for o in options if o.startswith(extra.split("=")[0])]
            if longer:
                return f"; did you mean {' or '.join(longer)}?"
        if extra.startswith("-"):
            near = difflib.get_close_matches(extra.split("=")[0], options, n=1, cutoff=0.6)
            if near:
                return f"; did you mean {near[0]}?"
    return ""


def nearest_choice(message: str) -> str:
    """`; did you mean 'run'?` for argparse's `invalid choice: 'rn' (choose from 'run', ...)`."""
    m = re.search(r"invalid choice: '(.*?)' \(choose from (.*)\)", message)
    if not m:
        return ""
    near = difflib.get_close_matches(m[1], re.findall(r"'([^']*)'", m[2]), n=1, cutoff=0.6)
    return f"; did you mean '{near[0]}'?" if near else ""


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every available subcommand."""
    from cell import __version__
    from cell.cli.guard import add_replace_args

    parser = Parser(
        prog="cell",
        description="A pick-and-throw robot cell with an elastic slingshot end-effector.",
    )
    parser.add_argument("--version", action="version", version=f"cell {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        try:
            mod = importlib.import_module(f"cell.cli.cmd_{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"cell.cli.cmd_{name}":
                continue  # not built yet
            raise
        mod.register(sub)
    add_replace_args(parser)
    return parser


def json_spelling(argv: list[str]) -> list[str]:
    """`--json` followed by anything but `-` or a name ending in .json is the bare flag (JSON
    on stdout), as it was before --json took a path: `cell ee --json status` keeps working,
    and `cell identify --json t.csv -o ee.yaml` reads t.csv instead of writing JSON into it."""
    out: list[str] = []
    for k, a in enumerate(argv):
        out.append(a)
        if a == "--":
            out.extend(argv[k + 1 :])
            break
        nxt = argv[k + 1] if k + 1 < len(argv) else "-"
        if a == "--json" and not nxt.startswith("-") and not nxt.lower().endswith(".json"):
            out.append("-")
    return out


class _Said(logging.Formatter):
    """The library's warnings said as the command's own, `cell: warning: ...` (a place
    that had not touched down, a fork that failed); its other records, and every other
    library's, as `LEVEL logger: ...`."""

    def format(self, record: logging.LogRecord) -> str:
        if record.levelno == logging.WARNING and record.name.split(".")[0] == "cell":
            return f"cell: warning: {record.getMessage()}"
        return super().format(record)


class Terminated(KeyboardInterrupt):
    """A SIGTERM (`kill`, `timeout`, a service manager stopping the cell): the command
    ends as Ctrl-C ends it, through every `finally` (the servos' torque off, the throw
    log closed, what was done said), rather than dying where it stood."""


def _terminate_as_interrupt(signum: int, frame: object) -> NoReturn:
    raise Terminated()


def main(argv: list[str] | None = None) -> int:
    """Entry point of the `cell` console script: its standard streams made safe first
    (`cell.cli.streams`: a closed one given /dev/null, a failing one kept from ending the
    command before its output files are written)."""
    from cell.cli.streams import guarded_streams, open_standard_fds, said_failure

    open_standard_fds()
    with guarded_streams() as (out, err):
        code = _main(argv)
    return said_failure(out, err, code)


def _main(argv: list[str] | None) -> int:
    parser = build_parser()
    given = sys.argv[1:] if argv is None else list(argv)
    spelled = json_spelling(given)
    ends = given.index("--") if "--" in given else len(given)
    if isinstance(parser, Parser):
        after = zip(given[:ends], given[1:ends], strict=False)
        parser.json_not_paths = tuple(b for a, b in after if a == "--json")
    args = parser.parse_args(spelled)
    said = logging.StreamHandler()  # standard error
    said.setFormatter(_Said("%(levelname)s %(name)s: %(message)s"))
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING, handlers=[said])
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return 2
    # the handler is put back after: a process that calls main() keeps its own
    on_main = threading.current_thread() is threading.main_thread()
    before = signal.signal(signal.SIGTERM, _terminate_as_interrupt) if on_main else None
    try:
        return _run(args, parser)
    finally:
        if before is not None:
            signal.signal(signal.SIGTERM, before)


def _run(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """The command, its errors said as one line each (`main`)."""
    from cell.cli.guard import check_args

    try:
        check_args(args, parser)  # before the command's work starts
        with np.errstate(all="ignore"):  # a non-finite result is reported, not warned about
            return int(args.func(args) or 0)
    except CellError as exc:
        print(f"cell: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        how = "terminated (SIGTERM)" if isinstance(exc, Terminated) else "interrupted"
        print(f"cell {args.command}: {how}", file=sys.stderr)
        return 143 if isinstance(exc, Terminated) else 130
    except BrokenPipeError:  # output piped into a reader that stopped (e.g. `| head`)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except OSError as exc:  # a file that failed between the checks and the write
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"cell: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
