"""`cell calibrate`: throw a campaign in the PyBullet scene and identify its parameters."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from cell.identify import IdentifyResult
    from cell.log.table import ThrowTable
    from cell.workflows.calibrate import GapSummary, MassRule

from cell.cli.common import add_json_arg, json_to_stdout, plural, print_json, write_json

DEFAULT_OUTPUT = Path("ee_params.yaml")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "calibrate",
        help="throw catalogue items in the PyBullet scene and identify its end-effector parameters",
        description=(
            "Throws N catalogue items (the thesis14 set, cycled) in the PyBullet cell with the "
            "end-effector held at random release poses, logs them, and identifies η_ee and each "
            "object's η_o (two-stage least squares) so that the planner's model fits the scene. "
            "Then throws --adhoc ad-hoc items over the whole envelope and fits the effective-mass "
            "rule m_eff = κ √(m + m_b) (a / 0.05 m)^β that plans every object outside the "
            "campaign to their landings. Prints the gap between the nominal model and the scene."
        ),
    )
    p.add_argument("--n", type=int, default=112, help="number of throws (112)")
    p.add_argument("--seed", type=int, default=1, help="seed of the campaign (1)")
    p.add_argument(
        "--adhoc",
        type=int,
        default=160,
        metavar="N",
        help=(
            "throws of ad-hoc items (20-250 g, 25-90 mm, every shape) over the whole envelope "
            "that the mass rule for objects outside the campaign is fitted to (160; their own "
            "random stream of --seed, never the bench's; --log and --db hold the catalogue "
            "throws only); 0: fit the rule to the identified masses alone"
        ),
    )
    p.add_argument(
        "--validate",
        type=int,
        default=0,
        metavar="N",
        help=(
            "then throw N more catalogue throws of the campaign's kind from a random stream of "
            "their own (never the campaign's) and write the model's RMS landing miss on them "
            "per object to the file's validation section (0: no section)"
        ),
    )
    p.add_argument(
        "--params",
        metavar="FILE",
        help=(
            "with --validate: no campaign and no identification; validate FILE's parameters "
            "and write them, unchanged, with the validation section to -o"
        ),
    )
    p.add_argument(
        "-o",
        "--output",
        default=str(DEFAULT_OUTPUT),
        help=f"parameter file ({DEFAULT_OUTPUT} in the current folder)",
    )
    p.add_argument(
        "--replace",
        action="store_true",
        help="allow -o to overwrite the shipped scene parameters (robots/cell_scene/ee_params.yaml)",
    )
    p.add_argument(
        "--log", metavar="THROWS.csv", help="also write the campaign as docs/throw_log.md CSV"
    )
    p.add_argument(
        "--db",
        metavar="PATH",
        help="append the throws to this throw store (each chunk of 8 as it is thrown)",
    )
    p.add_argument(
        "--snapshot",
        metavar="FILE.png",
        help="render the cell scene headless (TinyRenderer) to a PNG; with --n 0 only that",
    )
    p.add_argument("--gui", action="store_true", help="watch the campaign in PyBullet's GUI")
    add_json_arg(p, "the result")
    p.add_argument("--record", metavar="CAL.rrd", help="write a Rerun recording (cell[record])")
    from cell.parallel import add_campaign_args

    add_campaign_args(p)
    p.set_defaults(func=run)


def _snapshot(path: str) -> None:
    from cell.endeffector.factory import make_end_effector
    from cell.sim import CellScene

    with CellScene() as sc:
        ee = make_end_effector("pybullet", plant=sc)
        for k, name in enumerate(("cube50", "cyl50", "sphere55", "duck", "rock_000")):
            sc.spawn_item(name, position=(0.38 + 0.07 * (k % 2), -0.48 + 0.05 * k, 0.3))
        sc.spawn_item("cuboid_b")
        sc.run_for(0.4)
        ee.grasp(0.06)
        for name, xy in (
            ("cube40", (0.45, 0.45)),
            ("teddy", (1.32, 0.28)),
            ("cyl60", (1.9, -0.35)),
        ):
            sc.spawn_item(name, position=(xy[0], xy[1], 0.3))
        sc.run_for(0.6)
        sc.snapshot(path)


def _check_outputs(args: argparse.Namespace) -> None:
    """Refuse unwritable outputs, and overwriting the shipped parameters, before the campaign."""
    from cell.cli.common import check_output_path
    from cell.errors import InvalidInput
    from cell.params import scene_params_path

    out = check_output_path(args.output, "-o")
    shipped = scene_params_path()
    if shipped and out.resolve() == Path(shipped).resolve() and not args.replace:
        raise InvalidInput(
            f"-o {out}: that is the shipped scene calibration the sort jobs use; write to "
            "another file (the default is ./ee_params.yaml), or add --replace to overwrite it"
        )
    for flag, path in (("--log", args.log), ("--record", args.record)):
        if path:
            check_output_path(path, flag)


def _open_store(path: str, plan: list[dict]) -> Any:  # type: ignore[type-arg]
    """The throw store, refused before the campaign if it already holds one of its throws."""
    from cell.errors import InvalidInput
    from cell.log.store import ThrowStore

    store = ThrowStore(path)
    known = store.existing_ids([p["throw_id"] for p in plan])
    if known:
        store.close()
        raise InvalidInput(
            f"--db {store.path}: already holds {plural(len(known), 'throw')} of this campaign "
            f"(e.g. {sorted(known)[0]!r}); give another --seed or another store"
        )
    return store


def _check_args(args: argparse.Namespace) -> None:
    """Refuse bad counts, --gui with workers, bad outputs and a missing rerun-sdk, before
    any throw.

    Raises:
        InvalidInput: naming the flag and what is valid.
    """
    from cell.errors import InvalidInput

    if args.n < 1:
        from cell.cli.cmd_identify import MIN_IDENTIFY_THROWS

        raise InvalidInput(
            f"--n {args.n}: give at least {MIN_IDENTIFY_THROWS} throws (0 only with --snapshot)"
        )
    if args.validate < 0:
        raise InvalidInput(f"--validate {args.validate}: give 0 (no validation) or more throws")
    if args.params and args.validate < 1:
        raise InvalidInput(
            f"--params {args.params}: only with --validate N (N ≥ 1): the file is validated, "
            "not identified again"
        )
    if args.adhoc < 0 or 0 < args.adhoc < 4:
        raise InvalidInput(
            f"--adhoc {args.adhoc}: give 0 (no ad-hoc campaign) or at least 4 throws"
        )
    if args.gui and (args.workers > 1 or args.ray_address):
        raise InvalidInput(
            "--gui shows the campaign in this process's window: give --workers 1 and no "
            "--ray-address with it"
        )
    _check_outputs(args)
    if args.record:  # fail before the campaign when rerun-sdk is missing
        from cell.record.stream import import_rerun

        import_rerun()
    _check_enough(args)


def _check_enough(args: argparse.Namespace) -> None:
    """Refuse a campaign too small to identify from (`MIN_IDENTIFY_THROWS`, as `cell
    identify` refuses such a log), but with --snapshot alone (--n 0).

    Raises:
        InvalidInput: naming --n, the least and why.
    """
    from cell.cli.cmd_identify import MIN_IDENTIFY_THROWS
    from cell.errors import InvalidInput
    from cell.identify.problem import EE_NAMES

    if args.n < MIN_IDENTIFY_THROWS and not args.params:  # --params: no campaign
        raise InvalidInput(
            f"--n {args.n}: give at least {MIN_IDENTIFY_THROWS} throws: identification "
            f"fits the end-effector's {len(EE_NAMES)} parameters ({', '.join(EE_NAMES)}) "
            "and each thrown object's own to 2 landing coordinates a throw, and refuses "
            f"fewer than {MIN_IDENTIFY_THROWS} (as `cell identify` does a log); "
            f"{args.n} would leave most of them at their start values"
        )


def _throw_campaign(args: argparse.Namespace, plan: list[dict]) -> ThrowTable:  # type: ignore[type-arg]
    """Throw the catalogue campaign (in the GUI with --gui), appending each chunk of throws
    to the --db store as it arrives; if the campaign stops, say how many were appended."""
    from tqdm import tqdm

    from cell.log.csvio import ThrowTable
    from cell.workflows.campaign import run_campaign

    store = _open_store(args.db, plan) if args.db else None
    appended = [0]

    def append(records: list[dict]) -> None:  # type: ignore[type-arg]
        # the driver is the only writer: each chunk of throws in one transaction, as it
        # arrives, so a dead worker or a Ctrl-C loses no throw already appended
        if store is not None:
            appended[0] += store.import_table(ThrowTable.from_records(records))

    scene = None
    if args.gui:
        from cell.sim import CellScene

        scene = CellScene(robot=None, bins=(), pick_station_xy=(-1.0, -1.0), gui=True)
    try:
        with tqdm(total=len(plan), desc="throws", disable=json_to_stdout(args) or None) as bar:
            table = run_campaign(
                plan,
                scene=scene,
                progress=lambda k: bar.update(k - bar.n),
                workers=args.workers,
                address=args.ray_address,
                on_records=append,
            )
    except BaseException:
        if store is not None:
            print(
                f"cell calibrate: {appended[0]} of {len(plan)} throws were appended to "
                f"{store.path} before the campaign stopped",
                file=sys.stderr,
            )
        raise
    finally:
        if scene is not None:
            scene.close()
        if store is not None:
            store.close()
    return table


def _throw_adhoc(args: argparse.Namespace) -> ThrowTable | None:
    """Throw the --adhoc items over the whole envelope (None with --adhoc 0)."""
    from tqdm import tqdm

    from cell.workflows.campaign import adhoc_plan, run_campaign

    if not args.adhoc:
        return None
    aplan = adhoc_plan(args.adhoc, seed=args.seed)
    with tqdm(total=len(aplan), desc="ad-hoc throws", disable=json_to_stdout(args) or None) as bar:
        return run_campaign(
            aplan,
            progress=lambda k: bar.update(k - bar.n),
            workers=args.workers,
            address=args.ray_address,
        )


def _identify(
    table: ThrowTable, adhoc: ThrowTable | None, quiet: bool
) -> tuple[IdentifyResult, GapSummary, GapSummary, MassRule]:
    """Identify the scene's parameters and the mass rule (`calibrate_table`), with a
    progress bar unless quiet."""
    from tqdm import tqdm

    from cell.sim.mechanism import DEFAULT_GEOMETRY
    from cell.workflows.calibrate import calibrate_table

    with tqdm(desc="identify", unit="it", disable=quiet or None) as bar:
        return calibrate_table(
            table,
            adhoc=adhoc,
            # the scene's carriage runs on to its end stop before the item flies free
            release_m=DEFAULT_GEOMETRY.end_stop_m,
            progress=lambda i, r: bar.update(1),
        )


def _summary(
    table: ThrowTable,
    out: Path,
    res: IdentifyResult,
    nominal: GapSummary,
    fitted: GapSummary,
    rule: MassRule,
    adhoc: ThrowTable | None,
) -> dict[str, Any]:
    """The result as `--json` prints it."""
    from cell.identify.report import evidence_json

    return {
        "throws": len(table),
        "output": str(out),
        "nominal_gap": nominal.as_dict(),
        "after_fit": fitted.as_dict(),
        "end_effector": res.params.ee.as_dict(),
        "converged": res.converged,
        **evidence_json(res),
        "mass_rule": {
            "kappa": rule.kappa,
            "band_mass_kg": rule.band_mass_kg,
            "width_exponent": rule.width_exponent,
            "adhoc_throws": 0 if adhoc is None else len(adhoc),
            "adhoc_reach_err_rms": rule.rms_reach_error,
        },
    }


def _print_summary(
    table: ThrowTable,
    out: Path,
    nominal: GapSummary,
    fitted: GapSummary,
    rule: MassRule,
    adhoc: ThrowTable | None,
) -> None:
    """Print the result as text: the gap before and after the fit, per object, and the
    mass rule."""
    print(f"{plural(len(table), 'throw')} in the scene; parameters written to {out}")
    print(
        f"nominal model vs scene: landing RMSE {nominal.rmse_m:.3f} m, reach error "
        f"{100 * nominal.reach_rel_rms:.1f} % RMS (bias {100 * nominal.reach_bias:+.1f} %)"
    )
    for oid, v in nominal.by_object.items():
        print(
            f"  {oid:12s} nominal reach error {100 * v:+6.1f} %   after fit {100 * fitted.by_object[oid]:+5.1f} %"
        )
    print(
        f"after the fit: landing RMSE {fitted.rmse_m:.3f} m, reach error "
        f"{100 * fitted.reach_rel_rms:.1f} % RMS"
    )
    if adhoc is None:
        fit = f"{100 * rule.rms_log_error:.1f} % RMS on the identified masses"
    else:
        fit = f"{100 * rule.rms_reach_error:.1f} % RMS reach error on {plural(len(adhoc), 'ad-hoc throw')}"
    print(
        f"effective mass rule m_eff = {rule.kappa:.4f} sqrt(m + {rule.band_mass_kg:.4f} kg) "
        f"(a / 0.05 m)^{rule.width_exponent:.3f} ({fit}) for the objects outside the campaign"
    )


def _validate(args: argparse.Namespace, params: Any) -> Any:
    """The parameters with the validation section of --validate held-out throws (as they
    are with --validate 0)."""
    from dataclasses import replace

    from tqdm import tqdm

    from cell.workflows.calibrate import validate
    from cell.workflows.campaign import campaign_plan, run_campaign

    if not args.validate:
        return params
    vplan = campaign_plan(args.validate, seed=args.seed, held_out=True)
    with tqdm(
        total=len(vplan), desc="held-out throws", disable=json_to_stdout(args) or None
    ) as bar:
        held = run_campaign(
            vplan,
            progress=lambda k: bar.update(k - bar.n),
            workers=args.workers,
            address=args.ray_address,
        )
    return replace(params, validation=validate(params, held, args.seed))


def _validation_json(params: Any) -> dict[str, Any] | None:
    return None if params.validation is None else params.validation.as_dict()


def _print_validation(params: Any) -> None:
    v = params.validation
    if v is None:
        return
    print(f"held-out landing miss (RMS, {plural(v.throws, 'throw')} never fitted to):")
    for oid, (x, m) in v.objects.items():
        print(f"  {oid:12s} {1000 * x:6.1f} mm ({m})")


def _validate_only(args: argparse.Namespace) -> int:
    """--params FILE --validate N: FILE's parameters validated and written to -o."""
    from cell.params import load_params, save_params

    params = _validate(args, load_params(args.params))
    out = Path(args.output)
    summary = {"output": str(out), "params": args.params, "validation": _validation_json(params)}
    if json_to_stdout(args):
        print_json(summary)
    else:
        _print_validation(params)
        print(f"parameters of {args.params} with their validation written to {out}")
    save_params(params, out)
    write_json(args, summary)
    return 0


