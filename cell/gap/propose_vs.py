"""A proposal against a named verdict: a law outside the vocabulary the verdict must beat.

An effect outside the vocabulary whose landings an effect of the vocabulary follows within
the verdict's ratio of the floor is named as that effect: a launch speed error growing with
the stroke, speed × (1 + 0.8 · stroke), was named `stroke_offset` at 1.13 F (the scene's
`s:launch-speed-stroke`, docs/HISTORY.md), while the proposal on the baseline's misses
told it apart. The proposal (`cell.gap.propose`) runs on `unknown` verdicts only; this
rule weighs a proposal of at most MAX_TERMS terms against a named one: one (with two, the
tosses of a real cube, tests/test_gap_real_tracks.py, had their right `bounce` beaten by the
bounce's own friction shift, or a constant elevation error that follows it, beside a
sideways force: 9.3-9.9 % of a 1.9 mm miss, 0.19 mm; one term against the one-parameter
verdicts compares like with like).

The law (`sparse_law`): the proposal's library without the lift across v, the objects'
terms, the camera's distortion and the floor's step (`cell.gap.propose.library` with
`lift` False; where tracks place the gap in phases, their terms only,
`cell.gap.propose_terms.allowed_phases`; collinear terms left out as there), every set
of one or two of its terms fitted to the baseline's misses by least squares, and the set
whose held-out RMSE on the problem's random folds, raised by
`cell.gap.propose.TERM_PENALTY` per term, is least; a term beyond its kind's bound
(`cell.gap.propose_bounds`) is left out and the set chosen again. Its held-out misses
(`_subset_law`) pay for the choice among some 10³ sets: each fold's throws are predicted
by the set chosen on the other folds' throws (on K_INNER folds of theirs) and fitted there.

The rule (`versus_check`): a verdict that names effects is `unknown`, those effects partial,
where that law predicts the held-out throws better than the verdict's effects by at least
MARGIN of the verdict's held-out RMSE, with the cut's bootstrap 95 % interval above zero.
The library's terms that are the verdict's own effect's law (`OWN_TERMS`: a bounce's
landing shifts along v_h, a drag factor's force along v ∝ |v| v, a release pitch's constant
elevation error) are left out: a law of them and one more term is the verdict with an
effect beside it, which must cut as a joining effect does (on a real cube's tosses, tests/
test_gap_real_tracks.py, the bounce's own friction shift with a sideways force cut 9.9 % of
the `bounce` verdict, 0.19 mm, and made a right name `unknown`). A law the same as the
verdict's effect cuts nothing (`o:slide-rolling`'s landing shift ∝ v
is its rolling bounce: cut 0.000, its interval about zero), so the margin only guards
against small cuts an interval puts above zero. Chosen on the tables (docs/HISTORY.md,
`propvs67`): over the scene's and the other implementation's named verdicts, the best law's
cut is at most +1.0 % of a right verdict's held-out RMSE (`s:scale-0.98`, interval across
zero), and 4.9 % and 9.3 % of the two wrong ones' (`s:downwash`'s `band_damping`, whose
truth is `none`, and `s:launch-speed-stroke`'s `stroke_offset`); the margin is half the share
a joining effect must cut (`cell.gap.select.MIN_CUT`).
The report's `proposal_vs_verdict` gives the law, both held-out RMSEs, the cut, its share
and interval and whether it `beats` the verdict, and `why` where it does; the proposal of
the `unknown` verdict (`cell.gap.run`) then says what is left.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.gap.problem import GapProblem
from cell.model.effects import Effect

__all__ = ["MARGIN", "MAX_TERMS", "K_INNER", "sparse_law", "versus_check"]

MAX_TERMS = 1  # the law weighed against a named verdict has at most this many terms
MARGIN = 0.05  # the law's held-out cut: at least this share of the verdict's held-out RMSE
OWN_TERMS = {  # the library's terms that are a named effect's own law: not outside it
    "bounce": ("landing shift [s] = k · v_h", "landing shift [s²/m] = k · |v_h| v_h"),
    "drag_scale": ("force along v [1/m] = k · |v| v",),
    "release_pitch": ("elevation error [rad] = k",),
}
K_INNER = 5  # the folds within each fold's training throws that choose its terms


def _sets(p: int) -> np.ndarray:
    """Every set of one to MAX_TERMS (≤ 2) of p columns as (m, 2) indices, a single column i
    as (i, i)."""
    i, j = np.triu_indices(p) if MAX_TERMS > 1 else (np.arange(p), np.arange(p))
    return np.c_[i, j]


def _fit_sets(g: np.ndarray, b: np.ndarray, sets: np.ndarray) -> np.ndarray:
    """Each set's least-squares θ (m, 2) from the Gram matrix g = aᵀa (p, p) and b = aᵀy
    (p,); a single column's θ in the first place, 0 in the second; nan where the set's two
    columns are (near) collinear or a column is nil."""
    i, j = sets[:, 0], sets[:, 1]
    one = i == j
    gii, gjj, gij = g[i, i], g[j, j], g[i, j]
    det = gii * gjj - gij * gij
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = np.where(one, b[i] / gii, (gjj * b[i] - gij * b[j]) / det)
        t2 = np.where(one, 0.0, (gii * b[j] - gij * b[i]) / det)
    bad = (gii <= 0) | (gjj <= 0) | (~one & (det <= 1e-9 * gii * gjj))
    return np.where(bad[:, None], np.nan, np.c_[t1, t2])


def _sse(g: np.ndarray, b: np.ndarray, yy: float, sets: np.ndarray, th: np.ndarray
         ) -> np.ndarray:  # fmt: skip
    """Each set's sum of squared misses ‖y − a θ‖² [m²] on the throws whose aᵀa, aᵀy and
    yᵀy are g, b and yy; inf where θ is nan."""
    i, j = sets[:, 0], sets[:, 1]
    t1, t2 = th[:, 0], th[:, 1]
    out = yy - 2 * (t1 * b[i] + t2 * b[j]) + t1 * t1 * g[i, i] + t2 * t2 * g[j, j]
    out = out + 2 * t1 * t2 * g[i, j]
    return np.where(np.isfinite(out), out, np.inf)


def _rows(throws: np.ndarray) -> np.ndarray:
    """The rows (x, y) of throws in the (2n,) throw-major layout."""
    return np.stack([2 * throws, 2 * throws + 1], 1).ravel()


def _choose(a: np.ndarray, y: np.ndarray, folds: list[tuple[np.ndarray, np.ndarray]],
            sets: np.ndarray) -> np.ndarray:  # fmt: skip
    """The columns of the set whose held-out RMSE over `folds` (throw indices), raised by
    TERM_PENALTY per term, is least."""
    from cell.gap.propose import TERM_PENALTY

    sse = np.zeros(len(sets))
    count = 0
    for train, test in folds:
        tr, te = _rows(train), _rows(test)
        th = _fit_sets(a[tr].T @ a[tr], a[tr].T @ y[tr], sets)
        sse += _sse(a[te].T @ a[te], a[te].T @ y[te], float(y[te] @ y[te]), sets, th)
        count += len(test)
    n_terms = np.where(sets[:, 0] == sets[:, 1], 1, 2)
    best = int(np.argmin(np.sqrt(sse / max(count, 1)) * (1.0 + TERM_PENALTY * n_terms)))
    return np.unique(sets[best])


def _inner(train: np.ndarray, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """K_INNER random folds of the throws `train`."""
    part = np.random.default_rng(seed).permutation(len(train)) % K_INNER
    return [(train[part != k], train[part == k]) for k in range(K_INNER)]


def _subset_law(prob: GapProblem, a: np.ndarray, y: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """(the columns of the set chosen on every throw, their θ fitted on every throw, each
    throw's squared held-out miss [m²] under the set chosen and fitted on the other folds)."""
    sets = _sets(a.shape[1])
    sq = np.zeros(len(prob))
    for k, (train, test) in enumerate(prob.folds["random"]):
        cols = _choose(a, y, _inner(train, prob.seed + 31 + k), sets)
        th = np.linalg.lstsq(a[_rows(train)][:, cols], y[_rows(train)], rcond=None)[0]
        e = (y - a[:, cols] @ th).reshape(-1, 2)[test]
        sq[test] = np.sum(e * e, axis=1)
    cols = _choose(a, y, prob.folds["random"], sets)
    return cols, np.linalg.lstsq(a[:, cols], y, rcond=None)[0], sq


def sparse_law(prob: GapProblem, effects: tuple[Effect, ...], r: np.ndarray,
               phases: set[str] | None = None,
               without: frozenset[str] = frozenset()) -> dict[str, Any]:  # fmt: skip
    """The law of at most MAX_TERMS terms of the misses r (n, 2) [m] the `effects` leave
    (module docstring): {"law" (None where no term is left), "terms" (each with "phase",
    "term", "k"), "sq" (each throw's squared held-out miss [m²]), "implausible_left_out"};
    the terms named in `without` left out of the library."""
    from cell.gap.propose import _library, independent
    from cell.gap.propose_bounds import beyond, written

    terms, jac, ctx = _library(prob, effects, lift=False)
    a = jac.reshape(2 * len(prob), -1)
    if phases is not None or without:
        on = [(phases is None or t["phase"] in phases) and t["term"] not in without for t in terms]
        terms, a = [t for t, o in zip(terms, on, strict=True) if o], a[:, on]
    free = independent(a)
    terms, a = [t for t, f in zip(terms, free, strict=True) if f], a[:, free]
    y = np.nan_to_num(np.asarray(r, float)).reshape(-1)
    every = np.ones(len(prob), bool)
    left: list[dict[str, Any]] = []
    got: list[dict[str, Any]] = []
    sq = np.sum(y.reshape(-1, 2) ** 2, axis=1)
    while terms:
        cols, th, sq = _subset_law(prob, a, y)
        got = [{**terms[j], "k": float(t)} for j, t in zip(cols, th, strict=True)]
        bad = beyond(got, ctx, every)
        if not bad:
            break
        left += bad
        on = [t["term"] not in {b["term"] for b in bad} for t in terms]
        terms, a, got = [t for t, o in zip(terms, on, strict=True) if o], a[:, on], []
        sq = np.sum(y.reshape(-1, 2) ** 2, axis=1)
    law = " + ".join(written(t["term"], t["k"]) for t in got) if got else None
    return {"law": law, "terms": got, "sq": sq, "implausible_left_out": left}


def versus_check(prob: GapProblem, verdict: list[str], r0: np.ndarray, v_sq: np.ndarray,
                 floor_m: float, identified: Any = None,
                 tracks: dict[str, Any] | None = None) -> dict[str, Any]:  # fmt: skip
    """For a verdict that names effects, the report's `proposal_vs_verdict`: the law of at
    most MAX_TERMS terms fitted to the baseline's misses r0 (n, 2) [m] (of the model with
    the `identified` band law, a `cell.gap.fit.Score`, where there is one), its held-out
    RMSE against the verdict's (`v_sq`: per throw, the squared held-out miss [m²]), the cut,
    its share of the verdict's and its interval, whether it `beats` the verdict (module
    docstring) and then `why`; {} for `none` and `unknown`. `tracks`: the tracks' evidence
    (`cell.gap.tracks.track_phase`) or None."""
    from cell.gap.propose_terms import allowed_phases
    from cell.gap.stats import bootstrap_cut

    if verdict[0] in ("none", "unknown"):
        return {}
    base = tuple(identified.full.effects) if identified is not None else ()
    own = frozenset(t for e in verdict for t in OWN_TERMS.get(e, ()))
    got = sparse_law(prob, base, r0, allowed_phases(tracks, floor_m), own)
    sq = got.pop("sq")
    a_v = float(np.sqrt(np.mean(v_sq)))
    cut, lo, hi = bootstrap_cut(v_sq, sq, seed=prob.seed + 13)
    out: dict[str, Any] = {
        **got, "heldout_rmse_m": float(np.sqrt(sq.mean())), "verdict_heldout_rmse_m": a_v,
        "cut_m": cut, "cut_ci95_m": [lo, hi], "cut_share": cut / a_v if a_v > 0 else 0.0,
        "margin_share": MARGIN,
        "beats": bool(got["law"] is not None and lo > 0 and cut >= MARGIN * a_v),
    }  # fmt: skip
    if out["beats"]:
        out["why"] = (
            f"the law {got['law']} predicts the held-out throws better than "
            f"{' + '.join(verdict)}: {out['heldout_rmse_m']:.4f} against {a_v:.4f} m, a cut of "
            f"{out['cut_share']:.1%} (interval [{lo:.4f}, {hi:.4f}] m; {MARGIN:.0%} asked): "
            f"its terms are outside the vocabulary"
        )
    return out
