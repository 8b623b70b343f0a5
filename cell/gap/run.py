"""The whole diagnosis of a throw log: problem, tracks, verdict, where and conditions.

Outliers (`cell.gap.outliers`) are the throws whose miss under the verdict's effects (or an
`unknown` verdict's proposed law) is impossible: the diagnosis runs again without them
(until the rows a pass leaves out are the rows its verdict flags), they are reported by
row, and the held-out errors are reported plain and robust. An `unknown` verdict carries
the law proposed for what is left (`cell.gap.propose`)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from cell.errors import InvalidInput
from cell.gap.conditions import conditions, worst_conditions
from cell.gap.diagnose import AGREE_SHARE, Diagnosis, diagnose
from cell.gap.noise import NoiseFloor
from cell.gap.outliers import flag, threshold_sq
from cell.gap.problem import GapProblem, build_problem
from cell.gap.track_latency import add_offset
from cell.gap.tracks import fit_tracks, launch_arrays, phase_evidence, track_phase
from cell.log.table import ThrowTable
from cell.model.effects import EFFECTS, Effect
from cell.model.objects import SHAPES
from cell.model.params import EndEffectorParams
from cell.model.throw import drag_constant
from cell.params import Validation

__all__ = ["diagnose_log"]


def _k_of(table: ThrowTable) -> np.ndarray:
    codes = np.array([SHAPES.index(s) for s in table.text("shape")])
    size = np.stack([table.num("size_x_m"), table.num("size_y_m"), table.num("size_z_m")], -1)
    return drag_constant(codes, table.num("mass_kg"), size)


def _phase_from_verdict(d: Diagnosis) -> dict[str, Any]:
    rep = d.report
    v = rep["verdict"]["effects"]
    base = rep["baseline"]["heldout_rmse_m"]
    if v == ["none"]:
        return {
            "phase": "none",
            "evidence": (
                f"no tracks; the held-out miss {base:.3f} m is within 10% of the noise "
                f"floor {rep['noise_floor_m']:.3f} m"
            ),
        }
    if v == ["unknown"]:
        plausible = [c for c in rep["candidates"] if not c.get("refused")]
        best = (plausible or rep["candidates"] or [None])[0]
        if best is not None and "one_configuration" in rep:  # explained, alike
            return {
                "phase": best["phase"],
                "evidence": "no tracks; " + rep["one_configuration"]["why"],
            }
        prop = rep.get("proposal") or {}
        if prop.get("law") and (
            best is None or prop["heldout_rmse_after_m"] < best["heldout_rmse_m"]
        ):
            # the proposed law explains more than any effect of the vocabulary: its phase
            # is where the gap lies, not the phase of a partial effect that cut less
            return {
                "phase": prop["phase"],
                "evidence": (
                    f"no tracks; no named effect explains the landing misses; the proposed "
                    f"law ({prop['phase']}: {prop['law']}) takes the held-out RMSE to "
                    f"{prop['heldout_rmse_after_m']:.3f} m, below the best partial effect's "
                    + (f"{best['heldout_rmse_m']:.3f} m" if best else "none")
                    + f" (noise floor {rep['noise_floor_m']:.3f} m)"
                ),
            }
        if best is None:
            return {"phase": "unknown", "evidence": "no effect could be tried"}
        return {
            "phase": best["phase"],
            "evidence": (
                f"no tracks; no named effect explains the landing misses; the best partial "
                f"one, {best['effect']} ({best['phase']}), takes the held-out RMSE from "
                f"{base:.3f} to {best['heldout_rmse_m']:.3f} m (noise floor "
                f"{rep['noise_floor_m']:.3f} m)"
            ),
        }
    phases = [EFFECTS[e].phase for e in v]
    return {
        "phase": phases[0],
        "evidence": (
            f"no tracks; the structure of the landing misses is that of "
            f"{' + '.join(f'{e} ({p})' for e, p in zip(v, phases, strict=True))}: held-out "
            f"RMSE {base:.3f} → {rep['verdict']['heldout_rmse_m']:.3f} m"
        ),
    }


def _where_from_tracks(d: Diagnosis, tp: dict[str, Any]) -> dict[str, Any]:
    """The phase the tracks place the gap in; where they allow the verdict's phase too (or
    cannot tell), the verdict's."""
    rep = d.report
    ev = phase_evidence(tp, rep["noise_floor_m"])
    tp["significant"] = ev["significant"]
    v = rep["verdict"]["effects"]
    v_phase = EFFECTS[v[0]].phase if v[0] not in ("none", "unknown") else None
    top = ev["phase"]
    text = "tracks: " + tp["evidence"]
    if top is None:
        if v_phase is None:
            best = _phase_from_verdict(d)
            return {
                "phase": best["phase"],
                "evidence": text
                + "; no phase share is significant in the tracks; "
                + best["evidence"].replace("no tracks; ", ""),
            }
        return {
            "phase": v_phase,
            "evidence": text + f"; no phase share is significant in the tracks (the first "
            f"samples after a release are not seen); the verdict's effect acts in the {v_phase}",
        }
    if v_phase and v_phase != top and top != "measurement":
        own = ev["shares"].get(v_phase, float("nan"))
        if np.isfinite(own) and (
            ev["significant"].get(v_phase) or own >= AGREE_SHARE * ev["shares"][top]
        ):
            return {
                "phase": v_phase,
                "evidence": text + f"; the tracks allow the {v_phase} ({own:.3f} m) beside the "
                f"{top} ({ev['shares'][top]:.3f} m), and the verdict's effect acts there",
            }
    return {"phase": top, "evidence": text}


