"""Beyond the vocabulary: the law that explains what an `unknown` verdict leaves (GAP.md).

A library of candidate terms, each a small change of the throw whose effect on the
landing is linear in its coefficient θ near θ = 0:

| phase | term | what changes |
|---|---|---|
| launch | speed error (× 1, stroke, mass or width) | the launch velocity relative to the base scaled by 1 + θ·c |
| launch | elevation error (× 1, stroke, mass or width) | the launch velocity turned up by θ·c [rad] |
| launch | azimuth error (× 1, stroke, mass or width) | the launch velocity turned about the vertical by θ·c [rad] |
| launch | speed, elevation, azimuth error × order | the same, growing over the log: order = 0 at its first throw, 1 at its last (by `time_s` where every row has it, else by row) |
| launch | speed, elevation, azimuth error × session | the same, in every session but the first (`session`, 2 to MAX_SESSIONS of them) |
| flight | force x, force y | a constant acceleration θ [m/s²] along world x or y |
| flight | wind x, wind y × session | air moving at θ [m/s] along world x or y in every session but the first (a wind or a draught changed between sessions) |
| flight | along ∝ v, ∝ v² | an acceleration θ·v, θ·|v|·v along the velocity |
| flight | across ∝ v, ∝ v² | θ·v, θ·|v|·v turned 90° about the vertical (horizontal, to the left) |
| flight | up ∝ v² | θ·|v|² upwards |
| flight | lift across v ∝ v², lift coefficient C_L | θ·|v|²·n̂, n̂ across v in v's vertical plane, upwards; θ·½ρA/m·|v|²·n̂ (`cell.gap.propose_terms`) |
| landing | shift ∝ v, ∝ v² | the landing moved by θ·v_h or θ·|v_h|·v_h along the impact velocity |
| measurement | shift ∝ v with k < 0 (its interval below 0) | the landing logged −k s before the touchdown: no slide ends behind it, a tracker lagging does |
| landing | shift x, shift y | every landing moved by θ [m] along world x or y: a surface that carries it (a conveyor), or the landings measured from an origin off by θ |
| landing | plane height × [x > x_b] | a step in the surface landed on beyond x_b, fitted, where such a step beats the verdict (`cell.gap.plane_step`) |
| landing | plane height (× 1, x, y) | the surface landed on is θ·c [m] above the logged `land_z_m`, c = 1 or the landing's x or y [m]: a floor off its logged height, or tilted (the landing moves by θ·c·v_h / v_z) |
| launch, flight, landing | speed error (× 1, × order), lift coefficient, shift ∝ v × [object = X] | the same on one object's throws only, tried object by object (`cell.gap.propose_terms`): × order, one object's drift over the log (a bag that leaks) |

A log's drift (a band wearing, a motor warming) and its sessions (a band changed, a
launcher set up again) are common on a real cell and outside the vocabulary, so the
launch terms also come in the throw's order over the log and in its session; a surface
off level is a landing plane's height growing with x or y.

A covariate enters the library only where it takes at least `cell.gap.laws.MIN_LEVELS`
values in the log (with two objects, terms in their mass, their size and the constant
are three names for two numbers), and a term whose sensitivity is less than
COLLINEAR_TOL independent of the terms before it (in the table's order) is left out
(`collinear_left_out`): collinear terms otherwise take coefficients of 1e4 and more, of
opposite signs, that say nothing a person could test.

Each term's landing sensitivity J_j (n, 2) is taken by finite differences of the model
with the effects already joined; the misses they leave, r, are regressed on the
library by sequentially thresholded least squares (SINDy): fit, zero the terms whose
contribution (|θ_j|·‖J_j‖/√n) falls below λ, refit on the rest, repeat. λ is chosen on
held-out throws (the problem's random folds) with a penalty of TERM_PENALTY per term.
The proposal reports its terms with 95 % intervals, the phase they act in and how far
the law shrinks the held-out miss. Where tracks place the gap in a phase, the library
holds the terms of the phases they measure only (`cell.gap.propose_terms.allowed_phases`).
A term beyond its kind's bound on a throw (a speed error over half, an angle over 0.5
rad, a force over a third of the weight plus thrice the model's drag:
`cell.gap.propose_bounds`) is left out and the law fitted again. The verdict stays
`unknown`: the proposal is what a person would test next.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from cell.gap.plane_step import step_term
from cell.gap.problem import GapProblem
from cell.gap.propose_bounds import PLANE_MAX_M, beyond, why_none, within_bounds, written
from cell.gap.propose_radial import radial_term
from cell.gap.propose_sessions import MAX_SESSIONS, log_covariates, session_winds
from cell.gap.propose_terms import MAX_OBJECTS, lift_terms, object_columns
from cell.model.effects import Effect
from cell.model.effects_apply import flight_accel
from cell.model.flight3d import fly
from cell.model.throw import drag_constant
from cell.parallel import one_blas_thread

__all__ = ["propose", "library", "log_covariates", "MAX_SESSIONS"]

TERM_PENALTY = 0.03  # held-out RMSE raised by this share per term
COVS = {"1": None, "stroke_m": "stroke", "mass_kg": "mass", "size_x_m": "width"}
H_ANGLE = 1e-3
H_SPEED = 1e-3
H_ACC = 0.05
COLLINEAR_TOL = 0.01  # a term less than this share independent of the terms before it is out
SHIFT_V = "landing shift [s] = k · v_h"
MIN_VZ = 0.5  # [m/s] a landing plane's terms are nil for throws descending slower than this
PLANE_CONST = "landing plane height [m] = k"


def _cov(prob: GapProblem, name: str) -> np.ndarray:
    b = prob.batch
    return {"1": np.ones(len(b)), "stroke_m": b.stroke, "mass_kg": b.mass,
            "size_x_m": b.size[:, 0]}[name]  # fmt: skip


def covariates(prob: GapProblem) -> list[str]:
    """The library's covariates on this log: the constant, and each covariate that takes
    at least MIN_LEVELS values (on two values, a log of two objects, a term in the mass,
    one in the size and the constant are two numbers shared by three terms)."""
    from cell.gap.laws import MIN_LEVELS, levels

    return ["1"] + [c for c in COVS if c != "1" and levels(prob.batch, c) >= MIN_LEVELS]


def independent(a: np.ndarray, tol: float = COLLINEAR_TOL) -> np.ndarray:
    """Which columns of a (m, p) to keep: in order, a column is left out when the part of
    it the kept columns before it do not explain is under `tol` of its size (each kept
    column then raises the library's condition number by at most about 1 / tol)."""
    keep = np.zeros(a.shape[1], bool)
    basis = np.zeros((a.shape[0], 0))
    for j in range(a.shape[1]):
        col = a[:, j]
        size = float(np.linalg.norm(col))
        if size <= 0:
            continue
        rest = col - basis @ (basis.T @ col)
        left = float(np.linalg.norm(rest))
        if left >= tol * size:
            keep[j] = True
            basis = np.c_[basis, rest / left]
    return keep


def _turn(v: np.ndarray, vb: np.ndarray, d_el: np.ndarray, d_az: np.ndarray) -> np.ndarray:
    rel = v - vb
    sp = np.linalg.norm(rel, axis=1)
    el = np.arcsin(np.clip(rel[:, 2] / np.maximum(sp, 1e-9), -1, 1)) + d_el
    az = np.arctan2(rel[:, 1], rel[:, 0]) + d_az
    u = np.c_[np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)]
    return vb + sp[:, None] * u


