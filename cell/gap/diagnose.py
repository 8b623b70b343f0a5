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
  fitted and scored, and the one that predicts held-out throws best, with a penalty
  per term more than the family's fewest, stands for the effect;
* an effect's parameter may follow a law of the throw (`cell.gap.laws`: constant,
  proportional or linear in the stroke, mass or grip width, or one value per object;
  a member of two parameters in those it names, the drop law's 1/μ, its depth common),
  chosen by held-out RMSE with a penalty per extra term when the effect joins; the
  other effects whose constant alone would have joined first get their law too, and
  one whose law cuts MIN_CUT of what the first leaves replaces it (`Selection.rival_law`);
* an effect is refused (does not join, and the report says why) when a parameter
  sits at a bound, when its value is one no real cell has (outside the effect's
  plausible range), or when the tracks contradict it: its phase carries less than
  AGREE_SHARE of the largest phase share of the landing miss the tracks show, a
  measurement effect without an apparent gravity off g, or a tracking scale off the
  tracks' apparent gravity ratio by more than SCALE_AGREE; a tracking scale beside a
  landing effect is refused where the landing misses across the impact velocity show no
  scale (within ACROSS_Z standard errors of 1, `cell.gap.select.across_refusal`);
* on a log of one configuration, a verdict naming effects the log cannot tell apart is
  `unknown`, those effects its partials (`cell.gap.one_config`);
* a verdict naming `wind` is `unknown`, the wind partial, where the tracks show its
  sideways pull growing along the flight (a late gust, `cell.gap.track_gust`); a `none`
  is `unknown` (flight) where the tracks bend off the model's flight (`flight_bends`).
* a verdict naming effects is `unknown`, those effects partial, where a parameter of theirs
  drifts over the log's throw order (`cell.gap.param_drift`: a band that tires), or where a
  law of ≤ 2 terms outside the vocabulary predicts held-out throws better by a margin
  (`cell.gap.propose_vs`).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cell.gap.fit import Score, fit_start, score_set
from cell.gap.noise import NoiseFloor, noise_floor
from cell.gap.one_config import one_configuration
from cell.gap.param_drift import drift_check
from cell.gap.plane_step import step_check
from cell.gap.problem import BandStiffness, GapProblem, rmse
from cell.gap.propose_vs import versus_check
from cell.gap.select import (
    ACROSS_Z,
    AGREE_SHARE,
    MIN_CUT,
    PERM_SHARE,
    SCALE_AGREE,
    VERDICT_RATIO,
    Selection,
    at_bound,
    member_rank_of,
    public,
    refusal,
)
from cell.gap.track_gust import flight_bends, unsteady_wind
from cell.model.effects import EFFECTS, FAMILIES, Effect
from cell.model.flight_batch import together

__all__ = ["Diagnosis", "diagnose", "NONE_RATIO", "VERDICT_RATIO", "applicable_effects",
           "spread_report"]  # fmt: skip

log = logging.getLogger(__name__)

