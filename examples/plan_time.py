"""The planning's cost of a job, item by item: wall time (`plan_s`) and the CPU time of each
decision, and a hash of the items' results to check that a speedup decides the same.

    PYTHONPATH=$PWD python examples/plan_time.py tasks/bins.yaml 8   # the demo's first 8 items
    PYTHONPATH=$PWD python examples/plan_time.py 0 5                 # tune layout 0's first 5
    PYTHONPATH=$PWD python examples/plan_time.py tasks/bins.yaml 0 release_timed_max=0
        # the whole demo with a constant of `cell.arm.tuning.ArmTuning` set otherwise

Prints one JSON object: the run's items, in_bin, sim_s, items/h (simulated and real time),
plan_s's p95/median/max/sum [s] (wall), decide_cpu_p95/sum [s] (`time.process_time`
around `Orchestrator.decide`), the run's CPU time [s], its wall time and the plant's
stepping wall time [s], the 1-minute load average, and `sig`: a hash of the items'
results without `plan_s` and the throw ids (equal before and after a pure speedup).
docs/realtime.md's table was measured with it. With two plan workers (`cell.arm.fork`;
`plan_workers=1` plans serially) also the children's CPU time per decision and its sum
(not in the process's CPU time), the parent's wall time waiting for them, each
decision's CPU time on its critical path (`decide_critical_cpu`: the parent's, plus what
its child took beyond the parent's own branch; its p95 and max) and what the forks did.
"""

from __future__ import annotations

import ast
import dataclasses
import hashlib
import json
import os
import sys
import time

import numpy as np
import yaml
from threadpoolctl import threadpool_limits

from cell.arm.tuning import TUNING
from cell.jobgen import random_job
from cell.jobs import load_job, parse_job
from cell.orchestrator import Orchestrator


def main(what: str, n: int, tuning: dict[str, object] | None = None) -> dict[str, object]:
    if what.endswith(".yaml"):
        job = load_job(what)
    else:  # a random layout's seed (Panda), as `cell bench sort` draws it
        doc = random_job(int(what), "panda", refused=[])
        job = parse_job(yaml.safe_dump(doc, sort_keys=False), f"<random layout {what}>")
    if n:
        job = dataclasses.replace(job, max_items=n)
    tuning = dict(tuning or {})
    workers = tuning.pop("plan_workers", None)
    orch = Orchestrator(
        job,
        session="plan-time",
        tuning=dataclasses.replace(TUNING, **tuning),
        plan_workers=workers,  # type: ignore[arg-type]
    )
    dec_cpu: list[float] = []
    child_cpu: list[float] = []  # the forked branches' CPU (`cell.arm.fork`)
    waits: list[float] = []  # the parent's wall time waiting for their answers
    crit: list[float] = []  # CPU on the critical path: the parent's, the child's beyond it
    decide = orch.decide

    def timed(*args: object) -> object:
        c, k, w = time.process_time(), orch.fork_stats.child_cpu_s, orch.fork_stats.wait_s
        b = orch.fork_stats.beyond_cpu_s
        try:
            return decide(*args)  # type: ignore[arg-type]
        finally:
            dec_cpu.append(time.process_time() - c)
            child_cpu.append(orch.fork_stats.child_cpu_s - k)
            waits.append(orch.fork_stats.wait_s - w)
            crit.append(dec_cpu[-1] + orch.fork_stats.beyond_cpu_s - b)

    orch.decide = timed  # type: ignore[method-assign]
    with threadpool_limits(limits=1):  # one BLAS thread, as `cell bench sort` runs
        c0 = time.process_time()
        s = orch.run()
        cpu = time.process_time() - c0
    orch.close()
    keep = [
        {k: v for k, v in dataclasses.asdict(r).items() if k not in ("plan_s", "throw_id")}
        for r in s.results
    ]
    p = np.array([r.plan_s for r in s.results])
    return {
        "job": what,
        "items": s.items,
        "in_bin": s.in_bin,
        "sim_s": round(s.sim_time_s, 3),
        "items_per_hour": round(s.items_per_hour),
        "items_per_hour_realtime": round(s.items_per_hour_realtime),
        "plan_s_p95": round(float(np.percentile(p, 95)), 3),
        "plan_s_median": round(float(np.median(p)), 3),
        "plan_s_max": round(float(p.max()), 3),
        "plan_s_sum": round(float(p.sum()), 2),
        "decide_cpu_p95": round(float(np.percentile(dec_cpu, 95)), 3),
        "decide_cpu_sum": round(sum(dec_cpu), 2),
        "decide_cpu": [round(x, 2) for x in dec_cpu],
        "decide_child_cpu_sum": round(sum(child_cpu), 2),
        "decide_critical_cpu_p95": round(float(np.percentile(crit, 95)), 3),
        "decide_critical_cpu_max": round(max(crit), 3),
        "decide_critical_cpu": [round(x, 2) for x in crit],
        "decide_child_cpu": [round(x, 2) for x in child_cpu],
        "decide_wait": [round(x, 2) for x in waits],
        "plan_s": [round(float(x), 2) for x in p],
        "plan_workers": orch.plan_workers,
        "forks": dataclasses.asdict(orch.fork_stats),
        "cpu_s": round(cpu, 2),
        "wall_s": round(s.wall_time_s, 1),
        "step_wall_s": round(orch.scene.step_wall_s, 1),
        "load_1min": round(os.getloadavg()[0], 1),
        "sig": hashlib.sha1(json.dumps(keep, sort_keys=True).encode()).hexdigest()[:12],
    }


if __name__ == "__main__":
    # name=value: an ArmTuning constant, its value a Python literal (None, 3, (6, 30.0)),
    # or plan_workers=N (`Orchestrator`'s; default: 2 where two cores are free)
    over = {k: ast.literal_eval(v) for k, v in (a.split("=", 1) for a in sys.argv[3:])}
    print(json.dumps(main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 0, over)))
