"""The model's inverse in the stroke, and the residual-learning target ΔL_s.

For a throw whose release pose is fixed, the reach along the throw's azimuth
falls monotonically as the stroke L_s grows (a longer stroke leaves the band
less stretched). `stroke_for_reach` inverts that map for a whole batch at once:
it evaluates the reach at both ends of the stroke range, flags the throws whose
wanted reach lies outside, and closes the bracket of the others with the
Illinois variant of regula falsi (a secant step that cannot stall), safeguarded
by bisection.

Sign convention of the residual. With g the model's reach and w the world's,
the planner wants w(L_c) = r for a target reach r, and the model alone would
command L_m = g⁻¹(r). A logged throw made with stroke L_used landed at r_obs;
the model's inverse says L_model = g⁻¹(r_obs) would have put it there, so the
stroke that truly reaches r_obs exceeds the model's plan for r_obs by

    ΔL_s = L_used - L_model          [m]

and the planner commands L_s + ΔL_s (thesis Fig. 5.1). (The opposite order,
L_model - L_used, is the correction to subtract.)
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from cell.model.params import EndEffectorParams
from cell.model.throw import Landing, ThrowBatch, predict_landing

__all__ = [
    "OK",
    "TOO_FAR",
    "TOO_NEAR",
    "NO_LANDING",
    "NO_OBSERVATION",
    "STATUS_NAMES",
    "StrokeSolution",
    "ResidualTargets",
    "reach_along_azimuth",
    "stroke_for_reach",
    "residual_targets",
]

log = logging.getLogger(__name__)

OK, TOO_FAR, TOO_NEAR, NO_LANDING, NO_OBSERVATION = 0, 1, 2, 3, 4
STATUS_NAMES = {
    OK: "ok",
    TOO_FAR: "beyond the model's reach at stroke_min",
    TOO_NEAR: "short of the model's reach at stroke_max",
    NO_LANDING: "never lands in the model",
    NO_OBSERVATION: "no observed landing",
}
_BAD = (TOO_FAR, TOO_NEAR, NO_LANDING, NO_OBSERVATION)

Predictor = Callable[[ThrowBatch], Landing]


def reach_along_azimuth(batch: ThrowBatch, xy: np.ndarray) -> np.ndarray:
    """Horizontal distance [m] from the release point to the points `xy` (n, 2),
    projected on the throw's azimuth direction (cos a, sin a) in W."""
    d = np.asarray(xy, float) - batch.position[:, :2]
    return d[:, 0] * np.cos(batch.azimuth) + d[:, 1] * np.sin(batch.azimuth)


@dataclass(frozen=True)
class StrokeSolution:
    """The strokes that reach given distances.

    Attributes:
        stroke: L_s [m], shape (n,); the nearer end of the range where status != OK.
        status: OK, TOO_FAR, TOO_NEAR or NO_LANDING per throw, shape (n,).
        miss: model reach at `stroke` minus the wanted reach [m], shape (n,).
        iterations: root-finding iterations used.
    """

    stroke: np.ndarray
    status: np.ndarray
    miss: np.ndarray
    iterations: int

    @property
    def ok(self) -> np.ndarray:
        """True where the wanted reach lies inside the model's reachable range."""
        return self.status == OK


def _with_stroke(batch: ThrowBatch, stroke: np.ndarray) -> ThrowBatch:
    return ThrowBatch(
        **{**{k: getattr(batch, k) for k in batch.__dataclass_fields__}, "stroke": stroke}
    )


def _illinois(
    a: np.ndarray,
    b: np.ndarray,
    fa: np.ndarray,
    fb: np.ndarray,
    c: np.ndarray,
    fc: np.ndarray,
    side: np.ndarray,
) -> tuple[np.ndarray, ...]:
    """One bracket update of the Illinois method at c (value fc), f(a) >= 0 >= f(b): the
    new (a, b, f(a), f(b), side kept), the stale end's value halved when the same end is
    kept twice (`side`: 1 the left one moved last, -1 the right one)."""
    left = fc > 0  # the root lies beyond c, between c and b
    a_new = np.where(left, c, a)
    fa_new = np.where(left, fc, fa)
    b_new = np.where(left, b, c)
    fb_new = np.where(left, fb, fc)
    fb_new = np.where(left & (side == 1), 0.5 * fb_new, fb_new)
    fa_new = np.where(~left & (side == -1), 0.5 * fa_new, fa_new)
    return a_new, b_new, fa_new, fb_new, np.where(left, 1, -1)