NONE_RATIO = 1.10  # B ≤ this × F: within noise


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
    verdict_effects: tuple[Effect, ...] = ()  # the verdict's effects fitted on all throws


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
    or implausible only when every member is (`member_rank_of`).

    Returns:
        (each effect's score, the member standing for it, and for families of several
        laws each law's held-out RMSE [m], all by effect name).
    """
    scores: dict[str, Score] = {}
    members: dict[str, type[Effect]] = {}
    member_rank: dict[str, tuple[bool, float]] = {}
    laws: dict[str, dict[str, float]] = {}
    todo = [(family, cls) for family in applicable_families(prob) for cls in family]
    fits: list[Any] = []
    for _, cls in todo:
        tick(cls.name + (f" ({cls.law})" if cls.law else ""))
        warm = None
        if identified is not None:
            warm = np.r_[identified.full.x, fit_start(cls) / np.asarray(cls.scale, float)]
        fits.append(lambda c=cls, w=warm: score_set(prob, prefix + [c], warm=w))
    for (family, cls), sc in zip(todo, together(fits), strict=True):  # flights as one batch
        if len(family) > 1:
            laws.setdefault(cls.name, {})[cls.law] = sc.heldout_rmse_m
        rank = member_rank_of(sc)
        if cls.name not in scores or rank < member_rank[cls.name]:
            scores[cls.name] = sc
            members[cls.name] = cls
            member_rank[cls.name] = rank
    return scores, members, laws


def _verdict(B: float, A: float, F: float, chosen: list[Score]) -> list[str]:
    """The verdict's effects, or ["none"] or ["unknown"].

    Args:
        B: the baseline's held-out RMSE [m].
        A: the held-out RMSE with the joined effects [m].
        F: the noise floor [m].
        chosen: the joined sets (`Selection.join`).
    """
    if B <= NONE_RATIO * F:
        return ["none"]
    if chosen and A <= VERDICT_RATIO * F:
        return public(chosen[-1].names)
    if not chosen and B <= VERDICT_RATIO * F:
        return ["none"]
    return ["unknown"]


def _candidate(s: Score, base_sq: np.ndarray, B: float, laws: dict[str, dict[str, float]],
               tracks: dict[str, Any] | None, F: float, seed: int) -> dict[str, Any]:  # fmt: skip
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
        "at_bound": at_bound(eff),
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
    ci = _verdict_ci(chosen[-1]) if chosen else {}
    A_v = float(np.sqrt(v_sq.mean()))
    _, slo, shi = _shrink_ci(base_sq, v_sq, seed)
    return {
        "effects": verdict,
        "heldout_rmse_m": A_v,
        "shrink_pct": _shrink(B, A_v),
        "shrink_ci_pct": [slo, shi],
        "params": (
            {e.name: _law_params(e, ci.get(e.name)) for e in public_effects}
            if verdict[0] != "none"
            else {}
        ),
        "laws": ({e.name: e.law for e in public_effects if e.law} if verdict[0] != "none" else {}),
        "phases": ({e.name: e.phase for e in public_effects} if verdict[0] != "none" else {}),
        "params_ci95": (ci if verdict[0] != "none" else {}),
        "partial_effects": ([e.name for e in public_effects] if verdict[0] == "unknown" else []),
    }


def _noise_report(nf: NoiseFloor) -> dict[str, Any]:
    """The report's account of the noise floor: its method and each estimate [m]."""
    return {"method": nf.method, "repeats_m": nf.repeats_m, "repeat_dof": nf.repeat_dof,
            "neighbours_m": nf.neighbours_m, "model_m": nf.model_m,
            "validated_m": nf.validated_m, "validated_share": nf.validated_share,
            **({"time_sessions": nf.time_sessions} if nf.time_sessions is not None else {})}  # fmt: skip


def _rules() -> dict[str, float]:
    """The rules' thresholds, as the report states them."""
    return {"agree_share": AGREE_SHARE, "scale_agree": SCALE_AGREE, "across_z": ACROSS_Z,
            "none_ratio": NONE_RATIO, "verdict_ratio": VERDICT_RATIO, "min_cut_share": MIN_CUT,
            "permutation_share": PERM_SHARE}  # fmt: skip


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
    sel = Selection(prob, prefix, scores, members, tracks, F, tick)
    chosen, cur_sq = sel.join(base_sq) if B > NONE_RATIO * F else ([], base_sq)
    sel.mark_joined(chosen)
    A = float(np.sqrt(cur_sq.mean()))
    verdict = _verdict(B, A, F, chosen)
    spread = None
    if verdict == ["unknown"] and chosen:
        tick("parameter (throw to throw)")
        spread = _spread_verdict(prob, chosen[-1], A, nf)
        if spread is not None and spread["names"]:
            verdict = public(chosen[-1].names)
    unsteady, bends = unsteady_wind(verdict, tracks), flight_bends(verdict, tracks)
    drift = drift_check(prob, verdict, chosen, F)  # a named effect's parameter drifting
    step = step_check(prob, verdict, r0, cur_sq if chosen else base_sq)  # a step in the floor
    verdict = ["unknown"] if unsteady or bends or drift.get("why") or step.get("why") else verdict
    vs = versus_check(prob, verdict, r0, cur_sq, F, identified, tracks)  # a law outside it
    verdict = ["unknown"] if vs.get("why") else verdict
    named = verdict[0] not in ("none", "unknown")
    v_sq = cur_sq if named or (verdict[0] == "unknown" and chosen) else base_sq
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
        "laws_tried_heldout_rmse_m": sel.law_tries,
        "identified": (
            {"band_stiffness_factor": identified.full.effects[0].params()["factor"]}
            if identified is not None
            else {}
        ),
        "rules": _rules(),
        **({"wind_not_steady": unsteady} if unsteady else {}),
        **({"flight_bends": bends} if bends else {}),
        **({"parameter_drifts": drift} if drift else {}),
        **({"landing_step": step} if step else {}),
        **({"proposal_vs_verdict": vs} if vs else {}),
    }
    if (v1 := one_configuration(prob, report, verdict, r0)) != verdict:
        verdict = v1  # one configuration: the effects it cannot tell apart as partials
        report["verdict"] = _verdict_report(verdict, chosen, B, base_sq, v_sq, prob.seed)
        report["verdict"]["partial_effects"] = report["one_configuration"]["explained_alike"]
    report["verdict"]["law_mean"] = (
        _law_means(chosen[-1].full.effects, prob) if chosen and verdict[0] != "none" else {}
    )
    if spread is not None:
        spread_report(report, spread)
    if chosen and verdict[0] not in ("none", "unknown") and "wind" in verdict:
        tick("wind (throw to throw)")
        _wind_throw_report(report, prob, tuple(chosen[-1].full.effects))
    return Diagnosis(
        report=report,
        baseline_residual=r0,
        baseline_sq=base_sq,
        verdict_sq=v_sq,
        verdict_residual=v_res,
        verdict_effects=(tuple(chosen[-1].full.effects) if chosen and verdict[0] != "none" else ()),
        scores=scores,
        noise=nf,
    )


