"""`cell bench`: speed and accuracy figures."""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path
from typing import Any

from cell.bench import available
from cell.cli.common import add_json_arg, human, json_to_stdout, print_json, write_json
from cell.jobs import ORDERS
from cell.outfile import write_whole


def _add_sort_run_args(p: argparse.ArgumentParser) -> None:
    """`cell bench sort`'s options for how each layout is run (as `cell run`'s)."""
    p.add_argument(
        "--speed-scale",
        type=float,
        default=1.0,
        help="sort: fraction of the arm's joint limits its moves use, in (0, 1] (1)",
    )
    p.add_argument(
        "--turn-release",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="sort: release throws turned toward the pick station (cell run --turn-release; on "
        "by default)",
    )
    p.add_argument(
        "--cycle-search",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="sort: each throw's release chosen by its cycle (cell run --cycle-search; on by "
        "default)",
    )
    p.add_argument(
        "--order",
        choices=ORDERS,
        default="job",
        help="sort: the order the items are taken in (cell run --order; job, the default)",
    )
    p.add_argument(
        "--floor",
        action="store_true",
        help=(
            "sort: also time each approach and throw's carry as one direct move at the arm's "
            "full limits (the carry as the grip allows): floor_items_per_hour"
        ),
    )


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "bench",
        help="speed and accuracy figures (flat JSON with --json); `cell bench sort`: random layouts",
        description=(
            "Without a subject: the speed and accuracy figures of the model, planner, IK, "
            "identification and gap diagnosis. `cell bench sort`: sort N random layouts "
            "(cell job random) in the scene and report in_bin_rate (95 %% interval), "
            "in_bin_rate_unseen, items_per_hour and failures by reason, on the test set of "
            "layouts (seeds from 1000, never tuned on) unless --set tune. `cell bench tradeoff`: "
            "the same at several arm speed scales, items per hour against in-bin rate."
        ),
    )
    p.add_argument(
        "what",
        nargs="?",
        choices=("sort", "tradeoff"),
        help="sort: the random-layout benchmark; tradeoff: it at several arm speed scales",
    )
    add_json_arg(p, "one flat object of the figures")
    p.add_argument("--layouts", type=int, default=8, help="sort: layouts to draw (8)")
    p.add_argument(
        "--set",
        choices=("tune", "test"),
        default="test",
        help="sort, tradeoff: the layouts drawn: test (the default), seeds from 1000 that no "
        "constant of the cell was chosen on; tune, seeds 0-999, where the arm's constants "
        "were chosen (on 0-19)",
    )
    p.add_argument(
        "--seed",
        type=int,
        default=None,
        help="sort, tradeoff: seed of the first layout, within the --set (its first: 1000 for "
        "test, 0 for tune)",
    )
    p.add_argument(
        "--robots",
        default="panda",
        help="sort: arms taken in turn, comma-separated, each a name or a mount file's path "
        "(panda; e.g. panda,ur5)",
    )
    p.add_argument("--learn", action="store_true", help="sort: the flywheel on (cell run --learn)")
    p.add_argument("--out", metavar="DIR", help="sort: also write each layout's result here")
    p.add_argument(
        "--max-items", type=int, default=0, help="sort: only the first N items of each layout"
    )
    _add_sort_run_args(p)
    p.add_argument(
        "--scales",
        default="0.4,0.6,0.8,1.0",
        help="tradeoff: speed scales, comma-separated (0.4,0.6,0.8,1.0)",
    )
    p.add_argument("--plot", metavar="PNG", help="tradeoff: write the plot here")
    from cell.parallel import add_campaign_args

    add_campaign_args(p)
    p.add_argument("--only", nargs="+", metavar="NAME", help="run only these benchmarks")
    p.add_argument("--quick", action="store_true", help="smaller batches (a smoke run)")
    p.set_defaults(func=run)


def run_sort(args: argparse.Namespace) -> int:
    import json
    from pathlib import Path

    from cell.arm.base import check_speed_scale
    from cell.bench.bench_sort import first_seed, layout_units, summarise_layouts
    from cell.errors import InvalidInput

    robots = _robots(args.robots)
    if not 1 <= args.layouts <= 10_000:
        raise InvalidInput(f"--layouts {args.layouts}: give 1 to 10000")
    for robot in robots:
        check_speed_scale(args.speed_scale, robot, "--speed-scale")
    out = Path(args.out) if args.out else None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    first = first_seed(args.set, args.layouts, args.seed)
    units = layout_units(
        args.layouts,
        first,
        robots,
        args.learn,
        max(0, args.max_items),
        args.speed_scale,
        args.turn_release,
        args.floor,
        args.cycle_search,
        args.order,
        1 if args.workers > 1 or args.ray_address else None,  # on Ray: `LayoutUnit`
    )

    def keep(i: int, res: dict) -> None:  # type: ignore[type-arg]
        if out is not None:  # written by the driver as each layout arrives
            text = json.dumps(res, indent=1)
            write_whole(out / f"layout_{units[i].seed}.json", lambda p: p.write_text(text))

    layouts = _campaign(args, units, "random layouts", on_result=keep)
    figures = {**_set_figures(args.set, first, args.layouts), **summarise_layouts(layouts)}
    if json_to_stdout(args):
        print_json(figures)
    else:
        rows = figures["per_layout"]
        for k, v in figures.items():
            if k != "per_layout":
                print(f"{k:28s} {v if not isinstance(v, (float, dict, list)) else human(v)}")
        print(
            f"\n{'seed':>6s} {'robot':6s} {'in bin':>8s} {'sim [s]':>8s} {'items/h':>8s} "
            f"{'median cycle [s]':>16s}  slowest item [s]"
            + ("  floor [items/h]" if args.floor else "")
        )
        for r in rows:
            print(
                f"{r['seed']:>6d} {r['robot']:6s} {r['in_bin']:>3d}/{r['items']:<4d} "
                f"{r['sim_time_s']:>8.1f} {r['items_per_hour']:>8.0f} {r['median_cycle_s']:>16.2f}  "
                f"{r['slowest_item']} {r['slowest_cycle_s']:.2f}"
                + (f"  {r['floor_items_per_hour']:.0f}" if "floor_items_per_hour" in r else "")
                + ("  (refused)" if r["refused"] else "")
            )
        write_json(args, figures)
    for lay in layouts:  # why, in the job check's words (its last line: its first error)
        if lay["refused"]:
            why = lay["refused"].splitlines()[-1]
            print(f"layout {lay['seed']} ({lay['robot']}) refused: {why}", file=sys.stderr)
    if all(lay["refused"] for lay in layouts):
        print("cell bench sort: every layout was refused (above)", file=sys.stderr)
        return 4  # as `cell run` that sorts nothing (EXIT_NOTHING_SORTED)
    return 0


