"""The withheld-effect check: campaigns with a known injected effect, diagnosed blind.

Every campaign is written to a throw log (and its tracks to a tracks file) and read back,
so the diagnosis sees exactly what a user's files would give it, and nothing of the world
that drew it. The check reports the confusion table (truth against verdict), and the
shrink found against the shrink the true effect allows (the held-out RMSE of a model that
knew the effect exactly is the injected scatter itself).

The cases (`CASES`): every effect of the vocabulary drawn with the tool's own formula at a
random size (`cell.gap.world`), none, and a tilted floor outside the vocabulary; then
worlds drawn with other laws than the tool's (`cell.gap.world_laws`): a rolling and a
Coulomb slide, a Gaussian rotor jet decaying with depth, a higher drag, a breeze and a
higher drag at once (a compound flight gap), a tracker off in scale seen only through
another launcher's tracks with disturbed first samples, a slide seen the same way, and a
launch turned about the vertical (outside the vocabulary) with tracks. A case is a plain
dict and `check_case` maps one to a plain dict, so that cases can run anywhere.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from cell.gap.diagnose import VERDICT_RATIO
from cell.gap.run import diagnose_log
from cell.gap.world import TRUTHS, draw_campaign
from cell.gap.world_laws import draw_law_campaign
from cell.log.csvio import read_throws_csv, read_tracks_csv, write_throws_csv
from cell.model.params import DEFAULT_EE

__all__ = ["CASES", "CheckRow", "check_case", "make_cases", "run_check", "confusion_table",
           "format_check"]  # fmt: skip

# cases drawn with other laws than the tool's: name -> (truth, laws, options)
LAW_CASES: dict[str, tuple[str, list[dict[str, Any]], dict[str, Any]]] = {
    "rolling~bounce": ("bounce", [{"law": "rolling", "tau_s": 0.06}], {}),
    "coulomb~bounce": ("bounce", [{"law": "friction", "mu": 1.5}], {}),
    "jet~downwash": (
        "downwash",
        [{"law": "jet", "w_mps": 6.0, "p": 1.0, "radius_m": 0.5, "depth_m": 1.5}],
        {"tracked": True, "disturbed": True},
    ),
    "cd~drag_scale": ("drag_scale", [{"law": "drag", "factor": 1.6}], {}),
    "breeze+cd~pair": (
        "drag_scale+wind",
        [{"law": "breeze", "x_mps": 1.0, "y_mps": 0.6}, {"law": "drag", "factor": 1.7}],
        {},
    ),
    "tracks-only~scale": (
        "tracking_scale",
        [{"law": "scale", "s": 1.04}],
        {"other_launcher": True, "disturbed": True},
    ),
    "tracks-only~rolling": (
        "bounce",
        [{"law": "rolling", "tau_s": 0.05}],
        {"other_launcher": True, "disturbed": True},
    ),
    "yaw~unknown": (
        "unknown",
        [{"law": "yaw", "delta_rad": 0.04}],
        {"tracked": True, "disturbed": True},
    ),
}
CASES: tuple[str, ...] = TRUTHS + tuple(LAW_CASES)


def make_cases(
    names: tuple[str, ...] = CASES, *, n: int = 865, seed: int = 0, repeats: int = 2
) -> list[dict[str, Any]]:
    """The check's cases as plain dicts (each with its own world seed)."""
    rng = np.random.default_rng(seed)
    out = []
    for i, name in enumerate(names):
        case: dict[str, Any] = {
            "name": name,
            "n": n,
            "repeats": repeats,
            "world_seed": int(rng.integers(2**31)),
            "seed": seed + i,
        }
        if name in LAW_CASES:
            truth, laws, opts = LAW_CASES[name]
            case.update(truth=truth, laws=laws, options=opts)
        else:
            case.update(truth=name)
        out.append(case)
    return out


@dataclass(frozen=True)
class CheckRow:
    """One blind diagnosis of a drawn campaign (RMSEs [m], shrinks [%])."""

    truth: str
    verdict: str
    throws: int
    noise_floor_m: float
    baseline_m: float
    after_m: float
    shrink_found_pct: float
    shrink_allowed_pct: float
    scatter_m: float
    seconds: float
    params: dict[str, Any]
    case: str = ""
    where: str = ""
    after_robust_m: float = float("nan")
    outliers_flagged: int = 0

    @property
    def correct(self) -> bool:
        """Verdict equals the truth (and, for a named effect, A ≤ 1.3 F)."""
        if self.verdict != self.truth:
            return False
        if self.truth in ("none", "unknown"):
            return True
        return self.after_m <= VERDICT_RATIO * self.noise_floor_m