def _where(d: Diagnosis, tp: dict[str, Any] | None) -> dict[str, Any]:
    """Where the gap lies: from the tracks where they place it, else from the verdict."""
    rep = d.report
    where: dict[str, Any] = {}
    if tp is not None:
        rep["tracks"] = {k: v for k, v in tp.items() if not k.startswith("_")}
        if tp.get("phase"):
            where = _where_from_tracks(d, tp)  # adds the phases' significance to tp
            rep["tracks"].update((k, v) for k, v in tp.items() if not k.startswith("_"))
    if rep["verdict"]["effects"] == ["none"]:
        evidence = _phase_from_verdict(d)["evidence"]
        if where:
            evidence = where["evidence"] + "; " + evidence.replace("no tracks; ", "")
        where = {"phase": "none", "evidence": evidence}
    if tp is not None and "flight_bends" in rep:  # a `none` the tracks' bend made `unknown`
        where = {
            "phase": "flight",
            "evidence": f"tracks: {tp['evidence']}; {rep['flight_bends']['why']}",
        }
    if not where:
        where = _phase_from_verdict(d)
    return where


def _one_pass(
    full: GapProblem,
    pre: np.ndarray,
    tracks: dict[str, np.ndarray] | None,
    identify: bool,
    progress: Callable[[str], None] | None,
) -> tuple[GapProblem, dict[str, Any] | None, Diagnosis]:
    """The diagnosis of the throws not in `pre` (the problem, the tracks' evidence, the
    diagnosis)."""
    prob = full.subset(~pre) if pre.any() and (~pre).sum() >= MIN_THROWS else full
    tp: dict[str, Any] | None = None
    if tracks:
        tf = fit_tracks(prob.table.text("throw_id"), tracks, _k_of(prob.table))
        tp = track_phase(prob, tf)
        add_offset(tp, prob, tf.t0, tf.p0, tf.v0)
    return prob, tp, diagnose(prob, identify=identify, tracks=tp, progress=progress)


