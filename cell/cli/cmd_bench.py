"""`cell bench`: speed and accuracy figures."""

from __future__ import annotations

import argparse
import platform
import time

from cell.bench import available
from cell.cli.common import print_json


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bench", help="speed and accuracy figures (flat JSON with --json)")
    p.add_argument("--json", action="store_true", help="print one flat JSON object")
    p.add_argument("--only", nargs="+", metavar="NAME", help="run only these benchmarks")
    p.add_argument("--quick", action="store_true", help="smaller batches (a smoke run)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    benches = available()
    if args.only:
        unknown = [n for n in args.only if n not in benches]
        if unknown:
            from cell.errors import InvalidInput

            raise InvalidInput(f"unknown benchmark(s) {unknown}; available: {', '.join(benches)}")
        benches = {k: v for k, v in benches.items() if k in args.only}
    figures: dict[str, float | str] = {
        "machine": f"{platform.machine()} {platform.python_version()}"
    }
    for name, fn in benches.items():
        t0 = time.perf_counter()
        figures.update(fn(args.quick))
        if not args.json:
            print(f"[{name}: {time.perf_counter() - t0:.1f} s]")
    if args.json:
        print_json(figures)
    else:
        for k, v in figures.items():
            print(f"{k:32s} {v}")
    return 0
