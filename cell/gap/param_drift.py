"""A named effect whose parameter drifts over the log: no steady effect, `unknown`.

A band that tires over a session loses a little more of its push with every throw; an
encoder that creeps, a tracker that warms up. A steady effect of the vocabulary fitted to
such a log takes the drift's mean and leaves its course in the misses; where the log's
repeats were thrown at other times in the session, they part by the drift as well, the
floor they give grows with it, and the steady effect comes within the verdict's ratio of
that floor: the log is called a steady effect it does not have (a band that tires by 5 %
over 300 throws, shuffled repeats, was named `tracking_scale` ~ N(0.966, 0.021)).

None of the other rules reads the throws' order. This one does, for a verdict that names
effects: each named effect's parameter θ is given a trend over the log, θ + c · (o − ō)
(o the throw's order, 0 at the first throw and 1 at the last, by `time_s` where every row
has it, else by row: `cell.gap.propose.log_covariates`), linearised about the fit,

    r_i ≈ J_i a + J_i (o_i − ō) c,   J_i = ∂ landing_i / ∂ θ   [m per unit of θ],

by least squares over the verdict's misses r_i, with its standard error clustered by throw
(a throw's two coordinates share its draw; a heavy-tailed miss widens it). Where
|c| / se(c) exceeds `DRIFT_Z` and the trend moves the landings (RMS of J_i c (o_i − ō))
by at least `DRIFT_SHARE` of the noise floor, the effect is not steady: the verdict is
`unknown` with the effects as its partials, and the report's `parameter_drifts` says which
parameter drifts, by how much over the log, and why (the proposal then says what is left).
Effects whose parameters are not plain numbers (a law per object) are not tried.
"""

from __future__ import annotations

from dataclasses import fields, replace
from typing import Any

import numpy as np

from cell.gap.problem import GapProblem
from cell.model.effects import Effect

__all__ = ["DRIFT_Z", "DRIFT_SHARE", "param_drifts", "drift_check"]

DRIFT_Z = 5.0  # the trend over the log is this many standard errors from none
DRIFT_SHARE = 0.5  # and moves the landings by at least this share of the noise floor F
JAC_SHARE = 0.02  # central-difference step, a share of the parameter's unit


def _unit(e: Effect, j: int, value: float) -> float:
    scale = getattr(type(e), "scale", None)
    typical = float(scale[j]) if scale is not None and j < len(scale) else 0.0
    return max(abs(value), 10.0 * typical, 1e-6)


def _jacobian(prob: GapProblem, effects: tuple[Effect, ...], k: int, name: str
              ) -> np.ndarray | None:  # fmt: skip
    """∂ landing / ∂ θ (n, 2) of parameter `name` of effect k, or None where it is no
    plain number."""
    e = effects[k]
    value = getattr(e, name, None)
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        return None
    if name not in {f.name for f in fields(e)}:
        return None
    j = list(e.param_names()).index(name)
    bounds = getattr(type(e), "bounds", None)
    lo, hi = bounds[j] if bounds is not None and j < len(bounds) else (-np.inf, np.inf)
    h = JAC_SHARE * _unit(e, j, float(value))
    a, b = max(float(value) - h, lo), min(float(value) + h, hi)
    if not b > a:
        return None
    idx = np.arange(len(prob))
    out = []
    for v in (b, a):
        trial = list(effects)
        trial[k] = replace(e, **{name: float(v)})
        out.append(prob.landing(idx, tuple(trial)).xy)
    return np.nan_to_num((out[0] - out[1]) / (b - a))


def _trend(r: np.ndarray, jac: np.ndarray, o: np.ndarray) -> tuple[float, float, float]:
    """(c, its standard error clustered by throw, the RMS landing move of the trend [m])."""
    oc = o - o.mean()
    X = np.stack([jac, jac * oc[:, None]], axis=2)  # (n, 2 coordinates, 2 columns)
    XtX = np.einsum("nki,nkj->ij", X, X)
    if np.linalg.cond(XtX) > 1e12:
        return 0.0, float("inf"), 0.0
    inv = np.linalg.inv(XtX)
    coef = inv @ np.einsum("nki,nk->i", X, r)
    e = r - np.einsum("nki,i->nk", X, coef)
    score = np.einsum("nki,nk->ni", X, e)  # per throw: its two coordinates together
    cov = inv @ (score.T @ score) @ inv
    se = float(np.sqrt(max(cov[1, 1], 0.0)))
    move = float(np.sqrt(np.mean(np.sum((jac * (coef[1] * oc)[:, None]) ** 2, axis=1))))
    return float(coef[1]), se, move


def param_drifts(prob: GapProblem, effects: tuple[Effect, ...], floor_m: float
                 ) -> list[dict[str, Any]]:  # fmt: skip
    """Each plain parameter of `effects` with its trend over the log's order: `effect`,
    `param`, `value`, `change_over_log` (c, in the parameter's unit), `z`, `move_m`, and
    `drifts` (z over `DRIFT_Z` and the move over `DRIFT_SHARE` × `floor_m`)."""
    from cell.gap.propose import log_covariates

    order = log_covariates(prob).get("order")
    if order is None or len(prob) < 3:
        return []
    idx = np.arange(len(prob))
    r = prob.residual(idx, effects)
    ok = np.all(np.isfinite(r), axis=1)
    out = []
    for k, e in enumerate(effects):
        if e.name == "band_stiffness" or getattr(type(e), "object_ids", None) is not None:
            continue
        for name in e.param_names():
            jac = _jacobian(prob, effects, k, name)
            if jac is None:
                continue
            c, se, move = _trend(r[ok], jac[ok], order[ok])
            z = abs(c) / se if se > 0 else 0.0
            out.append({
                "effect": e.name, "param": name, "value": float(getattr(e, name)),
                "change_over_log": c, "change_se": se, "z": z, "move_m": move,
                "drifts": bool(z > DRIFT_Z and move >= DRIFT_SHARE * floor_m),
            })  # fmt: skip
    return out


def drift_check(prob: GapProblem, verdict: list[str], chosen: list[Any], floor_m: float
                ) -> dict[str, Any]:  # fmt: skip
    """For a verdict that names effects (`chosen`: the joined sets, the last the verdict's),
    the report's `parameter_drifts`: `drift_z`, `drift_share`, each parameter `tried`, and
    `why` (one sentence) where one drifts, which makes the verdict `unknown`; {} otherwise."""
    if verdict[0] in ("none", "unknown") or not chosen:
        return {}
    tried = param_drifts(prob, tuple(chosen[-1].full.effects), floor_m)
    out: dict[str, Any] = {"drift_z": DRIFT_Z, "drift_share": DRIFT_SHARE, "tried": tried}
    worst = max((t for t in tried if t["drifts"]), key=lambda t: t["z"], default=None)
    if worst is not None:
        out["why"] = (
            f"{worst['effect']}'s {worst['param']} drifts over the log: "
            f"{worst['change_over_log']:+.4g} from its first throw to its last "
            f"(z {worst['z']:.1f}), moving the landings by {worst['move_m']:.4f} m RMS "
            f"(F {floor_m:.4f} m): no steady {worst['effect']}"
        )
    return out
