"""A wind that varies from throw to throw: its mean and spread by maximum marginal likelihood.

A steady wind's least-squares fit is, to first order, the draws' mean weighted by each
throw's sensitivity (`cell.gap.scene_wind.weighted_wind`): when the wind is drawn anew for
every throw, a few throws the wind moves most set it. The throw-to-throw (random-effect)
form of the wind says instead, for each throw i (landing miss r_i [m], world frame,
linearised about a wind w₀ with J_i = ∂ landing / ∂ level wind [s], 2 × 2):

    y_i = r_i + J_i w₀ = J_i w_i + e_i,   w_i ~ N(μ, s² I₂),   e_i ~ N(0, σ² I₂)

so y_i ~ N(J_i μ, V_i), V_i = σ² I₂ + s² J_i J_iᵀ. μ [m/s] (horizontal), s [m/s] and σ
[m] are fitted by maximum marginal likelihood: for given (s, σ) μ is the GLS estimate
(Σ Jᵀ V⁻¹ J)⁻¹ Σ Jᵀ V⁻¹ y, which down-weights the throws the wind moves most when s is
large and is the least-squares fit when s = 0. σ is fitted with them: the floor from
repeats (`cell.gap.noise`) holds the throw-to-throw wind too (a repeat is thrown in another
draw), so it cannot stand for e alone. The vertical part of a wind with one, and every
partner effect of the verdict, stay at their steady fit. The linearisation is made at the
steady fit, then once more at μ (`RELINEARISE`).

The varying form stands for the wind only on held-out evidence: every fold's training
throws fit both forms (steady: s = 0), each scores its held-out throws' log density, and the
varying form is chosen when its mean held-out log density per throw is higher by more than
`LOGLIK_PENALTY` (the laws' TERM_PENALTY, 3 % on an RMSE, as log density: a 2-D Gaussian
whose scale grows 3 % loses 2 ln 1.03 nats) with a bootstrap 95 % interval of the gain
above zero. The held-out RMSE of the mean prediction cannot prefer it (the steady fit
minimises it); the log density sees the spread that grows with J.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
from scipy.optimize import minimize

from cell.gap.laws import TERM_PENALTY
from cell.gap.noise import MIN_REPEAT_DOF, repeat_groups
from cell.gap.problem import GapProblem
from cell.model.effects import Effect

__all__ = [
    "LAW",
    "LOGLIK_PENALTY",
    "fit_marginal",
    "heldout",
    "loglik",
    "mean_ci95",
    "repeat_pairs",
    "repeat_test",
    "sd_interval",
    "whiten",
    "whitened_misses",
    "wind_throw",
]

LAW = "wind_i ~ N(mean, sd)"
LOGLIK_PENALTY = 2.0 * float(np.log1p(TERM_PENALTY))  # [nats per throw] for the term s
JAC_STEP_MPS = 0.05  # central-difference step of ∂ landing / ∂ wind [m/s]
S_MIN_MPS = 1e-4  # the spread's lower bound in the fit [m/s]
S_ZERO_MPS = 1e-3  # a fitted spread below this is none (the refinement's start off s = 0)
MIN_PAIRS = MIN_REPEAT_DOF // 2  # repeat pairs the repeats' test needs: 2 axes each, the floor's
REPEAT_LR = 2.71  # χ²₁'s 90 % point: a 5 % test of sd > 0 on its boundary (50:50 χ²₀, χ²₁)
RELINEARISE = 1  # passes re-linearised at the fitted mean after the first at the steady fit
_LN2PI = float(np.log(2.0 * np.pi))


def _with_wind(effects: tuple[Effect, ...], j: int, w: np.ndarray) -> tuple[Effect, ...]:
    out = list(effects)
    out[j] = replace(effects[j], **{"x_mps": float(w[0]), "y_mps": float(w[1])})
    return tuple(out)


def _linearised(prob: GapProblem, effects: tuple[Effect, ...], j: int, w0: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(y (n, 2) [m], J (n, 2, 2) [s]) about the level wind w0 [m/s] of effect j."""
    idx = np.arange(len(prob))
    r0 = prob.residual(idx, _with_wind(effects, j, w0))
    cols = []
    for e in np.eye(2):
        hi = prob.landing(idx, _with_wind(effects, j, w0 + JAC_STEP_MPS * e)).xy
        lo = prob.landing(idx, _with_wind(effects, j, w0 - JAC_STEP_MPS * e)).xy
        cols.append((hi - lo) / (2 * JAC_STEP_MPS))
    jac = np.nan_to_num(np.stack(cols, axis=-1))
    return r0 + np.einsum("nij,j->ni", jac, w0), jac