def library(prob: GapProblem, effects: tuple[Effect, ...], lift: bool = True
            ) -> tuple[list[dict[str, Any]], np.ndarray]:  # fmt: skip
    """The candidate terms and their landing sensitivities J (n, 2, p) [m per unit θ]
    (`lift`: with the lift across v, `cell.gap.propose_terms.lift_terms`)."""
    terms, jac, _ = _library(prob, effects, lift)
    return terms, jac


def _library(prob: GapProblem, effects: tuple[Effect, ...], lift: bool
             ) -> tuple[list[dict[str, Any]], np.ndarray, dict[str, Any]]:  # fmt: skip
    """`library`, and what the terms' bounds read (`cell.gap.propose_bounds.size_of`)."""
    idx = np.arange(len(prob))
    effs = [e for e in effects if e.name != "band_stiffness"]
    land = prob.landing(idx, effects)
    b = prob.batch
    p1, v1 = land.launch_position, land.launch_velocity
    ok = np.all(np.isfinite(p1), axis=1) & np.all(np.isfinite(v1), axis=1)
    p1, v1 = np.where(ok[:, None], p1, b.position), np.where(ok[:, None], v1, b.base_velocity)
    k = drag_constant(b.shape, b.mass, b.size)
    base_acc = flight_accel(b, list(prob.base_effects) + effs, prob.rotor_rpm)
    t0 = prob.ee.dt

    def land_xy(v: np.ndarray, extra: Callable[..., np.ndarray] | None = None,
                air: Callable[..., np.ndarray] | None = None) -> np.ndarray:  # fmt: skip
        def acc(p: np.ndarray, vv: np.ndarray, i: np.ndarray) -> tuple[Any, Any]:
            w, ex = base_acc(p, vv, i) if base_acc is not None else (None, None)
            if extra is not None:
                e2 = extra(p, vv, i)
                ex = e2 if ex is None else ex + e2
            if air is not None:
                w2 = air(p, vv, i)
                w = w2 if w is None else w + w2
            return w, ex

        use = acc if (extra is not None or air is not None or base_acc is not None) else None
        return fly(p1, v, k, b.land_z, accel=use, t0=t0, step=prob.step).position[:, :2]

    x0 = land_xy(v1)
    terms: list[dict[str, Any]] = []
    cols: list[np.ndarray] = []

    def add(phase: str, name: str, xy: np.ndarray, h: float) -> None:
        terms.append({"phase": phase, "term": name})
        cols.append(np.nan_to_num((xy - x0) / h))

    zero = np.zeros(len(b))
    in_log = log_covariates(prob)
    for c in covariates(prob) + list(in_log):
        cv = in_log[c] if c in in_log else _cov(prob, c)
        tail = "" if c == "1" else f" · {c}"
        rel = v1 - b.base_velocity
        add("launch", f"speed error [share] = k{tail}", land_xy(v1 + H_SPEED * cv[:, None] * rel),
            H_SPEED)  # fmt: skip
        add("launch", f"elevation error [rad] = k{tail}",
            land_xy(_turn(v1, b.base_velocity, H_ANGLE * cv, zero)), H_ANGLE)  # fmt: skip
        add("launch", f"azimuth error [rad] = k{tail}",
            land_xy(_turn(v1, b.base_velocity, zero, H_ANGLE * cv)), H_ANGLE)  # fmt: skip

    def left(v: np.ndarray) -> np.ndarray:
        return np.c_[-v[:, 1], v[:, 0], np.zeros(len(v))]

    flight: list[tuple[str, Callable[..., np.ndarray]]] = [
        ("force x [m/s²] = k", lambda p, v, i: np.tile([H_ACC, 0.0, 0.0], (len(v), 1))),
        ("force y [m/s²] = k", lambda p, v, i: np.tile([0.0, H_ACC, 0.0], (len(v), 1))),
        ("force along v [1/s] = k · v", lambda p, v, i: H_ACC * v),
        (
            "force along v [1/m] = k · |v| v",
            lambda p, v, i: H_ACC * np.linalg.norm(v, axis=1)[:, None] * v,
        ),  # fmt: skip
        ("force across v [1/s] = k · v⊥", lambda p, v, i: H_ACC * left(v)),
        (
            "force across v [1/m] = k · |v| v⊥",
            lambda p, v, i: H_ACC * np.linalg.norm(v, axis=1)[:, None] * left(v),
        ),  # fmt: skip
        (
            "force up [1/m] = k · |v|²",
            lambda p, v, i: H_ACC * np.c_[np.zeros((len(v), 2)), np.sum(v * v, axis=1)],
        ),  # fmt: skip
    ] + (lift_terms(b, H_ACC) if lift else [])
    for name, fn in flight:
        add("flight", name, land_xy(v1, fn), H_ACC)
    for name, fn, h in session_winds(in_log):  # a wind changed between sessions
        add("flight", name, land_xy(v1, air=fn), h)
    vh = np.nan_to_num(land.impact_velocity[:, :2])
    terms.append({"phase": "landing", "term": SHIFT_V})
    cols.append(vh)
    terms.append({"phase": "landing", "term": "landing shift [s²/m] = k · |v_h| v_h"})
    cols.append(np.linalg.norm(vh, axis=1)[:, None] * vh)
    # the surface θ·c above the logged plane: the item crosses it Δz / v_z earlier
    vz = np.nan_to_num(land.impact_velocity[:, 2])
    down = vz < -MIN_VZ
    per_m = np.where(down[:, None], vh / np.where(down, vz, -1.0)[:, None], 0.0)
    xy_land = np.nan_to_num(x0)
    planes = (("", np.ones(len(b))), (" · x_m", xy_land[:, 0]), (" · y_m", xy_land[:, 1]))
    for name, at in planes:
        terms.append({"phase": "landing", "term": f"landing plane height [m] = k{name}"})
        cols.append(per_m * at[:, None])
    # every landing moved alike in the world frame: a surface carrying what lands on it (a
    # conveyor), or the landings' measurement off in its origin
    for j, axis in enumerate("xy"):
        terms.append({"phase": "landing", "term": f"landing shift {axis} [m] = k"})
        cols.append(np.tile(np.eye(2)[j], (len(b), 1)))
    ctx = {
        "cov": {**{c: _cov(prob, c) for c in COVS}, **in_log},
        "object": prob.table.text("object_id"),
        "speed": np.linalg.norm(v1, axis=1),
        "drag_k": k,
        "xy": x0,
    }  # fmt: skip
    return terms, np.stack(cols, axis=2), ctx


