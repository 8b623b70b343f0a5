"""`cell learn`: train the residual ΔL_s on a throw log, with the Table 5.1 evaluation."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace
from typing import Any

from cell.cli.common import (
    add_json_arg,
    human,
    json_to_stdout,
    plural,
    print_json,
    write_json,
)
from cell.errors import CellError, InvalidInput
from cell.log import read_throws_csv
from cell.params import load_params
from cell.residual.learners import LEARNERS, SEARCH_ROWS

# the residual saved where the inner cross-validation chose no learner (`best_params['null']`)
NULL_RESIDUAL = {"zero": "none", "mean": "constant"}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "learn",
        help="learn the stroke residual ΔL_s from a throw log (thesis ch. 5, Table 5.1)",
        description=(
            "Compute ΔL_s for every logged throw by the model's inverse, evaluate SVR, random "
            "forest and MLP by holding out two objects at a time (Table 5.1), and save the "
            "chosen learner trained on every object. The planner then commands L_s + ΔL_s. "
            "The saved learner is judged on the round-robin's held-out throws: unless its "
            "residual lowers their landing RMSE beyond the spread over the held-out objects "
            "(the 95 % interval of a paired bootstrap over them below 1), no residual is "
            "saved (the physics model alone), and the command says so; --keep-learner saves "
            "the learner anyway."
        ),
    )
    p.add_argument("throws", help="throws.csv (docs/throw_log.md)")
    p.add_argument(
        "-o", "--output", required=True, help="the residual model file (.skops; never a pickle)"
    )
    p.add_argument(
        "--params", metavar="EE.yaml", help="identified parameter file (default: reference values)"
    )
    p.add_argument(
        "--identified-objects",
        action="store_true",
        help=(
            "use the parameter file's identified η_o too (default: its η_ee only, with the "
            "logged η_o, which is what an unseen object has; identified η_o soak up the "
            "shape effects the residual is meant to learn)"
        ),
    )
    p.add_argument(
        "--learner", choices=LEARNERS, default="svr", help="learner to save (svr, the thesis')"
    )
    p.add_argument(
        "--compare",
        default=",".join(LEARNERS),
        metavar="L1,L2",
        help="learners of the round-robin table (default: svr,rf,mlp; empty: skip it)",
    )
    p.add_argument("--hold-out", type=int, default=2, metavar="K", help="objects per fold (2)")
    p.add_argument(
        "--keep-learner",
        action="store_true",
        help=(
            "save the learner's residual even where it does not beat the physics model alone "
            "on the round-robin's held-out throws (default: save no residual then, the "
            "physics model alone, and say so)"
        ),
    )
    p.add_argument(
        "--grid",
        choices=("small", "medium", "full"),
        default="medium",
        help=(
            "hyper-parameter grids (medium: full's estimators, without the candidates the "
            "inner CV never chose on 865-throw campaigns; docs/HISTORY.md); a log of more "
            f"than {SEARCH_ROWS} throws is searched on {SEARCH_ROWS} of them, each object's "
            "share, and the choice fitted on all"
        ),
    )
    p.add_argument("--seed", type=int, default=0, help="fold shuffling and learner seed (0)")
    p.add_argument("--plot", metavar="PNG", help="write the Table 5.1 bar chart here")
    add_json_arg(p, "the table")
    from cell.parallel import add_campaign_args

    add_campaign_args(p)  # the round-robin's fits (learner x fold) on Ray
    p.set_defaults(func=run)


MIN_THROWS = 20  # usable throws (and distinct ones in the log) a residual is learned from


def _enough(data: Any, path: str) -> None:
    """Refuse a log with fewer than MIN_THROWS usable throws, or of fewer than 2 objects.

    Raises:
        InvalidInput: naming the log, the counts and the minimums.
    """
    n = int(data.usable.sum())
    objects = len(set(data.groups[data.usable].tolist()))
    if n < MIN_THROWS or objects < 2:
        raise InvalidInput(
            f"{path}: learning the residual needs at least {MIN_THROWS} usable throws of at "
            f"least 2 objects; this log has {plural(n, 'usable throw')} of "
            f"{plural(objects, 'object')}"
        )


def _learners(text: str) -> tuple[str, ...]:
    names = tuple(t.strip() for t in text.split(",") if t.strip())
    bad = [n for n in names if n not in LEARNERS]
    if bad:
        raise InvalidInput(f"--compare: unknown learner(s) {bad}; valid: {', '.join(LEARNERS)}")
    return names


def run(args: argparse.Namespace) -> int:
    from cell.residual.model import training_data

    compare = _learners(args.compare)
    table = read_throws_csv(args.throws)
    table.require_varied(MIN_THROWS, "learning the residual")
    mp = load_params(args.params)
    if mp.effects:
        raise InvalidInput(
            f"{args.params}: effects {sorted(mp.effects)} are switched on; `cell learn` learns "
            "the residual of the nominal (identified) model: use a file without effects"
        )
    data = training_data(table, mp.ee, objects=mp.objects if args.identified_objects else None)
    n_bad = int((~data.usable).sum())
    if n_bad:
        why = {k: v for k, v in data.targets.excluded_counts().items() if v}
        print(
            f"cell learn: {n_bad} of {plural(len(table), 'throw')} excluded (no observed "
            f"landing, or observed reach outside the model's range): {human(why)}",
            file=sys.stderr,
        )
    _enough(data, args.throws)
    try:
        with _one_fit_per_core(args):
            summary, model = _fit(args, data, compare)
    except CellError:
        raise
    except ValueError as exc:  # scikit-learn's refusal of a split too small to fit
        raise InvalidInput(
            f"{args.throws}: too few throws of some objects for the learners' "
            f"cross-validation ({exc}); log more throws of each object"
        ) from None
    model, saved, judged = _judge(args, data, summary, model)
    doc: dict[str, Any] = {name: s.as_dict() for name, s in summary.items()}
    doc["saved"] = saved
    if json_to_stdout(args):
        print_json(doc)
        _say(saved, model)
    else:
        _print(args, summary, compare, model, saved, judged)
    model.save(args.output)  # the results are printed before any file is written
    if args.plot and summary:
        from cell.residual.plot import plot_table51

        plot_table51(summary, args.plot)
    write_json(args, doc)
    return 0


@contextmanager
def _one_fit_per_core(args: argparse.Namespace) -> Iterator[None]:
    """In this process (no Ray), a grid search run here (the saved learner's, with
    `--compare ""`) fits its candidates one per core of the machine (joblib's processes;
    every fit is seeded, so the same model as one at a time); the round-robin's units run
    whole one per core (`round_robin_and_save`). On Ray (`--workers` > 1 or an address)
    each unit fits alone."""
    import os

    from joblib import parallel_config

    alone = args.workers == 1 and not args.ray_address  # run_campaign's in-process case
    with parallel_config(n_jobs=(os.cpu_count() or 1) if alone else 1):
        yield


def _fit(
    args: argparse.Namespace, data: Any, compare: tuple[str, ...]
) -> tuple[dict[str, Any], Any]:
    """The round-robin table (when --compare names learners) and the learner to save,
    its fit one more unit of the round-robin's (beside them, not after them)."""
    from tqdm import tqdm

    from cell.residual.evaluate import round_robin_and_save, round_robin_folds
    from cell.residual.model import train_residual

    if not compare:
        return {}, train_residual(data, learner=args.learner, grid=args.grid, seed=args.seed)
    ids = sorted(set(data.groups[data.usable].tolist()))
    n_fits = len(compare) * len(round_robin_folds(ids, hold_out=args.hold_out, seed=args.seed))
    with tqdm(total=n_fits + 1, desc="round-robin", disable=json_to_stdout(args) or None) as bar:

        def step(text: str) -> None:
            bar.set_postfix_str(text, refresh=False)
            bar.update()

        return round_robin_and_save(
            data,
            save=args.learner,
            learners=compare,
            hold_out=args.hold_out,
            grid=args.grid,
            seed=args.seed,
            progress=step,
            workers=args.workers,
            address=args.ray_address,
            jobs=os.cpu_count() or 1,  # in this process: whole fits one per core
        )


