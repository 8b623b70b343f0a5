"""Fitting effects on training throws and scoring them on held-out throws.

An effect set's parameters are fitted with `scipy.optimize.least_squares`
(bounded, trust-region reflective) on the landing misses of the training
throws, in coordinates scaled by each parameter's typical size. The held-out
score pools both schemes of the problem (leave-objects-out and random
folds): every throw is predicted by fits that never saw it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from cell.gap.fit_jac import (
    clipped_blocks,
    misses_many,
    refit_folds,
    side_by_side_fun_jac,
    stackable,
    stacked_fun_jac,
)
from cell.gap.problem import GapProblem, rmse
from cell.model.effects import Effect
from cell.model.flight_batch import together as side_by_side

__all__ = ["Fit", "fit_set", "fit_start", "score_set", "Score"]

DIFF_STEP = 1e-3  # relative step of the fit's forward-difference Jacobian


@dataclass(frozen=True)
class Fit:
    """Fitted effects and their training RMSE [m]."""

    effects: tuple[Effect, ...]
    x: np.ndarray  # scaled parameter vector
    train_rmse_m: float
    ci: np.ndarray | None = None  # 95 % intervals of the parameters (p, 2), physical units


@dataclass(frozen=True)
class Score:
    """An effect set fitted on all throws and scored held-out.

    Attributes:
        names: the effects' names.
        full: the fit on all throws (its parameters are the ones reported).
        heldout: per throw, the mean squared held-out miss over the schemes [m²], shape (n,).
        heldout_rmse_m: pooled held-out RMSE [m].
        permuted: True if the effects read their logged quantity permuted.
    """

    names: tuple[str, ...]
    full: Fit
    heldout: np.ndarray
    heldout_rmse_m: float
    permuted: bool = False


def fit_start(cls: type[Effect]) -> np.ndarray:
    """Where a fit of `cls` without a warm start begins (physical units): its `start`, or
    its neutral size (`cell.model.effects.Effect.start`)."""
    return np.asarray(cls.start if cls.start is not None else cls.neutral().vector(), float)


def _layout(classes: list[type[Effect]]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    scale = np.concatenate([np.asarray(c.scale, float) for c in classes])
    lo = np.concatenate([[b[0] for b in c.bounds] for c in classes])
    hi = np.concatenate([[b[1] for b in c.bounds] for c in classes])
    x0 = np.concatenate([fit_start(c) for c in classes])
    return scale, lo / scale, hi / scale, x0 / scale


def _unpack(classes: list[type[Effect]], x: np.ndarray, scale: np.ndarray) -> tuple[Effect, ...]:
    return tuple(c.from_vector(v) for c, v in clipped_blocks(classes, np.asarray(x) * scale))


def fit_set(
    prob: GapProblem,
    classes: list[type[Effect]],
    train: np.ndarray,
    *,
    x0: np.ndarray | None = None,
    permute: bool = False,
    max_nfev: int | None = None,
) -> tuple[Fit, np.ndarray, np.ndarray]:
    """Fit an effect set's parameters on the training throws.

    Args:
        prob: the problem.
        classes: the effect classes to fit together.
        train: indices of the training throws.
        x0: a warm start (scaled parameters), else each effect's `fit_start`.
        permute: the permutation control (effects read their quantity shuffled).
        max_nfev: a cap on function evaluations.

    Returns:
        The fit, the residual vector (2m,) and its Jacobian (2m, p) at the solution.
    """
    scale, lo, hi, start = _layout(classes)
    start = np.clip(start if x0 is None else x0, lo, hi)
    # TRF crawls from a start on (or next to) a bound: the neutral size of many effects is
    # a bound (no band mass, no slide), so start one typical size inside
    inset = np.minimum(1.0, 0.05 * (hi - lo))
    start = np.clip(start, lo + inset, hi - inset)

    def one(x: np.ndarray) -> np.ndarray:
        return prob.residual(train, _unpack(classes, x, scale), permute=permute).ravel()

    # scipy's own forward differences, every perturbed vector in one flight (bitwise the
    # same), made with each residual: the Jacobian at an accepted step is already there
    fun: Callable[[np.ndarray], np.ndarray] = one
    jac: Any
    if stackable(classes, permute):
        fun, jac = stacked_fun_jac(prob, classes, train, scale, (lo, hi), DIFF_STEP)
    else:  # scipy's differences, the perturbed vectors' flights integrated together
        fun, jac = side_by_side_fun_jac(one, (lo, hi), DIFF_STEP)
    res = least_squares(
        fun,
        start,
        jac=jac,
        bounds=(lo, hi),
        method="trf",
        diff_step=DIFF_STEP,
        x_scale=1.0,
        max_nfev=max_nfev or 40 * len(start),
        xtol=1e-5,
        ftol=1e-6,
    )
    eff = _unpack(classes, res.x, scale)
    r = res.fun.reshape(-1, 2)
    j_sol = np.asarray(res.jac)
    ci = intervals(res.x, res.fun, j_sol, scale, lo, hi)
    return Fit(effects=eff, x=res.x, train_rmse_m=rmse(r), ci=ci), res.fun, j_sol


def intervals(
    x: np.ndarray, r: np.ndarray, jac: np.ndarray, scale: np.ndarray, lo: np.ndarray,
    hi: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """95 % intervals of least-squares parameters (p, 2) [physical units]: ±1.96 standard
    errors from the Gauss-Newton covariance σ² (JᵀJ)⁻¹, σ² the residual variance; clipped
    to the bounds."""
    m, p = jac.shape
    s2 = float(r @ r) / max(m - p, 1)
    cov = s2 * np.linalg.pinv(jac.T @ jac)
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    lo_x = np.clip(x - 1.96 * se, lo, hi)
    hi_x = np.clip(x + 1.96 * se, lo, hi)
    return np.stack([lo_x * scale, hi_x * scale], axis=1)


def _refit(
    prob: GapProblem,
    classes: list[type[Effect]],
    train: np.ndarray,
    x: np.ndarray,
    r_all: np.ndarray,
    jac_all: np.ndarray,
    permute: bool,
) -> np.ndarray:
    """Parameters fitted on the training throws only: Gauss-Newton (chord) iterations on
    the training rows' misses, started from the all-throws fit and its Jacobian; a step
    that does not lower the training cost is halved (up to three times) or dropped."""
    scale, lo, hi, _ = _layout(classes)
    rows = np.stack([2 * train, 2 * train + 1], axis=1).ravel()
    j = jac_all[rows]
    r = r_all[rows]
    cost = float(r @ r)
    # the misses at each x tried: a step clipped to a bound (or halved onto one) can try
    # the same x again, and so can the second iteration from an accepted step
    tried: dict[bytes, np.ndarray] = {}
    for _ in range(2):
        step = np.linalg.lstsq(j, -r, rcond=1e-8)[0]
        for _ in range(4):
            x_new = np.clip(x + step, lo, hi)
            key = x_new.tobytes()
            if key not in tried:
                tried[key] = prob.residual(
                    train, _unpack(classes, x_new, scale), permute=permute
                ).ravel()
            r_new = tried[key]
            c_new = float(r_new @ r_new)
            if c_new <= cost:
                x, r, cost = x_new, r_new, c_new
                break
            step = 0.5 * step
    return x


def score_set(
    prob: GapProblem,
    classes: list[type[Effect]],
    *,
    permute: bool = False,
    warm: np.ndarray | None = None,
) -> Score:
    """Fit an effect set on all throws and score it on held-out throws of every scheme.

    Each fold's parameters come from the fold's training throws alone, by
    Gauss-Newton iterations on their misses started from the all-throws fit
    (with its Jacobian): they only have to move a little, which keeps the
    diagnosis fast.
    """
    n = len(prob)
    scale = _layout(classes)[0]
    # a warm start (a pair from its singles) needs fewer evaluations than a cold one
    cap = 15 * len(_layout(classes)[0]) if warm is not None else None
    full, r_all, jac = fit_set(prob, classes, np.arange(n), x0=warm, permute=permute, max_nfev=cap)
    sq = np.zeros(n)
    schemes = 0
    # the folds of every scheme refitted and predicted in lockstep
    together = stackable(classes, permute) and bool(prob.folds)
    if together:
        flat = [f for folds in prob.folds.values() for f in folds]
        lo, hi = _layout(classes)[1:3]
        xs = refit_folds(prob, classes, [t for t, _ in flat], full.x, r_all, jac, (lo, hi))
        got = iter(misses_many(prob, classes, [t for _, t in flat], np.array(xs), scale))
    else:  # each fold refitted and predicted on its own, their flights integrated together

        def fold(train: np.ndarray, test: np.ndarray) -> np.ndarray:
            x = _refit(prob, classes, train, full.x, r_all, jac, permute)
            return prob.residual(test, _unpack(classes, x, scale), permute=permute)

        flat = [f for folds in prob.folds.values() for f in folds]
        got = iter(side_by_side([partial(fold, train, test) for train, test in flat]))
    for folds in prob.folds.values():
        r = np.zeros((n, 2))
        for _, test in folds:
            r[test] = np.reshape(next(got), (-1, 2))
        sq += np.sum(r * r, axis=1)
        schemes += 1
    sq /= max(schemes, 1)
    return Score(
        names=tuple(c.name for c in classes),
        full=full,
        heldout=sq,
        heldout_rmse_m=float(np.sqrt(np.mean(sq))),
        permuted=permute,
    )