def _stlsq(a: np.ndarray, y: np.ndarray, lam: float, iters: int = 8) -> np.ndarray:
    """Sequentially thresholded least squares of y ≈ a θ; a term whose RMS contribution
    is below lam [m] is dropped."""
    p = a.shape[1]
    norm = np.sqrt(np.mean(a * a, axis=0)) + 1e-300
    keep = np.ones(p, bool)
    th = np.zeros(p)
    for _ in range(iters):
        th = np.zeros(p)
        if not keep.any():
            break
        th[keep] = np.linalg.lstsq(a[:, keep], y, rcond=None)[0]
        small = np.abs(th) * norm < lam
        if not (keep & small).any():
            break
        keep &= ~small
    return th


def propose(
    prob: GapProblem,
    effects: tuple[Effect, ...],
    floor_m: float,
    keep: np.ndarray | None = None,
    phases: set[str] | None = None,
    extended: bool = True,
    step: bool = False,
) -> tuple[dict[str, Any], np.ndarray]:
    """The law proposed for what the effects leave (see the module docstring), fitted and
    scored on the throws in `keep` (all when None: outliers left out), from the terms of
    `phases` only (all when None: `cell.gap.propose_terms.allowed_phases`), then with the
    terms of one object and another added where they earn their place
    (`cell.gap.propose_terms`). `extended` False: the library without the lift across v
    and the objects' terms (the law whose misses flag outliers, `cell.gap.run`). `step`:
    with a step in the landing plane (`cell.gap.plane_step`, where its rule made the
    verdict `unknown`).

    Returns:
        (the proposal, every throw's miss with the proposed law added (n, 2) [m]).
    """
    with one_blas_thread():  # small least squares: a second BLAS thread only spins
        return _propose(prob, effects, floor_m, keep, phases, extended, step)


