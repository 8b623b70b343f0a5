"""Landings the noise model calls impossible: outliers flagged by row (GAP.md).

A logged landing is an outlier when its miss lies farther from what explains its
neighbours than the scatter allows: with a 2-D Gaussian scatter of per-axis σ, a miss
d beyond c σ has probability exp(−c²/2); c is set so that a log of n throws flags an
in-noise throw with probability OUTLIER_P in all (c² = 2 ln(n / OUTLIER_P)). σ is robust:
the median of d² over the log divided by that of χ²₂ (2 ln 2).

Passes: the diagnosis runs on every throw; the misses of every throw under the verdict's
effects (or under the law proposed for an `unknown` verdict, `cell.gap.propose`) are
tested against the threshold, and when that flags rows, the diagnosis runs again without
them (so that they do not drive the verdict), and again without the rows that pass's
verdict flags, until a pass is fitted without the very rows its verdict flags (at most
`cell.gap.run.MAX_PASSES`): the verdict is judged on the rows it reports. A first pass
that the outliers' misses pull to `none` (they widen the repeats' floor) flags on the
baseline's misses, the throws a large real gap moves most among them; the next pass's
verdict explains those and puts them back. The rows are reported by row. (A
screen before any fit, on the misses of trajectory neighbours, was tried and dropped: it
screens out the throws a large real gap moves most.)

The held-out error is then reported plain (every throw) and robust (trimmed: the flagged
throws left out); the verdict's 1.3 × F test uses the robust one.
"""

from __future__ import annotations

import numpy as np

__all__ = ["flag", "threshold_sq", "OUTLIER_P"]

OUTLIER_P = 0.01  # chance that a log with no outlier has one flagged
CHI2_2_MEDIAN = 2.0 * np.log(2.0)


def threshold_sq(n: int) -> float:
    """c² of a log of n throws: P(χ²₂ > c²) = OUTLIER_P / n."""
    return float(2.0 * np.log(max(n, 1) / OUTLIER_P))


def _robust_sigma_sq(d2: np.ndarray) -> float:
    return float(np.median(d2) / CHI2_2_MEDIAN)


def flag(miss: np.ndarray, factor: float = 1.0) -> np.ndarray:
    """Throws whose 2-D miss (n, 2) [m] is impossible under a robust Gaussian scatter
    (beyond factor · c σ)."""
    d2 = np.sum(np.nan_to_num(np.asarray(miss, float), nan=1e3) ** 2, axis=1)
    s2 = _robust_sigma_sq(d2)
    if s2 <= 0:
        return np.zeros(d2.size, bool)
    return np.asarray(d2 > factor**2 * threshold_sq(d2.size) * s2)
