"""`cell argv` run in the test's own process, for the tests of its refusals."""

from __future__ import annotations

from cell.cli import main


def cell_exit(argv: list[str]) -> int:
    """`cell argv` through the parser and the error handling `python -m cell` runs
    (`cell.__main__` is `sys.exit(main())`): its exit status, argparse's own refusals
    (`SystemExit`) included. An exception `main` does not turn into a message is raised,
    and fails the test that called it."""
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