def _propose(prob: GapProblem, effects: tuple[Effect, ...], floor_m: float,
             keep: np.ndarray | None, phases: set[str] | None, extended: bool,
             step: bool = False) -> tuple[dict[str, Any], np.ndarray]:  # fmt: skip
    idx = np.arange(len(prob))
    n = len(prob)
    keep = np.ones(n, bool) if keep is None else np.asarray(keep, bool)
    r = np.nan_to_num(prob.residual(idx, effects))
    terms, jac, ctx = _library(prob, effects, lift=extended)
    a_all = jac.reshape(2 * n, -1)  # rows: throw-major (x, y)
    if extended:  # a camera's radial distortion (`cell.gap.propose_radial`)
        rad, col, ctx["cov"]["r² d"] = radial_term(ctx["xy"], prob.table.landed, r, keep)
        terms, a_all = [*terms, rad], np.c_[a_all, col]
    if extended and step:  # a step in the floor (`cell.gap.plane_step`)
        st, col = step_term(prob, r, keep)
        terms, a_all = [*terms, st], np.c_[a_all, col]
    if phases is not None:  # the phases the tracks allow
        on = [t["phase"] in phases for t in terms]
        terms, a_all = [t for t, o in zip(terms, on, strict=True) if o], a_all[:, on]
    # terms the ones before them explain (collinear on this log) are left out
    free = independent(a_all[np.repeat(keep, 2)])
    left_out = [t["term"] for t, f in zip(terms, free, strict=True) if not f]
    per_object = object_columns(prob, terms, a_all) if extended else []
    terms = [t for t, f in zip(terms, free, strict=True) if f]
    a_all = a_all[:, free]
    y_all = r.reshape(-1)
    out, miss = _sparse_law(prob, terms, a_all, y_all, keep, floor_m)
    if extended:  # every term held to its kind's bound (`cell.gap.propose_bounds`)

        def fit(ts: list[dict[str, Any]], a: np.ndarray) -> tuple[dict[str, Any], np.ndarray]:
            return _sparse_law(prob, ts, a, y_all, keep, floor_m)

        out, miss, terms, a_all = within_bounds(fit, terms, a_all, keep, ctx, out, miss)
    elif PLANE_CONST in [t["term"] for t in terms] and any(
        t["term"] == PLANE_CONST and abs(t["k"]) > PLANE_MAX_M for t in out["terms"]
    ):
        # a floor further off its logged height than any cell's: the term stands for
        # something else; the law is fitted again without it
        own = [t for t in out["terms"] if t["term"] == PLANE_CONST][0]["k"]
        rest = [j for j, t in enumerate(terms) if t["term"] != PLANE_CONST]
        terms, a_all = [terms[j] for j in rest], a_all[:, rest]
        out, miss = _sparse_law(prob, terms, a_all, y_all, keep, floor_m)
        out["implausible_left_out"] = [{"term": PLANE_CONST, "k": float(own)}]
    dropped = out.get("implausible_left_out")
    out, miss = _object_law(prob, terms, a_all, y_all, keep, floor_m, per_object, out, miss,
                            ctx)  # fmt: skip
    if dropped:
        out["implausible_left_out"] = dropped
    if extended and out["law"] and out["heldout_rmse_after_m"] >= out["heldout_rmse_before_m"]:
        # a law that predicts the held-out throws no better than none is no law
        before, law = out["heldout_rmse_before_m"], out["law"]
        why = (f"no law of the library predicts the held-out throws better than none: the "
               f"best, {law}, leaves {out['heldout_rmse_after_m']:.4g} m against {before:.4g} m")  # fmt: skip
        out = {k: v for k, v in out.items() if k not in ("phase", "within_floor", "objects")}
        out.update(law=None, terms=[], heldout_rmse_after_m=before, shrink_pct=0.0, why=why)
        miss = r
    elif extended and out["law"] is None:
        out["why"] = why_none(dropped) if dropped else (
            f"no term of the library predicts the held-out throws better by more than its "
            f"penalty ({TERM_PENALTY:.0%} of the held-out miss per term)")  # fmt: skip
    out["collinear_left_out"] = left_out
    if phases is not None:
        out["phases_from_tracks"] = sorted(phases)
    return out, miss


