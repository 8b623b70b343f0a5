"""The launch state of each tracked throw, from its whole track with drag in the dynamics.

The track is fitted by the flight integrated with quadratic drag (`cell.gap.track_ode`,
model "accel_drag": start position and velocity, a free constant acceleration besides
gravity and drag, so that any steady flight effect and a tracker's scale show as such,
and the drag's scale over the configured C_d where the track identifies it).
The first samples after a release may still be disturbed (contact with the launcher, the
tracker's lock): a fit to the samples after DISTURBED_S gives the scatter σ of the rest;
the leading run of samples off that fit by more than DROP_SIGMA σ is dropped (and the
two after it: a disturbance decays), and the state is fitted again from the first sample
kept. A track under 2 × DISTURBED_S long drops nothing: its samples after DISTURBED_S span
less than the stretch they would be extrapolated over, and the extrapolation's own error
passes for a disturbance (a cube's falls of 0.1 to 0.15 s, tracked within 0.04 mm, lost
up to 12 leading samples so). All tracks are fitted at once.
"""

from __future__ import annotations

import numpy as np

from cell.gap.track_ode import fit_ode, predict_ode
from cell.model.params import G

__all__ = ["DISTURBED_S", "DROP_SIGMA", "pad_tracks", "start_guess", "whole_track_launch"]

DISTURBED_S = 0.08  # [s] the first samples a release may still disturb (fit to the rest)
DROP_SIGMA = 3.0  # a leading sample this many σ (per axis) off the rest's fit is dropped
MIN_KEPT = 8  # samples kept at least
MIN_G_SPAN_S = 0.1  # [s] a shorter kept track gives no apparent gravity


def pad_tracks(tracks: list[np.ndarray], start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Times from each track's sample `start` [s] and positions [m], NaN-padded:
    shapes (n, m) and (n, m, 3); samples before `start` are NaN."""
    m = max((len(tr) - int(s) for tr, s in zip(tracks, start, strict=True)), default=1)
    tau = np.full((len(tracks), max(m, 1)), np.nan)
    pos = np.full((len(tracks), max(m, 1), 3), np.nan)
    for i, (tr, s) in enumerate(zip(tracks, start, strict=True)):
        part = tr[int(s) :]
        tau[i, : len(part)] = part[:, 0] - part[0, 0]
        pos[i, : len(part)] = part[:, 1:4]
    return tau, pos


def start_guess(tau: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """Start parameters (n, 12): position and velocity of a parabola through each track."""
    th = np.zeros((tau.shape[0], 12))
    for i in range(tau.shape[0]):
        ok = np.isfinite(tau[i])
        t = tau[i, ok]
        deg = 2 if t.size >= 3 else 1
        c = np.polynomial.polynomial.polyfit(t, pos[i, ok], deg)
        th[i, 0:3], th[i, 3:6] = c[0], c[1]
    return th


def _drops(tracks: list[np.ndarray], k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The leading samples each track's start should drop, and the scatter σ [m] of the
    fit to its samples after DISTURBED_S (fitted from the track's first sample time, the
    samples before DISTURBED_S left out, then compared with them)."""
    n = len(tracks)
    tau_all, pos_all = pad_tracks(tracks, np.zeros(n, int))
    core = tau_all >= DISTURBED_S
    last = np.nanmax(np.where(np.isfinite(tau_all), tau_all, -np.inf), axis=1)
    short = (core.sum(axis=1) < MIN_KEPT) | (last < 2 * DISTURBED_S)
    core[short] = np.isfinite(tau_all[short])
    tau_c = np.where(core, tau_all, np.nan)
    pos_c = np.where(core[..., None], pos_all, np.nan)
    fit = fit_ode(tau_c, pos_c, k, "accel", start_guess(tau_c, pos_c))
    sigma = np.sqrt(fit.ssr / np.maximum(fit.m, 1))
    pred = predict_ode(fit.theta, k, tau_all)
    drops = np.zeros(n, int)
    for i, tr in enumerate(tracks):
        if short[i]:
            continue
        off = np.linalg.norm(tr[:, 1:4] - pred[i, : len(tr)], axis=1)
        off = off / max(sigma[i] / np.sqrt(3.0), 1e-4)
        out = off[: max(len(tr) // 2, 1)] > DROP_SIGMA
        d = int(np.argmin(out)) if not out.all() else int(out.size)
        d = d + 2 if d else 0
        drops[i] = min(d, max(len(tr) - MIN_KEPT, 0))
    return drops, sigma


def whole_track_launch(tracks: list[np.ndarray], k: np.ndarray) -> dict[str, np.ndarray]:
    """The launch state of each track (checked: sorted, finite, ≥ 8 samples).

    Args:
        tracks: the tracks, (k_i, 4) arrays t [s], x, y, z [m].
        k: drag constant per track [1/m], shape (n,).

    Returns:
        {"t0": time of the first kept sample [s], "p0" [m], "v0" [m/s] there, "a0": the
        constant acceleration besides gravity and drag [m/s²], "g_ratio": apparent gravity
        / G (NaN: kept span under 0.1 s), "drag_ratio": the drag over the configured one,
        "dropped": leading samples dropped, "sigma": the
        fit's scatter [m], "theta": the fitted flight (`track_ode`), "rms_m": RMS residual
        of the final fit [m]}.
    """
    k = np.asarray(k, float)
    n = len(tracks)
    if n == 0:
        z = np.zeros(0)
        return {"t0": z, "p0": np.zeros((0, 3)), "v0": np.zeros((0, 3)),
                "a0": np.zeros((0, 3)), "g_ratio": z, "dropped": z, "sigma": z,
                "theta": np.zeros((0, 12)), "rms_m": z}  # fmt: skip
    drops, sigma = _drops(tracks, k)
    tau, pos = pad_tracks(tracks, drops)
    fit = fit_ode(tau, pos, k, "accel_drag", start_guess(tau, pos))
    t0 = np.array([tr[d, 0] for tr, d in zip(tracks, drops, strict=True)])
    span = np.array([tr[-1, 0] - tr[d, 0] for tr, d in zip(tracks, drops, strict=True)])
    g_ratio = np.where(span >= MIN_G_SPAN_S, 1.0 - fit.theta[:, 8] / G, np.nan)
    return {
        "t0": t0,
        "p0": fit.theta[:, 0:3],
        "v0": fit.theta[:, 3:6],
        "a0": fit.theta[:, 6:9],
        "g_ratio": g_ratio,
        "dropped": drops.astype(float),
        "sigma": sigma,
        "theta": fit.theta,
        "rms_m": np.sqrt(fit.ssr / np.maximum(fit.m, 1)),
        "drag_ratio": np.exp(fit.theta[:, 9]),
    }