def _cov(jac: np.ndarray, s: float, sig: float) -> np.ndarray:
    return sig**2 * np.eye(2) + s**2 * np.einsum("nik,njk->nij", jac, jac)


def _gls(y: np.ndarray, jac: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The GLS mean [m/s] and its covariance [(m/s)²] for covariances v (n, 2, 2)."""
    vi = np.linalg.inv(v)
    a = np.einsum("nki,nkl,nlj->ij", jac, vi, jac)
    b = np.einsum("nki,nkl,nl->i", jac, vi, y)
    cov = np.linalg.pinv(a)
    return cov @ b, cov


def mean_ci95(y: np.ndarray, jac: np.ndarray, s: float, sig: float,
              centre: np.ndarray | None = None) -> list[list[float]]:  # fmt: skip
    """The GLS mean's 95 % intervals [[lo, hi] per parameter] under spread s and noise σ,
    about `centre` (the fitted mean) where given, else about the GLS mean itself."""
    mu, cov = _gls(y, jac, _cov(jac, s, sig))
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    at = mu if centre is None else centre
    return [[float(m - 1.96 * e), float(m + 1.96 * e)] for m, e in zip(at, se, strict=True)]


def whiten(y: np.ndarray, jac: np.ndarray, mu: np.ndarray, s: float, sig: float) -> np.ndarray:
    """Each miss y_i − J_i μ (n, 2) [m] whitened to the scatter σ: σ · L_i⁻¹ (y_i − J_i μ),
    L_i L_iᵀ = σ² I + s² J_i J_iᵀ. Its squared length is σ² times the Mahalanobis distance,
    so `cell.gap.outliers.flag` tests it as it tests a plain miss."""
    low = np.linalg.cholesky(_cov(jac, s, sig))
    r = y - np.einsum("nij,j->ni", jac, mu)
    return sig * np.linalg.solve(low, r[:, :, None])[:, :, 0]


def loglik(y: np.ndarray, jac: np.ndarray, mu: np.ndarray, s: float, sig: float) -> np.ndarray:
    """Each throw's log density [nats] under y_i ~ N(J_i μ, σ² I + s² J_i J_iᵀ)."""
    v = _cov(jac, s, sig)
    r = y - np.einsum("nij,j->ni", jac, mu)
    q = np.einsum("ni,nij,nj->n", r, np.linalg.inv(v), r)
    return -0.5 * (q + np.log(np.linalg.det(v)) + 2 * _LN2PI)


def _nll_grid(y: np.ndarray, jac: np.ndarray, s: np.ndarray, sig: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Minus the summed log density at each (s, σ) pair of the arrays s, sig (g,), μ its
    GLS mean at each: (nll (g,), μ (g, 2)); the 2 × 2 algebra written out."""
    j00, j01, j10, j11 = jac[:, 0, 0], jac[:, 0, 1], jac[:, 1, 0], jac[:, 1, 1]
    m00, m01, m11 = j00**2 + j01**2, j00 * j10 + j01 * j11, j10**2 + j11**2  # J Jᵀ
    a = sig[:, None] ** 2
    s2 = s[:, None] ** 2
    p, q, r = a + s2 * m00, s2 * m01, a + s2 * m11
    det = p * r - q * q
    v00, v01, v11 = r / det, -q / det, p / det  # V⁻¹, (g, n) each
    col = ((j00, j10), (j01, j11))  # column i of J: (J_0i, J_1i)

    def form(u: tuple[np.ndarray, np.ndarray], w: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
        """Σ_n uᵀ V⁻¹ w over the throws, for each grid point (g,)."""
        return v00 @ (u[0] * w[0]) + v01 @ (u[0] * w[1] + u[1] * w[0]) + v11 @ (u[1] * w[1])

    yy = (y[:, 0], y[:, 1])
    aa = np.stack([np.stack([form(col[i], col[k]) for k in range(2)], -1) for i in range(2)], -2)
    bb = np.stack([form(col[i], yy) for i in range(2)], -1)
    mu = np.linalg.solve(aa, bb[..., None])[..., 0]
    e0 = y[None, :, 0] - j00 * mu[:, :1] - j01 * mu[:, 1:]
    e1 = y[None, :, 1] - j10 * mu[:, :1] - j11 * mu[:, 1:]
    quad = e0 * e0 * v00 + 2 * e0 * e1 * v01 + e1 * e1 * v11
    return 0.5 * np.sum(quad + np.log(det) + 2 * _LN2PI, axis=1), mu


def _nll_grid_one(y: np.ndarray, jac: np.ndarray, s: np.ndarray, sig: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """`_nll_grid` for one parameter, J (n, 2, 1): V = σ² I + s² j jᵀ is of rank one in s,
    so V⁻¹ = (I − c j jᵀ) / σ², c = s² / (σ² + s² |j|²) (Sherman-Morrison), det V =
    σ² (σ² + s² |j|²); the 2 × 2 inverse would cancel where s² |j|² ≫ σ²."""
    j0, j1 = jac[:, 0, 0], jac[:, 1, 0]
    m = j0**2 + j1**2
    a = sig[:, None] ** 2
    den = a + s[:, None] ** 2 * m  # σ² + s² |j|², (g, n)
    jy = j0 * y[:, 0] + j1 * y[:, 1]
    mu = (np.sum(jy / den, axis=1) / np.sum(m / den, axis=1))[:, None]
    e0, e1 = y[None, :, 0] - j0 * mu, y[None, :, 1] - j1 * mu
    je = j0 * e0 + j1 * e1
    quad = (e0 * e0 + e1 * e1 - s[:, None] ** 2 * je * je / den) / a
    return 0.5 * np.sum(quad + np.log(a * den) + 2 * _LN2PI, axis=1), mu


# `_nll_grid_one` takes a large grid this many (grid point, throw) pairs at a time: each
# grid point's arithmetic is its own (elementwise, and its sums over the throws), so the
# blocks give the same numbers as the whole grid, without temporaries of tens of MB (the
# profile interval's 9,211 points × 1,000 throws: 2.9 → 0.5 s)
_GRID_BLOCK = 1 << 15


def _nll(y: np.ndarray, jac: np.ndarray, s: np.ndarray, sig: np.ndarray
         ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(nll (g,), μ (g, K)) for J (n, 2, K): the wind's two level components or one
    parameter of another effect."""
    if jac.shape[2] != 1:  # its sums over the throws are BLAS products: kept whole
        return _nll_grid(y, jac, s, sig)
    rows = max(1, _GRID_BLOCK // max(y.shape[0], 1))
    if s.size <= rows:
        return _nll_grid_one(y, jac, s, sig)
    parts = [_nll_grid_one(y, jac, s[i : i + rows], sig[i : i + rows])
             for i in range(0, s.size, rows)]  # fmt: skip
    return np.concatenate([v for v, _ in parts]), np.concatenate([m for _, m in parts])


def _grid(sig0: float, steady: bool, unit: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    sig = sig0 * np.geomspace(0.05, 2.0, 41)
    if steady:
        return np.zeros_like(sig), sig
    sv = np.r_[0.0, unit * np.geomspace(0.01, 5.0, 40)]
    gs, gg = np.meshgrid(sv, sig, indexing="ij")
    return gs.ravel(), gg.ravel()


def fit_marginal(y: np.ndarray, jac: np.ndarray, *, steady: bool = False, unit: float = 1.0
                 ) -> tuple[np.ndarray, float, float, float]:  # fmt: skip
    """(μ [m/s], s [m/s], σ [m], the summed log density) by maximum marginal likelihood;
    `steady` holds s = 0 (μ then is the least-squares fit). A grid over (s, σ) (s = 0
    among its values), then L-BFGS-B from its best point. `unit` is the parameter's size
    (1 m/s for the wind): the spread's grid and bounds are in it."""
    sig0 = max(float(np.sqrt(np.mean(y * y) / 2)), 1e-6)
    gs, gg = _grid(sig0, steady, unit)
    grid_nll = _nll(y, jac, gs, gg)[0]
    k = int(np.argmin(grid_nll))

    def nll(th: np.ndarray) -> float:
        sv = 0.0 if steady else float(np.exp(th[1]))
        return float(_nll(y, jac, np.array([sv]), np.array([np.exp(th[0])]))[0][0])

    x0 = [np.log(gg[k])] + ([] if steady else [np.log(max(gs[k], 2 * S_MIN_MPS * unit))])
    bounds = [(np.log(1e-6), np.log(10.0))] + (
        [] if steady else [(np.log(S_MIN_MPS * unit), np.log(10.0 * unit))]
    )
    best = minimize(nll, np.array(x0), method="L-BFGS-B", bounds=bounds)
    sig = float(np.exp(best.x[0]))
    s = 0.0 if steady else float(np.exp(best.x[1]))
    if not steady and s < S_ZERO_MPS * unit:
        s = 0.0
    if best.fun > grid_nll[k]:  # the grid's own point is better (s = 0 is on the grid)
        s, sig = float(gs[k]), float(gg[k])
    val, mu = _nll(y, jac, np.array([s]), np.array([sig]))
    return mu[0], s, sig, -float(val[0])


def sd_interval(y: np.ndarray, jac: np.ndarray, s: float, sig: float, ll: float,
                unit: float = 1.0, span: tuple[float, float] | None = None
                ) -> list[float]:  # fmt: skip
    """The spread's 95 % profile-likelihood interval [m/s] (σ and μ refitted at each s, σ
    on a grid of 1.5 % steps; the log-likelihood within χ²₁(0.95)/2 = 1.92 of its
    maximum), s on a grid of 61 over `span` (by default from 0 to max(3 s, unit / 2))."""
    sv = np.linspace(*(span or (0.0, max(3.0 * s, 0.5 * unit))), 61)
    sg = sig * np.geomspace(1 / 3, 3.0, 151)
    gs, gg = np.meshgrid(sv, sg, indexing="ij")
    prof = -_nll(y, jac, gs.ravel(), gg.ravel())[0].reshape(gs.shape).min(axis=1)
    inside = sv[prof >= ll - 1.92]
    return [float(inside.min()), float(inside.max())] if inside.size else [s, s]


def heldout(prob: GapProblem, y: np.ndarray, jac: np.ndarray, unit: float = 1.0
            ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Per throw, the held-out log density [nats] of the steady and the varying form,
    averaged over the problem's fold schemes."""
    n = y.shape[0]
    steady, vary = np.zeros(n), np.zeros(n)
    for folds in prob.folds.values():
        for tr, te in folds:
            mu0, _, sig0, _ = fit_marginal(y[tr], jac[tr], steady=True)
            mu1, s1, sig1, _ = fit_marginal(y[tr], jac[tr], unit=unit)
            steady[te] += loglik(y[te], jac[te], mu0, 0.0, sig0)
            vary[te] += loglik(y[te], jac[te], mu1, s1, sig1)
    k = max(len(prob.folds), 1)
    return steady / k, vary / k


def repeat_pairs(prob: GapProblem) -> np.ndarray:
    """Disjoint pairs (k, 2) of throws logged as repeats of one configuration
    (`cell.gap.noise`'s key: same object, stroke, pose, platform and plane)."""
    groups = repeat_groups(prob)
    pairs = [(g[a], g[a + 1]) for g in groups for a in range(0, len(g) - 1, 2)]
    return np.array(pairs, int).reshape(-1, 2)


def repeat_test(y: np.ndarray, jac: np.ndarray, pairs: np.ndarray, unit: float = 1.0
                ) -> dict[str, Any]:  # fmt: skip
    """The spread the repeats show: the difference of two throws of one configuration
    keeps a wind drawn per throw (covariance 2σ² I + sd² (J_a J_aᵀ + J_b J_bᵀ)) and
    cancels what the model misses on the configuration itself (a drag or a wind response
    off by a factor per object grows with J just as a spread does). Fitted by maximum
    likelihood (J_a, J_b taken as their mean), with the likelihood ratio of sd > 0."""
    if len(pairs) < MIN_PAIRS:
        return {"pairs": int(len(pairs)), "sd_mps": None, "lr": None, "noise_sd_m": None}
    a, b = pairs[:, 0], pairs[:, 1]
    d = y[a] - y[b]
    jm = np.sqrt(2.0) * 0.5 * (jac[a] + jac[b])
    _, s1, sig1, ll1 = fit_marginal(d, jm, unit=unit)
    ll0 = fit_marginal(d, jm, steady=True)[3]
    # the difference's scatter is 2σ² per axis: σ is the noise of one throw
    return {"pairs": int(len(pairs)), "sd_mps": s1, "lr": float(2.0 * (ll1 - ll0)),
            "noise_sd_m": float(sig1 / np.sqrt(2.0))}  # fmt: skip


def wind_throw(prob: GapProblem, effects: tuple[Effect, ...]) -> dict[str, Any] | None:
    """The throw-to-throw form of the verdict's wind, fitted and judged held-out.

    Args:
        prob: the problem.
        effects: the verdict's effects fitted on all throws (one of them the wind).

    Returns:
        None without a wind; else the form's account: `chosen` (the varying form stands
        for the wind), `mean_mps` [x, y], `sd_mps`, `noise_sd_m` (σ per axis), their 95 %
        intervals, the steady fit's level wind, the held-out log density per throw of
        each form [nats], the gain's bootstrap interval and the penalty.
    """
    from cell.gap.stats import N_BOOT, _indices

    j = next((i for i, e in enumerate(effects) if e.name == "wind"), None)
    if j is None:
        return None
    w_steady = np.array(effects[j].vector()[:2], float)  # level: x_mps, y_mps first
    y, jac = _linearised(prob, effects, j, w_steady)
    ll0 = fit_marginal(y, jac, steady=True)[3]
    mu, s, sig, ll = fit_marginal(y, jac)
    first = mu.copy()
    for _ in range(RELINEARISE):
        y, jac = _linearised(prob, effects, j, mu)
        mu, s, sig, ll = fit_marginal(y, jac)
    h0, h1 = heldout(prob, y, jac)
    d = h1 - h0
    gain = float(np.mean(d))
    lo, hi = np.percentile(d[_indices(d.size, prob.seed + 11, N_BOOT)].mean(axis=1), [2.5, 97.5])
    reps = repeat_test(y, jac, repeat_pairs(prob))
    shown = reps["lr"] is None or reps["lr"] > REPEAT_LR
    chosen = bool(s > 0 and gain > LOGLIK_PENALTY and lo > 0 and shown)
    return {
        "law": LAW,
        "chosen": chosen,
        "mean_mps": mu.tolist(),
        "mean_ci95_mps": mean_ci95(y, jac, s, sig, centre=mu),
        "sd_mps": s,
        "sd_ci95_mps": sd_interval(y, jac, s, sig, ll),
        "noise_sd_m": sig,
        "steady_mps": w_steady.tolist(),
        "mean_first_pass_mps": first.tolist(),
        "loglik_gain_in_sample": float(ll - ll0),
        "heldout_loglik_steady": float(np.mean(h0)),
        "heldout_loglik_varying": float(np.mean(h1)),
        "heldout_gain_per_throw": gain,
        "heldout_gain_ci95": [float(lo), float(hi)],
        "penalty_per_throw": LOGLIK_PENALTY,
        "repeats": {**reps, "lr_needed": REPEAT_LR},
    }


def whitened_misses(prob: GapProblem, effects: tuple[Effect, ...], form: dict[str, Any]
                    ) -> np.ndarray:  # fmt: skip
    """Each throw's miss (n, 2) [m] under the wind's throw-to-throw form (`wind_throw`'s
    account `form`), whitened to the scatter σ: σ · L_i⁻¹ (y_i − J_i μ), V_i = L_i L_iᵀ.
    Its squared length is σ² times the Mahalanobis distance, so `cell.gap.outliers.flag`
    tests it as it tests a plain miss: a throw the wind's own spread explains is not
    called impossible."""
    j = next(i for i, e in enumerate(effects) if e.name == "wind")
    mu = np.asarray(form["mean_mps"], float)
    y, jac = _linearised(prob, effects, j, mu)
    return whiten(y, jac, mu, float(form["sd_mps"]), float(form["noise_sd_m"]))
