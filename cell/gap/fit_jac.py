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
keeps scipy's own differences, written out (`side_by_side_fun_jac`) so that its p
perturbed residuals are made side by side, their flights integrated as one batch
(`cell.model.flight_batch.together`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import fields
from functools import partial

import numpy as np

from cell.gap.problem import GapProblem
from cell.model.effects import (
    BandDamping,
    BandMass,
    Downwash,
    DownwashDecay,
    DownwashJet,
    DragScale,
    Effect,
    ReleasePitch,
    ShapeStretch,
    Spin,
    StrokeOffset,
    Wind,
)
from cell.model.flight_batch import together

__all__ = ["STACKABLE", "clipped_blocks", "forward_steps", "misses_many", "refit_folds",
           "side_by_side_fun_jac", "stackable", "stacked_fun_jac", "stacked_jacobian",
           "stacked_misses"]  # fmt: skip

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
    DownwashJet,
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


def clipped_blocks(
    classes: list[type[Effect]], vals: np.ndarray
) -> Iterator[tuple[type[Effect], np.ndarray]]:
    """Each class with its block of the parameter values (unscaled; along the last axis of
    vals, one vector (p,) or many (k, p)), clipped to the class's bounds."""
    i = 0
    for c in classes:
        n = len(c.bounds)
        lo = np.array([b[0] for b in c.bounds])
        hi = np.array([b[1] for b in c.bounds])
        yield c, np.clip(vals[..., i : i + n], lo, hi)
        i += n


def _stacked_effects(
    classes: list[type[Effect]], xs: np.ndarray, scale: np.ndarray, counts: np.ndarray
) -> list[Effect]:
    """The effects with one value per stacked row: parameter vectors xs (k, p) (scaled),
    each repeated over the counts[i] rows of its copy; clipped to the bounds as
    `fit._unpack`."""
    out: list[Effect] = []
    for c, v in clipped_blocks(classes, xs * scale):
        e = object.__new__(c)
        for j, f in enumerate(fields(c)):  # type: ignore[arg-type]
            object.__setattr__(e, f.name, np.repeat(v[:, j], counts))
        out.append(e)
    return out


def misses_many(
    prob: GapProblem,
    classes: list[type[Effect]],
    sets: list[np.ndarray],
    xs: np.ndarray,
    scale: np.ndarray,
) -> list[np.ndarray]:
    """The residual vectors (2 m_i,) of throws sets[i] at parameter vector xs[i] (scaled),
    all from one prediction of the sets stacked."""
    sets = [np.asarray(t) for t in sets]
    counts = np.array([t.size for t in sets])
    effs = _stacked_effects(classes, np.asarray(xs, float), scale, counts)
    r = np.asarray(prob.residual(np.concatenate(sets), effs))
    return [a.ravel() for a in np.split(r, np.cumsum(counts)[:-1])]


def stacked_misses(
    prob: GapProblem,
    classes: list[type[Effect]],
    train: np.ndarray,
    xs: np.ndarray,
    scale: np.ndarray,
) -> np.ndarray:
    """The residual vectors (k, 2m) of the training throws at each parameter vector of xs
    (k, p), from one prediction of the throws stacked k times."""
    return np.stack(misses_many(prob, classes, [np.asarray(train)] * xs.shape[0], xs, scale))


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
        return _misses_and_jacobian(prob, classes, train, scale, (lo, hi), rel_step, x)[1]

    return jac


def _misses_and_jacobian(
    prob: GapProblem,
    classes: list[type[Effect]],
    train: np.ndarray,
    scale: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray],
    rel_step: float,
    x: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The residual vector (2m,) at x and its forward-difference Jacobian (2m, p), from one
    prediction of x and its p perturbed copies stacked."""
    lo, hi = bounds
    x = np.asarray(x, float)
    h = forward_steps(x, lo, hi, rel_step)
    p = x.size
    xs = np.repeat(x[None, :], p + 1, axis=0)
    for i in range(p):
        xs[1 + i, i] = x[i] + h[i]
    r = stacked_misses(prob, classes, train, xs, scale)
    dx = np.array([(x[i] + h[i]) - x[i] for i in range(p)])
    return r[0], np.asarray(((r[1:] - r[0]) / dx[:, None]).T)


def stacked_fun_jac(
    prob: GapProblem,
    classes: list[type[Effect]],
    train: np.ndarray,
    scale: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray],
    rel_step: float,
) -> tuple[Callable[[np.ndarray], np.ndarray], Callable[[np.ndarray], np.ndarray]]:
    """A `fun` and a `jac` for `least_squares` that share their flights: each residual is
    predicted together with the Jacobian's perturbed copies (one stacked call; a call's
    cost is mostly its fixed part, 5.5 ms, against 0.01 ms a throw), and the Jacobian
    least_squares asks for next at that x (after every accepted step) is the one already
    made. The residual is the stacked call's first copy (bitwise the residual's own call,
    as the Jacobian's base already is), the Jacobian bitwise `stacked_jacobian`'s."""
    made: dict[bytes, np.ndarray] = {}

    def fun(x: np.ndarray) -> np.ndarray:
        r, j = _misses_and_jacobian(prob, classes, train, scale, bounds, rel_step, x)
        made.clear()
        made[np.asarray(x, float).tobytes()] = j
        return r

    def jac(x: np.ndarray) -> np.ndarray:
        j = made.pop(np.asarray(x, float).tobytes(), None)
        if j is None:
            j = _misses_and_jacobian(prob, classes, train, scale, bounds, rel_step, x)[1]
        return j

    return fun, jac


def side_by_side_fun_jac(
    one: Callable[[np.ndarray], np.ndarray],
    bounds: tuple[np.ndarray, np.ndarray],
    rel_step: float,
) -> tuple[Callable[[np.ndarray], np.ndarray], Callable[[np.ndarray], np.ndarray]]:
    """A `fun` and a `jac` for `least_squares` for any residual `one` (a set that cannot be
    stacked): scipy's '2-point' differences (`_dense_difference`: each perturbed vector a
    copy of x with one entry x_i + h_i, the steps of `forward_steps`, the base the
    residual at x), each perturbed residual its own call of `one`, the calls made side by
    side (`cell.model.flight_batch.together`: their flights integrated as one batch), so
    the Jacobian is bitwise scipy's."""
    lo, hi = bounds
    made: dict[bytes, np.ndarray] = {}

    def fun(x: np.ndarray) -> np.ndarray:
        r = np.atleast_1d(one(x))
        made.clear()
        made[np.asarray(x, float).tobytes()] = r
        return r

    def jac(x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, float)
        f0 = made.get(x.tobytes())
        if f0 is None:
            f0 = np.atleast_1d(one(x))
        h = forward_steps(x, lo, hi, rel_step)
        xs = []
        for i in range(x.size):
            x1 = np.copy(x)
            x1[i] = x[i] + h[i]
            xs.append(x1)
        f = together([partial(one, x1) for x1 in xs])
        dx = [(x[i] + h[i]) - x[i] for i in range(x.size)]
        return np.array([(np.atleast_1d(fi) - f0) / d for fi, d in zip(f, dx, strict=True)]).T

    return fun, jac


