"""`cell gap check` on worlds from another implementation (`cell.gap.world_other`).

Each case is a world (a list of effects, each with its law form), the verdict it should
get, the phase of each effect, and the parameters the diagnosis should find (the world's
law in the diagnosis' terms). A case passes when the verdict names the effects right
(diagonal), every effect's phase is right, every expected parameter is within 30 % of
the world's (a tracking scale within 0.5 %; a constant the tool gave per object: every
object's value), and the verdict's robust held-out RMSE is
within 1.3 × the world's own floor (the logged landings' RMS distance from the world
without scatter and without throw-to-throw variation) counted on the rows that RMSE was
counted on: the rows the tool flags left out, and the injected outliers (mis-logged, no
part of the world's noise) never counted.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from cell.gap.run import diagnose_log
from cell.gap.world_other import draw_other_campaign
from cell.log.csvio import read_throws_csv, write_throws_csv
from cell.log.table import ThrowTable
from cell.model.params import DEFAULT_EE

__all__ = ["OTHER_CASES", "FAST_OTHER", "check_other_case", "judge_campaign", "kept_rows",
           "other_cases", "run_other_check", "other_json", "format_other"]  # fmt: skip

PARAM_TOL = 0.30
SCALE_TOL = 0.005
FLOOR_RATIO = 1.30

BM = "band_mass"
RP = "release_pitch"


def _e(kind: str, form: str = "const", **kw: Any) -> dict[str, Any]:
    return {"kind": kind, "form": form, **kw}


_PER_OBJ_BM = {"cube50": 0.010, "cube30": 0.006, "cuboid_c": 0.030, "cyl50": 0.015,
               "cyl70": 0.035, "sphere40": 0.008, "sphere70": 0.020, "block40": 0.012}  # fmt: skip
_PER_OBJ_CD = {"cube50": 1.4, "cube30": 2.0, "cuboid_c": 1.2, "cyl50": 1.6, "cyl70": 1.3,
               "sphere40": 2.2, "sphere70": 1.5, "block40": 1.8}  # fmt: skip

# name -> (effects, truth, {effect: phase}, {effect: {param: value}}, options)
OTHER_CASES: dict[
    str, tuple[list[dict[str, Any]], str, dict[str, str], dict[str, Any], dict[str, Any]]
] = {  # fmt: skip
    "o:none": ([], "none", {}, {}, {}),
    "o:none+outliers": ([], "none", {}, {}, {"outliers": 0.05}),
    "o:bm-const": ([_e(BM, value=0.02)], BM, {BM: "launch"}, {BM: {"mass_kg": 0.02}}, {}),
    "o:bm-stroke": ([_e(BM, "stroke", k=0.15)], BM, {BM: "launch"}, {BM: {"k": 0.15}}, {}),
    "o:bm-mass": ([_e(BM, "mass", k=0.3)], BM, {BM: "launch"}, {BM: {"k": 0.3}}, {}),
    "o:bm-object": (
        [_e(BM, "object", value=0.015, per_object=_PER_OBJ_BM)],
        BM,
        {BM: "launch"},
        {},
        {},
    ),  # fmt: skip
    "o:bm-throw": (
        [_e(BM, "throw", value=0.02, sd=0.004)],
        BM,
        {BM: "launch"},
        {BM: {"mass_kg": 0.02}},
        {},
    ),  # fmt: skip
    "o:bm-const+outliers": (
        [_e(BM, value=0.02)],
        BM,
        {BM: "launch"},
        {BM: {"mass_kg": 0.02}},
        {"outliers": 0.05},
    ),  # fmt: skip
    "o:bm-stroke+outliers": (
        [_e(BM, "stroke", k=0.3)],
        BM,
        {BM: "launch"},
        {BM: {"k": 0.3}},
        {"outliers": 0.05},
    ),  # fmt: skip
    "o:pitch-const": ([_e(RP, value=0.08)], RP, {RP: "launch"}, {RP: {"delta_rad": 0.08}}, {}),
    "o:pitch-neg": ([_e(RP, value=-0.06)], RP, {RP: "launch"}, {RP: {"delta_rad": -0.06}}, {}),
    "o:pitch-mass": ([_e(RP, "mass", k=-1.0)], RP, {RP: "launch"}, {RP: {"k": -1.0}}, {}),
    "o:pitch-stroke": ([_e(RP, "stroke", k=1.2)], RP, {RP: "launch"}, {RP: {"k": 1.2}}, {}),
    "o:pitch-throw": (
        [_e(RP, "throw", value=0.07, sd=0.01)],
        RP,
        {RP: "launch"},
        {RP: {"delta_rad": 0.07}},
        {},
    ),  # fmt: skip
    "o:pitch-mass+outliers": (
        [_e(RP, "mass", k=-1.0)],
        RP,
        {RP: "launch"},
        {RP: {"k": -1.0}},
        {"outliers": 0.05},
    ),  # fmt: skip
    "o:damping": (
        [_e("band_damping", value=3.0)],
        "band_damping",
        {"band_damping": "launch"},
        {"band_damping": {"per_m": 3.0}},
        {},
    ),  # fmt: skip
    "o:stroke-offset": (
        [_e("stroke_offset", value=0.008)],
        "stroke_offset",
        {"stroke_offset": "launch"},
        {"stroke_offset": {"delta_m": 0.008}},
        {},
    ),
    "o:wind": (
        [_e("wind", x_mps=1.2, y_mps=-0.6)],
        "wind",
        {"wind": "flight"},
        {"wind": {"x_mps": 1.2, "y_mps": -0.6}},
        {},
    ),  # fmt: skip
    "o:wind-throw": (
        [_e("wind", "throw", x_mps=1.0, y_mps=0.8, sd=0.3)],
        "wind",
        {"wind": "flight"},
        {"wind": {"x_mps": 1.0, "y_mps": 0.8}},
        {},
    ),
    "o:wind+outliers": (
        [_e("wind", x_mps=-1.0, y_mps=1.0)],
        "wind",
        {"wind": "flight"},
        {"wind": {"x_mps": -1.0, "y_mps": 1.0}},
        {"outliers": 0.05},
    ),
    "o:drag-const": (
        [_e("drag_scale", value=1.8)],
        "drag_scale",
        {"drag_scale": "flight"},
        {"drag_scale": {"factor": 1.8}},
        {},
    ),  # fmt: skip
    "o:drag-low": (
        [_e("drag_scale", value=0.5)],
        "drag_scale",
        {"drag_scale": "flight"},
        {"drag_scale": {"factor": 0.5}},
        {},
    ),  # fmt: skip
    "o:drag-object": (
        [_e("drag_scale", "object", value=1.6, per_object=_PER_OBJ_CD)],
        "drag_scale",
        {"drag_scale": "flight"},
        {},
        {},
    ),  # fmt: skip
    "o:drag-throw": (
        [_e("drag_scale", "throw", value=1.8, sd=0.15)],
        "drag_scale",
        {"drag_scale": "flight"},
        {"drag_scale": {"factor": 1.8}},
        {},
    ),
    "o:downwash": (
        [_e("downwash", w_mps=8.0, radius_m=0.4, depth_m=1.2)],
        "downwash",
        {"downwash": "flight"},
        {},
        {"drone_share": 0.5},
    ),  # fmt: skip
    "o:slide-rolling": (
        [_e("slide", "const", tau_s=0.05)],
        "bounce",
        {"bounce": "landing"},
        {"bounce": {"tau_s": 0.05}},
        {},
    ),  # fmt: skip
    "o:slide-friction": (
        [_e("slide", "friction", mu=1.2)],
        "bounce",
        {"bounce": "landing"},
        {"bounce": {"inv_mu": 1 / 1.2}},
        {},
    ),  # fmt: skip
    "o:slide+outliers": (
        [_e("slide", "const", tau_s=0.05)],
        "bounce",
        {"bounce": "landing"},
        {"bounce": {"tau_s": 0.05}},
        {"outliers": 0.05},
    ),  # fmt: skip
    "o:scale": (
        [_e("tracking_scale", value=1.03)],
        "tracking_scale",
        {"tracking_scale": "measurement"},
        {"tracking_scale": {"scale_factor": 1.03}},
        {},
    ),  # fmt: skip
    "o:bm-stroke+slide": (
        [_e(BM, "stroke", k=0.3), _e("slide", "const", tau_s=0.05)],
        "band_mass+bounce",
        {BM: "launch", "bounce": "landing"},
        {BM: {"k": 0.3}, "bounce": {"tau_s": 0.05}},
        {},
    ),  # fmt: skip
    "o:pitch+slide": (
        [_e(RP, value=0.08), _e("slide", "friction", mu=1.2)],
        "bounce+release_pitch",
        {RP: "launch", "bounce": "landing"},
        {RP: {"delta_rad": 0.08}, "bounce": {"inv_mu": 1 / 1.2}},
        {},
    ),
    "o:wind+slide": (
        [_e("wind", x_mps=1.0, y_mps=0.5), _e("slide", "const", tau_s=0.05)],
        "bounce+wind",
        {"wind": "flight", "bounce": "landing"},
        {"wind": {"x_mps": 1.0, "y_mps": 0.5}, "bounce": {"tau_s": 0.05}},
        {},
    ),
    "o:bm+wind": (
        [_e(BM, value=0.02), _e("wind", x_mps=-0.8, y_mps=0.8)],
        "band_mass+wind",
        {BM: "launch", "wind": "flight"},
        {BM: {"mass_kg": 0.02}, "wind": {"x_mps": -0.8, "y_mps": 0.8}},
        {},
    ),
    "o:downwash+wind": (
        [_e("downwash", w_mps=8.0, radius_m=0.4, depth_m=1.2), _e("wind", x_mps=1.0, y_mps=-0.5)],
        "downwash+wind",
        {"downwash": "flight", "wind": "flight"},
        {"wind": {"x_mps": 1.0, "y_mps": -0.5}},
        {"drone_share": 0.5},
    ),
    "o:drag+slide": (
        [_e("drag_scale", value=1.7), _e("slide", "friction", mu=1.5)],
        "bounce+drag_scale",
        {"drag_scale": "flight", "bounce": "landing"},
        {"drag_scale": {"factor": 1.7}},
        {},
    ),  # fmt: skip
    "o:yaw-stroke": ([_e("release_yaw", "stroke", k=1.0)], "unknown", {}, {}, {}),
    "o:yaw-const": ([_e("release_yaw", value=0.05)], "unknown", {}, {}, {}),
    "o:side-force": ([_e("side_force", x_mps2=0.0, y_mps2=0.25)], "unknown", {}, {}, {}),
    "o:yaw+outliers": (
        [_e("release_yaw", "stroke", k=1.0)],
        "unknown",
        {},
        {},
        {"outliers": 0.05},
    ),  # fmt: skip
    "o:none-arm": ([], "none", {}, {}, {"drone_share": 0.0}),
    "o:bm-stroke-arm": (
        [_e(BM, "stroke", k=0.25)],
        BM,
        {BM: "launch"},
        {BM: {"k": 0.25}},
        {"drone_share": 0.0},
    ),  # fmt: skip
    "o:wind-drone": (
        [_e("wind", x_mps=0.8, y_mps=0.8)],
        "wind",
        {"wind": "flight"},
        {"wind": {"x_mps": 0.8, "y_mps": 0.8}},
        {"drone_share": 0.6},
    ),
}
FAST_OTHER = ("o:bm-stroke", "o:none", "o:yaw-stroke")


def other_cases(names: tuple[str, ...] | None = None, *, n: int = 400, seed: int = 0
                ) -> list[dict[str, Any]]:  # fmt: skip
    """The cases as plain dicts (each with its own world seed)."""
    rng = np.random.default_rng(seed + 57)
    # seeds drawn over every case in table order: a case named alone is the table's row
    seeds = {name: (int(rng.integers(2**31)), seed + i) for i, name in enumerate(OTHER_CASES)}
    out = []
    for name in names or tuple(OTHER_CASES):
        effects, truth, phases, expect, opts = OTHER_CASES[name]
        world_seed, case_seed = seeds[name]
        out.append({"name": name, "n": n, "world_seed": world_seed,
                    "seed": case_seed, "effects": effects, "truth": truth, "phases": phases,
                    "expect": expect, "options": opts})  # fmt: skip
    return out


def _params_ok(expect: dict[str, Any], got: dict[str, Any],
               law_mean: dict[str, Any] | None = None) -> tuple[bool, dict[str, Any]]:  # fmt: skip
    """Whether every expected parameter is within tolerance; the relative errors.

    A `one_of` expectation is a value the world measured as one constant over the log
    (a bounce's slide); where the tool chose a law in a covariate for it, the law's value
    averaged over the log's throws (the report's `law_mean`) is what is compared."""
    errs: dict[str, Any] = {}
    ok = True
    for eff, ps in expect.items():
        if "one_of" in ps:  # the law the tool chose among the world's measured ones
            have = got.get(eff, {})
            mean = (law_mean or {}).get(eff, {})
            if not any(set(a) <= set(have) for a in ps["one_of"]) and mean:
                got = {**got, eff: {**have, **mean}}
                have = got[eff]
            ps = next((a for a in ps["one_of"] if set(a) <= set(have)), ps["one_of"][0])
        flat = dict(ps)
        if "per_object" in flat:
            per = flat.pop("per_object")
            have = got.get(eff, {}).get("per_object", {})
            flat.update({f"per_object.{o}": val for o, val in per.items()})
            got = {
                **got,
                eff: {**got.get(eff, {}), **{f"per_object.{o}": val for o, val in have.items()}},
            }
        for k, v in flat.items():
            val = got.get(eff, {}).get(k)
            tol = SCALE_TOL if eff == "tracking_scale" else PARAM_TOL
            per = got.get(eff, {}).get("per_object")
            if val is None and isinstance(per, dict) and per and eff != "tracking_scale":
                # a constant world told by a per-object law: every object's value is judged
                rel = max(abs(float(x) - v) / abs(v) for x in per.values())
                errs[f"{eff}.{k}"] = float(rel)
                ok = ok and rel <= tol
                continue
            if val is None:
                errs[f"{eff}.{k}"] = None
                ok = False
                continue
            rel = abs(val - v) / abs(v) if eff != "tracking_scale" else abs(val - v)
            errs[f"{eff}.{k}"] = float(rel)
            ok = ok and rel <= tol
    return ok, errs


def check_other_case(case: dict[str, Any]) -> dict[str, Any]:
    """Draw one case's campaign, write it to a throw log, read it back and diagnose it blind
    (`judge_campaign`)."""
    rng = np.random.default_rng(case["world_seed"])
    camp = draw_other_campaign(case["effects"], rng, n=case["n"], **case["options"])
    return judge_campaign(case, camp.records, camp.floor_on, camp.outliers)


def kept_rows(n: int, flagged: list[int]) -> np.ndarray:
    """The mask over a log's n records of the rows the robust held-out RMSE is counted on:
    every row but those flagged (`flagged`: rows, 1 = the first data row)."""
    keep = np.ones(n, bool)
    keep[np.asarray(flagged, int) - 1] = False
    return keep


def judge_campaign(case: dict[str, Any], records: list[dict[str, Any]],
                   floor_on: Callable[[np.ndarray | None], float],
                   outliers: tuple[int, ...], *, ee: Any = DEFAULT_EE,
                   objects: dict[str, Any] | None = None,
                   validation: Any = None,
                   tracks: dict[str, np.ndarray] | None = None) -> dict[str, Any]:  # fmt: skip
    """Write a case's campaign to a throw log, read it back, diagnose it blind against the
    model as configured (`ee`, `objects`, the parameter file's `validation`) and judge the
    verdict.

    `floor_on(keep)` is the world's floor [m] counted on the records `keep` (a mask; every
    record when None), an injected outlier never counted. The robust held-out RMSE (the
    flagged rows left out) is judged against the floor on the rows it was counted on
    (`world_floor_kept_m`: a flagged row out, and with it its repeat's share of the
    repeats' scatter); the plain one (every row) against the floor on every row
    (`world_floor_m`), which judges only where the report has no robust RMSE (`judged`).

    Returns:
        The row as a plain dict: the verdict, its phases, parameters and their errors, the
        world's floors and the tool's, the held-out RMSEs plain and robust, the outliers
        flagged against the true ones, and whether it passes.
    """
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "throws.csv"
        write_throws_csv(ThrowTable.from_records(records), path)
        table = read_throws_csv(path)
    t0 = time.perf_counter()
    d, _ = diagnose_log(
        table, ee, objects=objects, seed=case["seed"], validation=validation, tracks=tracks
    )
    secs = time.perf_counter() - t0
    rep = d.report
    v = rep["verdict"]
    effects = v["effects"]
    verdict = "+".join(sorted(effects))
    phases = v.get("phases", {})
    phase_ok = all(phases.get(e) == p for e, p in case["phases"].items())
    params_ok, errs = _params_ok(case["expect"], v.get("params", {}), v.get("law_mean"))
    rows = sorted(rep.get("outliers", {}).get("rows", []))
    floor_m = floor_on(None)
    floor_kept = floor_on(kept_rows(len(records), rows))
    robust = "heldout_rmse_robust_m" in v
    after = v["heldout_rmse_robust_m"] if robust else v["heldout_rmse_m"]
    judge_floor = floor_kept if robust else floor_m
    diag = verdict == case["truth"]
    floor_ok = case["truth"] in ("none", "unknown") or after <= FLOOR_RATIO * judge_floor
    flagged = set(rows)
    true_out = {i + 1 for i in outliers}  # rows: 1 = first data row
    return {
        "case": case["name"], "truth": case["truth"], "verdict": verdict,
        "diagonal": bool(diag), "phases": phases, "phase_ok": bool(phase_ok),
        "laws": v.get("laws", {}), "params": v.get("params", {}), "param_errors": errs,
        "params_ok": bool(params_ok), "world_floor_m": floor_m,
        "world_floor_kept_m": floor_kept,
        "tool_floor_m": rep["noise_floor_m"], "baseline_m": rep["baseline"]["heldout_rmse_m"],
        "after_m": v["heldout_rmse_m"], "after_robust_m": after,
        "after_over_floor": after / judge_floor,
        "plain_over_floor": v["heldout_rmse_m"] / floor_m,
        "judged": ("after_robust_m / world_floor_kept_m" if robust
                   else "after_m / world_floor_m"),
        "floor_ok": bool(floor_ok),
        "outliers_true": len(true_out), "outliers_found": len(flagged & true_out),
        "outliers_false": len(flagged - true_out), "outlier_rows": rows,
        "proposal": rep.get("proposal", {}).get("law"),
        "wind_throw_to_throw": rep.get("wind_throw_to_throw"),
        "parameter_throw_to_throw": rep.get("parameter_throw_to_throw"),
        "passes": bool(diag and phase_ok and params_ok and floor_ok), "seconds": secs,
    }  # fmt: skip


def run_other_check(
    names: tuple[str, ...] | None = None,
    *,
    n: int = 400,
    seed: int = 0,
    progress: Any = None,
    workers: int = 1,
    address: str | None = None,
) -> list[dict[str, Any]]:
    """Every case (or `names`) drawn, diagnosed blind and judged; one row per case (the
    same rows serially or on Ray: each case carries its own seeds)."""
    from cell.parallel import run_campaign

    cases = other_cases(names, n=n, seed=seed)

    def done(i: int, row: dict[str, Any]) -> None:
        if progress:
            progress(cases[i]["name"])

    return list(
        run_campaign(check_other_case, cases, workers=workers, address=address,
                     desc="cell gap check --worlds other", on_result=done, progress=False)
    )  # fmt: skip


def other_json(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The table as a JSON-ready dict, with its totals per criterion."""
    return {
        "criteria": {"param_tol": PARAM_TOL, "scale_tol": SCALE_TOL, "floor_ratio": FLOOR_RATIO},
        "campaigns": rows,
        "diagonal": sum(r["diagonal"] for r in rows),
        "phase_ok": sum(r["phase_ok"] for r in rows),
        "params_ok": sum(r["params_ok"] for r in rows),
        "floor_ok": sum(r["floor_ok"] for r in rows),
        "passes": sum(r["passes"] for r in rows),
        "total": len(rows),
    }


def format_other(rows: list[dict[str, Any]]) -> str:
    """The table as text: per case the verdict, its laws, A / world floor and the checks."""
    out = [f"{'case':24s}{'truth':>20s}{'verdict':>20s}{'A/Fw':>7s}{'out':>7s}  "
           f"diag phase param floor  law or proposal"]  # fmt: skip
    for r in rows:
        law = "; ".join(f"{k}: {v}" for k, v in r["laws"].items()) or (r["proposal"] or "")
        ok = " ".join(f"{'yes' if r[k] else 'NO':>5s}" for k in
                      ("diagonal", "phase_ok", "params_ok", "floor_ok"))  # fmt: skip
        outl = f"{r['outliers_found']}/{r['outliers_true']}" + (
            f"+{r['outliers_false']}" if r["outliers_false"] else "")  # fmt: skip
        out.append(f"{r['case']:24s}{r['truth']:>20s}{r['verdict']:>20s}"
                   f"{r['after_over_floor']:7.2f}{outl:>7s}  {ok}  {law}")  # fmt: skip
    j = other_json(rows)
    out.append(f"{j['passes']}/{j['total']} cases pass (diagonal {j['diagonal']}, phase "
               f"{j['phase_ok']}, parameters within 30 % {j['params_ok']}, A ≤ 1.3 × world "
               f"floor {j['floor_ok']})")  # fmt: skip
    return "\n".join(out)
