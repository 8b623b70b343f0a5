"""The diagnosis: noise floor, effects ranked on held-out throws, and the verdict (GAP.md).

Verdict rules:

* the baseline B is the configured model on held-out throws (with
  `identify`, its end-effector parameters are refitted on training throws);
* B within 10 % of the noise floor F: `none`;
* otherwise effects join one at a time, best first: one joins when it cuts
  the held-out RMSE by ≥ 10 % of what is left, with a bootstrap interval of
  the cut above zero, and survives the permutation control (for an effect
  that hangs on a logged quantity, shuffling that quantity between throws
  must take away at least a quarter of its cut, with an interval above zero);
* when the joined effects bring the held-out RMSE A within 1.3 F, they are
  the verdict; otherwise it is `unknown` (a second effect is tried together
  with the first when one alone leaves a real gap; it joins only for the cut it adds
  over the first effect refitted from the pair's solution);
* an effect is a family of laws (`cell.model.effects.FAMILIES`): every member is
  fitted and scored, and the one that predicts held-out throws best stands for
  the effect;
* an effect is refused (does not join, and the report says why) when a parameter
  sits at a bound, when its value is one no real cell has (outside the effect's
  plausible range), or when the tracks contradict it: its phase carries less than
  AGREE_SHARE of the largest phase share of the landing miss the tracks show, a
  measurement effect without an apparent gravity off g, or a tracking scale off the
  tracks' apparent gravity ratio by more than SCALE_AGREE.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cell.gap.fit import Score, score_set
from cell.gap.noise import NoiseFloor, noise_floor
from cell.gap.problem import BandStiffness, GapProblem, rmse
from cell.gap.stats import bootstrap_cut
from cell.gap.tracks import phase_evidence
from cell.model.effects import EFFECTS, FAMILIES, Effect, TrackingScale

__all__ = ["Diagnosis", "diagnose", "NONE_RATIO", "VERDICT_RATIO", "applicable_effects"]

log = logging.getLogger(__name__)

NONE_RATIO = 1.10  # B ≤ this × F: within noise
VERDICT_RATIO = 1.30  # A ≤ this × F: explained
MIN_CUT = 0.10  # an effect must cut this share of what is left
PERM_SHARE = 0.25  # the permuted quantity must take away this share of the cut
MAX_EFFECTS = 3
# partners tried with one, with two chosen effects: this many of the best single effects,
# and as many of those that best fit what the chosen ones leave
PAIR_TRIES = (2, 1)
AGREE_SHARE = 0.35  # a phase the tracks give less than this share of the largest is clean
SCALE_AGREE = 0.005  # a tracking scale within this of the tracks' apparent gravity ratio
BOUND_TOL = 2e-3  # a parameter within this share of its range from a bound sits at it


@dataclass
class Diagnosis:
    """The diagnosis of a log: the GAP.md report and what its plots need."""

    report: dict[str, Any]
    baseline_residual: np.ndarray  # (n, 2) [m]
    baseline_sq: np.ndarray  # per-throw held-out squared miss [m²]
    verdict_sq: np.ndarray  # per-throw held-out squared miss after the verdict's effects [m²]
    verdict_residual: np.ndarray  # (n, 2) [m] with the verdict's effects fitted on all
    scores: dict[str, Score] = field(default_factory=dict)
    noise: NoiseFloor | None = None


def refusal(eff: Effect, tracks: dict[str, Any] | None, floor_m: float = 0.0) -> str | None:
    """Why a fitted effect may not join the verdict (None: it may).

    Args:
        eff: the fitted effect.
        tracks: the tracks' evidence (`cell.gap.tracks.track_phase`) or None.
        floor_m: the noise floor [m] (the landing share's significance).
    """
    bound = _at_bound(eff)
    if bound:
        return f"at a bound: {', '.join(bound)}"
    bad = eff.implausible()
    if bad:
        p = eff.params()
        return "implausible: " + ", ".join(f"{k}={p[k]:.4g}" for k in bad)
    side = (tracks or {}).get("sideways") or {}
    if eff.name == "wind" and side.get("prefers") == "scale":
        return "the tracks bend nothing sideways: a tracker scale explains them, a wind does not"
    if isinstance(eff, TrackingScale) and side.get("prefers") == "wind":
        return "the tracks bend sideways: a wind explains them, a tracker scale does not"
    if not tracks or not tracks.get("phase"):
        return None
    if eff.phase == "measurement":
        if not tracks.get("measurement"):
            return f"the tracks' apparent gravity is {tracks['g_ratio']:.3f} g: no measurement gap"
        if isinstance(eff, TrackingScale):
            g = tracks["g_ratio"]
            tol = max(SCALE_AGREE, 3 * tracks.get("g_ratio_se", 0.0))
            if abs(eff.scale_factor - g) > tol:
                return (
                    f"scale {eff.scale_factor:.4f} disagrees with the tracks' apparent "
                    f"gravity ratio {g:.4f}"
                )
        return None
    ev = phase_evidence(tracks, floor_m)
    top = ev["phase"]
    if top is None or top == "measurement" or top == eff.phase:
        return None
    own = ev["shares"].get(eff.phase, float("nan"))
    if not np.isfinite(own) or ev["significant"].get(eff.phase):
        return None
    if own < AGREE_SHARE * ev["shares"][top]:
        return (
            f"the tracks place the gap in the {top} ({ev['shares'][top]:.3f} m), not the "
            f"{eff.phase} ({own:.3f} m)"
        )
    return None


def applicable_families(prob: GapProblem) -> list[tuple[type[Effect], ...]]:
    """The effects the log can say anything about, each as its family of laws."""
    return [FAMILIES[c.name] for c in applicable_effects(prob)]


def applicable_effects(prob: GapProblem) -> list[type[Effect]]:
    """The effects the log can say anything about."""
    out: list[type[Effect]] = []
    launch_rows = bool(prob.has_stroke.any())
    curved = np.isin(prob.batch.shape, [2, 3, 4])
    for cls in EFFECTS.values():
        if cls.phase == "launch" and not launch_rows:
            continue
        if cls.name == "downwash" and not np.any(prob.rotor_rpm > 0):
            continue
        if cls.name == "shape_stretch" and not (curved.any() and (~curved).any()):
            continue
        if cls.name == "band_mass" and np.ptp(prob.batch.mass[prob.has_stroke]) <= 0:
            continue
        out.append(cls)
    return out


def _partners(prob: GapProblem, first: Score, rest: list[type[Effect]]) -> list[str]:
    """Effects ranked by how well each alone fits what the chosen ones leave (fitted on all
    throws on top of the chosen effects held at their sizes): a quick ranking of partners,
    whose joint fit and held-out score come after."""
    from dataclasses import replace

    from cell.gap.fit import fit_set

    held = tuple(e for e in first.full.effects if not isinstance(e, BandStiffness))
    fixed = replace(prob, base_effects=prob.base_effects + held)
    all_idx = np.arange(len(prob))
    fits = {c.name: fit_set(fixed, [c], all_idx, max_nfev=15 * len(c.bounds))[0] for c in rest}
    return sorted(fits, key=lambda nm: fits[nm].train_rmse_m)


def _at_bound(eff: Effect) -> list[str]:
    """Parameters fitted onto a bound that is not their neutral value (a sign that the
    effect is stretched to mimic something else)."""
    out = []
    neutral = eff.neutral().params()
    for (name, v), (lo, hi) in zip(eff.params().items(), eff.bounds, strict=True):
        span = hi - lo
        if (v <= lo + BOUND_TOL * span or v >= hi - BOUND_TOL * span) and abs(
            v - neutral[name]
        ) > BOUND_TOL * span:
            out.append(name)
    return out


def classes_names(classes: list[type[Effect]]) -> tuple[str, ...]:
    """The names of effect classes."""
    return tuple(c.name for c in classes)


def _cls(name: str, chosen: dict[str, type[Effect]] | None = None) -> type[Effect]:
    if name == BandStiffness.name:
        return BandStiffness
    if chosen and name in chosen:
        return chosen[name]
    return EFFECTS[name]


def _shrink(before: float, after: float) -> float:
    return 100.0 * (1.0 - after / before) if before > 0 else 0.0


def _baseline(
    prob: GapProblem, identify: bool
) -> tuple[Score | None, np.ndarray, np.ndarray, float]:
    """The configured model on held-out throws (with `identify`, its band stiffness
    refitted on the training throws of every fold).

    Returns:
        (the identified baseline's score, or None without `identify`; the residual on
        all throws (n, 2) [m]; the per-throw held-out squared miss [m²]; the RMSE of the
        fit on all throws [m]).
    """
    all_idx = np.arange(len(prob))
    if identify:
        identified = score_set(prob, [BandStiffness])
        r0 = prob.residual(all_idx, identified.full.effects)
        return identified, r0, identified.heldout, identified.full.train_rmse_m
    r0 = prob.residual(all_idx)
    return None, r0, np.sum(r0 * r0, axis=1), rmse(r0)


def _score_members(
    prob: GapProblem,
    prefix: list[type[Effect]],
    identified: Score | None,
    tick: Callable[[str], None],
) -> tuple[dict[str, Score], dict[str, type[Effect]], dict[str, dict[str, float]]]:
    """Fit and score every member of every applicable family alone (on top of the
    identified band law, if any).

    The member that predicts held-out throws best stands for its effect; one at a bound
    or implausible only when every member is.

    Returns:
        (each effect's score, the member standing for it, and for families of several
        laws each law's held-out RMSE [m], all by effect name).
    """
    scores: dict[str, Score] = {}
    members: dict[str, type[Effect]] = {}
    member_rank: dict[str, tuple[bool, float]] = {}
    laws: dict[str, dict[str, float]] = {}
    for family in applicable_families(prob):
        for cls in family:
            tick(cls.name + (f" ({cls.law})" if cls.law else ""))
            warm = None
            if identified is not None:
                neutral = cls.neutral().vector() / np.asarray(cls.scale, float)
                warm = np.r_[identified.full.x, neutral]
            sc = score_set(prob, prefix + [cls], warm=warm)
            if len(family) > 1:
                laws.setdefault(cls.name, {})[cls.law] = sc.heldout_rmse_m
            stretched = bool(_at_bound(sc.full.effects[-1]) or sc.full.effects[-1].implausible())
            rank = (stretched, sc.heldout_rmse_m)
            if cls.name not in scores or rank < member_rank[cls.name]:
                scores[cls.name] = sc
                members[cls.name] = cls
                member_rank[cls.name] = rank
    return scores, members, laws


class _Selection:
    """Effects joining the verdict one at a time, best first, and the tests they took.

    Args:
        prob: the problem.
        prefix: the effect classes under every fit (the band law when identifying).
        scores: each effect's score alone (`_score_members`); the sets tried as pairs are
            added as they are scored.
        members: the family member standing for each effect.
        tracks: the tracks' evidence or None.
        floor_m: the noise floor F [m].
        tick: the progress callback.

    Attributes:
        ranked: the effects' scores alone, best held-out RMSE first.
        tests: per candidate set ("a+b"), its cut [m] with interval, refusal, permutation
            control, whether it passes and (after `mark_joined`) whether it joined.
    """

    def __init__(
        self,
        prob: GapProblem,
        prefix: list[type[Effect]],
        scores: dict[str, Score],
        members: dict[str, type[Effect]],
        tracks: dict[str, Any] | None,
        floor_m: float,
        tick: Callable[[str], None],
    ) -> None:
        self.prob = prob
        self.prefix = prefix
        self.scores = scores
        self.members = members
        self.tracks = tracks
        self.floor_m = floor_m
        self.tick = tick
        self.ranked = sorted(scores.values(), key=lambda s: s.heldout_rmse_m)
        self.perm_cache: dict[tuple[str, ...], Score] = {}
        self.tests: dict[str, dict[str, Any]] = {}

    def refuse(self, cand: Score) -> str | None:
        """Why one of a candidate set's effects may not join (`refusal`), or None."""
        for e in cand.full.effects:
            if isinstance(e, BandStiffness):
                continue
            why = refusal(e, self.tracks, self.floor_m)
            if why:
                return f"{e.name}: {why}"
        return None

    def _survives_permutation(self, cand: Score, cut: float, t: dict[str, Any]) -> bool:
        """The permutation control of a candidate whose newest effect hangs on a logged
        quantity: shuffling it between throws must take away PERM_SHARE of the cut [m],
        with an interval above zero. Records the control in t."""
        newest = _cls(cand.names[-1], self.members)
        self.tick(f"permutation {newest.name}")
        classes = [_cls(nm, self.members) for nm in cand.names]
        key = cand.names
        if key not in self.perm_cache:
            self.perm_cache[key] = score_set(self.prob, classes, permute=True, warm=None)
        ps = self.perm_cache[key]
        gain, plo, _ = bootstrap_cut(ps.heldout, cand.heldout, seed=self.prob.seed + 1)
        survive = gain >= PERM_SHARE * cut and plo > 0
        t["permutation"] = {
            "quantity": newest.hangs_on,
            "heldout_rmse_m": ps.heldout_rmse_m,
            "gain_over_shuffled_m": gain,
            "survives": bool(survive),
        }
        return survive

    def passes(self, prev_sq: np.ndarray, cand: Score) -> bool:
        """Whether a candidate set joins over the misses before it (prev_sq [m²] per
        throw): it cuts MIN_CUT of the held-out RMSE left with a bootstrap interval above
        zero, is not refused and survives the permutation control. Records the tests."""
        prev = float(np.sqrt(prev_sq.mean()))
        cut, lo, hi = bootstrap_cut(prev_sq, cand.heldout, seed=self.prob.seed)
        t: dict[str, Any] = {
            "cut_m": cut,
            "cut_ci_m": [lo, hi],
            "cut_share": cut / prev if prev > 0 else 0.0,
        }
        ok = cut >= MIN_CUT * prev and lo > 0
        why = self.refuse(cand)
        if why:
            t["refused"] = why
            ok = False
        newest = _cls(cand.names[-1], self.members)
        if ok and newest.hangs_on is not None:
            ok = ok and self._survives_permutation(cand, cut, t)
        t["passes"] = bool(ok)
        self.tests["+".join(_public(cand.names))] = t
        return ok

    def join(self, base_sq: np.ndarray) -> tuple[list[Score], np.ndarray]:
        """Join the best single effect that passes, then partners while a real gap is left
        (held-out RMSE above VERDICT_RATIO F) and fewer than MAX_EFFECTS have joined.

        Args:
            base_sq: the baseline's per-throw held-out squared miss [m²].

        Returns:
            (the joined sets in order, each holding the ones before it; the per-throw
            held-out squared miss after the last [m²]).
        """
        chosen: list[Score] = []
        cur_sq = base_sq
        for s in self.ranked:
            if self.passes(cur_sq, s):
                chosen.append(s)
                cur_sq = s.heldout
                break
        while chosen and len(chosen[-1].names) < MAX_EFFECTS:
            A = float(np.sqrt(cur_sq.mean()))
            if A <= VERDICT_RATIO * self.floor_m:
                break
            best = self._partner(chosen[-1], cur_sq)
            if best is None:
                break
            chosen.append(best)
            cur_sq = best.heldout
        return chosen, cur_sq

    def _pairs(self, last: Score) -> list[Score]:
        """The chosen effects scored together with each likely partner, best first.

        Partners: PAIR_TRIES of the best single effects and as many of those that best fit
        what the chosen ones leave (`_partners`), each warm-started from the chosen
        effects' and its own solution.
        """
        have = last.names
        tries = PAIR_TRIES[min(len(_public(have)), len(PAIR_TRIES)) - 1]
        combos: list[Score] = []
        rest = [sc for sc in self.ranked if sc.names[-1] not in have]
        quick = _partners(self.prob, last, [_cls(sc.names[-1], self.members) for sc in rest])
        pick = list(dict.fromkeys([sc.names[-1] for sc in rest[:tries]] + quick[:tries]))
        for sc in [sc for sc in rest if sc.names[-1] in pick]:
            classes = [_cls(nm, self.members) for nm in have] + [_cls(sc.names[-1], self.members)]
            warm = np.concatenate([last.full.x, sc.full.x[len(self.prefix) :]])
            self.tick("+".join(_public(classes_names(classes))))
            combo = score_set(self.prob, classes, warm=warm)
            self.scores["+".join(_public(combo.names))] = combo
            combos.append(combo)
        combos.sort(key=lambda c: c.heldout_rmse_m)
        return combos

    def _partner(self, last: Score, cur_sq: np.ndarray) -> Score | None:
        """The best of the two best pairs that passes (or None), each tested against the
        chosen effects alone refitted from where the pair put them (drop-one), so that a
        partner only joins for what it adds itself."""
        n_have = len(last.full.x)
        for combo in self._pairs(last)[:2]:
            prev = [_cls(nm, self.members) for nm in last.names]
            drop = score_set(self.prob, prev, warm=combo.full.x[:n_have])
            prev_sq = drop.heldout if drop.heldout.mean() < cur_sq.mean() else cur_sq
            if self.passes(prev_sq, combo):
                return combo
        return None

    def mark_joined(self, chosen: list[Score]) -> None:
        """Record in every test whether its set joined."""
        joined = {"+".join(_public(c.names)) for c in chosen}
        for key, t in self.tests.items():
            t["joins"] = key in joined


def _verdict(B: float, A: float, F: float, chosen: list[Score]) -> list[str]:
    """The verdict's effects, or ["none"] or ["unknown"].

    Args:
        B: the baseline's held-out RMSE [m].
        A: the held-out RMSE with the joined effects [m].
        F: the noise floor [m].
        chosen: the joined sets (`_Selection.join`).
    """
    if B <= NONE_RATIO * F:
        return ["none"]
    if chosen and A <= VERDICT_RATIO * F:
        return _public(chosen[-1].names)
    if not chosen and B <= VERDICT_RATIO * F:
        return ["none"]
    return ["unknown"]


def _candidate(
    s: Score,
    base_sq: np.ndarray,
    B: float,
    laws: dict[str, dict[str, float]],
    tracks: dict[str, Any] | None,
    F: float,
    seed: int,
) -> dict[str, Any]:
    """The report's entry for one effect alone: its law, held-out score, shrink over the
    baseline (B [m], base_sq [m²] per throw) with interval, parameters with intervals, and
    why it may not join."""
    _, lo, hi = _shrink_ci(base_sq, s.heldout, seed)
    eff = s.full.effects[-1]
    ci = s.full.ci[-len(eff.bounds) :] if s.full.ci is not None else None
    return {
        "effect": eff.name,
        "law": eff.law,
        "phase": eff.phase,
        "heldout_rmse_m": s.heldout_rmse_m,
        "shrink_pct": _shrink(B, s.heldout_rmse_m),
        "shrink_ci_pct": [lo, hi],
        "fit_rmse_m": s.full.train_rmse_m,
        "params": eff.params(),
        "params_ci95": (
            {k: [float(a), float(b)] for k, (a, b) in zip(eff.params(), ci, strict=True)}
            if ci is not None
            else {}
        ),
        "laws_heldout_rmse_m": laws.get(eff.name, {}),
        "at_bound": _at_bound(eff),
        "implausible": eff.implausible(),
        "refused": refusal(eff, tracks, F),
    }


def _verdict_report(
    verdict: list[str],
    chosen: list[Score],
    B: float,
    base_sq: np.ndarray,
    v_sq: np.ndarray,
    seed: int,
) -> dict[str, Any]:
    """The report's verdict: its effects, held-out RMSE [m], shrink over the baseline
    with interval [%], parameters, laws and intervals (an `unknown` verdict names the
    effects that joined as partial)."""
    public_effects = (
        [e for e in chosen[-1].full.effects if e.name != BandStiffness.name] if chosen else []
    )
    A_v = float(np.sqrt(v_sq.mean()))
    _, slo, shi = _shrink_ci(base_sq, v_sq, seed)
    return {
        "effects": verdict,
        "heldout_rmse_m": A_v,
        "shrink_pct": _shrink(B, A_v),
        "shrink_ci_pct": [slo, shi],
        "params": ({e.name: e.params() for e in public_effects} if verdict[0] != "none" else {}),
        "laws": ({e.name: e.law for e in public_effects if e.law} if verdict[0] != "none" else {}),
        "params_ci95": (_verdict_ci(chosen[-1]) if chosen and verdict[0] != "none" else {}),
        "partial_effects": ([e.name for e in public_effects] if verdict[0] == "unknown" else []),
    }


def _noise_report(nf: NoiseFloor) -> dict[str, Any]:
    """The report's account of the noise floor: its method and each estimate [m]."""
    return {
        "method": nf.method,
        "repeats_m": nf.repeats_m,
        "repeat_dof": nf.repeat_dof,
        "neighbours_m": nf.neighbours_m,
        "model_m": nf.model_m,
    }


def _rules() -> dict[str, float]:
    """The rules' thresholds, as the report states them."""
    return {
        "agree_share": AGREE_SHARE,
        "scale_agree": SCALE_AGREE,
        "none_ratio": NONE_RATIO,
        "verdict_ratio": VERDICT_RATIO,
        "min_cut_share": MIN_CUT,
        "permutation_share": PERM_SHARE,
    }


def diagnose(
    prob: GapProblem,
    *,
    identify: bool = False,
    tracks: dict[str, Any] | None = None,
    progress: Callable[[str], None] | None = None,
) -> Diagnosis:
    """Diagnose the gap between the logged throws and the configured model.

    Args:
        prob: the problem (the log and the configured model).
        identify: re-identify the nominal band law (one stiffness factor) on the
            training throws of every fit, the baseline's included.
        tracks: the tracks' evidence of where the gap lies (`track_phase`), or None.
        progress: called with a short label before each step (the CLI's progress bar).

    Returns:
        The diagnosis.
    """
    tick = progress or (lambda s: None)
    all_idx = np.arange(len(prob))
    prefix: list[type[Effect]] = [BandStiffness] if identify else []
    tick("baseline")
    identified, r0, base_sq, fit_rmse = _baseline(prob, identify)
    B = float(np.sqrt(base_sq.mean()))
    tick("noise floor")
    nf = noise_floor(prob, r0, prob.landing(all_idx, identified.full.effects if identified else ()))
    F = nf.floor_m
    scores, members, laws = _score_members(prob, prefix, identified, tick)
    sel = _Selection(prob, prefix, scores, members, tracks, F, tick)
    chosen, cur_sq = sel.join(base_sq) if B > NONE_RATIO * F else ([], base_sq)
    sel.mark_joined(chosen)
    verdict = _verdict(B, float(np.sqrt(cur_sq.mean())), F, chosen)
    if verdict[0] in ("none", "unknown"):
        v_sq = base_sq if verdict[0] == "none" or not chosen else cur_sq
    else:
        v_sq = cur_sq
    if chosen and verdict[0] != "none":
        v_res = prob.residual(all_idx, chosen[-1].full.effects)
    else:
        v_res = r0
    report: dict[str, Any] = {
        "throws": len(prob),
        "noise_floor_m": F,
        "baseline": {"fit_rmse_m": fit_rmse, "heldout_rmse_m": B},
        "where": {},
        "candidates": [_candidate(s, base_sq, B, laws, tracks, F, prob.seed) for s in sel.ranked],
        "verdict": _verdict_report(verdict, chosen, B, base_sq, v_sq, prob.seed),
        "noise": _noise_report(nf),
        "tests": sel.tests,
        "identified": (
            {"band_stiffness_factor": identified.full.effects[0].params()["factor"]}
            if identified is not None
            else {}
        ),
        "rules": _rules(),
    }
    return Diagnosis(
        report=report,
        baseline_residual=r0,
        baseline_sq=base_sq,
        verdict_sq=v_sq,
        verdict_residual=v_res,
        scores=scores,
        noise=nf,
    )


def _verdict_ci(score: Score) -> dict[str, dict[str, list[float]]]:
    """95 % intervals of the verdict's parameters {effect: {param: [lo, hi]}}."""
    out: dict[str, dict[str, list[float]]] = {}
    if score.full.ci is None:
        return out
    i = 0
    for e in score.full.effects:
        m = len(e.bounds)
        if not isinstance(e, BandStiffness):
            out[e.name] = {
                k: [float(a), float(b)]
                for k, (a, b) in zip(e.params(), score.full.ci[i : i + m], strict=True)
            }
        i += m
    return out


def _public(names: tuple[str, ...] | list[str]) -> list[str]:
    return [nm for nm in names if nm != BandStiffness.name]


def _shrink_ci(
    before_sq: np.ndarray, after_sq: np.ndarray, seed: int
) -> tuple[float, float, float]:
    """Shrink [%] and its 95 % bootstrap interval."""
    rng = np.random.default_rng(seed + 2)
    n = before_sq.size
    ix = rng.integers(0, n, size=(1000, n))
    b = np.sqrt(before_sq[ix].mean(axis=1))
    a = np.sqrt(after_sq[ix].mean(axis=1))
    vals = 100.0 * (1.0 - a / np.maximum(b, 1e-300))
    lo, hi = np.percentile(vals, [2.5, 97.5])
    return (
        _shrink(float(np.sqrt(before_sq.mean())), float(np.sqrt(after_sq.mean()))),
        float(lo),
        float(hi),
    )
