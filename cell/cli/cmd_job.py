"""`cell job random`: draw a sort job to look at, edit and run."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("job", help="sort-job tools (draw a random job)")
    jsub = p.add_subparsers(dest="job_command", metavar="JOB_COMMAND", required=True)
    r = jsub.add_parser(
        "random",
        help="draw a random sort job (the layouts of `cell bench sort`)",
        description=(
            "Draws 4-7 bins 0.4-3.2 m from the base at any azimuth the arm faces (rims "
            "0.05-0.30 m, 0.25-0.40 m wide) and 20-40 items from the whole catalogue and ad-hoc "
            "primitives (20-250 g, 25-90 mm), a third or more outside the calibration set. The "
            "same seed gives the same job; `cell run` runs it."
        ),
    )
    r.add_argument("--seed", type=int, default=0, help="names the job (0)")
    r.add_argument(
        "--robot",
        default="panda",
        help="the arm: a name under robots/ or a mount file's path (docs/arms.md) (panda)",
    )
    r.add_argument(
        "-o",
        "--output",
        metavar="JOB.yaml",
        help="write here (default: stdout); a name ending in .json is written as JSON, "
        "which `cell run` reads as it reads YAML",
    )
    r.set_defaults(func=run_random)


def job_yaml(doc: dict) -> str:  # type: ignore[type-arg]
    """A job as YAML with one line per bin and per item."""
    import yaml

    head = {k: v for k, v in doc.items() if k not in ("bins", "items")}
    lines = [yaml.safe_dump(head, sort_keys=False, width=100).rstrip()]
    for key in ("bins", "items"):
        lines.append(f"{key}:")
        for entry in doc[key]:
            lines.append(
                "  - "
                + yaml.safe_dump(entry, default_flow_style=True, width=200, sort_keys=False).strip()
            )
    return "\n".join(lines) + "\n"


def run_random(args: argparse.Namespace) -> int:
    from cell.errors import JobError
    from cell.jobgen import PICK_STATION_XY_M, random_job
    from cell.jobs import parse_job

    doc = random_job(args.seed, args.robot)
    as_json = bool(args.output) and str(args.output).lower().endswith(".json")
    text = json.dumps(doc, indent=2, ensure_ascii=False) + "\n" if as_json else job_yaml(doc)
    try:
        parse_job(text, f"<cell job random --seed {args.seed}>")  # what we write always loads
    except JobError as exc:
        if "pick_station" not in str(exc):
            raise
        # a random layout's station is the default one: no layout drawn for this arm loads
        x, y = PICK_STATION_XY_M
        raise JobError(
            f"{exc}\ncell job random: every random layout has its pick station at ({x}, {y}) m "
            f"(cell.jobgen.PICK_STATION_XY_M), which arm {args.robot} does not reach: write "
            "its job by hand (docs/jobs.md) with the station within its reach"
        ) from None
    if args.output:
        from cell.outfile import write_whole

        out = Path(args.output)
        write_whole(out, lambda p: p.write_text(text))
        print(f"wrote {out}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0
