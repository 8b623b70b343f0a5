"""The diagnosis time for a thesis-sized campaign (865 throws)."""

from __future__ import annotations

import time

import numpy as np

from cell.gap.run import diagnose_log
from cell.gap.world import draw_campaign
from cell.model.params import DEFAULT_EE


def run(quick: bool = False) -> dict[str, float | str]:
    """`gap_s`: seconds to diagnose a campaign (band mass withheld) of 865 throws."""
    n = 300 if quick else 865
    camp = draw_campaign("band_mass", np.random.default_rng(2026), n=n)
    t0 = time.perf_counter()
    d, _ = diagnose_log(camp.table, DEFAULT_EE)
    secs = time.perf_counter() - t0
    return {
        "gap_s": round(secs, 2),
        "gap_throws": len(camp.table),
        "gap_verdict": "+".join(d.report["verdict"]["effects"]),
    }
