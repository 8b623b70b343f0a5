"""Landings the noise model calls impossible: outliers flagged by row (GAP.md).

A logged landing is an outlier when its miss lies farther from what explains its
neighbours than the scatter allows: with a 2-D Gaussian scatter of per-axis σ, a miss
d beyond c σ has probability exp(−c²/2); c is set so that a log of n throws flags an
in-noise throw with probability OUTLIER_P in all (c² = 2 ln(n / OUTLIER_P)). σ is robust:
the median of d² over the log divided by that of χ²₂ (2 ln 2).

Two passes:

* before the diagnosis (`screen`): the baseline's miss of each throw against the
  component-wise median miss of its NEIGHBOURS nearest throws on the model's trajectory
  (landing point, impact and launch velocity, flight time): throws on the same
  trajectory share whatever effect acts on it. Flagged throws are left out of every fit
  and score, so they do not drive the verdict.
* after it (`flag`): the misses of every throw under the verdict's effects (fitted on
  the kept throws) against the same threshold: these rows are reported.

The held-out error is then reported plain (every throw) and robust (trimmed: the flagged
throws left out); the verdict's 1.3 × F test uses the robust one.
"""

from __future__ import annotations

import numpy as np

from cell.model.throw import Landing

__all__ = ["screen", "flag", "threshold_sq", "OUTLIER_P", "NEIGHBOURS"]

OUTLIER_P = 0.01  # chance that a log with no outlier has one flagged
NEIGHBOURS = 6
CHI2_2_MEDIAN = 2.0 * np.log(2.0)


def threshold_sq(n: int) -> float:
    """c² of a log of n throws: P(χ²₂ > c²) = OUTLIER_P / n."""
    return float(2.0 * np.log(max(n, 1) / OUTLIER_P))


def _robust_sigma_sq(d2: np.ndarray) -> float:
    return float(np.median(d2) / CHI2_2_MEDIAN)


def flag(miss: np.ndarray) -> np.ndarray:
    """Throws whose 2-D miss (n, 2) [m] is impossible under a robust Gaussian scatter."""
    d2 = np.sum(np.nan_to_num(np.asarray(miss, float), nan=1e3) ** 2, axis=1)
    s2 = _robust_sigma_sq(d2)
    if s2 <= 0:
        return np.zeros(d2.size, bool)
    return np.asarray(d2 > threshold_sq(d2.size) * s2)


def screen(residual: np.ndarray, land: Landing) -> np.ndarray:
    """Throws whose baseline miss (n, 2) [m] departs from its trajectory neighbours' by
    more than the scatter allows (bool mask)."""
    from scipy.spatial import cKDTree

    r = np.nan_to_num(np.asarray(residual, float), nan=3.0)
    n = r.shape[0]
    if n < 3 * NEIGHBOURS:
        return np.zeros(n, bool)
    f = np.c_[land.xy, land.impact_velocity, land.t_flight, land.launch_velocity]
    f = np.where(np.isfinite(f), f, 0.0)
    z = (f - f.mean(axis=0)) / np.maximum(f.std(axis=0), 1e-12)
    _, j = cKDTree(z).query(z, k=NEIGHBOURS + 1)
    own = np.arange(n)[:, None]
    others = np.where(j == own, -1, j)
    med = np.empty_like(r)
    for i in range(n):
        nb = others[i][others[i] >= 0][:NEIGHBOURS]
        med[i] = np.median(r[nb], axis=0)
    return flag(r - med)
