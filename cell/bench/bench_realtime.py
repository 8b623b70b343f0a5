"""Planning in real time: each item's planning wall time and the real-time rate.

`cell bench --only realtime` runs the demo (`tasks/bins.yaml`) and two random layouts of
the test set (seeds 1000 and 1001, Panda) with the default options and reports, for
each, the 95th percentile, median and maximum of the items' `plan_s` (the wall time
[s] the cell spends on an item other than stepping the plant, `cell.loop.ItemLoop`),
its process CPU time [s], and the simulated and real-time items per hour
(`cell.results.realtime_cycles`). `--quick`: the first 4 items of each.

`realtime_figures` gives the same figures of a `cell bench sort` campaign
(`cell.bench.bench_sort.summarise_layouts`). All of them are wall-clock figures of
this machine (`cell.results.WALL_CLOCK_KEYS`): a loaded machine inflates them; the
1-minute load average and the cores are reported with them.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from cell.results import cores, rate_per_hour, realtime_cycles

__all__ = ["DEMO_JOB", "LAYOUT_SEEDS", "realtime_figures", "run"]

DEMO_JOB = Path(__file__).resolve().parents[2] / "tasks" / "bins.yaml"
LAYOUT_SEEDS = (1000, 1001)  # the test set's first two (cell.bench.bench_sort.LAYOUT_SETS)


def _plan_stats(plans: list[float], prefix: str = "plan_s") -> dict[str, float]:
    p = np.array([v for v in plans if math.isfinite(v)], float)
    if not p.size:
        return {}
    return {
        f"{prefix}_median": float(np.median(p)),
        f"{prefix}_p95": float(np.percentile(p, 95)),
        f"{prefix}_max": float(p.max()),
    }


def realtime_figures(layouts: list[dict[str, Any]]) -> dict[str, Any]:
    """{plan_s_median, plan_s_p95, plan_s_max [s], items_per_hour_realtime, cores} of
    `run_layout` results: the items' planning wall times over all layouts, and the items
    in their bins per hour of the layouts' real-time cycles (each layout a run of its
    own, its first plan not hidden); {} when an item has no `plan_s` (a result written
    before it was measured)."""
    items = [it for lay in layouts for it in lay["items"]]
    if not items or any("plan_s" not in it for it in items):
        return {}
    real = sum(
        sum(
            realtime_cycles(
                [float(it["cycle_time_s"]) for it in lay["items"]],
                [float(it["plan_s"]) for it in lay["items"]],
            )
        )
        for lay in layouts
    )
    k = sum(bool(it["in_bin"]) for it in items)
    return {
        **_plan_stats([float(it["plan_s"]) for it in items]),
        "items_per_hour_realtime": rate_per_hour(k, real),
        "cores": cores(),
    }


def _run_job(job: Any, tag: str) -> dict[str, float]:
    """Run `job` with the default options: its planning and rate figures, named `tag`."""
    from cell.orchestrator import Orchestrator

    orch = Orchestrator(job)
    try:
        c0 = time.process_time()
        s = orch.run()
        cpu = time.process_time() - c0
    finally:
        orch.close()
    step = float(orch.scene.step_wall_s)
    return {
        f"{tag}_items": float(s.items),
        **_plan_stats([r.plan_s for r in s.results], f"{tag}_plan_s"),
        f"{tag}_wall_s": s.wall_time_s,
        f"{tag}_cpu_s": cpu,
        f"{tag}_step_wall_s": step,
        f"{tag}_sim_s": s.sim_time_s,
        f"{tag}_items_per_hour": s.items_per_hour,
        f"{tag}_items_per_hour_realtime": s.items_per_hour_realtime,
    }


def run(quick: bool = False) -> dict[str, float]:
    import yaml

    from cell.jobgen import random_job
    from cell.jobs import load_job, parse_job

    n = 4 if quick else 0
    demo = load_job(DEMO_JOB)
    figures = _run_job(replace(demo, max_items=n) if n else demo, "realtime_demo")
    for seed in LAYOUT_SEEDS:
        doc = random_job(seed, "panda", refused=[])
        job = parse_job(yaml.safe_dump(doc, sort_keys=False), f"<random layout {seed}>")
        figures.update(_run_job(replace(job, max_items=n) if n else job, f"realtime_{seed}"))
    figures["realtime_cores"] = float(cores())
    figures["realtime_load_1min"] = os.getloadavg()[0]
    return figures
