"""`cell run JOB.yaml`: a sort job in the cell."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="run a sort job (YAML) in the cell")
    p.add_argument("job", help="job file, e.g. tasks/bins.yaml")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    print(
        f"cell run {args.job}: the sort orchestrator is not yet built (the model is: try `cell throw --object cube50`)"
    )
    return 0