def _flags(full: GapProblem, pre: np.ndarray, d: Diagnosis) -> np.ndarray:
    """The throws whose miss under the verdict's effects is impossible (`outliers.flag`);
    an unknown verdict leaves a structured miss, so its rows are those already out (pre).
    A spread the verdict reads (a wind, or one parameter, drawn throw to throw) whitens
    the misses; a verdict that names its effects by their one value tries the one-parameter
    form where its misses flag rows (`_tail_flags`)."""
    if d.report["verdict"]["effects"] == ["unknown"]:
        return pre.copy()
    wind = d.report.get("wind_throw_to_throw")
    if wind and wind["chosen"]:
        # a wind drawn throw to throw: a miss its own spread explains is no outlier
        from cell.gap.wind_throw import whitened_misses

        return flag(whitened_misses(full, d.verdict_effects, wind))
    spread = d.report.get("parameter_throw_to_throw")
    if spread and spread["names"]:
        # a parameter drawn throw to throw: a miss its own spread explains is no outlier
        from cell.gap.param_throw import whitened_spread

        return flag(whitened_spread(full, d.verdict_effects, spread))
    plain = flag(full.residual(np.arange(len(full)), d.verdict_effects))
    if not plain.any() or d.noise is None:
        return plain
    return _tail_flags(full, pre, d, plain, d.noise)


def _tail_flags(full: GapProblem, pre: np.ndarray, d: Diagnosis, plain: np.ndarray,
                nf: NoiseFloor) -> np.ndarray:  # fmt: skip
    """The flags of a verdict that names its effects by their one value, where the plain
    misses (`plain`) flag rows: an effect's one parameter drawn throw to throw leaves its
    draw in each miss, and its tails are no outliers. The form (`cell.gap.param_throw`) is
    fitted on the throws the diagnosis ran on (`pre` out; on the first pass every throw,
    an injected outlier too, whose part along J_i widens the spread), then once more
    without the rows it flags; where it stands both times, the rows flagged on the misses
    whitened by the second fit, and the report carries it (`parameter_throw_to_throw`,
    `tried_for` "outliers": the verdict's effects are the same, the drawn one read as its
    mean and spread). Where it does not stand, the plain flags. `nf`: the diagnosis' floor."""
    from cell.gap.diagnose import spread_report
    from cell.gap.param_throw import param_spread, whitened_spread

    keep, form, out = ~pre, None, plain
    for _ in range(2):
        if keep.sum() < MIN_THROWS:
            break
        form = param_spread(full.subset(keep) if not keep.all() else full,
                            d.verdict_effects, nf)  # fmt: skip
        if form is None or not form["chosen"]:
            out = plain
            break
        out = flag(whitened_spread(full, d.verdict_effects, form))
        keep = ~out
    if form is not None:
        form.update(tried_for="outliers", names=bool(form["chosen"]),
                    verdict_floor_m=d.report["noise_floor_m"])  # fmt: skip
        spread_report(d.report, form)
    return out


def _robust_report(
    table: ThrowTable, full: GapProblem, pre: np.ndarray, flagged: np.ndarray, d: Diagnosis
) -> None:
    """The outliers by row (`cell.gap.outliers`), and the held-out errors plain and robust.

    The diagnosis ran on the throws not in `pre`; `flagged` are the rows reported.
    Plain: every throw (a left-out throw's miss is held out by construction); robust: the
    flagged throws left out."""
    rep = d.report
    all_idx = np.arange(len(full))
    miss = full.residual(all_idx, d.verdict_effects)
    base_sq = np.empty(len(full))
    v_sq = np.empty(len(full))
    base_sq[~pre], v_sq[~pre] = d.baseline_sq, d.verdict_sq
    base_sq[pre] = np.sum(full.residual(all_idx[pre]) ** 2, axis=1)
    v_sq[pre] = np.sum(miss[pre] ** 2, axis=1)
    keep = ~flagged
    row_of = {t: i + 1 for i, t in enumerate(table.text("throw_id"))}
    tids = full.table.text("throw_id")
    rep["outliers"] = {
        "rows": [row_of[tids[i]] for i in np.flatnonzero(flagged)],
        "throw_ids": [str(tids[i]) for i in np.flatnonzero(flagged)],
        "left_out_of_fit": int(pre.sum()),
        "threshold_sigma": float(np.sqrt(threshold_sq(len(full)))),
    }
    rep["baseline"]["heldout_rmse_m"] = float(np.sqrt(base_sq.mean()))
    rep["baseline"]["heldout_rmse_robust_m"] = float(np.sqrt(base_sq[keep].mean()))
    rep["verdict"]["heldout_rmse_m"] = float(np.sqrt(v_sq.mean()))
    rep["verdict"]["heldout_rmse_robust_m"] = float(np.sqrt(v_sq[keep].mean()))
    rep["throws"] = len(full)


