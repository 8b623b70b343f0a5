"""The proposal's law pruned of terms that do not pay (`cell.gap.propose`).

The sequentially thresholded least squares (`cell.gap.propose._stlsq`) drops a term whose
contribution falls below λ; terms nearly collinear on a log (an azimuth error constant,
in the stroke, in the mass and in the width, on objects whose mass and width go together)
take large coefficients of opposite signs, so each contributes much and none is dropped,
while the law with one of them predicts the held-out throws as well or better. So the
law λ chose is pruned backward: each of its terms is left out in turn, the rest fitted by
least squares on each fold's training throws and scored on its held-out throws, and the
smaller law whose held-out RMSE, raised by the proposal's penalty per term, is no higher
than the law's replaces it; repeated while a term can go. Where two collinear terms stand
for one (each left out alone raises the miss), no single step goes down; so the law is
also built forward, from no term, adding the term that lowers the penalised held-out
RMSE most while one does, and the lower of the two scores replaces λ's law.
"""

from __future__ import annotations

import numpy as np

__all__ = ["heldout_rmse", "prune"]


def heldout_rmse(a: np.ndarray, y: np.ndarray, folds: list[tuple[np.ndarray, np.ndarray]],
                 cols: list[int]) -> float:  # fmt: skip
    """The held-out RMSE [m] per throw of the law on columns `cols` of a (2n, p) (rows
    throw-major x, y) fitted by least squares on each fold's training throws."""
    sq = np.zeros(a.shape[0] // 2)
    for train, test in folds:
        rows = np.stack([2 * train, 2 * train + 1], 1).ravel()
        rt = np.stack([2 * test, 2 * test + 1], 1).ravel()
        th = np.linalg.lstsq(a[np.ix_(rows, cols)], y[rows], rcond=None)[0]
        e = y[rt] - a[np.ix_(rt, cols)] @ th
        sq[test] = np.sum(e.reshape(-1, 2) ** 2, axis=1)
    return float(np.sqrt(sq.mean()))


def prune(a: np.ndarray, y: np.ndarray, folds: list[tuple[np.ndarray, np.ndarray]],
          th: np.ndarray, score: float, penalty: float
          ) -> tuple[np.ndarray, float, float] | None:  # fmt: skip
    """The law th (p,) of the misses y (2n,) over a (2n, p) with fewer terms (module
    docstring): (its coefficients fitted on every throw, its held-out RMSE [m], its
    score), or None where no term can go. `score`: the law's held-out RMSE raised by
    `penalty` per term."""
    on = [int(j) for j in np.flatnonzero(th)]
    got: tuple[float, float, list[int]] | None = None
    fwd = _forward(a, y, folds, penalty)
    if fwd is not None and fwd[0] < score:
        got = fwd
        score = fwd[0]
    while len(on) > 1:
        best: tuple[float, float, list[int]] | None = None
        for j in on:
            sub = [c for c in on if c != j]
            ho = heldout_rmse(a, y, folds, sub)
            val = ho * (1.0 + penalty * len(sub))
            if val <= score and (best is None or val < best[0]):
                best = (val, ho, sub)
        if best is None:
            break
        got = best
        score, _, on = best
    if got is None:
        return None
    on = got[2]
    out = np.zeros_like(th)
    out[on] = np.linalg.lstsq(a[:, on], y, rcond=None)[0]
    return out, got[1], got[0]


def _forward(a: np.ndarray, y: np.ndarray, folds: list[tuple[np.ndarray, np.ndarray]],
             penalty: float) -> tuple[float, float, list[int]] | None:  # fmt: skip
    """The law built forward (module docstring): (its score, held-out RMSE, columns), or
    None where no term lowers the score of no law."""
    base = float(np.sqrt(np.mean(y * y) * 2))
    on: list[int] = []
    got: tuple[float, float, list[int]] | None = None
    score = base
    while True:
        best: tuple[float, float, list[int]] | None = None
        for j in range(a.shape[1]):
            if j in on or not np.any(a[:, j]):
                continue
            ho = heldout_rmse(a, y, folds, [*on, j])
            val = ho * (1.0 + penalty * (len(on) + 1))
            if val < score and (best is None or val < best[0]):
                best = (val, ho, [*on, j])
        if best is None:
            return got
        got, (score, _, on) = best, best
