"""A step in the landing plane: a candidate outside the vocabulary a named verdict must beat.

A floor higher beyond some x than before it (a mat, a platform, a bin's bottom on a
step), logged as one plane, shortens the landings beyond the step by height · v_h / |v_z|
and leaves the others. No effect of the vocabulary is that; a flight or measurement
effect that shortens the far throws most takes its place within the verdict's ratio of
the floor: a 0.03 m step beyond the median landing was named `spin` at 1.05 F, and
`tracking_scale` at 1.10 F (the eleventh lab round's E4, docs/HISTORY.md).

The step's law: the landing moved by (h0 + h1 · [x > x_b]) · v_h / v_z (v_h, v_z the
model's impact velocity; nil for throws descending slower than
`cell.gap.propose.MIN_VZ`), x the model's landing x, x_b a breakpoint among the
`STEP_GRID` quantiles of x from `STEP_LO` to `1 − STEP_LO`, h0 and h1 by least squares
at each and x_b where the misses' sum of squares is least (`fit_step`). Held out
(`step_heldout`): on each of the problem's random folds x_b, h0, h1 fitted on the other
folds predict its throws, so the breakpoint's choice is paid for on held-out throws.

The rule (`step_check`): the step beats a verdict where, fitted to the baseline's misses,
it predicts the held-out throws better than the verdict's effects (an `unknown`'s
partial effects, or the baseline where none joined) by a cut whose bootstrap 95 % interval
lies above zero and h1 is `STEP_Z` standard errors from zero. A verdict that names
effects is then `unknown`, and the report's `landing_step` says why; for either, the
proposal (`cell.gap.propose`, whose library then holds the step at the fitted breakpoint,
`step_term`) says what is left. A tilted plane is the same rule's second candidate
(`cell.gap.plane_tilt`, `landing_step.tilt`): where it beats a named verdict, its `why` is
the step's.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.gap.problem import GapProblem

__all__ = ["STEP_GRID", "STEP_LO", "STEP_Z", "fit_step", "step_heldout", "step_check", "step_term"]

STEP_GRID = 33  # breakpoints tried
STEP_LO = 0.1  # the lowest and highest tried are this quantile of the landings' x from the ends
STEP_Z = 5.0  # the step's height must be this many standard errors from zero


def _columns(prob: GapProblem) -> tuple[np.ndarray, np.ndarray]:
    """(per throw the landing's move per metre of plane height (n, 2), the model's
    landing x (n,)), both of the configured model without effects."""
    from cell.gap.propose import MIN_VZ

    land = prob.landing(np.arange(len(prob)), ())
    iv = np.nan_to_num(land.impact_velocity)
    down = iv[:, 2] < -MIN_VZ
    per_m = np.where(down[:, None], iv[:, :2] / np.where(down, iv[:, 2], -1.0)[:, None], 0.0)
    return per_m, np.nan_to_num(land.xy[:, 0])


def _design(per_m: np.ndarray, x: np.ndarray, xb: float) -> np.ndarray:
    """The step's columns (2n, 2): the plane's constant height and its step beyond xb."""
    return np.stack([per_m.reshape(-1), (per_m * (x > xb)[:, None]).reshape(-1)], axis=1)


def fit_step(per_m: np.ndarray, x: np.ndarray, r: np.ndarray, rows: np.ndarray
             ) -> tuple[float, np.ndarray, float]:  # fmt: skip
    """(x_b, (h0, h1) [m], the sum of squares left) fitted on the throws `rows`."""
    grid = np.quantile(x[rows], np.linspace(STEP_LO, 1 - STEP_LO, STEP_GRID))
    y = r[rows].reshape(-1)
    best: tuple[float, np.ndarray, float] | None = None
    for xb in np.unique(grid):
        a = _design(per_m[rows], x[rows], float(xb))
        h, *_ = np.linalg.lstsq(a, y, rcond=None)
        ss = float(np.sum((y - a @ h) ** 2))
        if best is None or ss < best[2]:
            best = (float(xb), h, ss)
    assert best is not None
    return best


def step_heldout(prob: GapProblem, per_m: np.ndarray, x: np.ndarray, r: np.ndarray
                 ) -> np.ndarray:  # fmt: skip
    """Each throw's squared held-out miss [m²] under the step fitted on the other folds."""
    sq = np.zeros(len(prob))
    for train, test in prob.folds["random"]:
        xb, h, _ = fit_step(per_m, x, r, train)
        e = r[test].reshape(-1) - _design(per_m[test], x[test], xb) @ h
        sq[test] = np.sum(e.reshape(-1, 2) ** 2, axis=1)
    return sq


