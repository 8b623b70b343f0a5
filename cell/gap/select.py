"""Effects joining the verdict one at a time (GAP.md "How a verdict is reached"): the
tests a candidate set takes (its cut with a bootstrap interval, the refusals, the
permutation control) and the pairs tried when one effect leaves a real gap.

An effect is refused (does not join, and the report says why) when a parameter sits at a
bound, when its value is one no real cell has (outside the effect's plausible range), or
when the tracks contradict it: its phase carries less than AGREE_SHARE of the largest
phase share of the landing miss the tracks show (a landing's net of the floor F), a
measurement effect without an apparent gravity off g, a tracking scale off the tracks'
apparent gravity ratio by more than SCALE_AGREE, or a drag factor the tracks' drag per
object contradicts (`cell.gap.track_drag`), or a flight effect whose own bend over the
tracks exceeds theirs (`cell.gap.track_member`). A tracking scale beside a landing effect is
refused, too, where the landing misses across the impact velocity do not show it
(`cell.gap.across`): a slide moves a landing along the impact velocity only, so across it a
scale is all that moves the landings in proportion to their distance from the origin.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any

import numpy as np

from cell.gap.across import (
    ACROSS_Z,
    across_refusal,
    across_scale,
    scale_beside_landing,
)
from cell.gap.fit import Score, fit_set, fit_start, score_set
from cell.gap.problem import BandStiffness, GapProblem
from cell.gap.stats import bootstrap_cut
from cell.gap.track_drag import drag_refusal
from cell.gap.track_member import bend_refusal
from cell.gap.tracks import phase_evidence
from cell.model.effects import EFFECTS, FAMILIES, DragScale, Effect, TrackingScale
from cell.model.flight_batch import together

__all__ = ["Selection", "refusal", "across_scale", "across_refusal", "scale_beside_landing",
           "at_bound", "public", "effect_class", "member_rank_of", "ACROSS_Z"]  # fmt: skip

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


def refusal(eff: Effect, tracks: dict[str, Any] | None, floor_m: float = 0.0) -> str | None:
    """Why a fitted effect may not join the verdict (None: it may).

    Args:
        eff: the fitted effect.
        tracks: the tracks' evidence (`cell.gap.tracks.track_phase`) or None.
        floor_m: the noise floor [m] (the landing share's significance).
    """
    bound = at_bound(eff)
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
    net = np.sqrt(max(own**2 - floor_m**2, 0.0)) if eff.phase == "landing" else own
    if net < AGREE_SHARE * ev["shares"][top]:
        over = f", {net:.3f} m over the floor" if own >= AGREE_SHARE * ev["shares"][top] else ""
        return (
            f"the tracks place the gap in the {top} ({ev['shares'][top]:.3f} m), not the "
            f"{eff.phase} ({own:.3f} m{over})"
        )
    return None


def _partners(prob: GapProblem, first: Score, rest: list[type[Effect]]) -> list[str]:
    """Effects ranked by how well each alone fits what the chosen ones leave (fitted on all
    throws on top of the chosen effects held at their sizes): a quick ranking of partners,
    whose joint fit and held-out score come after."""
    held = tuple(e for e in first.full.effects if not isinstance(e, BandStiffness))
    fixed = replace(prob, base_effects=prob.base_effects + held)
    all_idx = np.arange(len(prob))
    run = [partial(fit_set, fixed, [c], all_idx, max_nfev=15 * len(c.bounds)) for c in rest]
    fits = {c.name: f[0] for c, f in zip(rest, together(run), strict=True)}
    return sorted(fits, key=lambda nm: fits[nm].train_rmse_m)


def at_bound(eff: Effect) -> list[str]:
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


def member_rank_of(sc: Score) -> tuple[bool, float]:
    """How a family member's score ranks among its family's (lower is better): stretched
    (at a bound or implausible) last, then by held-out RMSE [m] raised by
    `cell.gap.laws.TERM_PENALTY` per term more than the family's fewest (the rule a law
    of the throw pays for its terms). A member with a term more (the wind's vertical
    part) stands for the effect only where that term predicts held-out throws better by
    more than the penalty and stays within its plausible range."""
    from cell.gap.laws import TERM_PENALTY

    eff = sc.full.effects[-1]
    fewest = min(len(c.bounds) for c in FAMILIES.get(eff.name, (type(eff),)))
    extra = max(len(type(eff).bounds) - fewest, 0)
    return bool(at_bound(eff) or eff.implausible()), sc.heldout_rmse_m * (
        1.0 + TERM_PENALTY * extra
    )


def classes_names(classes: list[type[Effect]]) -> tuple[str, ...]:
    """The names of effect classes."""
    return tuple(c.name for c in classes)


def effect_class(name: str, chosen: dict[str, type[Effect]] | None = None) -> type[Effect]:
    if name == BandStiffness.name:
        return BandStiffness
    if chosen and name in chosen:
        return chosen[name]
    return EFFECTS[name]


@dataclass(eq=False)
class Selection:
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

    prob: GapProblem
    prefix: list[type[Effect]]
    scores: dict[str, Score]
    members: dict[str, type[Effect]]
    tracks: dict[str, Any] | None
    floor_m: float
    tick: Callable[[str], None]
    ranked: list[Score] = field(init=False)
    perm_cache: dict[tuple[str, ...], Score] = field(init=False, default_factory=dict)
    tests: dict[str, dict[str, Any]] = field(init=False, default_factory=dict)
    law_tries: dict[str, dict[str, float]] = field(init=False, default_factory=dict)

    def __post_init__(self) -> None:
        self.ranked = sorted(self.scores.values(), key=lambda s: s.heldout_rmse_m)

    def learn_law(self, cand: Score) -> Score:
        """The set with each effect's law chosen among its forms (`cell.gap.laws`); the
        chosen forms stand for their effects in the pairs tried after."""
        from cell.gap.laws import choose_law

        out, tried = choose_law(self.prob, cand, self.tick)
        self.law_tries.update(tried)
        for e in out.full.effects:
            if e.name in self.members:
                self.members[e.name] = type(e)
        return out

    def rival_law(self, first: Score, base_sq: np.ndarray) -> Score:
        """The first effect to join, or a rival that beats it once the rival's own law is
        chosen (`cell.gap.laws`). The effects are ranked alone at their constant form; an
        effect whose parameter grows with a logged quantity (a drag growing with the
        stroke) can rank below one whose constant mimics it, and a partner is only sought
        where the first leaves a real gap. Each other effect of LAW_BASES alone whose
        constant passes over the baseline (base_sq [m²] per throw) has its law chosen; a
        rival whose chosen form is not its constant replaces the first effect when, with
        that form, it passes over the baseline (the permutation control shuffling the
        law's covariate) and over the first effect (it cuts MIN_CUT of what the first
        leaves, with a bootstrap interval above zero). A rival's test over the baseline
        is recorded under its name, over the first effect under `"<effect> (<law>) over
        <first>"`."""
        from cell.gap.laws import LAW_BASES, choose_law

        if len(public(first.names)) != 1:
            return first
        have = first.names[-1]
        best = first
        for sc in self.ranked:
            eff = sc.full.effects[-1]
            if eff.name == have or eff.name not in LAW_BASES or len(public(sc.names)) != 1:
                continue
            if self.refuse(sc) or not self._passes_quiet(base_sq, sc):
                continue
            law, tried = choose_law(self.prob, sc, self.tick)
            form = law.full.effects[-1]
            if not getattr(type(form), "law_base", None):
                continue
            t = self._test(best.heldout, law)
            why = self.refuse(law)
            if why:
                t["refused"] = why
            ok = t["passes"] and not why and self.passes(base_sq, law)
            t["passes"] = bool(ok)
            self.tests[f"{form.name} ({form.law}) over {'+'.join(public(best.names))}"] = t
            if ok:
                self.law_tries.update(tried)
                self.members[eff.name] = type(form)
                best = law
        return best

    def _test(self, prev_sq: np.ndarray, cand: Score) -> dict[str, Any]:
        """The cut of a candidate over the misses before it (prev_sq [m²] per throw): at
        least MIN_CUT of the held-out RMSE left, with a bootstrap interval above zero."""
        prev = float(np.sqrt(prev_sq.mean()))
        cut, lo, hi = bootstrap_cut(prev_sq, cand.heldout, seed=self.prob.seed)
        return {
            "cut_m": cut,
            "cut_ci_m": [lo, hi],
            "cut_share": cut / prev if prev > 0 else 0.0,
            "passes": bool(cut >= MIN_CUT * prev and lo > 0),
        }

    def _passes_quiet(self, prev_sq: np.ndarray, cand: Score) -> bool:
        """Whether a candidate's cut over prev_sq passes (`_test`), unrecorded."""
        return bool(self._test(prev_sq, cand)["passes"])

    def prune(self, cand: Score) -> Score:
        """The set without any earlier effect that, once the laws are chosen, no longer
        cuts MIN_CUT of what the others leave with a bootstrap interval above zero
        (backward elimination: an effect that joined to stand in for another's law)."""
        effs = list(cand.full.effects)
        sizes = [len(type(e).bounds) for e in effs]
        starts = np.cumsum([0, *sizes])
        for j in range(len(self.prefix), len(effs) - 1):
            keep = [i for i in range(len(effs)) if i != j]
            warm = np.concatenate([cand.full.x[starts[i] : starts[i + 1]] for i in keep])
            self.tick(f"without {effs[j].name}")
            without = score_set(self.prob, [type(effs[i]) for i in keep], warm=warm)
            cut, lo, _ = bootstrap_cut(without.heldout, cand.heldout, seed=self.prob.seed + 5)
            if cut < MIN_CUT * without.heldout_rmse_m or lo <= 0:
                self.tests.setdefault("pruned", {})[effs[j].name] = {  # type: ignore[index]
                    "cut_m": cut, "cut_ci_low_m": lo}  # fmt: skip
                return without
        return cand

    def refuse(self, cand: Score) -> str | None:
        """Why one of a candidate set's effects may not join (`refusal`), or None."""
        for e in cand.full.effects:
            if isinstance(e, BandStiffness):
                continue
            if why := refusal(e, self.tracks, self.floor_m):
                return f"{e.name}: {why}"
        if why := drag_refusal(self.prob, cand.full.effects, self.tracks):
            return f"{DragScale.name}: {why}"
        if why := bend_refusal(self.prob, cand.full.effects, self.tracks):
            return f"{'+'.join(e.name for e in cand.full.effects if e.phase == 'flight')}: {why}"
        why = across_refusal(self.prob, cand.full.effects)
        return f"{TrackingScale.name}: {why}" if why else None

    def _survives_permutation(self, cand: Score, cut: float, t: dict[str, Any]) -> bool:
        """The permutation control of a candidate whose newest effect hangs on a logged
        quantity: shuffling it between throws must take away PERM_SHARE of the cut [m],
        with an interval above zero. Records the control in t."""
        newest = type(cand.full.effects[-1])
        self.tick(f"permutation {newest.name}")
        classes = [type(e) for e in cand.full.effects]
        key = tuple(c.__name__ for c in classes)
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

    def passes(self, prev_sq: np.ndarray, cand: Score, key: str | None = None) -> bool:
        """Whether a candidate set joins over the misses before it (prev_sq [m²] per
        throw): it cuts MIN_CUT of the held-out RMSE left with a bootstrap interval above
        zero, is not refused and survives the permutation control. Records the tests
        (under `key`, or the set's names joined by "+"), and for a tracking scale beside a
        landing effect the scale the misses across the impact velocity show with its
        standard error (`across_scale`: the landings' evidence for the scale that no slide
        mimics, whether or not the set joins)."""
        t = self._test(prev_sq, cand)
        cut = t["cut_m"]
        ok = bool(t.pop("passes"))
        why = self.refuse(cand)
        if why:
            t["refused"] = why
            ok = False
        if scale_beside_landing(cand.full.effects):
            # what the landings show of the scale where no slide moves them, joined or not
            s, se, _ = across_scale(self.prob, cand.full.effects)
            t["across_scale"] = [s, se]
        newest = type(cand.full.effects[-1])
        if ok and newest.hangs_on is not None:
            ok = ok and self._survives_permutation(cand, cut, t)
        t["passes"] = bool(ok)
        self.tests[key or "+".join(public(cand.names))] = t
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
                s = self.rival_law(self.learn_law(s), base_sq)
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
            best = self.prune(self.learn_law(best))
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
        tries = PAIR_TRIES[min(len(public(have)), len(PAIR_TRIES)) - 1]
        combos: list[Score] = []
        rest = [sc for sc in self.ranked if sc.names[-1] not in have]
        quick = _partners(
            self.prob, last, [effect_class(sc.names[-1], self.members) for sc in rest]
        )
        pick = list(dict.fromkeys([sc.names[-1] for sc in rest[:tries]] + quick[:tries]))
        # every law of each partner's family (the member that stood for it alone was chosen
        # on misses the chosen effects no longer leave), fitted side by side
        todo, fits = [], []
        for sc in [sc for sc in rest if sc.names[-1] in pick]:
            for member in FAMILIES.get(sc.names[-1], (effect_class(sc.names[-1]),)):
                classes = [effect_class(nm, self.members) for nm in have] + [member]
                own = sc.full.x[len(self.prefix) :]
                if member is not self.members.get(sc.names[-1]):
                    own = fit_start(member) / np.asarray(member.scale, float)
                self.tick("+".join(public(classes_names(classes))))
                todo.append(sc.names[-1])
                fits.append(partial(score_set, self.prob, classes, warm=np.r_[last.full.x, own]))
        best: dict[str, tuple[tuple[bool, float], Score]] = {}
        for name, combo in zip(todo, together(fits), strict=True):
            if name not in best or member_rank_of(combo) < best[name][0]:
                best[name] = (member_rank_of(combo), combo)
        for _, combo in best.values():
            self.scores["+".join(public(combo.names))] = combo
            combos.append(combo)
        combos.sort(key=lambda c: c.heldout_rmse_m)
        return combos

    def _partner(self, last: Score, cur_sq: np.ndarray) -> Score | None:
        """The best of the two best pairs that passes (or None), each tested against the
        chosen effects alone refitted from where the pair put them (drop-one), so that a
        partner only joins for what it adds itself."""
        n_have = len(last.full.x)
        for combo in self._pairs(last)[:2]:
            prev = [effect_class(nm, self.members) for nm in last.names]
            drop = score_set(self.prob, prev, warm=combo.full.x[:n_have])
            prev_sq = drop.heldout if drop.heldout.mean() < cur_sq.mean() else cur_sq
            if self.passes(prev_sq, combo):
                return combo
        return None

    def mark_joined(self, chosen: list[Score]) -> None:
        """Record in every test whether its set joined."""
        joined = {"+".join(public(c.names)) for c in chosen}
        for key, t in self.tests.items():
            t["joins"] = key in joined


def public(names: tuple[str, ...] | list[str]) -> list[str]:
    return [nm for nm in names if nm != BandStiffness.name]
