"""The evaluation of thesis Table 5.1: hold two objects out at a time in a
round-robin, train on the rest (hyper-parameters tuned by inner CV on the rest
only), and report per learner the mean ± std over folds of the ΔL_s MSE on the
held-out objects, and the landing RMSE on the held-out throws without and with
the residual.

Landing error on a plain log (the world is unknown): without the residual, the
model's landing at the stroke used against the observed landing; with it, the
model's landing at L_used - ΔL_s (the model-equivalent stroke of the throw,
ΔL_s predicted at that stroke by a short fixed-point iteration) against the
observed landing.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cell.errors import InvalidParameter
from cell.model.throw import Landing, ThrowBatch, predict_landing
from cell.residual.features import FEATURE_NAMES
from cell.residual.learners import LEARNERS
from cell.residual.model import ResidualModel, TrainingData, train_residual

__all__ = [
    "Fold",
    "FoldResult",
    "LearnerSummary",
    "round_robin_folds",
    "round_robin",
    "residual_landing",
    "FitUnit",
    "SaveUnit",
    "fit_fold",
    "fit_saved",
    "round_robin_and_save",
]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Fold:
    """One round-robin fold.

    Attributes:
        held_out: object ids held out (tested on).
        train: object ids trained on.
    """

    held_out: tuple[str, ...]
    train: tuple[str, ...]


@dataclass(frozen=True)
class FoldResult:
    """One learner on one fold.

    Attributes:
        fold: the fold.
        learner: learner name.
        test_rows: indices of the held-out usable throws in the log.
        delta_pred_m: predicted ΔL_s on them [m].
        dls_mse_mm2: ΔL_s MSE on them [mm²].
        sq_err_before_m2: squared landing error without the residual [m²] per throw.
        sq_err_after_m2: squared landing error with it [m²] per throw.
        training_objects: objects the fitted model was trained on.
        best_params: the inner CV's choice.
        model: the fold's fitted residual.
    """

    fold: Fold
    learner: str
    test_rows: np.ndarray
    delta_pred_m: np.ndarray
    dls_mse_mm2: float
    sq_err_before_m2: np.ndarray
    sq_err_after_m2: np.ndarray
    training_objects: tuple[str, ...]
    best_params: dict[str, Any] = field(default_factory=dict)
    model: ResidualModel | None = None


@dataclass(frozen=True)
class LearnerSummary:
    """Table 5.1's row of one learner.

    Attributes:
        dls_mse_mean: mean over folds of the held-out ΔL_s MSE [mm²].
        dls_mse_std: its standard deviation over folds [mm²].
        heldout_rmse_before_m: landing RMSE of all held-out throws without the residual [m].
        heldout_rmse_after_m: the same with the residual [m].
        folds: per-fold results.
    """

    dls_mse_mean: float
    dls_mse_std: float
    heldout_rmse_before_m: float
    heldout_rmse_after_m: float
    folds: list[FoldResult]

    def as_dict(self) -> dict[str, Any]:
        """The JSON form (`cell learn --json`)."""
        return {
            "dls_mse_mean": self.dls_mse_mean,
            "dls_mse_std": self.dls_mse_std,
            "heldout_rmse_before_m": self.heldout_rmse_before_m,
            "heldout_rmse_after_m": self.heldout_rmse_after_m,
            "folds": [
                {
                    "held_out": list(f.fold.held_out),
                    "dls_mse_mm2": f.dls_mse_mm2,
                    "n_test": int(f.test_rows.size),
                    "rmse_before_m": float(np.sqrt(np.mean(f.sq_err_before_m2))),
                    "rmse_after_m": float(np.sqrt(np.mean(f.sq_err_after_m2))),
                    "best_params": {k: _plain(v) for k, v in f.best_params.items()},
                }
                for f in self.folds
            ],
        }


def _plain(v: Any) -> Any:
    return list(v) if isinstance(v, tuple) else v


def round_robin_folds(object_ids: list[str], *, hold_out: int = 2, seed: int = 0) -> list[Fold]:
    """Disjoint folds of `hold_out` objects each, every object held out exactly once
    (a leftover smaller than `hold_out` joins the last fold); objects are shuffled
    with `seed` first.

    Raises:
        InvalidParameter: fewer objects than hold_out + 2 (training needs 2 for its inner CV).
    """
    ids = sorted(set(object_ids))
    if hold_out < 1:
        raise InvalidParameter(f"--hold-out {hold_out}: hold out at least 1 object per fold")
    if len(ids) < hold_out + 2:
        raise InvalidParameter(
            f"a round-robin holding out {hold_out} objects needs at least {hold_out + 2} objects; "
            f"the log has {len(ids)}"
        )
    order = [ids[i] for i in np.random.default_rng(seed).permutation(len(ids))]
    chunks = [order[i : i + hold_out] for i in range(0, len(order), hold_out)]
    if len(chunks) > 1 and len(chunks[-1]) < hold_out:
        chunks[-2].extend(chunks.pop())
    return [Fold(held_out=tuple(sorted(c)), train=tuple(sorted(set(ids) - set(c)))) for c in chunks]


def residual_landing(
    model: ResidualModel,
    data: TrainingData,
    rows: np.ndarray,
    predict: Callable[[ThrowBatch], Landing],
    iterations: int = 2,
) -> tuple[np.ndarray, np.ndarray]:
    """The model-with-residual landing of logged throws: the model's landing at
    L_used - ΔL_s, with ΔL_s predicted at that stroke (fixed-point iteration).

    Returns:
        (landing points [m, W] shape (k, 2), ΔL_s [m] shape (k,)).
    """
    batch = data.batch.take(rows)
    x = data.features[rows].copy()
    x[:, FEATURE_NAMES.index("stroke_m")] = batch.stroke
    from cell.model.band import band_angle, band_stretch

    width = batch.size[:, 0]
    delta = np.zeros(len(batch))
    for _ in range(iterations + 1):
        s = batch.stroke - delta
        x[:, FEATURE_NAMES.index("stroke_m")] = s
        x[:, FEATURE_NAMES.index("band_stretch_m")] = band_stretch(s, width, model.ee)
        x[:, FEATURE_NAMES.index("band_angle_rad")] = band_angle(s, width, model.ee)
        delta = model.predict_features(x)
    eq = ThrowBatch(
        **{
            **{k: getattr(batch, k) for k in batch.__dataclass_fields__},
            "stroke": batch.stroke - delta,
        }
    )
    return predict(eq).xy, delta


@dataclass(frozen=True)
class FitUnit:
    """One fit of the round-robin: a learner on a fold (a picklable unit of a campaign).

    Attributes:
        data: the training data (all rows; the fold's held-out objects are left out).
        learner: learner name.
        fold: the fold.
        grid: "small", "medium" or "full".
        seed: the learner's random state.
        predict: the model, batch -> Landing (None: nominal with the data's ee).
    """

    data: TrainingData
    learner: str
    fold: Fold
    grid: str
    seed: int
    predict: Callable[[ThrowBatch], Landing] | None = None


@dataclass(frozen=True)
class SaveUnit:
    """The learner `cell learn` saves, tuned and fitted on every usable throw, as one more
    unit of the round-robin's campaign (it does not depend on the round-robin's results).

    Attributes:
        data: the training data.
        learner: learner name.
        grid: "small", "medium" or "full".
        seed: the learner's random state.
    """

    data: TrainingData
    learner: str
    grid: str
    seed: int


def fit_saved(unit: SaveUnit) -> ResidualModel:
    """`train_residual` on every usable throw of the unit's data."""
    return train_residual(unit.data, learner=unit.learner, grid=unit.grid, seed=unit.seed)


def _fit_unit(unit: FitUnit | SaveUnit) -> Any:
    return fit_saved(unit) if isinstance(unit, SaveUnit) else fit_fold(unit)


# CPU seconds of one grid candidate (its fits on the inner folds) by learner, on 711
# training throws: the round-robin's units of `cell synth --seed 0` (865 throws, --grid
# medium; rf 7.9, mlp 4.7, svr 3.5 CPU-s a unit of 4, 2 and 24 candidates, in joblib's
# processes, one per core). Only the order the units start in reads them.
CANDIDATE_CPU_S = {"rf": 1.97, "mlp": 2.34, "svr": 0.147}
CANDIDATE_CPU_ROWS = 711
CANDIDATE_CPU_POWER = {"rf": 1.0, "mlp": 1.0, "svr": 2.0}  # the SVR's kernel: rows squared


def unit_cost(unit: FitUnit | SaveUnit) -> float:
    """A unit's estimated CPU time [s]: its grid's candidates, each CANDIDATE_CPU_S
    scaled by the usable throws the unit trains on (not by any time measured in the run)."""
    from cell.residual.learners import GRIDS

    data = unit.data
    rows = data.usable
    if isinstance(unit, FitUnit):
        rows = rows & ~np.isin(data.groups, unit.fold.held_out)
    n_candidates = int(np.prod([len(v) for v in GRIDS[unit.learner][unit.grid].values()]))
    scale = (float(np.sum(rows)) / CANDIDATE_CPU_ROWS) ** CANDIDATE_CPU_POWER[unit.learner]
    return n_candidates * CANDIDATE_CPU_S[unit.learner] * scale


def _nominal(ee: Any) -> Callable[[ThrowBatch], Landing]:
    def predict(b: ThrowBatch) -> Landing:
        return predict_landing(b, ee, strict=False, check_stroke=False)

    return predict


def fit_fold(unit: FitUnit) -> tuple[np.ndarray, np.ndarray, np.ndarray, ResidualModel]:
    """Train on the fold's training objects and predict its held-out throws.

    Returns:
        (held-out usable rows, their predicted ΔL_s [m], their landings with the
        residual [m, W] shape (k, 2), the fitted model).
    """
    data = unit.data
    held = np.isin(data.groups, unit.fold.held_out)
    model = train_residual(data, learner=unit.learner, grid=unit.grid, rows=~held, seed=unit.seed)
    if set(model.training_objects) & set(unit.fold.held_out):
        raise InvalidParameter("internal: a held-out object reached training")
    test = np.flatnonzero(held & data.usable)
    pred = model.predict_features(data.features[test])
    after_xy, _ = residual_landing(model, data, test, unit.predict or _nominal(data.ee))
    return test, pred, after_xy, model


def _summary(name: str, results: list[FoldResult]) -> LearnerSummary:
    """Learner `name`'s summary over its folds, logged: the ΔL_s MSE's mean and spread
    [mm²], the held-out landing RMSE before and after [m]."""
    mses = np.array([r.dls_mse_mm2 for r in results])
    out = LearnerSummary(
        dls_mse_mean=float(mses.mean()),
        dls_mse_std=float(mses.std()),
        heldout_rmse_before_m=float(
            np.sqrt(np.mean(np.concatenate([r.sq_err_before_m2 for r in results])))
        ),
        heldout_rmse_after_m=float(
            np.sqrt(np.mean(np.concatenate([r.sq_err_after_m2 for r in results])))
        ),
        folds=results,
    )
    log.info(
        "%s: ΔL_s MSE %.4f ± %.4f mm², held-out landing RMSE %.4f -> %.4f m",
        name,
        out.dls_mse_mean,
        out.dls_mse_std,
        out.heldout_rmse_before_m,
        out.heldout_rmse_after_m,
    )
    return out


def _fit_in_processes(
    units: list[FitUnit | SaveUnit], jobs: int, done: Callable[[int, Any], None]
) -> list[Any]:
    """`fit_fold` / `fit_saved` on every unit, `jobs` at a time in joblib's processes;
    results in unit order. A whole fit (its grid search and its refit) runs in one
    process. The units start longest first (`unit_cost`, a fixed estimate), so the last
    ones to finish are short and no core waits long for the other's last fit; `done` is
    called as each finishes, in that order."""
    from joblib import Parallel, delayed

    order = sorted(range(len(units)), key=lambda i: -unit_cost(units[i]))
    out: list[Any] = [None] * len(units)
    fits = Parallel(n_jobs=jobs, return_as="generator")(delayed(_fit_unit)(units[i]) for i in order)
    for i, r in zip(order, fits, strict=True):  # a process's grid searches: one fit at a time
        out[i] = r
        done(i, r)
    return out


def round_robin(
    data: TrainingData,
    *,
    learners: tuple[str, ...] = LEARNERS,
    hold_out: int = 2,
    grid: str = "full",
    seed: int = 0,
    predict: Callable[[ThrowBatch], Landing] | None = None,
    progress: Callable[[str], None] | None = None,
    workers: int = 1,
    address: str | None = None,
    jobs: int = 1,
) -> dict[str, LearnerSummary]:
    """Table 5.1: the round-robin evaluation of each learner.

    Args:
        data: from `training_data`.
        learners: which learners.
        hold_out: objects held out per fold (thesis: 2).
        grid: "small", "medium" or "full" hyper-parameter grids.
        seed: shuffles the objects into folds; random state of the learners.
        predict: the model, batch -> Landing (default: nominal with the data's ee).
        progress: called with a short text after each fit (the CLI's progress bar).
        workers, address: fit on Ray (cell.parallel), one fit (learner × fold) a unit;
            the same table as in this process (every fit is seeded).
        jobs: in this process (workers 1, no address), how many fits (learner × fold)
            run at a time, one per joblib process (each fit alone inside, its grid
            search and refit on one core); the same table as one at a time (seeded).

    Returns:
        learner name -> its summary.
    """
    summary, _ = _round_robin(
        data, learners, hold_out, grid, seed, predict, progress, workers, address, jobs, None
    )
    return summary


def round_robin_and_save(
    data: TrainingData,
    *,
    save: str,
    learners: tuple[str, ...] = LEARNERS,
    hold_out: int = 2,
    grid: str = "full",
    seed: int = 0,
    predict: Callable[[ThrowBatch], Landing] | None = None,
    progress: Callable[[str], None] | None = None,
    workers: int = 1,
    address: str | None = None,
    jobs: int = 1,
) -> tuple[dict[str, LearnerSummary], ResidualModel]:
    """`round_robin`, and the learner `save` tuned and fitted on every usable throw
    (`train_residual(data, learner=save, grid=grid, seed=seed)`, the model `cell learn`
    saves) as one more unit of the same campaign: it runs beside the round-robin's fits,
    not after them. The same table and model as the two one after the other (seeded).

    Returns:
        (learner name -> its summary, the saved learner's model).
    """
    summary, model = _round_robin(
        data, learners, hold_out, grid, seed, predict, progress, workers, address, jobs, save
    )
    assert model is not None
    return summary, model


def _round_robin(
    data: TrainingData,
    learners: tuple[str, ...],
    hold_out: int,
    grid: str,
    seed: int,
    predict: Callable[[ThrowBatch], Landing] | None,
    progress: Callable[[str], None] | None,
    workers: int,
    address: str | None,
    jobs: int,
    save: str | None,
) -> tuple[dict[str, LearnerSummary], ResidualModel | None]:
    from cell.parallel import run_campaign

    usable_ids = sorted(set(data.groups[data.usable].tolist()))
    folds = round_robin_folds(usable_ids, hold_out=hold_out, seed=seed)
    observed = data.table.landed
    before_all = (predict or _nominal(data.ee))(data.batch).xy
    rr_units = [
        FitUnit(data, name, fold, grid, seed, predict) for name in learners for fold in folds
    ]
    units: list[FitUnit | SaveUnit] = [*rr_units]
    if save is not None:
        units.append(SaveUnit(data, save, grid, seed))

    def done(i: int, r: Any) -> None:
        if progress is not None:
            u = units[i]
            if isinstance(u, SaveUnit):
                progress(f"{u.learner} on every object")
            else:
                progress(f"{u.learner} held out {', '.join(u.fold.held_out)}")

    if jobs > 1 and workers == 1 and not address:
        fits = _fit_in_processes(units, jobs, done)
    else:
        fits = run_campaign(
            _fit_unit,
            units,
            workers=workers,
            address=address,
            desc="round-robin",
            on_result=done,
            progress=False,
        )
    saved = fits.pop() if save is not None else None
    out: dict[str, LearnerSummary] = {}
    for name in learners:
        results: list[FoldResult] = []
        for unit, (test, pred, after_xy, model) in zip(rr_units, fits, strict=True):
            if unit.learner != name:
                continue
            err = (pred - data.targets.delta_stroke[test]) * 1000.0
            results.append(
                FoldResult(
                    fold=unit.fold,
                    learner=name,
                    test_rows=test,
                    delta_pred_m=pred,
                    dls_mse_mm2=float(np.mean(err**2)),
                    sq_err_before_m2=np.sum((before_all[test] - observed[test]) ** 2, axis=1),
                    sq_err_after_m2=np.sum((after_xy - observed[test]) ** 2, axis=1),
                    training_objects=model.training_objects,
                    best_params=model.best_params,
                    model=model,
                )
            )
        out[name] = _summary(name, results)
    return out, saved
