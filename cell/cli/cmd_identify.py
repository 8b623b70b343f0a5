"""`cell identify`: two-stage identification of η_ee and η_o from a throw log."""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from cell.cli.common import print_json
from cell.errors import InvalidInput
from cell.log.table import ThrowTable
from cell.params import ModelParams


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
        "throws", nargs="?", help="throws.csv (THROW_LOG.md); default: every throw in the store"
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
    p.add_argument("--max-iter", type=int, default=30, help="most stage-1 + stage-2 iterations")
    p.add_argument("--tol", type=float, default=2e-3, help="relative parameter change to stop at")
    p.add_argument("--ee-only", action="store_true", help="stage 1 only (keep the objects' η_o)")
    p.add_argument("--plot", metavar="DIR", help="write reach-vs-stroke PNGs into DIR")
    p.add_argument("--json", action="store_true", help="print the results as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from cell.identify import IdentifyOptions, identify
    from cell.identify.report import (
        errors_by_object,
        format_table,
        heldout_split,
        predicted_landing,
    )
    from cell.params import load_params, save_params

    table, source = _throws(args)
    table.require_varied(10, "identification")
    if args.max_iter < 1:
        raise InvalidInput(f"--max-iter {args.max_iter} must be ≥ 1")
    start = load_params(args.start)
    fit_idx, held_idx = heldout_split(table, args.holdout, args.seed)
    fit, held = table.take(fit_idx), table.take(held_idx)
    evaluated = held if len(held) else fit
    opts = IdentifyOptions(max_iter=args.max_iter, tol=args.tol, fit_objects=not args.ee_only)
    with tqdm(
        total=args.max_iter, desc="identify", unit="it", disable=args.json or None, leave=False
    ) as bar:

        def progress(it: int, rmse: float) -> None:
            bar.update(1)
            bar.set_postfix(rmse_m=f"{rmse:.4f}")

        result = identify(fit, start, options=opts, progress=progress)
    params = result.params
    where = (
        f"{len(held)} held-out throws (a stratified {args.holdout:.0%} of each object's, "
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
    save_params(params, args.output)
    n_fit: dict[str, int] = {}
    for oid in fit.text("object_id"):
        n_fit[oid] = n_fit.get(oid, 0) + 1
    plots = []
    if args.plot:
        plots = [str(p) for p in _plot(table, start, params, args.plot, np.asarray(held_idx))]
    if args.json:
        print_json(_report(args, source, table, held, result, params, before, after, n_fit, plots))
        return 0
    print(f"{source}: {len(table)} throws of {len(set(table.text('object_id')))} objects")
    print(f"fitted on {result.n_throws} throws; errors below are on {where}")
    print(format_table(before, after, params, n_fit))
    print(
        f"\n{result.iterations} iteration(s), "
        f"{'converged' if result.converged else 'stopped at --max-iter'} "
        f"({result.seconds:.1f} s); landing RMSE on the fitted throws "
        f"{result.rmse_start_m:.4f} -> {result.rmse_fit_m:.4f} m"
    )
    print("end effector (start -> identified):")
    for k in start.ee.IDENTIFIABLE:
        print(f"  {k:4s} {getattr(start.ee, k):12.6g} -> {getattr(params.ee, k):12.6g}")
    print(f"wrote {args.output}")
    for p in plots:
        print(f"wrote {p}")
    return 0


def _throws(args: argparse.Namespace) -> tuple[Any, str]:
    """(the throws to identify from, where they came from): --throws' CSV, else the
    store's throws (InvalidInput when it holds none)."""
    from cell.log import ThrowStore, read_throws_csv

    if args.throws:
        return read_throws_csv(args.throws), args.throws
    with ThrowStore(args.db, read_only=True) as store:
        table = store.table()
        source = str(store.path)
    if len(table) == 0:
        raise InvalidInput(f"{source}: the store holds no throws; give a throws.csv")
    return table, source


def _report(
    args: argparse.Namespace,
    source: str,
    table: Any,
    held: Any,
    result: Any,
    params: Any,
    before: list[Any],
    after: list[Any],
    n_fit: dict[str, int],
    plots: list[str],
) -> dict[str, Any]:
    """`cell identify --json`'s report (see `run`)."""
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
        "end_effector": params.ee.as_dict(),
        "object_params": {
            k: {"mass_kg": o.mass, "size_m": list(o.size)} for k, o in params.objects.items()
        },
        "output": args.output,
        "plots": plots,
    }


def _plot(
    table: ThrowTable, start: ModelParams, params: ModelParams, out_dir: str, held: np.ndarray
) -> list[Path]:
    from cell.identify.plot import plot_reach

    return plot_reach(table, start, params, out_dir, held_out=held)
