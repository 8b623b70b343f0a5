"""`cell identify`: two-stage identification of η_ee and η_o from a throw log."""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from cell.cli.common import add_json_arg, json_to_stdout, plural, print_json, write_json
from cell.errors import InvalidInput
from cell.log.table import ThrowTable
from cell.params import ModelParams

if TYPE_CHECKING:
    from cell.synth import NoiseModel


# The fewest distinct throws identification works from (`cell identify`, and the campaign
# `cell calibrate` throws): stage 1 alone fits the end-effector's 8 parameters
# (`cell.identify.problem.EE_NAMES`) to landings of 2 coordinates a throw, and each object
# thrown adds its own
MIN_IDENTIFY_THROWS = 10


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "identify",
        help="identify end-effector and object parameters from throws (thesis Algorithm 1)",
        description=(
            "Fits η_ee (band law, geometry, push duration) and each object's mass and "
            "extents to the observed landings, holding a stratified share of each "
            "object's throws out of the fit, and reports the prediction errors on those "
            "held-out throws before (start parameters) and after."
        ),
    )
    p.add_argument(
        "throws",
        nargs="?",
        help="throws.csv (docs/throw_log.md); default: every throw in the store",
    )
    p.add_argument("-o", "--output", required=True, help="parameter file to write (YAML)")
    p.add_argument("--db", metavar="PATH", help="throw store when no CSV is given")
    p.add_argument(
        "--start", metavar="PARAMS.yaml", help="start/prior parameters (default: reference)"
    )
    p.add_argument(
        "--holdout",
        type=float,
        default=0.2,
        metavar="FRACTION",
        help="share of each object's throws held out of the fit (default 0.2; 0 = fit all)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the held-out split")
    p.add_argument(
        "--max-iter",
        type=int,
        default=30,
        help="most stage-1 + stage-2 iterations of a pass (the fit makes a second pass once "
        "the objects' priors are chosen, unless --ee-only)",
    )
    p.add_argument("--tol", type=float, default=2e-3, help="relative parameter change to stop at")
    p.add_argument("--ee-only", action="store_true", help="stage 1 only (keep the objects' η_o)")
    for flag, meta, text in (
        ("--noise-along", "REL", "σ along the throw per metre of reach (default 0.0807)"),
        ("--noise-across", "REL", "σ across the throw per metre of reach (default 0.04)"),
        ("--noise-floor", "M", "reach-independent σ [m], > 0 (default 0.005)"),
    ):
        p.add_argument(
            flag, type=float, default=None, metavar=meta,
            help=f"landing noise the residuals are weighed by: {text}",
        )  # fmt: skip
    p.add_argument("--plot", metavar="DIR", help="write reach-vs-stroke PNGs into DIR")
    add_json_arg(p, "the results")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from cell.identify import IdentifyOptions, identify
    from cell.identify.report import (
        errors_by_object,
        heldout_split,
        predicted_landing,
    )
    from cell.log import ThrowStore, read_throws_csv
    from cell.params import load_params, save_params

    if args.throws:
        table = read_throws_csv(args.throws)
        source = args.throws
    else:
        with ThrowStore(args.db, read_only=True) as store:
            table = store.table()
            source = str(store.path)
        if len(table) == 0:
            raise InvalidInput(f"{source}: the store holds no throws; give a throws.csv")
    table.require_varied(MIN_IDENTIFY_THROWS, "identification")
    if args.max_iter < 1:
        raise InvalidInput(f"--max-iter {args.max_iter} must be ≥ 1")
    start = load_params(args.start)
    fit_idx, held_idx = heldout_split(table, args.holdout, args.seed)
    fit, held = table.take(fit_idx), table.take(held_idx)
    evaluated = held if len(held) else fit
    opts = IdentifyOptions(
        max_iter=args.max_iter, tol=args.tol, fit_objects=not args.ee_only, noise=_noise(args)
    )
    with tqdm(
        total=args.max_iter,
        desc="identify",
        unit="it",
        disable=json_to_stdout(args) or None,
        leave=False,
    ) as bar:

        def progress(it: int, rmse: float) -> None:
            bar.update(1)
            bar.set_postfix(rmse_m=f"{rmse:.4f}")

        result = identify(fit, start, options=opts, progress=progress)
    params = result.params
    where = (
        f"{plural(len(held), 'held-out throw')} (a stratified {args.holdout:.0%} of each object's, "
        f"seed {args.seed}), not used in the fit"
        if len(held)
        else "the fitted throws themselves (--holdout 0: in-sample figures)"
    )
    before = errors_by_object(evaluated, predicted_landing(evaluated, start))
    after = errors_by_object(evaluated, predicted_landing(evaluated, params))
    note = (
        f"{params.note}; source {source}; {where}: landing RMSE "
        f"{before[-1].landing_rmse_m:.4f} m -> {after[-1].landing_rmse_m:.4f} m"
    )
    params = replace(params, note=note)
    n_fit: dict[str, int] = {}
    for oid in fit.text("object_id"):
        n_fit[oid] = n_fit.get(oid, 0) + 1
    doc = _doc(args, table, source, result, held, before, after, params, n_fit)
    if not json_to_stdout(args):  # the results are printed before any file is written
        _print(table, source, result, where, before, after, params, start, n_fit, args.max_iter)
    save_params(params, args.output)
    plots = []
    if args.plot:
        plots = [str(p) for p in _plot(table, start, params, args.plot, np.asarray(held_idx))]
    doc["plots"] = plots
    if json_to_stdout(args):  # after the plots, whose files it lists
        print_json(doc)
        return 0
    print(f"wrote {args.output}")
    for p in plots:
        print(f"wrote {p}")
    write_json(args, doc)
    return 0


