"""The gap fit's Jacobian with every perturbed parameter vector in one flight integration.

`scipy.optimize.least_squares` with a finite-difference Jacobian ('2-point', a relative
step) calls the residual once per parameter per iteration: one whole batched flight each.
`stacked_jacobian` makes the same forward differences (the steps of scipy's
`approx_derivative`: relative step times |x| with x's sign, the EPS**0.5 fallback when that
step vanishes, a step that would leave the bounds turned round or shortened to the
nearest bound) but predicts the throws of every perturbed vector in one call, the
training throws stacked once per vector. The model is row-independent (each throw's
arithmetic reads only its own row), so each copy's misses are bitwise those of its own
call and the Jacobian is bitwise scipy's (tests/test_gap_fit_jac.py).

Only effects whose parameters enter the model elementwise can be given one value per
stacked row (`STACKABLE`, and the covariate laws of `cell.gap.laws` over them); a set with
any other effect, or the permutation control (its shuffle depends on the number of rows),
keeps scipy's own differences.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import fields

import numpy as np

from cell.gap.problem import GapProblem
from cell.model.effects import (
    BandDamping,
    BandMass,
    Downwash,
    DownwashDecay,
    DragScale,
    Effect,
    ReleasePitch,
    ShapeStretch,
    Spin,
    StrokeOffset,
    Wind,
)

__all__ = ["STACKABLE", "forward_steps", "stackable", "stacked_jacobian", "stacked_misses"]

# effects whose parameters enter the launch or the flight elementwise (a per-row array
# gives each row the arithmetic of its own scalar)
STACKABLE: tuple[type[Effect], ...] = (
    BandMass,
    BandDamping,
    ShapeStretch,
    StrokeOffset,
    ReleasePitch,
    DragScale,
    Wind,
    Downwash,
    DownwashDecay,
    Spin,
)


def stackable(classes: list[type[Effect]], permute: bool) -> bool:
    """True if the set's misses can be predicted for many parameter vectors at once."""
    if permute or not classes:
        return False
    for c in classes:
        if hasattr(c, "object_index"):  # one value per object: its own vector() arithmetic
            return False
        base = getattr(c, "law_base", c)
        if base not in STACKABLE:
            return False
    return True


def forward_steps(x: np.ndarray, lo: np.ndarray, hi: np.ndarray, rel_step: float) -> np.ndarray:
    """The signed forward steps (p,) scipy's '2-point' `approx_derivative` takes at x with
    a relative step and bounds [lo, hi] (`_compute_absolute_step` and
    `_adjust_scheme_to_bounds`, one-sided, one step)."""
    sign = (x >= 0).astype(float) * 2 - 1
    h = rel_step * sign * np.abs(x)
    dx = (x + h) - x
    h = np.where(dx == 0, np.finfo(np.float64).eps ** 0.5 * sign * np.maximum(1.0, np.abs(x)), h)
    if np.all((lo == -np.inf) & (hi == np.inf)):
        return np.asarray(h)
    out = h.copy()
    lower, upper = x - lo, hi - x
    xh = x + h
    violated = (xh < lo) | (xh > hi)
    fitting = np.abs(h) <= np.maximum(lower, upper)
    out[violated & fitting] *= -1
    forward = (upper >= lower) & ~fitting
    out[forward] = upper[forward]
    backward = (upper < lower) & ~fitting
    out[backward] = -lower[backward]
    return np.asarray(out)


def _stacked_effects(
    classes: list[type[Effect]], xs: np.ndarray, scale: np.ndarray, m: int
) -> list[Effect]:
    """The effects with one value per stacked row: parameter vectors xs (k, p) (scaled),
    each repeated over the m rows of its copy; clipped to the bounds as `fit._unpack`."""
    vals = xs * scale
    out: list[Effect] = []
    i = 0
    for c in classes:
        n = len(c.bounds)
        lo = np.array([b[0] for b in c.bounds])
        hi = np.array([b[1] for b in c.bounds])
        v = np.clip(vals[:, i : i + n], lo, hi)
        e = object.__new__(c)
        for j, f in enumerate(fields(c)):  # type: ignore[arg-type]
            object.__setattr__(e, f.name, np.repeat(v[:, j], m))
        out.append(e)
        i += n
    return out


def stacked_misses(
    prob: GapProblem,
    classes: list[type[Effect]],
    train: np.ndarray,
    xs: np.ndarray,
    scale: np.ndarray,
) -> np.ndarray:
    """The residual vectors (k, 2m) of the training throws at each parameter vector of xs
    (k, p), from one prediction of the throws stacked k times."""
    train = np.asarray(train)
    k, m = xs.shape[0], train.size
    effs = _stacked_effects(classes, xs, scale, m)
    r = prob.residual(np.tile(train, k), effs)
    return np.asarray(r).reshape(k, 2 * m)


def stacked_jacobian(
    prob: GapProblem,
    classes: list[type[Effect]],
    train: np.ndarray,
    scale: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray],
    rel_step: float,
) -> Callable[[np.ndarray], np.ndarray]:
    """A `jac` for `least_squares`: the residual's forward-difference Jacobian (2m, p) at
    x, bitwise scipy's '2-point' with `diff_step=rel_step` and these bounds, with x and
    its p perturbed copies predicted in one stacked call."""
    lo, hi = bounds

    def jac(x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, float)
        h = forward_steps(x, lo, hi, rel_step)
        p = x.size
        xs = np.repeat(x[None, :], p + 1, axis=0)
        for i in range(p):
            xs[1 + i, i] = x[i] + h[i]
        r = stacked_misses(prob, classes, train, xs, scale)
        dx = np.array([(x[i] + h[i]) - x[i] for i in range(p)])
        return np.asarray(((r[1:] - r[0]) / dx[:, None]).T)

    return jac