def _judge(
    args: argparse.Namespace, data: Any, summary: dict[str, Any], model: Any
) -> tuple[Any, dict[str, Any], Any]:
    """The saved learner against the physics model alone on the round-robin's held-out
    throws (`cell.residual.heldout`): the model to save (none, the physics alone, where the
    learner does not beat it, unless --keep-learner), the JSON record of the choice, and
    the judgement (None: the round-robin did not run the saved learner)."""
    from cell.residual.heldout import judge_summary
    from cell.residual.model import physics_only

    null = model.best_params.get("null")
    fitted = NULL_RESIDUAL.get(null, args.learner)
    if args.learner not in summary:
        record: dict[str, Any] = {
            "learner": args.learner,
            "residual": fitted,
            "heldout": None,
            "reason": (
                f"{args.learner} not judged on held-out throws: --compare does not name it, "
                "so no fit of it left objects out; saved as the inner cross-validation chose"
            ),
        }
        return replace(model, heldout=record), record, None
    j = judge_summary(args.learner, summary[args.learner], data.groups, seed=args.seed)
    record = {"learner": args.learner, "heldout": j.as_dict()}
    if fitted == "none" or j.beats_physics:
        record["residual"] = fitted
        record["reason"] = (
            "no correction: the inner cross-validation on every throw chose none"
            if fitted == "none"
            else f"{args.learner} beats the physics model alone on the held-out throws"
        )
    elif args.keep_learner:
        record["residual"] = fitted
        record["reason"] = (
            f"--keep-learner: {args.learner} saved though it does not beat the physics model "
            "alone on the held-out throws"
        )
    else:
        record["residual"] = "none"
        record["reason"] = (
            f"{args.learner} does not beat the physics model alone on the held-out throws: "
            "no residual saved (the planner commands the model's own stroke); "
            "--keep-learner saves it anyway"
        )
        return physics_only(model, record), record, j
    return replace(model, heldout=record), record, j


