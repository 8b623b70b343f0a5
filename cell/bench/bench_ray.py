"""Campaigns on Ray (cell.parallel): what a task costs besides its own work.

Figures:
    ray_start_s              wall time to start a local Ray of 2 CPUs (what
                             `--workers 2` pays once per command);
    ray_task_overhead_ms     wall time per trivial task of a campaign through
                             `cell.parallel.run_campaign` on those 2 workers (the
                             driver submits, waits, gathers: its cost per unit,
                             which bounds how many units a second one driver feeds);
    ray_roundtrip_ms         median wall time of one trivial task, submitted and
                             gathered alone (a unit's latency);
    scene_chunk_cpu_s        CPU time [s] of one `cell calibrate` unit (8 throws in a
                             fresh scene, in this process): a unit's own work;
    store_chunk_append_ms    median wall time for the driver to append one such unit's
                             8 records to a throw store (one transaction, WAL, full
                             synchronisation), in a temporary folder.

Ray is started here and shut down at the end; a Ray already running in this
process is used as it is (its start time is then not measured: NaN).
"""

from __future__ import annotations

import math
import time

import numpy as np

__all__ = ["run", "echo"]


def echo(k: int) -> int:
    """The trivial unit: its argument back."""
    return k


def _chunk_cpu_s(n_chunks: int) -> tuple[float, list[dict]]:  # type: ignore[type-arg]
    """Mean CPU time of a calibrate unit [s], and the records of the last one."""
    from cell.workflows.campaign import CHUNK, campaign_plan, throw_chunk

    plan = campaign_plan(CHUNK * n_chunks, seed=11)
    cpu = []
    records: list[dict] = []  # type: ignore[type-arg]
    for k in range(n_chunks):
        t0 = time.process_time()
        records = throw_chunk(plan[k * CHUNK : (k + 1) * CHUNK])
        cpu.append(time.process_time() - t0)
    return float(np.mean(cpu)), records


def _append_ms(records: list[dict], n: int) -> float:  # type: ignore[type-arg]
    """Median wall time [ms] of appending the records to a fresh store as one chunk, n times."""
    import tempfile
    from pathlib import Path

    from cell.log.csvio import ThrowTable
    from cell.log.store import ThrowStore

    times = []
    with tempfile.TemporaryDirectory(prefix="cell_bench_store_") as folder:
        with ThrowStore(Path(folder) / "throws.sqlite") as store:
            for k in range(n):
                recs = [{**r, "throw_id": f"{r['throw_id']}-{k}"} for r in records]
                table = ThrowTable.from_records(recs)
                t0 = time.perf_counter()
                store.import_table(table)
                times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def run(quick: bool = False) -> dict[str, float]:
    """The figures above (quick: fewer tasks and one chunk)."""
    import logging

    import ray

    from cell.parallel import run_campaign

    n_tasks = 200 if quick else 2000
    started = not ray.is_initialized()
    start_s = math.nan
    if started:
        t0 = time.perf_counter()
        ray.init(
            address="local",
            num_cpus=2,
            include_dashboard=False,
            log_to_driver=False,
            logging_level=logging.ERROR,
        )
        start_s = time.perf_counter() - t0
    try:
        task = ray.remote(echo)
        ray.get([task.remote(k) for k in range(20)])  # both workers up and warm
        t0 = time.perf_counter()
        out = run_campaign(echo, list(range(n_tasks)), workers=2, progress=False)
        per_task = (time.perf_counter() - t0) / n_tasks
        if out != list(range(n_tasks)):
            raise RuntimeError("internal: the trivial campaign returned wrong results")
        trips = []
        for k in range(20 if quick else 50):
            t0 = time.perf_counter()
            ray.get(task.remote(k))
            trips.append(time.perf_counter() - t0)
    finally:
        if started:
            ray.shutdown()
    chunk_cpu_s, records = _chunk_cpu_s(1 if quick else 2)
    return {
        "ray_start_s": start_s,
        "ray_task_overhead_ms": 1e3 * per_task,
        "ray_roundtrip_ms": 1e3 * float(np.median(trips)),
        "scene_chunk_cpu_s": chunk_cpu_s,
        "store_chunk_append_ms": _append_ms(records, 5 if quick else 20),
    }