def step_check(prob: GapProblem, verdict: list[str], r0: np.ndarray, v_sq: np.ndarray
               ) -> dict[str, Any]:  # fmt: skip
    """For a verdict other than `none`, the report's `landing_step`: the step fitted on
    every throw (`break_x_m`, `height_m` h0 and `step_m` h1 with its `step_z`), its
    held-out RMSE against the verdict's (an `unknown`'s: its partial effects', else the
    baseline's) with the cut's interval, whether it `beats` the verdict (module docstring;
    the proposal then holds the step), and for a verdict that names effects `why` (one
    sentence) where it does, which makes the verdict `unknown`; {} for `none`."""
    from cell.gap.plane_tilt import tilt_check
    from cell.gap.stats import bootstrap_cut

    if verdict[0] == "none":
        return {}
    r = np.nan_to_num(np.asarray(r0, float))
    per_m, x = _columns(prob)
    every = np.arange(len(prob))
    xb, h, ss = fit_step(per_m, x, r, every)
    a = _design(per_m, x, xb)
    cov = ss / max(a.shape[0] - 3, 1) * np.linalg.pinv(a.T @ a)
    z = float(abs(h[1]) / max(np.sqrt(max(cov[1, 1], 0.0)), 1e-300))
    sq = step_heldout(prob, per_m, x, r)
    cut, lo, hi = bootstrap_cut(v_sq, sq, seed=prob.seed + 11)
    out: dict[str, Any] = {
        "break_x_m": xb, "height_m": float(h[0]), "step_m": float(h[1]), "step_z": z,
        "heldout_rmse_m": float(np.sqrt(sq.mean())),
        "verdict_heldout_rmse_m": float(np.sqrt(np.mean(v_sq))),
        "cut_m": cut, "cut_ci95_m": [lo, hi], "step_bound_z": STEP_Z,
        "beats": bool(lo > 0 and z > STEP_Z),
    }  # fmt: skip
    out["tilt"] = tilt = tilt_check(prob, verdict, r, v_sq, per_m)  # `cell.gap.plane_tilt`
    if out["beats"] and verdict[0] != "unknown":
        out["why"] = (
            f"the landing plane {h[1]:+.3f} m beyond x = {xb:.3f} m (z {z:.1f}) predicts the "
            f"held-out throws better than {' + '.join(verdict)}: {out['heldout_rmse_m']:.4f} "
            f"against {out['verdict_heldout_rmse_m']:.4f} m (cut interval "
            f"[{lo:.4f}, {hi:.4f}] m): no effect of the vocabulary is a step in the floor"
        )
    if "why" in tilt and "why" not in out:
        out["why"] = tilt["why"]
    return out


def step_term(prob: GapProblem, r: np.ndarray, keep: np.ndarray
              ) -> tuple[dict[str, Any], np.ndarray]:  # fmt: skip
    """The proposal's term of a step in the landing plane at the breakpoint fitted on the
    throws in `keep` (`fit_step`): (the term, its column (2n,) [m per m of height])."""
    per_m, x = _columns(prob)
    xb, _, _ = fit_step(per_m, x, np.nan_to_num(r), np.flatnonzero(keep))
    term = {"phase": "landing", "term": f"landing plane height [m] = k · [x_m > {xb:.3f}]"}
    return term, (per_m * (x > xb)[:, None]).reshape(-1)