def _doc(args, table, source, result, held, before, after, params, n_fit) -> dict:  # type: ignore[no-untyped-def,type-arg]
    """The results as `--json` gives them."""
    from cell.identify.report import evidence_json

    return {
        "source": source,
        "throws": len(table),
        "fit_throws": result.n_throws,
        "heldout_throws": int(len(held)),
        "evaluated_on": "heldout" if len(held) else "fit",
        "iterations": result.iterations,
        "converged": result.converged,
        "seconds": result.seconds,
        "rmse_fit_start_m": result.rmse_start_m,
        "rmse_fit_m": result.rmse_fit_m,
        "objective_start": result.objective_start,
        "objective_fit": result.objective_fit,
        "kept_start": result.kept_start,
        "chi2_per_throw_by_object": {k: v[1] for k, v in result.chi2_by_object.items()},
        "objects": {
            b.object_id: {
                "n_fit": n_fit.get(b.object_id, result.n_throws),
                "n_eval": b.n,
                "reach_rmse_before_m": b.reach_rmse_m,
                "reach_rmse_after_m": a.reach_rmse_m,
                "landing_rmse_before_m": b.landing_rmse_m,
                "landing_rmse_after_m": a.landing_rmse_m,
            }
            for b, a in zip(before, after, strict=True)
        },
        **evidence_json(result),
        "end_effector": params.ee.as_dict(),
        "object_params": {
            k: {"mass_kg": o.mass, "size_m": list(o.size)} for k, o in params.objects.items()
        },
        "output": args.output,
    }


def _iterations(result: Any, max_iter: int) -> str:
    """The fit's iterations and how it ended: a count over --max-iter is two passes (the
    second once the objects' priors are chosen), each of at most --max-iter."""
    end = "converged" if result.converged else f"stopped at --max-iter {max_iter}"
    if result.iterations <= max_iter:
        return f"{plural(result.iterations, 'iteration')}, {end}"
    return (
        f"{plural(result.iterations, 'iteration')} in two passes (the second once the "
        f"objects' priors were chosen), each of at most --max-iter {max_iter}; the second {end}"
    )


def _print(table, source, result, where, before, after, params, start, n_fit, max_iter) -> None:  # type: ignore[no-untyped-def]
    """The results as text."""
    from cell.identify.report import evidence_lines, format_table

    print(
        f"{source}: {plural(len(table), 'throw')} of {plural(len(set(table.text('object_id'))), 'object')}"
    )
    print(f"fitted on {plural(result.n_throws, 'throw')}; errors below are on {where}")
    print(format_table(before, after, params, n_fit))
    print(
        f"\n{_iterations(result, max_iter)} "
        f"({result.seconds:.1f} s); landing RMSE on the fitted throws "
        f"{result.rmse_start_m:.4f} -> {result.rmse_fit_m:.4f} m"
    )
    print(_objective_line(result))
    print("end effector (start -> identified, 95 % interval):")
    for k in start.ee.IDENTIFIABLE:
        half = result.intervals.get(k, (0.0, float("nan")))[1]
        print(
            f"  {k:4s} {getattr(start.ee, k):12.6g} -> {getattr(params.ee, k):12.6g} ± {half:.3g}"
        )
    print("\n".join(evidence_lines(result)))


def _objective_line(result) -> str:  # type: ignore[no-untyped-def]
    """The objective the fit minimised, start and end, and the object that weighs most in it
    (the landing RMSE is not that objective: cell/identify/objective.py)."""
    chi2 = result.chi2_by_object
    total = sum(n * c for n, c in chi2.values())
    top = max(chi2, key=lambda k: chi2[k][0] * chi2[k][1])
    n, c = chi2[top]
    line = (
        f"objective minimised (landing residuals over the noise model's σ, squared, and the "
        f"priors; the final weights) {result.objective_start:.1f} -> "
        f"{result.objective_fit:.1f}; {top}'s throws {n * c / total:.0%} of its residuals, "
        f"{c:.2f} a throw where the noise model expects 2 (--noise-* sets the noise)"
    )
    if result.kept_start:
        line += "; the fit ended worse on it than the start: the start parameters kept"
    return line


def _noise(args: argparse.Namespace) -> NoiseModel:
    """The landing noise from --noise-along/--noise-across/--noise-floor (documented defaults).

    Raises:
        InvalidInput: a value negative or not finite, or a floor of 0 (a throw of zero
            reach would weigh infinitely).
    """
    from cell.errors import InvalidParameter
    from cell.synth import NoiseModel

    given = {
        name: getattr(args, flag)
        for flag, name in (
            ("noise_along", "along_rel"),
            ("noise_across", "across_rel"),
            ("noise_floor", "floor_m"),
        )
        if getattr(args, flag) is not None
    }
    try:
        noise = replace(NoiseModel(), **given)
    except InvalidParameter as e:
        raise InvalidInput(f"--noise-*: {e}") from None
    if not noise.floor_m > 0:
        raise InvalidInput(f"--noise-floor {noise.floor_m}: give a σ > 0 [m], e.g. 0.005")
    return noise


def _plot(
    table: ThrowTable, start: ModelParams, params: ModelParams, out_dir: str, held: np.ndarray
) -> list[Path]:
    from cell.identify.plot import plot_reach

    return plot_reach(table, start, params, out_dir, held_out=held)