def check_case(case: dict[str, Any]) -> dict[str, Any]:
    """Draw one case's campaign, write it to files, read them back and diagnose it blind.

    Args:
        case: a dict of `make_cases`.

    Returns:
        The row as a plain dict (the fields of `CheckRow`).
    """
    rng = np.random.default_rng(case["world_seed"])
    tracks = None
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "throws.csv"
        if "laws" in case:
            lc = draw_law_campaign(
                case["laws"], rng, n=case["n"], repeats=case["repeats"], **case["options"]
            )
            table, scatter, params = lc.table, lc.noise_m, {"laws": case["laws"]}
            if lc.tracks is not None:
                tpath = Path(tmp) / "tracks.csv"
                _write_tracks(lc.tracks, tpath)
                tracks = read_tracks_csv(tpath)
        else:
            camp = draw_campaign(case["truth"], rng, n=case["n"], repeats=case["repeats"])
            table, scatter, params = camp.table, camp.noise_m, dict(camp.params)
        write_throws_csv(table, path)
        table = read_throws_csv(path)
    t0 = time.perf_counter()
    d, _ = diagnose_log(table, DEFAULT_EE, tracks=tracks, seed=case["seed"])
    secs = time.perf_counter() - t0
    rep = d.report
    B = rep["baseline"]["heldout_rmse_m"]
    truth = case["truth"]
    effects = rep["verdict"]["effects"]
    verdict = "+".join(sorted(effects)) if len(effects) > 1 else effects[0]
    return {
        "case": case["name"],
        "truth": truth,
        "verdict": verdict,
        "where": rep["where"]["phase"],
        "throws": rep["throws"],
        "noise_floor_m": rep["noise_floor_m"],
        "baseline_m": B,
        "after_m": rep["verdict"]["heldout_rmse_m"],
        "after_robust_m": rep["verdict"].get("heldout_rmse_robust_m", float("nan")),
        "outliers_flagged": len(rep.get("outliers", {}).get("rows", [])),
        "shrink_found_pct": rep["verdict"]["shrink_pct"],
        "shrink_allowed_pct": 100.0 * (1.0 - scatter / B) if truth != "none" else 0.0,
        "scatter_m": scatter,
        "seconds": secs,
        "params": params,
    }


def _write_tracks(tracks: dict[str, np.ndarray], path: Path) -> None:
    with open(path, "w") as fh:
        fh.write("throw_id,t_s,x_m,y_m,z_m\n")
        for tid, tr in tracks.items():
            for row in tr:
                fh.write(f"{tid},{row[0]:.4f},{row[1]:.5f},{row[2]:.5f},{row[3]:.5f}\n")


def run_check(
    truths: tuple[str, ...] = CASES,
    *,
    n: int = 865,
    seed: int = 0,
    repeats: int = 2,
    progress: Callable[[str], None] | None = None,
    workers: int = 1,
    address: str | None = None,
) -> list[CheckRow]:
    """Draw one campaign per case, diagnose each blind, and compare.

    Args:
        truths: case names (`CASES`: the vocabulary's effects, `none`, `unknown`, and the
            worlds with other laws).
        n: throws per campaign.
        seed: seed of the worlds.
        repeats: how many times each throw configuration is thrown (1: no repeats).
        progress: called with the case name as each campaign is done.
        workers, address: run the cases on Ray (cell.parallel), one case a unit; the
            same rows as the serial run (each case carries its own seeds).

    Returns:
        One row per case.
    """
    from cell.parallel import run_campaign

    cases = make_cases(truths, n=n, seed=seed, repeats=repeats)

    def done(i: int, row: dict[str, Any]) -> None:
        if progress:
            progress(cases[i]["name"])

    rows = run_campaign(
        check_case,
        cases,
        workers=workers,
        address=address,
        desc="cell gap check",
        on_result=done,
        progress=False,
    )
    return [CheckRow(**r) for r in rows]


def confusion_table(rows: list[CheckRow]) -> tuple[list[str], list[str], np.ndarray]:
    """(truth labels, verdict labels, counts[truth, verdict])."""
    truths = list(dict.fromkeys(r.truth for r in rows))
    verdicts = list(dict.fromkeys([*truths, *(r.verdict for r in rows)]))
    m = np.zeros((len(truths), len(verdicts)), int)
    for r in rows:
        m[truths.index(r.truth), verdicts.index(r.verdict)] += 1
    return truths, verdicts, m


def format_check(rows: list[CheckRow]) -> str:
    """The confusion table and the per-campaign figures as text."""
    truths, verdicts, m = confusion_table(rows)
    short = [v.replace("drag_scale", "drag").replace("tracking_scale", "tracking")[:10]
             for v in verdicts]  # fmt: skip
    out = ["confusion (rows: truth, columns: verdict)"]
    out.append(" " * 16 + " ".join(f"{s:>10s}" for s in short))
    for i, t in enumerate(truths):
        out.append(f"{t:16s}" + " ".join(f"{c:10d}" for c in m[i]))
    out.append("")
    out.append(
        f"{'case':20s}{'verdict':>16s}{'where':>12s}{'F [m]':>9s}{'B [m]':>9s}{'A [m]':>9s}{'A/F':>6s}"
        f"{'shrink':>8s}{'allowed':>8s}{'time':>7s}  ok"
    )
    for r in rows:
        out.append(
            f"{r.case or r.truth:20s}{r.verdict:>16s}{r.where:>12s}{r.noise_floor_m:9.4f}{r.baseline_m:9.4f}"
            f"{r.after_m:9.4f}{r.after_m / r.noise_floor_m:6.2f}{r.shrink_found_pct:7.1f}%"
            f"{r.shrink_allowed_pct:7.1f}%{r.seconds:6.1f}s  {'yes' if r.correct else 'NO'}"
        )
    ok = sum(r.correct for r in rows)
    out.append(f"{ok}/{len(rows)} campaigns diagnosed correctly")
    return "\n".join(out)


def check_json(rows: list[CheckRow]) -> dict[str, Any]:
    """The check's result as a JSON-ready dict."""
    truths, verdicts, m = confusion_table(rows)
    return {
        "confusion": {"truths": truths, "verdicts": verdicts, "counts": m.tolist()},
        "campaigns": [{**r.__dict__, "correct": r.correct} for r in rows],
        "correct": int(sum(r.correct for r in rows)),
        "total": len(rows),
    }