def _wind_throw_report(report: dict[str, Any], prob: GapProblem,
                       effects: tuple[Effect, ...]) -> None:  # fmt: skip
    """The wind's throw-to-throw form (`cell.gap.wind_throw`) under `wind_throw_to_throw`;
    where it stands for the wind, the verdict's wind is its mean and spread: law
    `wind_i ~ N(mean, sd)`, params `x_mps`, `y_mps` (the mean; a vertical part keeps its
    steady value) and `sd_mps`, with their 95 % intervals. The held-out RMSE and the
    misses stay the steady fit's (the mean prediction's best in least squares)."""
    from cell.gap.wind_throw import wind_throw

    wt = wind_throw(prob, effects)
    if wt is None:
        return
    v = report["verdict"]
    report["wind_throw_to_throw"] = {**wt, "member": v["laws"].get("wind")}
    if not wt["chosen"]:
        return
    v["params"]["wind"] = {**v["params"]["wind"], "x_mps": wt["mean_mps"][0],
                           "y_mps": wt["mean_mps"][1], "sd_mps": wt["sd_mps"]}  # fmt: skip
    v["laws"]["wind"] = wt["law"]
    ci = v["params_ci95"].setdefault("wind", {})
    ci.update({"x_mps": wt["mean_ci95_mps"][0], "y_mps": wt["mean_ci95_mps"][1],
               "sd_mps": wt["sd_ci95_mps"]})  # fmt: skip


def _spread_verdict(prob: GapProblem, score: Score, A: float, nf: NoiseFloor
                    ) -> dict[str, Any] | None:  # fmt: skip
    """The throw-to-throw form of the joined effects' one-parameter members
    (`cell.gap.param_throw`), and whether it names them: the form stands and A is within
    the verdict's ratio of the larger of the floor and the floor its spread sets."""
    from cell.gap.param_throw import param_spread

    form = param_spread(prob, tuple(score.full.effects), nf)
    if form is None:
        return None
    floor = max(nf.floor_m, form["floor_m"]) if np.isfinite(form["floor_m"]) else nf.floor_m
    form["verdict_floor_m"] = floor
    form["names"] = bool(form["chosen"] and A <= VERDICT_RATIO * floor)
    return form


def spread_report(report: dict[str, Any], form: dict[str, Any]) -> None:
    """The form under `parameter_throw_to_throw`; where it names the verdict, the effect's
    parameter is its mean and spread (`sd`, in the parameter's units) with their
    intervals, and its law `θ_i ~ N(mean, sd)`."""
    report["parameter_throw_to_throw"] = form
    if not form["names"]:
        return
    v = report["verdict"]
    name, p = form["effect"], form["param"]
    v["params"][name] = {**v["params"].get(name, {}), p: form["mean"], "sd": form["sd"]}
    v["laws"][name] = form["law"]
    v["params_ci95"].setdefault(name, {}).update({p: form["mean_ci95"], "sd": form["sd_ci95"]})


def _law_params(e: Effect, ci: dict[str, list[float]] | None) -> dict[str, Any]:
    """An effect's reported parameters: its fields, or for a per-object law each object's
    value shrunk toward the common one (`cell.gap.laws.shrunk`) by object id."""
    ids = getattr(type(e), "object_ids", None)
    if ids is None:
        return e.params()
    from cell.gap.laws import shrunk

    own = [f"o{j}" for j in range(len(ids))]
    arr = np.array([ci[k] for k in own]) if ci else None
    vals, common, tau = shrunk(np.array([getattr(e, k) for k in own], float), arr)
    return {
        "common": common,
        "spread": tau,
        "per_object": {o: float(v) for o, v in zip(ids, vals, strict=True)},
        **{k: v for k, v in e.params().items() if k not in own},  # a member's common values
    }


def _law_means(effects: Sequence[Effect], prob: GapProblem) -> dict[str, dict[str, float]]:
    """For each effect whose parameter follows a law (`cell.gap.laws`), the value the law
    gives its parameter averaged over the log's throws {effect: {param: mean}}."""
    out: dict[str, dict[str, float]] = {}
    for e in effects:
        if getattr(type(e), "law_base", None) is not None:
            p = type(e).law_param  # type: ignore[attr-defined]
            out[e.name] = {p: float(np.mean(getattr(e.per_throw(prob.batch), p)))}
    return out


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
