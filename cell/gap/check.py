"""The withheld-effect check: campaigns with a known injected effect, diagnosed blind.

Every campaign is written to a throw log and read back, so the diagnosis sees
exactly what a user's log would give it, and nothing of the world that drew
it. The check reports the confusion table (truth against verdict), and the
shrink found against the shrink the true effect allows (the held-out RMSE of
a model that knew the effect exactly is the injected scatter itself).
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
from cell.log.csvio import read_throws_csv, write_throws_csv
from cell.model.params import DEFAULT_EE

__all__ = ["CheckRow", "run_check", "confusion_table", "format_check"]


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
    params: dict[str, float]

    @property
    def correct(self) -> bool:
        """Verdict equals the truth (and, for a named effect, A ≤ 1.3 F)."""
        if self.verdict != self.truth:
            return False
        if self.truth in ("none", "unknown"):
            return True
        return self.after_m <= VERDICT_RATIO * self.noise_floor_m


def run_check(
    truths: tuple[str, ...] = TRUTHS,
    *,
    n: int = 865,
    seed: int = 0,
    repeats: int = 2,
    progress: Callable[[str], None] | None = None,
    workers: int = 1,
    address: str | None = None,
) -> list[CheckRow]:
    """Draw one campaign per truth, diagnose each blind, and compare.

    Args:
        truths: effect names of the vocabulary, `none` and `unknown`.
        n: throws per campaign.
        seed: seed of the world.
        repeats: how many times each throw configuration is thrown (1: no repeats).
        progress: called with the truth as each campaign is done.
        workers, address: run the campaigns on Ray (cell.parallel); the same rows as
            the serial run (each campaign carries its own seeds).

    Returns:
        One row per campaign.
    """
    from cell.parallel import run_campaign

    rng = np.random.default_rng(seed)
    units = [
        CheckCase(truth, int(rng.integers(2**31)), n, repeats, seed + i)
        for i, truth in enumerate(truths)
    ]

    def done(i: int, row: CheckRow) -> None:
        if progress:
            progress(row.truth)

    return run_campaign(
        check_case,
        units,
        workers=workers,
        address=address,
        desc="cell gap check",
        on_result=done,
        progress=False,
    )


@dataclass(frozen=True)
class CheckCase:
    """One campaign of `cell gap check`: its truth and seeds (a picklable unit)."""

    truth: str
    world_seed: int
    n: int
    repeats: int
    diagnose_seed: int


def check_case(case: CheckCase) -> CheckRow:
    """Draw the case's campaign, write and read it back as a log, diagnose it blind."""
    camp = draw_campaign(
        case.truth, np.random.default_rng(case.world_seed), n=case.n, repeats=case.repeats
    )
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "campaign.csv"
        write_throws_csv(camp.table, path)
        table = read_throws_csv(path)
    t0 = time.perf_counter()
    d, _ = diagnose_log(table, DEFAULT_EE, seed=case.diagnose_seed)
    secs = time.perf_counter() - t0
    rep = d.report
    B = rep["baseline"]["heldout_rmse_m"]
    allowed = 100.0 * (1.0 - camp.noise_m / B) if case.truth != "none" else 0.0
    return CheckRow(
        truth=case.truth,
        verdict="+".join(rep["verdict"]["effects"]),
        throws=rep["throws"],
        noise_floor_m=rep["noise_floor_m"],
        baseline_m=B,
        after_m=rep["verdict"]["heldout_rmse_m"],
        shrink_found_pct=rep["verdict"]["shrink_pct"],
        shrink_allowed_pct=allowed,
        scatter_m=camp.noise_m,
        seconds=secs,
        params=camp.params,
    )


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
    short = [v[:8] for v in verdicts]
    out = ["confusion (rows: truth, columns: verdict)"]
    out.append(" " * 16 + " ".join(f"{s:>8s}" for s in short))
    for i, t in enumerate(truths):
        out.append(f"{t:16s}" + " ".join(f"{c:8d}" for c in m[i]))
    out.append("")
    out.append(
        f"{'truth':16s}{'verdict':>16s}{'F [m]':>9s}{'B [m]':>9s}{'A [m]':>9s}{'A/F':>6s}"
        f"{'shrink':>8s}{'allowed':>8s}{'time':>7s}  ok"
    )
    for r in rows:
        out.append(
            f"{r.truth:16s}{r.verdict:>16s}{r.noise_floor_m:9.4f}{r.baseline_m:9.4f}"
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