def _campaign(
    args: argparse.Namespace, units: list[Any], desc: str, on_result: Any = None
) -> list[Any]:
    """`run_layout` over the units, on --workers processes or the Ray cluster --ray-address."""
    from cell.bench.bench_sort import run_layout
    from cell.parallel import run_campaign

    return run_campaign(
        run_layout,
        units,
        workers=args.workers,
        address=args.ray_address,
        desc=desc,
        on_result=on_result,
    )


def _set_figures(layout_set: str, first: int, layouts: int) -> dict[str, object]:
    """Which layouts a campaign ran: {"set": tune|test, "seeds": [first, last]}."""
    return {"set": layout_set, "seeds": [first, first + layouts - 1]}


def _robots(text: str) -> tuple[str, ...]:
    """The arms of `--robots`: names under robots/, or mount files of the user's own (as
    `cell job random --robot` and a job's `cell.mount` take), each checked against its
    URDF and given by its absolute path."""
    from cell.errors import InvalidInput
    from cell.robot.mount import check_against_urdf, load_mount, robot_names

    names = robot_names()
    robots = tuple(r.strip() for r in text.split(",") if r.strip())
    bad = [r for r in robots if r not in names and not Path(r).is_file()]
    if bad or not robots:
        raise InvalidInput(
            f"--robots {text!r}: give arms from {', '.join(names)}, or mount files (docs/arms.md)"
        )
    mounts = tuple(r if r in names else str(Path(r).resolve()) for r in robots)
    for r in mounts:
        try:
            check_against_urdf(load_mount(r))
        except ValueError as exc:  # InvalidParameter: the mount file named
            raise InvalidInput(f"--robots: {exc}") from None
    return mounts


def run_tradeoff(args: argparse.Namespace) -> int:
    import json

    from cell.arm.base import check_speed_scale
    from cell.bench.bench_sort import first_seed
    from cell.bench.bench_tradeoff import plot_tradeoff, tradeoff_rows, tradeoff_units
    from cell.errors import InvalidInput

    try:
        scales = tuple(sorted({float(v) for v in args.scales.split(",") if v.strip()}))
    except ValueError:
        scales = ()
    if not scales or not all(0.0 < s <= 1.0 for s in scales):
        raise InvalidInput(f"--scales {args.scales!r}: give fractions in (0, 1], e.g. 0.5,1.0")
    robots = _robots(args.robots)
    for robot in robots:
        check_speed_scale(scales[0], robot, "--scales")  # the slowest
    if not 1 <= args.layouts <= 10_000:
        raise InvalidInput(f"--layouts {args.layouts}: give 1 to 10000")
    first = first_seed(args.set, args.layouts, args.seed)
    units = tradeoff_units(scales, args.layouts, first, robots, max(0, args.max_items))
    results = _campaign(args, units, "layouts x speed scales")
    rows = tradeoff_rows(results)
    doc = {**_set_figures(args.set, first, args.layouts), "points": rows}
    if json_to_stdout(args):
        print(json.dumps(doc, indent=1))
    else:
        print(f"{args.set} set, seeds {first}-{first + args.layouts - 1}")
        print(f"{'scale':>6s} {'items/h':>8s} {'in-bin':>7s}  95 % interval  items")
        for r in rows:
            print(
                f"{r['speed_scale']:6.2f} {r['items_per_hour']:8.0f} {r['in_bin_rate']:7.3f}  "
                f"{r['in_bin_rate_lo']:.3f}-{r['in_bin_rate_hi']:.3f}   {r['items']}"
            )
        write_json(args, doc)
    if args.plot:  # after the results are printed
        plot_tradeoff(rows, args.plot, args.set)
    return 0


def run(args: argparse.Namespace) -> int:
    if args.what == "sort":
        return run_sort(args)
    if args.what == "tradeoff":
        return run_tradeoff(args)
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
        if not json_to_stdout(args):
            print(f"[{name}: {time.perf_counter() - t0:.1f} s]")
    if json_to_stdout(args):
        print_json(figures)
    else:
        for k, v in figures.items():
            print(f"{k:32s} {v}")
        write_json(args, figures)
    return 0