def refit_folds(
    prob: GapProblem,
    classes: list[type[Effect]],
    trains: list[np.ndarray],
    x: np.ndarray,
    r_all: np.ndarray,
    jac_all: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray],
) -> list[np.ndarray]:
    """`fit._refit` of every fold at once: the folds step in lockstep and the parameter
    vectors they try in a round are predicted in one stacked call; each fold's arithmetic
    is its own, so each result is bitwise `fit._refit`'s."""
    scale = np.concatenate([np.asarray(c.scale, float) for c in classes])
    lo, hi = bounds
    st = []
    for train in trains:
        rows = np.stack([2 * train, 2 * train + 1], axis=1).ravel()
        r = r_all[rows]
        st.append({"j": jac_all[rows], "r": r, "cost": float(r @ r), "x": x, "it": 0,
                   "tried": {}, "step": None, "half": 0})  # fmt: skip
    while True:
        todo: dict[int, np.ndarray] = {}
        for f, s in enumerate(st):
            if s["it"] == 2:
                continue
            if s["step"] is None:
                s["step"], s["half"] = np.linalg.lstsq(s["j"], -s["r"], rcond=1e-8)[0], 0
            x_new = np.clip(s["x"] + s["step"], lo, hi)
            s["x_new"] = x_new
            if x_new.tobytes() not in s["tried"]:
                todo[f] = x_new
        if not any(s["it"] < 2 for s in st):
            return [s["x"] for s in st]
        if todo:
            got = misses_many(
                prob, classes, [trains[f] for f in todo], np.array(list(todo.values())), scale
            )
            for f, r_new in zip(todo, got, strict=True):
                st[f]["tried"][todo[f].tobytes()] = r_new
        for s in st:
            if s["it"] < 2:
                _advance(s)


def _advance(s: dict) -> None:
    """One trial of a fold's refit: accept x_new if it does not raise the cost, else halve
    the step (after four trials the iteration ends without a step)."""
    r_new = s["tried"][s["x_new"].tobytes()]
    c_new = float(r_new @ r_new)
    if c_new <= s["cost"]:
        s["x"], s["r"], s["cost"] = s["x_new"], r_new, c_new
        s["it"], s["step"] = s["it"] + 1, None
        return
    s["step"], s["half"] = 0.5 * s["step"], s["half"] + 1
    if s["half"] == 4:
        s["it"], s["step"] = s["it"] + 1, None
