"""`cell bench`: speed and accuracy figures."""

from __future__ import annotations

import argparse
import platform
import time

from cell.bench import available
from cell.cli.common import print_json


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "bench",
        help="speed and accuracy figures (flat JSON with --json); `cell bench sort`: random layouts",
        description=(
            "Without a subject: the speed and accuracy figures of the model, planner, IK, "
            "identification and gap diagnosis. `cell bench sort`: sort N random layouts "
            "(cell job random) in the scene and report in_bin_rate (95 %% interval), "
            "in_bin_rate_unseen, items_per_hour and failures by reason."
        ),
    )
    p.add_argument("what", nargs="?", choices=("sort",), help="sort: the random-layout benchmark")
    p.add_argument("--json", action="store_true", help="print one flat JSON object")
    p.add_argument("--layouts", type=int, default=8, help="sort: layouts to draw (8)")
    p.add_argument("--seed", type=int, default=0, help="sort: seed of the first layout (0)")
    p.add_argument(
        "--robots",
        default="panda",
        help="sort: arms taken in turn, comma-separated (panda; e.g. panda,ur5)",
    )
    p.add_argument("--learn", action="store_true", help="sort: the flywheel on (cell run --learn)")
    p.add_argument("--out", metavar="DIR", help="sort: also write each layout's job and result")
    p.add_argument("--only", nargs="+", metavar="NAME", help="run only these benchmarks")
    p.add_argument("--quick", action="store_true", help="smaller batches (a smoke run)")
    p.set_defaults(func=run)


def run_sort(args: argparse.Namespace) -> int:
    import json
    import sys
    from pathlib import Path

    from tqdm import tqdm

    from cell.bench.bench_sort import layout_units, run_layout, summarise_layouts
    from cell.errors import InvalidInput
    from cell.jobs import ROBOTS

    robots = tuple(r.strip() for r in args.robots.split(",") if r.strip())
    bad = [r for r in robots if r not in ROBOTS]
    if bad or not robots:
        raise InvalidInput(f"--robots {args.robots!r}: give arms from {', '.join(ROBOTS)}")
    if not 1 <= args.layouts <= 10_000:
        raise InvalidInput(f"--layouts {args.layouts}: give 1 to 10000")
    out = Path(args.out) if args.out else None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    units = layout_units(args.layouts, args.seed, robots, args.learn)
    layouts = []
    with tqdm(
        total=len(units), desc="random layouts", unit="layout", file=sys.stderr, disable=None
    ) as bar:
        for u in units:
            res = run_layout(u)
            layouts.append(res)
            if out is not None:
                (out / f"layout_{u.seed}.json").write_text(json.dumps(res, indent=1))
            ok = sum(it["in_bin"] for it in res["items"])
            bar.set_postfix_str(f"seed {u.seed}: {ok}/{len(res['items'])} in bin")
            bar.update(1)
    figures = summarise_layouts(layouts)
    if args.json:
        print_json(figures)
    else:
        for k, v in figures.items():
            print(f"{k:28s} {v if not isinstance(v, float) else round(v, 4)}")
    return 0


def run(args: argparse.Namespace) -> int:
    if args.what == "sort":
        return run_sort(args)
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
