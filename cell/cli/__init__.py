"""The `cell` command line: one module per subcommand in this package.

Each subcommand module defines `register(subparsers)`, adding its parser with
`set_defaults(func=...)`; `func(args) -> int` is the exit status. The CLI owns
logging configuration and progress bars; the library does neither.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import sys

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


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every available subcommand."""
    parser = argparse.ArgumentParser(
        prog="cell",
        description="A pick-and-throw robot cell with an elastic slingshot end-effector.",
    )
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
    return parser


# Options that name a file a command writes: checked before the command's work starts, so a
# long run never ends in an unwritable path. (--json is a path only where it takes a value.)
_OUTPUT_OPTIONS = (
    ("output", "-o"),
    ("json", "--json"),
    ("report", "--report"),
    ("snapshot", "--snapshot"),
    ("record", "--record"),
    ("learn_save", "--learn-save"),
)


def _check_outputs(args: argparse.Namespace) -> None:
    """Check the seed and every output path before a command starts its work."""
    from cell.cli.common import check_output_path
    from cell.errors import InvalidInput

    seed = getattr(args, "seed", None)
    if isinstance(seed, int) and not 0 <= seed < 2**32:
        raise InvalidInput(f"--seed {seed}: a seed is an integer from 0 to {2**32 - 1}")
    workers = getattr(args, "workers", None)
    if isinstance(workers, int) and not 1 <= workers <= 4096:
        raise InvalidInput(f"--workers {workers}: give 1 (in this process) to 4096")
    for attr, flag in _OUTPUT_OPTIONS:
        value = getattr(args, attr, None)
        if isinstance(value, str) and value:
            check_output_path(value, flag)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the `cell` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        _check_outputs(args)
        return int(args.func(args) or 0)
    except CellError as exc:
        print(f"cell: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"cell {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into a reader that stopped (e.g. `| head`)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141


if __name__ == "__main__":
    sys.exit(main())