def _object_law(prob: GapProblem, terms: list[dict[str, Any]], a_all: np.ndarray,
                y_all: np.ndarray, keep: np.ndarray, floor_m: float,
                per_object: list[tuple[str, list[dict[str, Any]], np.ndarray]],
                out: dict[str, Any], miss: np.ndarray, ctx: dict[str, Any]
                ) -> tuple[dict[str, Any], np.ndarray]:  # fmt: skip
    """The law with the terms of one object after another (greedily, at most MAX_OBJECTS),
    each object's terms tried beside the library's (`terms`, `a_all`) and alone with the
    objects' chosen before; kept where the held-out score, with one term's penalty more
    for each object chosen, falls and every term is within its bound
    (`cell.gap.propose_bounds`). `out`, `miss`: the law without them."""
    rows = np.repeat(keep, 2)
    chosen: list[str] = []
    own_t: list[dict[str, Any]] = []
    own_a = np.zeros((a_all.shape[0], 0))
    score = out.pop("score")
    for _ in range(MAX_OBJECTS):
        best = None
        for o, ts, cols in per_object:
            if o in chosen:
                continue
            for lib_t, lib_a in ((terms, a_all), ([], a_all[:, :0])):
                a_try = np.c_[lib_a, own_a, cols]
                free = independent(a_try[rows])
                free[: lib_a.shape[1]] = True  # the library's terms stand; the object's may not
                t_try = [t for t, f in zip([*lib_t, *own_t, *ts], free, strict=True) if f]
                got = _plausible_law(prob, t_try, a_try[:, free], y_all, keep, floor_m, o,
                                     ctx)  # fmt: skip
                if got is None:
                    continue
                o_score = got[0] * (1.0 + TERM_PENALTY * (len(chosen) + 1))
                if o_score < score and (best is None or o_score < best[0]):
                    best = (o_score, o, *got[1:])
        if best is None:
            break
        score, o, t_got, a_got, out, miss = best
        chosen.append(o)
        mine = ["[object = " in t["term"] for t in t_got]
        own_t, own_a = [t for t, m in zip(t_got, mine, strict=True) if m], a_got[:, mine]
    if chosen:
        out["objects"] = chosen
    return out, miss


