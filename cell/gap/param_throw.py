"""An effect whose parameter varies from throw to throw: its mean and spread, and the floor
its spread sets.

A drag that changes with each throw's attitude, a band that loses a different share of its
push each time: the effect is real, but its size is drawn anew for every throw. The fit of
one value finds the mean and leaves each throw's draw in the miss, J_i (θ_i − θ̄), which
grows with how far the parameter moves that throw's landing (J_i = ∂ landing / ∂ θ [m per
unit]). No account of the mean removes it: it is floor, as a tracker's scatter is. The
floor from repeats holds it only where the repeated throws are the ones the parameter moves
most; a campaign whose few most sensitive throws happen to draw alike in their repeats
shows a floor well under what the draws scatter.

The throw-to-throw form of one parameter θ of effect e (one-parameter effects: a law in a
covariate or per object is a deterministic account, the wind has its own form,
`cell.gap.wind_throw`), linearised as the wind's is:

    y_i = r_i + J_i θ̄₀ = J_i θ_i + e_i,   θ_i ~ N(μ, s²),   e_i ~ N(0, σ² I₂)

μ, s and σ by maximum marginal likelihood (`cell.gap.wind_throw.fit_marginal`, K = 1).
It stands for the effect where (all three, as for the wind):
- its held-out log density per throw beats the one value's by more than `LOGLIK_PENALTY`,
  with a bootstrap 95 % interval of the gain above zero;
- the repeats show the spread (`repeat_test`: the difference of two throws of one
  configuration keeps the draws and cancels what the model misses on the configuration
  itself, so a deterministic misfit that grows with J, an effect outside the vocabulary,
  shows no spread there); a log without repeats cannot show it, and the form is not taken.

Where it stands, the verdict's floor is what the form says no account of the mean can
remove: the noise of one throw σ_r and the spread s_r the repeats show (both fitted on the
pairs' differences, where what the model misses on a configuration itself cancels: an
effect outside the vocabulary beside the drawn one is not taken up as spread), the spread
carried through each throw's sensitivity,

    F_s² = 2 σ_r² + s_r² · mean_i |J_i|²   (+ the validated misfit², as the floor has it),

and an `unknown` verdict whose held-out RMSE A is within the verdict's ratio of max(F, F_s)
names the effect, its law `θ_i ~ N(mean, sd)`. In expectation over the draws the repeats'
floor equals F_s (a repeat holds the spread too); F_s weighs each throw by its J, which the
repeats' plain mean square does not.

A verdict that names the effect by its one value leaves each throw's draw in its miss, and
the throws that drew far from the mean look impossible: where its misses flag rows,
`cell.gap.run` fits the form too and flags on the misses whitened by it
(`whitened_spread`).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from cell.gap.noise import NoiseFloor
from cell.gap.problem import GapProblem
from cell.gap.wind_throw import (
    LOGLIK_PENALTY,
    REPEAT_LR,
    fit_marginal,
    heldout,
    mean_ci95,
    repeat_pairs,
    repeat_test,
    sd_interval,
    whiten,
)
from cell.model.effects import Effect

__all__ = ["param_spread", "spread_law", "whitened_spread"]

JAC_SHARE = 0.02  # central-difference step of ∂ landing / ∂ θ, as a share of θ's unit
UNIT_SCALES = 10.0  # θ's unit: its size, or this many of the effect's typical sizes


def spread_law(param: str) -> str:
    """The law's text for parameter `param` drawn throw to throw."""
    return f"{param}_i ~ N(mean, sd)"


def _drawable(e: Effect) -> bool:
    """One plain parameter: no law in a covariate or per object, not the wind's."""
    cls = type(e)
    return (
        len(cls.bounds) == 1
        and e.name not in ("wind", "band_stiffness")
        and getattr(cls, "law_base", None) is None
        and getattr(cls, "object_ids", None) is None
    )


def _unit(e: Effect, value: float) -> float:
    """θ's unit about `value`: its size, or `UNIT_SCALES` of the effect's typical sizes."""
    return max(abs(value), UNIT_SCALES * float(type(e).scale[0]))


def _with(effects: tuple[Effect, ...], j: int, value: float) -> tuple[Effect, ...]:
    e = effects[j]
    lo, hi = type(e).bounds[0]
    out = list(effects)
    out[j] = replace(e, **{e.param_names()[0]: float(np.clip(value, lo, hi))})  # type: ignore[type-var]
    return tuple(out)