def _proposal(full: GapProblem, pre: np.ndarray, d: Diagnosis, tp: dict[str, Any] | None
              ) -> tuple[dict[str, Any], np.ndarray | None]:  # fmt: skip
    """The law proposed for an `unknown` verdict (`cell.gap.propose`), fitted on the
    throws not left out (pre) but for the rows left out that are one object's gap
    (`cell.gap.propose_terms.one_object_rows`), from the terms of the phases the tracks
    allow (`allowed_phases`): on the baseline's misses and on what the partial effects
    leave, whichever the law explains better. With it, every throw's miss under the law of
    the library without the lift across v and the objects' terms, on the throws not in pre
    and from every phase: the misses that flag outliers (`_pass_flags`), so that the
    passes, and the verdict, do not hang on the proposal's wider library (None where that
    law has no term)."""
    from cell.gap.propose_terms import allowed_phases, one_object_rows

    floor = d.report["noise_floor_m"]
    back = one_object_rows(full, pre)
    out, _ = _best_law(full, d, floor, ~pre | back, allowed_phases(tp, floor), True)
    flagging, miss = _best_law(full, d, floor, ~pre, None, False)
    if back.any():
        out["object_rows_kept"] = int(back.sum())
    return out, miss if flagging["law"] else None


def _best_law(full: GapProblem, d: Diagnosis, floor: float, keep: np.ndarray,
              phases: set[str] | None, extended: bool
              ) -> tuple[dict[str, Any], np.ndarray]:  # fmt: skip
    """The law on the baseline's misses or on what the partial effects leave, whichever
    explains more (`cell.gap.propose.propose`), and every throw's miss under it."""
    from cell.gap.propose import propose

    step = bool(d.report.get("landing_step", {}).get("beats"))  # `cell.gap.plane_step`
    prop, miss = propose(full, (), floor, keep=keep, phases=phases, extended=extended, step=step)
    out = {**prop, "on_top_of": []}
    if d.verdict_effects:
        part, miss_p = propose(full, d.verdict_effects, floor, keep=keep, phases=phases,
                               extended=extended, step=step)  # fmt: skip
        if part["heldout_rmse_after_m"] < out["heldout_rmse_after_m"]:
            out, miss = {**part, "on_top_of": [e.name for e in d.verdict_effects]}, miss_p
    return out, miss


MIN_THROWS = 20  # distinct throws: held-out folds, a noise floor and a fit need this many
MAX_PASSES = 4  # diagnoses of one log: every throw, then without the rows flagged


def _pass_flags(full: GapProblem, pre: np.ndarray, d: Diagnosis, from_law: bool,
                tp: dict[str, Any] | None = None
                ) -> tuple[np.ndarray, dict[str, Any] | None, bool]:  # fmt: skip
    """The rows a pass's verdict flags (the pass ran without `pre`), the law proposed for
    an `unknown` verdict (`_proposal`, else None), and whether the rows are that law's.

    A named verdict flags by `_flags`. An unknown one flags the misses its proposed law
    leaves (the scatter alone), once: a pass already run without a proposed law's rows
    (`from_law`) keeps them."""
    if d.report["verdict"]["effects"] != ["unknown"]:
        return _flags(full, pre, d), None, False
    proposal, miss = _proposal(full, pre, d, tp)
    if miss is not None and not from_law:
        return flag(miss), proposal, True
    return pre.copy(), proposal, from_law