def _plausible_law(prob: GapProblem, terms: list[dict[str, Any]], a_all: np.ndarray,
                   y_all: np.ndarray, keep: np.ndarray, floor_m: float, obj: str,
                   ctx: dict[str, Any]
                   ) -> tuple[float, list[dict[str, Any]], np.ndarray, dict[str, Any],
                              np.ndarray] | None:  # fmt: skip
    """The sparse law over these terms, fitted again without the terms beyond their bounds
    (`cell.gap.propose_bounds`: a lift coefficient over LIFT_CL_MAX, one no spin gives,
    stands for something else): (its score, the terms and columns it was fitted on, the
    law, the misses), or None where it takes no term of the object `obj`."""
    for _ in range(3):
        out, miss = _sparse_law(prob, terms, a_all, y_all, keep, floor_m)
        bad = {b["term"] for b in beyond(out["terms"], ctx, keep)}
        if not bad:
            break
        on = [t["term"] not in bad for t in terms]  # fmt: skip
        terms, a_all = [t for t, o in zip(terms, on, strict=True) if o], a_all[:, on]
    if bad or not any(f"[object = {obj}]" in t["term"] for t in out["terms"]):
        return None
    return out.pop("score"), terms, a_all, out, miss


def _sparse_law(prob: GapProblem, terms: list[dict[str, Any]], a_all: np.ndarray,
                y_all: np.ndarray, keep: np.ndarray, floor_m: float
                ) -> tuple[dict[str, Any], np.ndarray]:  # fmt: skip
    """The sparse law of the misses y_all (2n,) over the library's columns a_all (2n, p),
    its threshold chosen on held-out folds of the throws in `keep` (`propose`)."""
    rows_keep = np.repeat(keep, 2)
    a, y = a_all[rows_keep], y_all[rows_keep]
    base_rmse = float(np.sqrt(np.mean(y * y) * 2))
    # the folds renumbered onto the kept throws
    new = np.cumsum(keep) - 1
    folds = [(new[tr[keep[tr]]], new[te[keep[te]]]) for tr, te in prob.folds["random"]]
    n = int(keep.sum())
    lams = base_rmse * np.geomspace(0.02, 1.0, 14)
    best: tuple[float, float, np.ndarray] | None = None
    for lam in lams:
        sq = np.zeros(n)
        for train, test in folds:
            rows = np.stack([2 * train, 2 * train + 1], 1).ravel()
            th = _stlsq(a[rows], y[rows], lam)
            rt = np.stack([2 * test, 2 * test + 1], 1).ravel()
            e = y[rt] - a[rt] @ th
            sq[test] = np.sum(e.reshape(-1, 2) ** 2, axis=1)
        th_all = _stlsq(a, y, lam)
        ho = float(np.sqrt(sq.mean()))
        val = ho * (1.0 + TERM_PENALTY * int(np.count_nonzero(th_all)))
        if best is None or val < best[0]:
            best = (val, ho, th_all)
    assert best is not None
    score, ho, th = best
    on = np.flatnonzero(th)
    miss = (y_all - a_all @ th).reshape(-1, 2)
    if on.size == 0:
        return {"law": None, "terms": [], "heldout_rmse_before_m": base_rmse,
                "heldout_rmse_after_m": base_rmse, "shrink_pct": 0.0,
                "score": score}, miss  # fmt: skip
    e = y - a @ th
    s2 = float(e @ e) / max(y.size - on.size, 1)
    cov = s2 * np.linalg.pinv(a[:, on].T @ a[:, on])
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    norm = np.sqrt(np.mean(a[:, on] ** 2, axis=0))
    order = np.argsort(-np.abs(th[on]) * norm)
    out_terms = [
        {**terms[on[i]], "k": float(th[on[i]]),
         "k_ci95": [float(th[on[i]] - 1.96 * se[i]), float(th[on[i]] + 1.96 * se[i])],
         "rms_m": float(abs(th[on[i]]) * norm[i] * np.sqrt(2))}
        for i in order
    ]  # fmt: skip
    for t in out_terms:
        if t["term"] == SHIFT_V and t["k_ci95"][1] < 0:
            # a rest point behind the touchdown along the flight: no slide ends there; it
            # is where the item was -k s before touchdown, a tracker logging late
            t["phase"] = "measurement"
    phases = [t["phase"] for t in out_terms]
    return {
        "law": " + ".join(written(t["term"], t["k"]) for t in out_terms),
        "phase": phases[0],
        "terms": out_terms,
        "heldout_rmse_before_m": base_rmse,
        "heldout_rmse_after_m": ho,
        "shrink_pct": 100.0 * (1.0 - ho / base_rmse) if base_rmse > 0 else 0.0,
        "within_floor": bool(ho <= 1.3 * floor_m),
        "score": score,
    }, miss