def _linearised(prob: GapProblem, effects: tuple[Effect, ...], j: int, th0: float, unit: float
                ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(y (n, 2) [m], J (n, 2, 1) [m per unit]) about θ = th0 of effect j."""
    idx = np.arange(len(prob))
    lo, hi = type(effects[j]).bounds[0]
    a, b = max(th0 - JAC_SHARE * unit, lo), min(th0 + JAC_SHARE * unit, hi)
    up = prob.landing(idx, _with(effects, j, b)).xy
    down = prob.landing(idx, _with(effects, j, a)).xy
    jac = np.nan_to_num((up - down) / (b - a))[:, :, None]
    r0 = prob.residual(idx, _with(effects, j, th0))
    return r0 + jac[:, :, 0] * th0, jac


def _sd_ci95(y: np.ndarray, jac: np.ndarray, s: float, sig: float, ll: float, unit: float
             ) -> list[float]:  # fmt: skip
    """The sd's 95 % profile interval (`sd_interval`, in θ's unit), then again on a grid
    from one of its steps below it to one above: a spread small beside its unit (grams of
    a band mass in a unit of 0.1 kg) is narrower than one step of the first grid, which
    would give that one grid point as the interval."""
    lo, hi = sd_interval(y, jac, s, sig, ll, unit)
    step = max(3.0 * s, 0.5 * unit) / 60.0
    return sd_interval(y, jac, s, sig, ll, unit, span=(max(lo - step, 0.0), hi + step))


def _one(prob: GapProblem, effects: tuple[Effect, ...], j: int, nf: NoiseFloor
         ) -> dict[str, Any]:  # fmt: skip
    from cell.gap.stats import N_BOOT, _indices

    e = effects[j]
    name = e.param_names()[0]
    th0 = float(e.vector()[0])
    unit = _unit(e, th0)
    y, jac = _linearised(prob, effects, j, th0, unit)
    mu, s, sig, ll = fit_marginal(y, jac, unit=unit)
    y, jac = _linearised(prob, effects, j, float(mu[0]), unit)
    mu, s, sig, ll = fit_marginal(y, jac, unit=unit)
    ll0 = fit_marginal(y, jac, steady=True)[3]
    h0, h1 = heldout(prob, y, jac, unit)
    d = h1 - h0
    gain = float(np.mean(d))
    lo, hi = np.percentile(d[_indices(d.size, prob.seed + 13, N_BOOT)].mean(axis=1), [2.5, 97.5])
    reps = repeat_test(y, jac, repeat_pairs(prob), unit)
    shown = reps["lr"] is not None and reps["lr"] > REPEAT_LR
    chosen = bool(s > 0 and gain > LOGLIK_PENALTY and lo > 0 and shown)
    sens_sq = float(np.mean(np.sum(jac[:, :, 0] ** 2, axis=1)))  # mean |J_i|² [m² per unit²]
    floor = float("nan")
    if reps["noise_sd_m"] is not None:
        # the repeats' own spread and noise: what the model misses on a configuration
        # itself (an effect outside the vocabulary beside the drawn one) cancels in them,
        # where the spread fitted on all throws would take it up
        floor = float(np.sqrt(2.0 * reps["noise_sd_m"] ** 2 + reps["sd_mps"] ** 2 * sens_sq))
        if nf.validated_share > 0 and np.isfinite(nf.validated_m):
            floor = float(np.hypot(floor, nf.validated_m))
    return {
        "effect": e.name,
        "param": name,
        "law": spread_law(name),
        "chosen": chosen,
        "mean": float(mu[0]),
        "mean_ci95": mean_ci95(y, jac, s, sig)[0],
        "sd": s,
        "sd_ci95": _sd_ci95(y, jac, s, sig, ll, unit),
        "one_value": th0,
        "noise_sd_m": sig,
        "sensitivity_rms": float(np.sqrt(sens_sq)),
        "floor_m": floor,
        "loglik_gain_in_sample": float(ll - ll0),
        "heldout_gain_per_throw": gain,
        "heldout_gain_ci95": [float(lo), float(hi)],
        "penalty_per_throw": LOGLIK_PENALTY,
        "repeats": {**reps, "lr_needed": REPEAT_LR},
    }


def param_spread(prob: GapProblem, effects: tuple[Effect, ...], nf: NoiseFloor
                 ) -> dict[str, Any] | None:  # fmt: skip
    """The throw-to-throw form of each one-parameter effect of `effects` (fitted on all
    throws), the best chosen one first.

    Returns:
        None where no effect has one plain parameter; else the chosen form's account (or,
        where none is chosen, the one with the highest held-out gain): `effect`, `param`,
        `law`, `chosen`, `mean` and `sd` of the parameter (its units) with the sd's 95 %
        interval, `floor_m` (F_s [m]), the held-out gain per throw [nats] with its
        interval and penalty, the repeats' test, and `tried` (each effect's gain and
        whether it was chosen).
    """
    forms = [_one(prob, effects, j, nf) for j, e in enumerate(effects) if _drawable(e)]
    if not forms:
        return None
    forms.sort(key=lambda f: (not f["chosen"], -f["heldout_gain_per_throw"]))
    best = dict(forms[0])
    best["tried"] = {f["effect"]: {"chosen": f["chosen"], "heldout_gain_per_throw":
                                   f["heldout_gain_per_throw"]} for f in forms}  # fmt: skip
    return best


def whitened_spread(prob: GapProblem, effects: tuple[Effect, ...], form: dict[str, Any]
                    ) -> np.ndarray:  # fmt: skip
    """Each throw's miss (n, 2) [m] under the form (`param_spread`'s account), whitened to
    the scatter σ as `cell.gap.wind_throw.whitened_misses` does for the wind: a throw its
    parameter's own spread explains is not called impossible."""
    j = next(i for i, e in enumerate(effects) if e.name == form["effect"])
    mean = float(form["mean"])
    y, jac = _linearised(prob, effects, j, mean, _unit(effects[j], mean))
    return whiten(y, jac, np.array([mean]), float(form["sd"]), float(form["noise_sd_m"]))