def _print(
    args: argparse.Namespace,
    summary: dict[str, Any],
    compare: tuple[str, ...],
    model: Any,
    saved: dict[str, Any],
    judged: Any,
) -> None:
    """The Table 5.1 rows, the saved learner's held-out judgement, and what was saved, as
    text."""
    if summary:
        print(
            f"Table 5.1: hold out {plural(args.hold_out, 'object')} at a time "
            f"({plural(len(summary[compare[0]].folds), 'fold')})"
        )
        print(f"{'learner':8s} {'ΔL_s MSE [mm²]':>20s} {'held-out landing RMSE [m]':>28s}")
        for name, s in summary.items():
            print(
                f"{name:8s} {s.dls_mse_mean:10.4f} ± {s.dls_mse_std:<8.4f} "
                f"{s.heldout_rmse_before_m:12.4f} -> {s.heldout_rmse_after_m:.4f}"
            )
    if judged is not None:
        print(judged.text())
    params = {k: v for k, v in model.best_params.items() if k not in ("null", "learner_cv_mse_mm2")}
    null = model.best_params.get("null")
    if null is not None and saved["residual"] == NULL_RESIDUAL[null]:
        print(
            f"note: the {model.learner} learner did not beat "
            f"{'no correction' if null == 'zero' else 'a constant correction'} in the inner "
            f"cross-validation (its MSE {model.best_params['learner_cv_mse_mm2']:.3f} mm²): the "
            f"residual saved is that {'zero' if null == 'zero' else 'constant'} correction. "
            "The log shows no systematic ΔL_s this learner can predict."
        )
    if saved["residual"] == "none" and null != "zero":  # the held-out judgement's physics alone
        print(
            f"saved no residual, the physics model alone: {model.learner} does not beat it on "
            "the held-out throws (the planner commands the model's own stroke; --keep-learner "
            f"saves the {model.learner} trained on {plural(model.n_train, 'throw')} of "
            f"{plural(len(model.training_objects), 'object')}) -> {args.output}"
        )
        return
    _say(saved, model)
    if null is not None and saved["residual"] == NULL_RESIDUAL[null]:  # not the learner's
        print(f"saved {_null_text(model, null)} -> {args.output}")
        return
    print(
        f"saved {model.learner} residual ({plural(model.n_train, 'throw')} of "
        f"{plural(len(model.training_objects), 'object')}; "
        + ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in params.items())
        + f") -> {args.output}"
    )


def _null_text(model: Any, null: str) -> str:
    """What a residual the inner cross-validation chose instead of the learner is: the
    zero correction or a constant one (its value), not the learner's hyper-parameters."""
    import numpy as np

    what = (
        "the zero correction (ΔL_s = 0 for every throw: the physics model alone"
        if null == "zero"
        else "a constant correction (ΔL_s = "
        f"{float(np.ravel(model.pipeline[-1].constant_)[0]):+.2f} mm for every throw"
    )
    return (
        f"{what}; fitted on {plural(model.n_train, 'throw')} of "
        f"{plural(len(model.training_objects), 'object')}, not the {model.learner} learner)"
    )


def _say(saved: dict[str, Any], model: Any) -> None:
    """On standard error: a residual saved without the held-out throws' support (kept by
    --keep-learner, or not judged), or none saved for want of it; nothing where the inner
    cross-validation chose no correction itself (the text output says so)."""
    h = saved["heldout"]
    if model.best_params.get("null") == "zero":
        return
    if h is None or not h["beats_physics"]:
        print(f"cell learn: {saved['reason']}", file=sys.stderr)
