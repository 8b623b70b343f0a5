"""Split-half and end-window fits of a track: the free flight (a constant or linearly
varying acceleration besides gravity and drag) fitted to the even and to the odd samples,
and the state at a track's first or last samples.

Drag here is evaluated along the fitted path (velocity linear or quadratic in time, plus what
drag itself takes off it, by fixed-point passes) and integrated twice by the trapezoid rule:
the halves' states are then those of the drag flight itself, so the nominal flight from a
half's first state ends where the half's fit does (a bend of zero on a flight with no
effect, not the few centimetres drag evaluated off its own path left). The launch state
itself comes from the flight integrated with drag (`cell.gap.track_launch`).
"""

from __future__ import annotations

import numpy as np

from cell.model.params import G

__all__ = ["WINDOW_S", "MIN_SAMPLES", "end_state", "halves"]

WINDOW_S = 0.15  # [s] samples used for an end state
MIN_SAMPLES = 4
# passes of the drag along the path it slows (1: drag at the path without it, which left the
# half fits' start states up to 0.04 m/s off a drag flight's): tests/test_gap_halves_drag.py
PICARD = 6


def _state(
    tr: np.ndarray, k: float, at_start: bool
) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """Position and velocity at the first (or last) sample, fitted to the samples within
    WINDOW_S of it with gravity and drag (at the fitted velocity) as known acceleration."""
    if at_start:
        sel = tr[:, 0] <= tr[0, 0] + WINDOW_S
        if sel.sum() < MIN_SAMPLES:
            sel = np.arange(len(tr)) < MIN_SAMPLES
        t_ref = tr[0, 0]
    else:
        sel = tr[:, 0] >= tr[-1, 0] - WINDOW_S
        if sel.sum() < MIN_SAMPLES:
            sel = np.arange(len(tr)) >= len(tr) - MIN_SAMPLES
        t_ref = tr[-1, 0]
    tau = tr[sel, 0] - t_ref
    pos = tr[sel, 1:4]
    a_mat = np.stack([np.ones_like(tau), tau], axis=1)
    acc = np.array([0.0, 0.0, -G])
    sol = np.zeros((2, 3))
    for _ in range(3):
        rhs = pos - 0.5 * tau[:, None] ** 2 * acc
        sol = np.linalg.lstsq(a_mat, rhs, rcond=None)[0]
        v = sol[1]
        acc = np.array([0.0, 0.0, -G]) - k * np.linalg.norm(v) * v
    bias = np.linalg.lstsq(a_mat, 0.5 * tau**2, rcond=None)[0]
    return float(t_ref), sol[0], sol[1], bias


def _drag_path(
    tau: np.ndarray, v0: np.ndarray, acc: np.ndarray, k: float, jerk: np.ndarray | None = None
) -> np.ndarray:
    """Displacement [m] drag adds at times tau (from 0) along the path with start velocity
    v0, acceleration acc and jerk (drag evaluated on that path, integrated twice by the
    trapezoid rule from tau = 0)."""
    t = np.r_[0.0, tau] if tau[0] > 0 else tau
    pos, _ = _drag_integral(t, v0, acc, k, jerk)
    return pos[1:] if tau[0] > 0 else pos


def _drag_integral(
    t: np.ndarray, v0: np.ndarray, acc: np.ndarray, k: float, jerk: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """Displacement [m] and velocity [m/s] drag adds at times t (t[0] = 0) along the path
    v0 + acc t (+ jerk t²/2), the drag evaluated at the velocity drag itself changes
    (`PICARD` fixed-point passes of the trapezoid rule)."""
    v = v0[None, :] + t[:, None] * acc[None, :]
    if jerk is not None:
        v = v + 0.5 * t[:, None] ** 2 * jerk[None, :]
    dt = np.diff(t)[:, None]
    vel = np.zeros_like(v)
    for _ in range(PICARD):
        w = v + vel
        d = -k * np.linalg.norm(w, axis=1)[:, None] * w
        vel = np.vstack([np.zeros(3), np.cumsum(0.5 * (d[1:] + d[:-1]) * dt, axis=0)])
    pos = np.vstack([np.zeros(3), np.cumsum(0.5 * (vel[1:] + vel[:-1]) * dt, axis=0)])
    return pos, vel


def _free_fit(
    tau: np.ndarray, pos: np.ndarray, k: float, jerk: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Position, velocity at tau = 0 and a constant extra acceleration (besides gravity and
    drag) fitted to samples (tau (m,) [s], pos (m, 3) [m]); also the residuals (m, 3).
    With `jerk` the extra acceleration is linear in time (returned as (a, j) stacked, (2, 3))."""
    gvec = np.array([0.0, 0.0, -G])
    cols = [np.ones_like(tau), tau, 0.5 * tau**2] + ([tau**3 / 6] if jerk else [])
    a_mat = np.stack(cols, axis=1)
    sol = np.linalg.lstsq(a_mat, pos, rcond=None)[0]
    for _ in range(3):
        drag = _drag_path(tau, sol[1], sol[2], k, sol[3] if jerk else None)
        sol = np.linalg.lstsq(a_mat, pos - drag, rcond=None)[0]
    drag = _drag_path(tau, sol[1], sol[2], k, sol[3] if jerk else None)
    res = pos - drag - a_mat @ sol
    extra = np.stack([sol[2] - gvec, sol[3]]) if jerk else sol[2] - gvec
    return sol[0], sol[1], extra, res


def _halves(tr: np.ndarray, k: float, drop: int) -> np.ndarray | None:
    """The free flight (acceleration linear in time) fitted to the even and to the odd
    samples kept: per half, position and velocity at the first and at the last kept sample,
    the extra acceleration at the first and its rate, (2, 6, 3) [m, m/s, m/s², m/s³] (None:
    too few samples). Two independent estimates
    of the same path: the product of their deviations from a reference is free of the
    track's scatter on average."""
    t = tr[drop:, 0]
    pos = tr[drop:, 1:4]
    if len(t) < 16:
        return None
    out = np.zeros((2, 6, 3))
    gvec = np.array([0.0, 0.0, -G])
    for h in range(2):
        sel = slice(h, None, 2)
        p0, v0, aj, _ = _free_fit(t[sel] - t[0], pos[sel], k, jerk=True)
        a, j = aj
        grid = np.linspace(0.0, float(t[-1] - t[0]), 60)
        vg = v0 + np.outer(grid, gvec + a) + 0.5 * np.outer(grid**2, j)
        dpos, dvel = _drag_integral(grid, v0, gvec + a, k, j)
        tau = grid[-1]
        out[h, 0], out[h, 1] = p0, v0
        out[h, 2] = p0 + v0 * tau + 0.5 * (gvec + a) * tau**2 + j * tau**3 / 6 + dpos[-1]
        out[h, 3] = vg[-1] + dvel[-1]
        out[h, 4], out[h, 5] = a, j
    return out


def end_state(tr: np.ndarray, k: float) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """Position [m] and velocity [m/s] at the last sample (`_state`)."""
    return _state(tr, k, False)


def halves(tr: np.ndarray, k: float, drop: int) -> np.ndarray | None:
    """The free flight fitted to the even and to the odd samples kept (`_halves`)."""
    return _halves(tr, k, drop)