def diagnose_log(
    table: ThrowTable,
    ee: EndEffectorParams,
    *,
    base_effects: tuple[Effect, ...] = (),
    objects: dict | None = None,
    tracks: dict[str, np.ndarray] | None = None,
    identify: bool = False,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
    validation: Validation | None = None,
) -> tuple[Diagnosis, Any]:
    """Diagnose a throw log against the configured model.

    Args:
        table: the throw log.
        ee: the configured end-effector parameters.
        base_effects: effects the configured model already has (parameter file).
        objects: identified object parameters by object id (parameter file).
        tracks: observed tracks {throw_id: (k, 4) t, x, y, z} or None.
        identify: re-identify the nominal band law on training throws.
        seed: seed of folds, permutations and bootstraps.
        progress: called with a short label per step.
        validation: the parameter file's held-out misfits per object (added to a
            floor from repeats, `cell.gap.noise`), or None.

    Returns:
        The diagnosis (its `report` is the GAP.md JSON) and the problem it was made on.

    Raises:
        InvalidInput: too few throws to diagnose.
    """
    table.require_varied(MIN_THROWS, "the diagnosis")
    launch = None
    if tracks:
        fit_all = fit_tracks(table.text("throw_id"), tracks, _k_of(table))
        launch = launch_arrays(fit_all)
    try:
        full = build_problem(
            table, ee, base_effects=base_effects, objects=objects, launch=launch, seed=seed,
            validation=validation,
        )  # fmt: skip
    except InvalidInput as exc:
        if tracks and fit_all.unusable:  # say why the tracks did not give the launches
            u = fit_all.unusable
            raise InvalidInput(
                f"{exc}; {len(u)} of {len(tracks)} tracks unusable, e.g. {u[0]['throw_id']}: "
                f"{u[0]['why']}"
            ) from exc
        raise
    pre = np.zeros(len(full), bool)
    prob, tp, d = _one_pass(full, pre, tracks, identify, progress)
    flagged, proposal, by_law = _pass_flags(full, pre, d, False, tp)
    tried = [pre]
    # the rows flagged stay out of the next pass, until the rows a pass is fitted without
    # are the rows its verdict flags: the verdict is judged on the rows it reports (a first
    # pass that an outlier's miss pulls to `none` flags on the baseline's misses, and so the
    # throws the world's effect moves most, which the next pass's verdict takes back)
    while (
        not np.array_equal(flagged, pre)
        and (~flagged).sum() >= MIN_THROWS
        and len(tried) < MAX_PASSES
        and not any(np.array_equal(flagged, t) for t in tried)
    ):
        prob, tp, d = _one_pass(full, flagged, tracks, identify, progress)
        pre, from_law = flagged, by_law
        tried.append(pre)
        flagged, proposal, by_law = _pass_flags(full, pre, d, from_law, tp)
    # passes that do not settle (a cycle: rows a proposed law flagged, which the verdict
    # of the pass without them puts back; or MAX_PASSES run) report the last verdict's
    # flags: no row its own effects explain is called an outlier
    rep = d.report
    if proposal is not None:
        rep["proposal"] = proposal
    if tp is not None:
        # every track given is accounted for, also those of throws the problem dropped
        tp["unusable"], tp["mended"] = list(fit_all.unusable), list(fit_all.mended)
    where = _where(d, tp)
    _robust_report(table, full, pre, flagged, d)
    rows = conditions(prob, d.baseline_sq, d.verdict_sq)
    where["worst"] = worst_conditions(rows, rep["baseline"]["heldout_rmse_m"])
    rep["where"] = where
    rep["conditions"] = rows
    # counted on every throw, as `throws` is: the outliers among them said apart
    rep["other_launcher_throws"] = int((~full.has_stroke).sum())
    rep["outliers"]["other_launcher"] = int((~full.has_stroke & flagged).sum())
    return d, prob