def run(args: argparse.Namespace) -> int:
    """Throw the campaign (and the ad-hoc one), identify the parameters, validate them on
    --validate held-out throws, write them to -o and print the gap before and after the fit
    (or only render --snapshot with --n 0; or, with --params, only validate that file)."""
    from dataclasses import replace

    from cell.log.csvio import write_throws_csv
    from cell.params import save_params
    from cell.workflows.campaign import campaign_plan

    if args.snapshot and args.n == 0:
        _snapshot(args.snapshot)
        print(f"snapshot written to {args.snapshot}")
        return 0
    _check_args(args)
    if args.params:
        return _validate_only(args)
    plan = campaign_plan(args.n, seed=args.seed)
    table = _throw_campaign(args, plan)
    adhoc = _throw_adhoc(args)
    res, nominal, fitted, rule = _identify(table, adhoc, json_to_stdout(args))
    res = replace(res, params=_validate(args, res.params))
    out = Path(args.output)
    summary = _summary(table, out, res, nominal, fitted, rule, adhoc)
    summary["validation"] = _validation_json(res.params)
    if json_to_stdout(args):  # the results are printed before any file is written
        print_json(summary)
    else:
        _print_summary(table, out, nominal, fitted, rule, adhoc)
        from cell.identify.report import evidence_lines

        print("\n".join(evidence_lines(res)))
        _print_validation(res.params)
    if args.log:
        write_throws_csv(table, args.log)
    save_params(res.params, out)
    if args.record:
        from cell.record.calibrate import record_calibration

        record_calibration(args.record, table, res.params)
    if args.snapshot:
        _snapshot(args.snapshot)
    write_json(args, summary)
    return 0