def stroke_for_reach(
    batch: ThrowBatch,
    reach_m: np.ndarray,
    ee: EndEffectorParams,
    *,
    predict: Predictor | None = None,
    tol_m: float = 1e-9,
    max_iter: int = 60,
) -> StrokeSolution:
    """The stroke at which the model's reach along each throw's azimuth equals `reach_m`.

    Everything but the stroke is taken from `batch` (its own strokes are ignored).

    Args:
        batch: the throws (release pose, object).
        reach_m: wanted reach along the azimuth [m], shape (n,).
        ee: end-effector parameters (its stroke range bounds the search).
        predict: the model, batch -> Landing (not strict, no stroke check); the
            nominal `predict_landing` with `ee` when None.
        tol_m: stop when every bracket is narrower than this [m] of stroke.
        max_iter: iteration cap.

    Returns:
        The strokes and a status per throw (never silently clipped).
    """
    if predict is None:

        def predict(b: ThrowBatch) -> Landing:
            return predict_landing(b, ee, strict=False, check_stroke=False)

    n = len(batch)
    want = np.asarray(reach_m, float).reshape(n)

    def f(stroke: np.ndarray, idx: np.ndarray) -> np.ndarray:
        sub = _with_stroke(batch.take(idx), stroke)
        land = predict(sub)
        r = reach_along_azimuth(sub, land.xy)
        return np.where(land.landed, r - want[idx], np.nan)

    all_idx = np.arange(n)
    lo = np.full(n, ee.stroke_min)  # most stretch: farthest
    hi = np.full(n, ee.stroke_max)
    f_lo = f(lo, all_idx)
    f_hi = f(hi, all_idx)
    status = np.full(n, OK)
    status[~np.isfinite(f_lo) | ~np.isfinite(f_hi)] = NO_LANDING
    status[(status == OK) & (f_lo < 0)] = TOO_FAR
    status[(status == OK) & (f_hi > 0)] = TOO_NEAR
    stroke = np.where(status == TOO_NEAR, hi, lo)
    miss = np.where(status == TOO_NEAR, f_hi, f_lo)
    act = np.flatnonzero(status == OK)
    a, b, fa, fb = lo[act], hi[act], f_lo[act], f_hi[act]
    side = np.zeros(act.size, int)
    it = 0
    while act.size and it < max_iter:
        it += 1
        with np.errstate(divide="ignore", invalid="ignore"):
            c = (a * fb - b * fa) / (fb - fa)
        mid = 0.5 * (a + b)
        bad = ~np.isfinite(c) | (c <= np.minimum(a, b)) | (c >= np.maximum(a, b))
        c = np.where(bad, mid, c)
        fc = f(c, act)
        fc = np.where(np.isfinite(fc), fc, 0.0)
        a, b, fa, fb, side = _illinois(a, b, fa, fb, c, fc, side)
        done = (np.abs(b - a) < tol_m) | (fc == 0)
        stroke[act] = c
        miss[act] = fc
        if done.any():
            keep = ~done
            act, a, b, fa, fb, side = act[keep], a[keep], b[keep], fa[keep], fb[keep], side[keep]
    if act.size:
        stroke[act] = 0.5 * (a + b)
        miss[act] = f(stroke[act], act)
    return StrokeSolution(stroke=stroke, status=status, miss=miss, iterations=it)


@dataclass(frozen=True)
class ResidualTargets:
    """The learning targets of a throw log.

    Attributes:
        delta_stroke: ΔL_s = L_used - L_model [m], shape (n,); NaN where not usable.
        model_stroke: L_model, the model's stroke for the observed landing [m], shape (n,).
        status: OK or why the observed reach is outside the model's range, shape (n,).
        reach_m: observed reach along the azimuth [m], shape (n,).
    """

    delta_stroke: np.ndarray
    model_stroke: np.ndarray
    status: np.ndarray
    reach_m: np.ndarray

    @property
    def usable(self) -> np.ndarray:
        """True for the throws that can be learned from."""
        return self.status == OK

    def excluded_counts(self) -> dict[str, int]:
        """Number of excluded throws per reason."""
        return {STATUS_NAMES[s]: int(np.sum(self.status == s)) for s in _BAD}


def residual_targets(
    batch: ThrowBatch,
    observed_xy: np.ndarray,
    ee: EndEffectorParams,
    *,
    predict: Predictor | None = None,
) -> ResidualTargets:
    """ΔL_s for each logged throw, by the model's own inverse.

    Throws whose observed reach the model cannot produce within the stroke range,
    and throws without an observed landing (NaN), are marked (status) and get
    NaN; their count is logged as a warning, by reason.

    Args:
        batch: the logged throws, with the strokes used.
        observed_xy: observed landing points [m, W], shape (n, 2); NaN = not observed.
        ee: end-effector parameters (identified).
        predict: the model (see `stroke_for_reach`).

    Returns:
        The targets.
    """
    observed_xy = np.asarray(observed_xy, float)
    seen = np.all(np.isfinite(observed_xy), axis=1)
    reach = reach_along_azimuth(batch, np.where(seen[:, None], observed_xy, batch.position[:, :2]))
    status = np.full(len(batch), NO_OBSERVATION)
    model_stroke = np.full(len(batch), np.nan)
    idx = np.flatnonzero(seen)
    if idx.size:
        sol = stroke_for_reach(batch.take(idx), reach[idx], ee, predict=predict)
        status[idx] = sol.status
        model_stroke[idx] = np.where(sol.ok, sol.stroke, np.nan)
    reach = np.where(seen, reach, np.nan)
    delta = np.where(status == OK, batch.stroke - model_stroke, np.nan)
    n_bad = int(np.sum(status != OK))
    if n_bad:
        reasons = ", ".join(
            f"{int(np.sum(status == s))} {STATUS_NAMES[s]}" for s in _BAD if np.any(status == s)
        )
        log.warning(
            "%d of %d throws excluded from the residual targets (%s)",
            n_bad,
            len(batch),
            reasons,
        )
    return ResidualTargets(
        delta_stroke=delta, model_stroke=model_stroke, status=status, reach_m=reach
    )
