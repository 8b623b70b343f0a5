"""`cell gap`: the sim-to-real diagnosis of a throw log, and `cell gap check`."""

from __future__ import annotations

import argparse
import json

from cell.errors import InvalidInput, InvalidParameter

CHECK_HELP = (
    "`cell gap check` draws campaigns with each effect of the vocabulary injected at a "
    "random size (plus none, plus an effect outside it), and worlds that follow other laws "
    "than the tool's (rolling and Coulomb slides, a rotor jet, a higher drag, a compound "
    "flight gap, tracks-only campaigns with disturbed first samples, a launch gap outside "
    "the vocabulary), diagnoses them blind and prints the confusion table"
)


MAX_GAP_THROWS = 100_000  # 2 GB of the diagnosis' memory on a log of band throws


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "gap",
        help="sim-to-real diagnosis: where the gap lies, which effect, how far it shrinks",
        description=(
            "Diagnose the gap between logged throws (docs/throw_log.md) and the model as "
            "configured. " + CHECK_HELP + "."
        ),
    )
    p.add_argument("throws", help="throws.csv, or `check` for the withheld-effect check")
    p.add_argument("--tracks", metavar="CSV", help="observed tracks (tracks.csv)")
    p.add_argument("--params", metavar="EE.yaml", help="parameter file (default: reference)")
    p.add_argument(
        "--json",
        nargs="?",
        const="-",
        metavar="PATH",
        help="the report (or the check) as JSON: on standard output instead of the table "
        "(--json or --json -), or written to PATH, a name ending in .json (--json PATH)",
    )
    p.add_argument("--report", metavar="HTML", help="write the report as HTML with plots")
    p.add_argument(
        "--identify",
        action="store_true",
        help="re-identify the nominal band law on training throws of every fit",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of folds, permutations, bootstrap")
    p.add_argument("--record", metavar="GAP.rrd", help="write a Rerun recording (cell[record])")
    g = p.add_argument_group("check only")
    g.add_argument("--quick", action="store_true", help="small campaigns (a smoke run)")
    g.add_argument("--n", type=int, metavar="THROWS", help="throws per campaign (default 865)")
    g.add_argument(
        "--repeats",
        type=int,
        default=2,
        help="times each configuration is thrown (2; 1 = no repeats to estimate noise from)",
    )
    g.add_argument("--truths", nargs="+", metavar="NAME", help="only these cases")
    g.add_argument(
        "--worlds",
        choices=("own", "other", "scene"),
        default="own",
        help="own: worlds drawn with the tool's formulas (default); other: worlds from "
        "another implementation (cell.gap.world_other), judged on verdict, phase, "
        "parameters within 30 %% and A within 1.3 x the world's own floor; scene: "
        "campaigns thrown in the PyBullet scene with each effect applied as a force, a "
        "contact or a tracker (cell.gap.world_scene), judged the same way",
    )
    from cell.parallel import add_campaign_args

    add_campaign_args(g)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if args.throws == "check":
        return _check(args)
    from tqdm import tqdm

    from cell.gap.report import format_table, jsonable, write_html, write_json
    from cell.gap.run import diagnose_log
    from cell.log import read_throws_csv
    from cell.log.csvio import read_tracks_csv
    from cell.model.effects import effects_from_mapping
    from cell.params import load_params

    if args.record:  # fail before the diagnosis when rerun-sdk is missing
        from cell.record.stream import import_rerun

        import_rerun()
    table = read_throws_csv(args.throws)
    if len(table) > MAX_GAP_THROWS:  # memory grows about 20 kB a throw (4.1 GB at 200,000)
        raise InvalidInput(
            f"{args.throws}: {len(table):,} throws; `cell gap` diagnoses at most "
            f"{MAX_GAP_THROWS:,} (its memory grows with the log, about 20 kB a throw): give it "
            "one session, or a sample of the rows, at a time"
        )
    mp = load_params(args.params)
    try:
        base = tuple(effects_from_mapping(mp.effects))
    except InvalidParameter as exc:
        raise InvalidInput(f"{args.params}: {exc}") from None
    tracks = read_tracks_csv(args.tracks, keep_lost=True) if args.tracks else None
    with tqdm(desc="cell gap", unit="step", leave=False, disable=None) as bar:

        def tick(label: str) -> None:
            bar.set_postfix_str(label)
            bar.update(1)

        d, prob = diagnose_log(
            table,
            mp.ee,
            base_effects=base,
            objects=mp.objects,
            tracks=tracks,
            identify=args.identify,
            seed=args.seed,
            progress=tick,
            validation=mp.validation,
        )
    if args.json == "-":  # JSON on stdout instead of the table
        print(json.dumps(jsonable(d.report), indent=2, allow_nan=False))
    else:
        print(format_table(d.report))
    if args.json and args.json != "-":
        write_json(d.report, args.json)
        print(f"report -> {args.json}")
    if args.report:
        write_html(d, prob, args.report)
        print(f"html report -> {args.report}")
    if args.record:
        from cell.record.gap import record_gap

        print(f"recording -> {record_gap(args.record, d, prob, tracks)}")
    return 0


def _check(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    if args.worlds in ("other", "scene"):
        return _check_other(args)

    from cell.gap.check import CASES, check_json, format_check, run_check
    from cell.gap.report import jsonable, write_json

    truths = tuple(args.truths) if args.truths else CASES
    bad = [t for t in truths if t not in CASES]
    if bad:
        raise InvalidInput(f"--truths: unknown {bad}; valid: {', '.join(CASES)}")
    n = args.n or (300 if args.quick else 865)
    if n < 60:
        raise InvalidInput(f"--n {n}: a campaign needs at least 60 throws")
    if args.repeats < 1:
        raise InvalidInput(f"--repeats {args.repeats}: must be ≥ 1")
    with tqdm(
        total=len(truths), desc="cell gap check", unit="campaign", leave=False, disable=None
    ) as bar:

        def tick(label: str) -> None:
            bar.set_postfix_str(label)
            bar.update(1)

        rows = run_check(
            truths,
            n=n,
            seed=args.seed,
            repeats=args.repeats,
            progress=tick,
            workers=args.workers,
            address=args.ray_address,
        )
    if args.json == "-":  # JSON on stdout instead of the table
        print(json.dumps(jsonable(check_json(rows)), indent=2, allow_nan=False))
    else:
        print(format_check(rows))
    if args.json and args.json != "-":
        write_json(check_json(rows), args.json)
        print(f"check -> {args.json}")
    return 0 if all(r.correct for r in rows) else 1


def _check_other(args: argparse.Namespace) -> int:
    from cell.gap.check_other import (
        FAST_OTHER,
        OTHER_CASES,
        format_other,
        other_json,
        run_other_check,
    )
    from cell.gap.check_scene import FAST_SCENE, SCENE_CASES, run_scene_check
    from cell.gap.report import write_json

    scene = args.worlds == "scene"
    fast: tuple[str, ...] = FAST_SCENE if scene else FAST_OTHER
    cases = SCENE_CASES if scene else OTHER_CASES
    n_default, n_quick = (80, 60) if scene else (400, 240)
    names = tuple(args.truths) if args.truths else (fast if args.quick else None)
    bad = [t for t in names or () if t not in cases]
    if bad:
        raise InvalidInput(f"--truths: unknown {bad}; valid: {', '.join(cases)}")
    n = args.n or (n_quick if args.quick else n_default)
    if n < 60:
        raise InvalidInput(f"--n {n}: a campaign needs at least 60 throws")
    if scene:  # a scene case takes minutes: each row on standard error as it arrives
        rows = run_scene_check(names, n=n, seed=args.seed, workers=args.workers,
                               address=args.ray_address, on_row=_print_row)  # fmt: skip
    else:
        rows = run_other_check(names, n=n, seed=args.seed, workers=args.workers,
                               address=args.ray_address)  # fmt: skip
    print(format_other(rows))
    if args.json:
        write_json(other_json(rows), args.json)
        print(f"check -> {args.json}")
    return 0 if all(r["passes"] for r in rows) else 1


def _print_row(r: dict) -> None:
    import sys

    print(f"{r['case']}: {r['verdict']} (truth {r['truth']}), A/F {r['after_over_floor']:.2f}, "
          f"{'passes' if r['passes'] else 'fails'}", file=sys.stderr, flush=True)  # fmt: skip
