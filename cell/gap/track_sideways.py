"""A tracker's scale or a wind, told apart by what each predicts over the whole tracks.

Seen only through its tracks, another launcher's throws under a tracker off in scale s
and under a steady wind both miss the model's landings; their signatures differ over the
whole track. A scale s multiplies every position: the tracked flight is exactly a flight
under gravity s·G with drag k/s, in the same vertical plane, so it bends nothing
sideways. A wind pushes the flight across its plane, by an amount that grows with time,
and leaves gravity alone. Each track is fitted three ways with drag in the dynamics
(`cell.gap.track_ode`): nominal (the start state alone), "scale" (gravity and drag scale
free) and "wind" (a horizontal wind free), each freeing two parameters over the nominal.
The improvement of each over the nominal, in units of the tracks' scatter (χ²), says
which the tracks carry; a scale is adopted only where it is the one they carry.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.gap.track_launch import pad_tracks
from cell.gap.track_ode import fit_ode
from cell.model.params import G

__all__ = ["MAX_TRACKS", "scale_or_wind"]

MAX_TRACKS = 120  # tracks fitted at most (evenly chosen)
SIG = 5.0  # a χ² gain must pass its noise expectation by this many standard deviations


def scale_or_wind(
    samples: list[np.ndarray | None],
    dropped: np.ndarray,
    theta: np.ndarray,
    rms_m: np.ndarray,
    k: np.ndarray,
) -> dict[str, Any] | None:
    """Which of a tracker scale and a wind the tracks carry.

    Args:
        samples: the tracks (None: none).
        dropped: leading samples dropped per track.
        theta: the whole-track fits (`cell.gap.track_launch`), shape (n, 12).
        rms_m: their RMS residuals [m], shape (n,).
        k: drag constants [1/m], shape (n,).

    Returns:
        {"tracks": tracks fitted, "prefers": "scale", "wind" or "neither" (or "either":
        both explain the tracks alike), "scale_chi2_gain", "wind_chi2_gain": χ² gained
        over the nominal flight, "noise_chi2": what noise alone gains (2 per track),
        "g_ratio_scale": the scale fit's median apparent gravity / G, "wind_mps": the wind
        fit's median horizontal wind [m/s]}, or None with fewer than 3 tracks.
    """
    idx = [i for i, tr in enumerate(samples) if tr is not None and np.isfinite(theta[i]).all()]
    if len(idx) < 3:
        return None
    if len(idx) > MAX_TRACKS:
        idx = [idx[j] for j in np.linspace(0, len(idx) - 1, MAX_TRACKS).astype(int)]
    trs = [samples[i] for i in idx]
    tau, pos = pad_tracks(trs, np.asarray(dropped, int)[idx])  # type: ignore[arg-type]
    kk = np.asarray(k, float)[idx]
    th0 = theta[idx].copy()
    base = th0.copy()
    base[:, 6:12] = 0.0
    fits = {m: fit_ode(tau, pos, kk, m, base) for m in ("nominal", "wind")}
    sc0 = base.copy()
    sc0[:, 8] = th0[:, 8]
    fits["scale"] = fit_ode(tau, pos, kk, "scale", sc0)
    m = fits["nominal"].m
    var = float(np.median(rms_m[idx] ** 2 * m / np.maximum(3 * m - 9, 1))) / 1.0
    var = max(var, 1e-10)
    ssr = {name: float(np.sum(f.ssr)) for name, f in fits.items()}
    gain_s = (ssr["nominal"] - ssr["scale"]) / var
    gain_w = (ssr["nominal"] - ssr["wind"]) / var
    n = len(idx)
    noise = 2.0 * n
    thr = noise + SIG * np.sqrt(4.0 * n)
    diff_thr = SIG * np.sqrt(8.0 * n)
    if gain_s > thr and gain_s - gain_w > max(diff_thr, 0.1 * gain_s):
        prefers = "scale"
    elif gain_w > thr and gain_w - gain_s > max(diff_thr, 0.1 * gain_w):
        prefers = "wind"
    elif gain_s > thr and gain_w > thr:
        prefers = "either"
    else:
        prefers = "neither"
    return {
        "tracks": n,
        "prefers": prefers,
        "scale_chi2_gain": float(gain_s),
        "wind_chi2_gain": float(gain_w),
        "noise_chi2": float(noise),
        "g_ratio_scale": float(np.median(1.0 - fits["scale"].theta[:, 8] / G)),
        "wind_mps": [float(x) for x in np.median(fits["wind"].theta[:, 10:12], axis=0)],
    }
