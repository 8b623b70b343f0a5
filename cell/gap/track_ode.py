"""Whole-track fits with drag in the dynamics: many tracks at once, by Gauss-Newton.

Each track (samples at times τ ≥ 0 [s] from its first kept sample, positions [m] in the
tracker's frame, gaps allowed, any rate) is fitted by the flight

    ṗ = v,   v̇ = (0, 0, -G) + a - k·e^λ·|v - w|·(v - w),   w = (w_x, w_y, 0),

integrated from (p0, v0) at τ = 0 by RK4 on a fixed grid (positions at the sample times by
cubic Hermite interpolation between grid nodes), not along a constant-acceleration path:
on a light object's flight drag changes the velocity itself. The parameters are

    θ = (p0 [m] ×3, v0 [m/s] ×3, a [m/s²] ×3, λ [-], w_x, w_y [m/s])

and a model frees a subset of them (`MODELS`): "accel" (a free constant acceleration, the
apparent gravity is G - a_z), "accel_drag" (that and the drag scale λ: the launch
state of a track whose drag the configured C_d may miss), "scale" (a vertical acceleration and the drag scale λ free:
what a tracker off in scale s shows, g' = s·G and k' = k/s, bending nothing sideways),
"wind" (a steady horizontal wind, gravity and drag nominal: a wind bends the path
sideways), "nominal" (the start state alone), "drag" (the drag scale alone: where the
tracks identify it). λ and w carry weak priors (1 cm of misfit per e-fold of drag, per
10 m/s of wind) so that they stay put where the tracks do not identify them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cell.model.flight3d import KEEP_SHARE
from cell.model.params import G

__all__ = ["MODELS", "OdeFit", "fit_ode", "predict_ode"]

STEP_S = 0.01  # [s] RK4 grid (error ~1e-9 m at k|v| = 2/s; positions by Hermite cubics)
N_THETA = 12
MODELS: dict[str, tuple[int, ...]] = {
    "accel": (0, 1, 2, 3, 4, 5, 6, 7, 8),
    "accel_drag": (0, 1, 2, 3, 4, 5, 6, 7, 8, 9),
    "scale": (0, 1, 2, 3, 4, 5, 8, 9),
    "wind": (0, 1, 2, 3, 4, 5, 10, 11),
    "nominal": (0, 1, 2, 3, 4, 5),
    "drag": (0, 1, 2, 3, 4, 5, 9),
}
PRIOR_M = {9: 0.01, 10: 0.001, 11: 0.001}  # [m] misfit per unit of λ, of w [m/s]
MAX_ITER = 25


@dataclass(frozen=True)
class OdeFit:
    """A model fitted to n tracks.

    Attributes:
        theta: the parameters (p0, v0, a, λ, w_x, w_y), shape (n, 12).
        ssr: sum of squared position residuals [m²] per track, shape (n,).
        m: samples per track, shape (n,).
        residual: position residuals [m], shape (n, m_max, 3) (NaN past a track's end).
        converged: the fit converged, shape (n,).
    """

    theta: np.ndarray
    ssr: np.ndarray
    m: np.ndarray
    residual: np.ndarray
    converged: np.ndarray


def _acc_terms(th: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The wind w (n, P, 3), drag factor k·e^λ (n, P, 1) and extra acceleration (n, P, 3)
    under parameters th (n, P, 12), drag constants k (n,): the same at every state of the
    flight, taken from th once."""
    w = np.zeros(th.shape[:-1] + (3,))
    w[..., :2] = th[..., 10:12]
    return w, k[:, None, None] * np.exp(th[..., 9:10]), th[..., 6:9]


def _acc(v: np.ndarray, w: np.ndarray, kk: np.ndarray, extra: np.ndarray) -> np.ndarray:
    """v̇ at the states v (n, P, 3) (`_acc_terms`' w, kk, extra of the same rows)."""
    rel = v - w
    # |rel|: np.linalg.norm's arithmetic ((x² + y²) + z², as `np.add.reduce` over the
    # last axis sums three), without its per-call checks, the squares in one call
    sq = rel * rel
    out = extra - kk * np.sqrt((sq[..., 0] + sq[..., 1]) + sq[..., 2])[..., None] * rel
    out[..., 2] -= G
    return out


def _simulate(th: np.ndarray, k: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Positions [m] at times tau (n, m) (NaN: no sample), shape (n, P, m, 3), of the
    flights with parameters th (n, P, 12). Each track is integrated up to its own last
    sample (the rows are independent: every operation is elementwise per row)."""
    n, n_p, _ = th.shape
    ok = np.isfinite(tau)
    t_end = float(np.nanmax(tau)) if ok.any() else 0.0
    n_steps = max(int(np.ceil(t_end / STEP_S)), 1)
    h = t_end / n_steps if t_end > 0 else STEP_S
    ti, si = np.nonzero(ok)
    x = tau[ti, si] / h
    node = np.minimum(np.floor(x).astype(int), n_steps - 1)
    s = (x - node)[:, None, None]
    order = np.argsort(node, kind="stable")
    bounds = np.searchsorted(node[order], np.arange(n_steps + 1))
    out = np.full((n, n_p, tau.shape[1], 3), np.nan)
    # the step of each track's last sample (-1: none); `at` maps a track to its row in the
    # states integrated (the tracks `rows`)
    last = np.full(n, -1)
    np.maximum.at(last, ti, node)
    rows = np.arange(n)
    at = np.arange(n)
    p = th[..., 0:3].copy()
    v = th[..., 3:6].copy()
    w, kk, extra = _acc_terms(th, k)
    # each stage's velocity and each sample's s², s³ formed once (they were formed twice
    # and four times), the same numbers (tests/test_flight_same.py)
    half = 0.5 * h
    for i in range(n_steps):
        k1v = _acc(v, w, kk, extra)
        k2p = v + half * k1v
        k2v = _acc(k2p, w, kk, extra)
        k3p = v + half * k2v
        k3v = _acc(k3p, w, kk, extra)
        k4p = v + h * k3v
        k4v = _acc(k4p, w, kk, extra)
        p1 = p + h / 6 * (v + 2 * k2p + 2 * k3p + k4p)
        v1 = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        sel = order[bounds[i] : bounds[i + 1]]
        if sel.size:
            tt, ss, sv = ti[sel], si[sel], s[sel]
            r = at[tt]
            s2, s3 = sv**2, sv**3
            h00 = 2 * s3 - 3 * s2 + 1
            h10 = s3 - 2 * s2 + sv
            h01 = -2 * s3 + 3 * s2
            h11 = s3 - s2
            out[tt, :, ss] = h00 * p[r] + h10 * h * v[r] + h01 * p1[r] + h11 * h * v1[r]
        p, v = p1, v1
        if not np.all(np.isfinite(p)):
            p = np.where(np.isfinite(p), p, 1e6)
            v = np.where(np.isfinite(v), v, 0.0)
        ahead = last[rows] > i
        n_ahead = int(np.count_nonzero(ahead))
        if not n_ahead:
            break
        if n_ahead < KEEP_SHARE * rows.size:  # placed tracks dropped as flight3d drops landed ones
            rows, p, v = rows[ahead], p[ahead], v[ahead]
            w, kk, extra = w[ahead], kk[ahead], extra[ahead]
            at[rows] = np.arange(rows.size)
    return out


def predict_ode(theta: np.ndarray, k: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Positions [m] of flights theta (n, 12), drag constants k (n,) [1/m], at times
    tau (n, m) [s] from each start (NaN: none), shape (n, m, 3)."""
    return _simulate(theta[:, None, :], np.asarray(k, float), tau)[:, 0]


def _residuals(
    th: np.ndarray,
    k: np.ndarray,
    tau: np.ndarray,
    pos: np.ndarray,
    free: tuple[int, ...],
    priors: bool = True,
) -> np.ndarray:
    """Weighted residual vectors (n, P, 3 m + priors) of parameters th (n, P, 12)."""
    pred = _simulate(th, k, tau)
    r = np.nan_to_num(pred - pos[:, None])
    r = r.reshape(r.shape[0], r.shape[1], -1)
    pri = [th[..., j] * PRIOR_M[j] for j in free if j in PRIOR_M and priors]
    if pri:
        r = np.concatenate([r, np.stack(pri, axis=-1)], axis=-1)
    return r


def _jacobian(
    th: np.ndarray,
    k: np.ndarray,
    tau: np.ndarray,
    pos: np.ndarray,
    free: tuple[int, ...],
    eps: np.ndarray,
    priors: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """Residuals (a, R) at th (a, 12) and their Jacobian (a, f, R) in the free
    parameters. The start position only shifts the flight (no force depends on it): its
    columns are exact; the others are forward differences of step eps (f,)."""
    dyn = [c for c, j in enumerate(free) if j >= 3]
    stack = np.repeat(th[:, None], 1 + len(dyn), axis=1)
    for q, c in enumerate(dyn):
        stack[:, 1 + q, free[c]] += eps[c]
    r_all = _residuals(stack, k, tau, pos, free, priors)
    r0 = r_all[:, 0]
    jac = np.zeros((th.shape[0], len(free), r0.shape[1]))
    jac[:, dyn] = (r_all[:, 1:] - r0[:, None]) / eps[dyn][None, :, None]
    mask = np.isfinite(tau)
    for c, j in enumerate(free):
        if j < 3:
            col = np.zeros((th.shape[0], tau.shape[1], 3))
            col[..., j] = mask
            jac[:, c, : 3 * tau.shape[1]] = col.reshape(th.shape[0], -1)
    return r0, jac


def fit_ode(
    tau: np.ndarray,
    pos: np.ndarray,
    k: np.ndarray,
    model: str,
    theta0: np.ndarray,
    priors: bool = True,
) -> OdeFit:
    """Fit `model` to n tracks by Levenberg-Marquardt (forward-difference Jacobians, every
    track at once).

    Args:
        tau: sample times from each track's start [s], shape (n, m) (NaN: no sample).
        pos: positions [m], shape (n, m, 3) (NaN where tau is NaN).
        k: nominal drag constants [1/m], shape (n,).
        model: a key of MODELS.
        theta0: start parameters, shape (n, 12) (the parameters not freed stay).
        priors: with the weak priors on λ and w (`PRIOR_M`); without, a short track's
            wind is its data's alone (unbiased, however uncertain).

    Returns:
        The fit.
    """
    free = MODELS[model]
    k = np.asarray(k, float)
    n = tau.shape[0]
    th = theta0.astype(float).copy()
    lam = np.full(n, 1e-3)
    done = np.zeros(n, bool)
    cost = np.sum(_residuals(th[:, None], k, tau, pos, free, priors)[:, 0] ** 2, axis=1)
    eps = np.array([1e-6 if j < 3 else 1e-6 if j < 6 else 1e-5 for j in free])
    for _ in range(MAX_ITER):
        act = np.flatnonzero(~done)
        if act.size == 0:
            break
        ta = th[act]
        r0, jac = _jacobian(ta, k[act], tau[act], pos[act], free, eps, priors)
        jtj = np.einsum("afr,agr->afg", jac, jac)
        jtr = np.einsum("afr,ar->af", jac, r0)
        diag = np.einsum("aff->af", jtj)
        trial = ta.copy()
        step = np.zeros((act.size, len(free)))
        for _inner in range(4):
            a_mat = jtj + (lam[act][:, None] * np.maximum(diag, 1e-12))[:, :, None] * np.eye(
                len(free)
            )
            step = -np.linalg.solve(a_mat, jtr[..., None])[..., 0]
            trial = ta.copy()
            trial[:, list(free)] += step
            c_new = np.sum(
                _residuals(trial[:, None], k[act], tau[act], pos[act], free, priors)[:, 0] ** 2,
                1,
            )
            better = np.isfinite(c_new) & (c_new <= cost[act])
            rel = (cost[act] - np.where(better, c_new, cost[act])) / np.maximum(cost[act], 1e-30)
            th[act[better]] = trial[better]
            done[act[better & (rel < 1e-9)]] = True
            cost[act[better]] = c_new[better]
            lam[act[better]] = np.maximum(lam[act[better]] / 5, 1e-9)
            lam[act[~better]] *= 10
            done[act[~better & (lam[act] > 1e8)]] = True
            if better.all():
                break
            keep = ~better
            act, ta, jtj, jtr, diag = act[keep], ta[keep], jtj[keep], jtr[keep], diag[keep]
            if act.size == 0:
                break
    pred = predict_ode(th, k, tau)
    res = pred - pos
    ssr = np.nansum(res**2, axis=(1, 2))
    return OdeFit(
        theta=th,
        ssr=ssr,
        m=np.sum(np.isfinite(tau), axis=1),
        residual=res,
        converged=done,
    )
