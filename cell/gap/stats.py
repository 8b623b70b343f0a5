"""Bootstrap intervals of held-out RMSE differences."""

from __future__ import annotations

import numpy as np

__all__ = ["bootstrap_cut", "bootstrap_rmse"]

N_BOOT = 1000


def _indices(n: int, seed: int, n_boot: int) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, n, size=(n_boot, n))


def bootstrap_cut(
    before_sq: np.ndarray, after_sq: np.ndarray, *, seed: int = 0, n_boot: int = N_BOOT
) -> tuple[float, float, float]:
    """The cut RMSE(before) - RMSE(after) [m] and its 95 % bootstrap interval.

    Args:
        before_sq: per-throw squared held-out miss before [m²], shape (n,).
        after_sq: per-throw squared held-out miss after [m²], shape (n,).
        seed: seed of the resampling (throws drawn with replacement).
        n_boot: number of resamples.

    Returns:
        (cut, low, high) [m].
    """
    b = np.asarray(before_sq, float)
    a = np.asarray(after_sq, float)
    cut = float(np.sqrt(b.mean()) - np.sqrt(a.mean()))
    ix = _indices(b.size, seed, n_boot)
    cuts = np.sqrt(b[ix].mean(axis=1)) - np.sqrt(a[ix].mean(axis=1))
    lo, hi = np.percentile(cuts, [2.5, 97.5])
    return cut, float(lo), float(hi)


def bootstrap_rmse(
    sq: np.ndarray, *, seed: int = 0, n_boot: int = N_BOOT
) -> tuple[float, float, float]:
    """RMSE [m] of per-throw squared misses and its 95 % bootstrap interval."""
    s = np.asarray(sq, float)
    ix = _indices(s.size, seed, n_boot)
    vals = np.sqrt(s[ix].mean(axis=1))
    lo, hi = np.percentile(vals, [2.5, 97.5])
    return float(np.sqrt(s.mean())), float(lo), float(hi)
