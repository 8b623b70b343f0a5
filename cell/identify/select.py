"""Object factors by evidence: each object's prior width chosen by cross-validation.

With some 40 throws of an object and up to four factors (mass and extents), a free
fit of the factors absorbs noise: it lowers the training error and raises the error
on new throws. So each object's factors leave their start (catalogue) values only
as far as throws held out of their fit support. For every prior width p of a grid
(1 σ of each factor around 1; p = 0 keeps the start values) the object's throws are
split into K folds; the factors are fitted (η_ee fixed, MAP with that prior) on K−1
folds and the left-out fold is scored by its whitened squared residuals (−2 log L
under the documented noise, up to a constant). Each object gets the width with the
lowest score (mean over its throws); a tie goes to the narrower width. (The one-
standard-error rule, the narrowest width within one standard error of the lowest,
chose too narrow priors on the far campaigns: held-out RMSE 1.106 and 1.052 × the
floor instead of 1.053 and 1.011 on seeds 0 and 1 of 650 throws.) The objects'
fits are independent given η_ee, so one stage-2 solve per (width, fold) serves them
all.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import numpy as np

from cell.errors import plural
from cell.identify.problem import ThrowData
from cell.model.flight_batch import together
from cell.model.params import EndEffectorParams

__all__ = ["ObjectChoice", "choose_object_priors", "column_priors"]


@dataclass(frozen=True)
class ObjectChoice:
    """Which prior width cross-validation chose for one object, and the scores.

    Attributes:
        object_id: the object.
        throws: its throws in the fit.
        prior_std: the chosen width (1 σ of each factor); 0 = kept at the start values.
        scores: width -> cross-validated −2 log L per throw of the object (whitened
            squared residual of its held-out folds, summed over x and y, averaged).
    """

    object_id: str
    throws: int
    prior_std: float
    scores: dict[float, float] = field(default_factory=dict)

    @property
    def kept(self) -> bool:
        """True: the factors stay at their start (catalogue) values."""
        return self.prior_std == 0

    def reason(self) -> str:
        """Why, in one line."""
        nominal = self.scores.get(0.0, float("nan"))
        if not self.scores:
            return f"{plural(self.throws, 'throw')}: too few to cross-validate; " + (
                "kept" if self.kept else f"fitted with the default prior σ {self.prior_std:g}"
            )
        if self.kept:
            best = min((v for p, v in self.scores.items() if p > 0), default=float("nan"))
            return (
                f"kept: held-out score {nominal:.3f} with the catalogue values, "
                f"{best:.3f} at best when fitted"
            )
        return (
            f"fitted (prior σ {self.prior_std:g}): held-out score "
            f"{self.scores[self.prior_std]:.3f} against {nominal:.3f} with the catalogue values"
        )

    def as_dict(self) -> dict[str, Any]:
        """Plain numbers for JSON."""
        return {
            "throws": self.throws,
            "kept": self.kept,
            "prior_std": self.prior_std,
            "cv_score_by_prior": {f"{p:g}": v for p, v in self.scores.items()},
            "reason": self.reason(),
        }


def _folds(data: ThrowData, k: int) -> np.ndarray:
    """Fold of each throw: each object's throws dealt round the folds in a fixed shuffle
    (an object with fewer than 2k throws round fewer folds, each with two or more)."""
    rng = np.random.default_rng(0)
    fold = np.zeros(len(data), dtype=int)
    for j in range(len(data.object_ids)):
        rows = np.flatnonzero(data.obj == j)
        kj = max(2, min(k, rows.size // 2))  # at least two throws in each of its folds
        fold[rng.permutation(rows)] = np.arange(rows.size) % kj
    return fold


def choose_object_priors(
    data: ThrowData,
    ee: EndEffectorParams,
    grid: tuple[float, ...],
    folds: int,
    solve: Callable[[ThrowData, np.ndarray], np.ndarray],
    fallback: float,
) -> list[ObjectChoice]:
    """Choose each object's prior width by K-fold cross-validation (module docstring).

    Args:
        data: the fitted throws, weights set (`ThrowData.weigh`).
        ee: η_ee held while the factors are fitted.
        grid: prior widths to choose from (0 = keep the start values).
        folds: K.
        solve: (throws, per-factor prior σ) -> fitted factors (stage 2).
        fallback: the prior width of an object with too few throws to cross-validate
            (fewer than four): no held-out evidence either way, so the fixed prior of
            the fit without cross-validation (a scene's objects are not the catalogue's:
            `cell calibrate` on 20 throws, one or two an object, fitted them to a landing
            RMSE of 1.06 m against 0.67 m nominal when they were kept).

    Returns:
        One choice per object id, in `data.object_ids` order.
    """
    col, k = data.factor_columns()
    fold = _folds(data, folds)
    n_obj = len(data.object_ids)
    counts = np.bincount(data.obj, minlength=n_obj)
    widths = sorted(set(grid) | {0.0})
    per = np.zeros((len(widths), len(data)))  # each throw's held-out score per width

    def heldout(p: float, f: int) -> np.ndarray:
        """The held-out residuals of fold f under prior width p."""
        test = fold == f
        x = np.ones(k) if p == 0 else solve(data.take(np.flatnonzero(~test)), np.full(k, p))
        part = data.take(np.flatnonzero(test))
        return part.wres(part.batch_with(part.objects_from_factors(x)), ee)

    # every (width, fold) fit side by side, their flights integrated as one batch
    cells = [(w_i, p, f) for w_i, p in enumerate(widths) for f in range(folds)]
    got = together([partial(heldout, p, f) for _, p, f in cells])
    for (w_i, _, f), res in zip(cells, got, strict=True):
        per[w_i, fold == f] = np.sum(res**2, axis=1)
    out = []
    for j, oid in enumerate(data.object_ids):
        if counts[j] < 4:
            out.append(ObjectChoice(oid, int(counts[j]), fallback))
            continue
        mine = per[:, data.obj == j]
        score = mine.mean(axis=1)
        best = int(np.argmin(score))
        out.append(
            ObjectChoice(
                oid,
                int(counts[j]),
                widths[best],
                {p: float(score[w_i]) for w_i, p in enumerate(widths)},
            )
        )
    return out


def column_priors(data: ThrowData, choices: list[ObjectChoice]) -> np.ndarray:
    """The per-factor prior σ of the stage-2 vector from the per-object choices."""
    col, k = data.factor_columns()
    std = np.zeros(k)
    for j, c in enumerate(choices):
        std[col[j][col[j] >= 0]] = c.prior_std
    return std
