"""`cell synth`: a reproducible synthetic throw campaign, written as a throw log."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "synth",
        help="draw a synthetic throw campaign from a chosen world (docs/throw_log.md CSV)",
        description=(
            "Draws throws of catalogue objects at various strokes and release poses in a "
            "world of known parameters, adds landing noise like the thesis' repeatability "
            "(8.07 % of the reach along the throw, 4 % across, 5 mm floor) and writes a "
            "throw log. The log carries the catalogue's mass and extents; the landings "
            "come from the world's true ones."
        ),
    )
    p.add_argument("-o", "--output", required=True, help="throws.csv to write")
    p.add_argument("--n", type=int, default=865, help="number of throws (default 865)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument(
        "--world",
        metavar="PARAMS.yaml",
        help="the true parameters (parameter-file format); default: the reference "
        "parameters perturbed in the documented fixed way",
    )
    p.add_argument(
        "--objects",
        nargs="+",
        metavar="ID",
        help="catalogue ids to throw (default: the 14 thesis14 objects)",
    )
    p.add_argument("--save-world", metavar="PARAMS.yaml", help="also write the true parameters")
    p.add_argument(
        "--noise-along",
        type=float,
        default=None,
        metavar="REL",
        help="σ along the throw per metre of reach (default 0.0807)",
    )
    p.add_argument(
        "--noise-across",
        type=float,
        default=None,
        metavar="REL",
        help="σ across the throw per metre of reach (default 0.04)",
    )
    p.add_argument(
        "--noise-floor",
        type=float,
        default=None,
        metavar="M",
        help="reach-independent σ [m] (default 0.005)",
    )
    p.add_argument(
        "--db",
        metavar="PATH",
        nargs="?",
        const="",
        help="also append the throws to the store (default path if no PATH)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from cell.cli.common import plural
    from cell.errors import InvalidInput
    from cell.log import ThrowStore, write_throws_csv
    from cell.params import load_params, save_params
    from cell.synth import Campaign, NoiseModel, default_world, draw_campaign, world_from_params

    noise = NoiseModel()
    for flag, name in (
        ("noise_along", "along_rel"),
        ("noise_across", "across_rel"),
        ("noise_floor", "floor_m"),
    ):
        if getattr(args, flag) is not None:
            noise = replace(noise, **{name: getattr(args, flag)})
    world = (
        world_from_params(load_params(args.world), noise) if args.world else default_world(noise)
    )
    twice = sorted({o for o in args.objects or () if args.objects.count(o) > 1})
    if twice:  # the campaign throws each listed id an equal share: a repeat doubles it
        raise InvalidInput(
            f"--objects lists {', '.join(map(repr, twice))} more than once; a campaign "
            "throws each id listed an equal share of --n: give each id once"
        )
    campaign = (
        Campaign(n=args.n) if not args.objects else Campaign(n=args.n, objects=tuple(args.objects))
    )
    table = draw_campaign(world, campaign, seed=args.seed)
    write_throws_csv(table, args.output)
    print(
        f"drew {plural(len(table), 'throw')} of {plural(len(campaign.objects), 'object')} "
        f"(seed {args.seed}) -> {args.output}"
    )
    if args.save_world:
        save_params(
            world.as_params(
                note=f"true parameters of the synthetic world (`cell synth`, noise {noise})"
            ),
            args.save_world,
        )
        print(f"wrote the true parameters to {args.save_world}")
    if args.db is not None:
        with ThrowStore(args.db or None) as store:
            store.import_table(table)
            print(f"appended {plural(len(table), 'throw')} to {store.path}")
    return 0
