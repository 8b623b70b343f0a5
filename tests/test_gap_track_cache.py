"""The whole-track fits are kept between calls in a bounded cache: a log of more tracks than
it holds, or a call that fills it, loses none of its own fits (a traceback before: the
cache cleared half-way through a call's fits, and the rest of the call read them from it)."""

from __future__ import annotations

import numpy as np
import pytest

import cell.gap.tracks as tracks_mod
from cell.gap.tracks import fit_tracks

G = 9.81  # [m/s²]


def _tracks(n: int) -> dict[str, np.ndarray]:
    """n drag-free parabolas sampled at 100 Hz (closed form), 1 mm of scatter."""
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 0.6, 0.01)
    out = {}
    for i in range(n):
        v = np.array([2.0 + 0.1 * i, 0.3, 3.0])
        p = np.array([0.3, 0.0, 1.0]) + np.outer(t, v) + np.outer(0.5 * t**2, [0.0, 0.0, -G])
        out[f"t{i:02d}"] = np.c_[t, p + rng.normal(0.0, 0.001, p.shape)]
    return out


def test_a_call_of_more_tracks_than_the_cache_holds_keeps_all_its_fits(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(tracks_mod, "_CACHE", {})
    monkeypatch.setattr(tracks_mod, "_CACHE_MAX", 3)
    tr = _tracks(8)
    ids = list(tr)
    k = np.zeros(len(ids))
    first = fit_tracks(ids[:2], {i: tr[i] for i in ids[:2]}, k[:2])  # two cached
    fit = fit_tracks(ids, tr, k)  # eight more than the cache's three
    assert len(tracks_mod._CACHE) <= 3
    assert not fit.unusable
    # each fit is the track's own: a parabola's launch state, and the two fitted before alike
    assert np.all(np.isfinite(fit.v0))
    assert np.allclose(fit.v0[:, 0], 2.0 + 0.1 * np.arange(8), atol=0.02)
    assert np.allclose(fit.g_ratio, 1.0, atol=0.02)
    assert np.abs(fit.v0[:2] - first.v0).max() < 1e-9
    again = fit_tracks(ids, tr, k)  # from the cache where it holds them: the same to the last bits
    assert np.abs(again.v0 - fit.v0).max() < 1e-9, np.abs(again.v0 - fit.v0).max()
