"""A tilted landing plane: a second candidate outside the vocabulary a named verdict must beat.

A surface landed on that is not level (a floor off level, a board on a slope, a tray on a
wedge), logged as the level plane `land_z_m`, moves each landing by its height there,
h(x, y) = h0 + hx · x + hy · y, times v_h / v_z: the far throws on the raised side fall short,
the others long. A tracker off in scale moves the landings by (s − 1) times their position, much
as that does where the throws fly away from the origin, and a release pitch takes up the
rest: a plane z = 0.08 · x was named `tracking_scale` + `release_pitch` at 1.29 F (the
thirteenth lab round's W6, docs/HISTORY.md, branch `lab67`).

The rule is `cell.gap.plane_step`'s for a step: the plane's three heights fitted by least
squares to the baseline's misses, (h0 + hx · x + hy · y) · v_h / v_z with x, y the model's
landing point (`tilt_fit`), held out on the problem's random folds (`tilt_heldout`); where it
predicts the held-out throws better than the verdict's effects with a bootstrap 95 % interval
of the cut above zero and its slope (hx, hy) `STEP_Z` standard errors from zero (the
slope's Mahalanobis length), a verdict that names effects is `unknown`. Where it predicts
them as well (a cut of zero or more whose interval holds zero: it `ties`) with that slope,
the landings cannot tell the tilted floor from the verdict, and the verdict is `unknown`
too: a plane z = 0.03 · x on 120 throws was named `spin`, −131 rad/s on every object, the
plane held out 0.0144 m against the spin's 0.0148 (the fourteenth lab round, docs/HISTORY.md,
branch `lab68`). Its figures are the
report's `landing_step.tilt`; the proposal's library holds the plane's height in x and y
already (`cell.gap.propose`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.gap.problem import GapProblem

__all__ = ["tilt_fit", "tilt_heldout", "tilt_check"]


def _design(per_m: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """The plane's columns (2n, 3): its height, its slope along x and along y."""
    return np.stack([per_m.reshape(-1), (per_m * xy[:, :1]).reshape(-1),
                     (per_m * xy[:, 1:2]).reshape(-1)], axis=1)  # fmt: skip


def tilt_fit(per_m: np.ndarray, xy: np.ndarray, r: np.ndarray, rows: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """((h0 [m], hx, hy [-]), their covariance) fitted on the throws `rows`."""
    a = _design(per_m[rows], xy[rows])
    y = r[rows].reshape(-1)
    h, *_ = np.linalg.lstsq(a, y, rcond=None)
    ss = float(np.sum((y - a @ h) ** 2))
    return h, ss / max(a.shape[0] - 3, 1) * np.linalg.pinv(a.T @ a)


def tilt_heldout(prob: GapProblem, per_m: np.ndarray, xy: np.ndarray, r: np.ndarray
                 ) -> np.ndarray:  # fmt: skip
    """Each throw's squared held-out miss [m²] under the plane fitted on the other folds."""
    sq = np.zeros(len(prob))
    for train, test in prob.folds["random"]:
        h, _ = tilt_fit(per_m, xy, r, train)
        e = r[test].reshape(-1) - _design(per_m[test], xy[test]) @ h
        sq[test] = np.sum(e.reshape(-1, 2) ** 2, axis=1)
    return sq


def tilt_check(prob: GapProblem, verdict: list[str], r: np.ndarray, v_sq: np.ndarray,
               per_m: np.ndarray) -> dict[str, Any]:  # fmt: skip
    """The tilted plane's figures (`height_m`, `slope_x`, `slope_y`, `slope_z`, its held-out
    RMSE against the verdict's, the cut with its interval, `beats`, `ties`) and, where it
    beats or ties a verdict that names effects, `why` (one sentence). r: the baseline's
    misses (n, 2) [m]; v_sq: the verdict's squared held-out misses [m²]; per_m: each
    landing's move per metre of plane height (n, 2) (`cell.gap.plane_step`)."""
    from cell.gap.plane_step import STEP_Z
    from cell.gap.stats import bootstrap_cut

    xy = np.nan_to_num(prob.landing(np.arange(len(prob)), ()).xy[:, :2])
    h, cov = tilt_fit(per_m, xy, r, np.arange(len(prob)))
    c = cov[1:, 1:]
    z = float(np.sqrt(max(h[1:] @ np.linalg.pinv(c) @ h[1:], 0.0)))
    sq = tilt_heldout(prob, per_m, xy, r)
    cut, lo, hi = bootstrap_cut(v_sq, sq, seed=prob.seed + 13)
    out: dict[str, Any] = {
        "height_m": float(h[0]), "slope_x": float(h[1]), "slope_y": float(h[2]), "slope_z": z,
        "heldout_rmse_m": float(np.sqrt(sq.mean())), "cut_m": cut, "cut_ci95_m": [lo, hi],
        "beats": bool(lo > 0 and z > STEP_Z),
        "ties": bool(not (lo > 0) and cut >= 0 and z > STEP_Z),
    }  # fmt: skip
    if (out["ties"] or out["beats"]) and verdict[0] not in ("none", "unknown"):
        how, why = (
            ("better than", "no effect of the vocabulary tilts the floor")
            if out["beats"]
            else (
                "as well as",
                "the landings cannot tell a tilted floor, which no effect of the vocabulary "
                "is, from the verdict",
            )
        )
        out["why"] = (
            f"the landing plane tilted, {h[0]:+.3f} m {h[1]:+.4f} · x {h[2]:+.4f} · y (slope z "
            f"{z:.1f}), predicts the held-out throws {how} {' + '.join(verdict)}: "
            f"{out['heldout_rmse_m']:.4f} against {float(np.sqrt(np.mean(v_sq))):.4f} m (cut "
            f"interval [{lo:.4f}, {hi:.4f}] m): {why}"
        )
    return out
