"""Throw-planning latency (fast path and full NLP) and the plans' predicted miss.

Latencies are wall-clock per `plan_throw` call (median, 95th percentile);
the `_cpu_` figures are the process CPU time of the same calls, which a
shared, loaded machine inflates less (the 1-minute load average is
reported). `plan_fast_lookup_*` is the reach-table inverse alone, without the
`predict_landing` verification every returned plan gets.

Targets are reachable by construction: each is the landing, by
`predict_landing`, of a release state inside the default bounds, for the
catalogue's objects in turn. The fast-path targets come from the fast path's
own pose family (nominal release point toward the target, an interior
candidate elevation, a stroke inside the range); the NLP targets from release
states anywhere in the bounds.
"""

from __future__ import annotations

import math
import os
import time

import numpy as np

from cell.catalogue import catalogue
from cell.errors import UnreachableTarget
from cell.model import DEFAULT_EE, EndEffectorParams, ObjectParams, ThrowBatch, predict_landing
from cell.optimize import DEFAULT_BOUNDS, ThrowBounds, plan_throw
from cell.optimize.fast import reach_table
from cell.optimize.plan import Method

__all__ = ["family_targets", "box_targets", "measure", "run"]


def _land(
    obj: ObjectParams, sigma: np.ndarray, land_z: np.ndarray, ee: EndEffectorParams
) -> np.ndarray:
    n = sigma.shape[0]
    batch = ThrowBatch.build(
        stroke=sigma[:, 9],
        position=sigma[:, 0:3],
        elevation=sigma[:, 7],
        azimuth=sigma[:, 8],
        shape=np.full(n, obj.code),
        mass=np.full(n, obj.mass),
        size=np.tile(obj.size, (n, 1)),
        base_velocity=sigma[:, 3:6],
        land_z=land_z,
    )
    land = predict_landing(batch, ee)
    return np.c_[land.x, land.y, land_z]


def family_targets(
    obj: ObjectParams,
    n: int,
    rng: np.random.Generator,
    ee: EndEffectorParams = DEFAULT_EE,
    bounds: ThrowBounds = DEFAULT_BOUNDS,
) -> np.ndarray:
    """n targets (x, y, land_z) [m, W] thrown from the fast path's pose family, shape (n, 3)."""
    beta = rng.uniform(-math.pi, math.pi, n)
    elev = bounds.elevations()
    s_lo, s_hi = bounds.stroke_range(ee)
    sigma = np.zeros((n, 10))
    for i, b in enumerate(beta):
        sigma[i, 0:3] = bounds.nominal_release(np.array([math.cos(b), math.sin(b)]))
    sigma[:, 6] = bounds.roll
    sigma[:, 7] = elev[rng.integers(1, max(len(elev) - 1, 2), n) % len(elev)]
    sigma[:, 8] = beta
    sigma[:, 9] = rng.uniform(s_lo + 0.05 * (s_hi - s_lo), s_hi - 0.05 * (s_hi - s_lo), n)
    return _land(obj, sigma, rng.uniform(0.0, 0.3, n), ee)


def box_targets(
    obj: ObjectParams,
    n: int,
    rng: np.random.Generator,
    ee: EndEffectorParams = DEFAULT_EE,
    bounds: ThrowBounds = DEFAULT_BOUNDS,
) -> np.ndarray:
    """n targets (x, y, land_z) [m, W] thrown from release states anywhere in the bounds."""
    lo, hi = bounds.vectors(ee)
    sigma = rng.uniform(lo, hi, (n, 10))
    e_lo = max(lo[7], math.radians(10))
    e_hi = min(hi[7], math.radians(60))
    sigma[:, 7] = rng.uniform(min(e_lo, e_hi), max(e_lo, e_hi), n)
    return _land(obj, sigma, rng.uniform(0.0, 0.3, n), ee)


def _objects() -> list[ObjectParams]:
    return [e.params for e in catalogue().values()]


def _timed_plan(
    obj: ObjectParams,
    target: np.ndarray,
    method: Method,
    wall_s: list[float],
    cpu_s: list[float],
    misses_m: list[float],
) -> bool:
    """Plan one target, appending its wall and CPU time [s] and its miss [m]; False when
    it was unreachable (counted by the caller as a failure, not hidden)."""
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        plan = plan_throw(obj, target, method=method)
    except UnreachableTarget:
        return False
    wall_s.append(time.perf_counter() - t0)
    cpu_s.append(time.process_time() - c0)
    misses_m.append(plan.miss_m)
    return True


def measure(n_fast: int, n_nlp: int, seed: int = 0) -> dict[str, float]:
    """Plan n_fast family targets with the fast path and n_nlp box targets with the NLP."""
    rng = np.random.default_rng(seed)
    objs = _objects()
    strokes = DEFAULT_BOUNDS.stroke_range(DEFAULT_EE)
    for obj in objs:  # tables and the NLP are built once per process, not per target
        reach_table(obj, DEFAULT_EE, tuple(DEFAULT_BOUNDS.elevations()), strokes)
    fast_t: list[float] = []
    fast_cpu: list[float] = []
    lookup_t: list[float] = []
    nlp_t: list[float] = []
    nlp_cpu: list[float] = []
    misses: list[float] = []
    fast_fail = nlp_fail = 0
    per = max(1, math.ceil(n_fast / len(objs)))
    for k, obj in enumerate(objs):
        todo = min(per, n_fast - k * per)
        if todo <= 0:
            break
        table = reach_table(obj, DEFAULT_EE, tuple(DEFAULT_BOUNDS.elevations()), strokes)
        for tgt in family_targets(obj, todo, rng):
            p0 = DEFAULT_BOUNDS.nominal_release(tgt)
            t0 = time.perf_counter()
            table.invert(math.hypot(tgt[0] - p0[0], tgt[1] - p0[1]), p0[2] - tgt[2])
            lookup_t.append(time.perf_counter() - t0)
            fast_fail += not _timed_plan(obj, tgt, "fast", fast_t, fast_cpu, misses)
    plan_throw(objs[0], family_targets(objs[0], 1, rng)[0], method="nlp")  # build the NLP
    per = max(1, math.ceil(n_nlp / len(objs)))
    for k, obj in enumerate(objs):
        todo = min(per, n_nlp - k * per)
        if todo <= 0:
            break
        for tgt in box_targets(obj, todo, rng):
            nlp_fail += not _timed_plan(obj, tgt, "nlp", nlp_t, nlp_cpu, misses)

    def ms(v: list[float], q: float) -> float:
        return float(np.percentile(np.asarray(v) * 1e3, q)) if v else float("nan")

    return {
        "plan_fast_median_ms": ms(fast_t, 50),
        "plan_fast_p95_ms": ms(fast_t, 95),
        "plan_fast_lookup_median_ms": ms(lookup_t, 50),
        "plan_fast_lookup_p95_ms": ms(lookup_t, 95),
        "plan_fast_targets": len(fast_t) + fast_fail,
        "plan_fast_failed": fast_fail,
        "plan_nlp_median_ms": ms(nlp_t, 50),
        "plan_nlp_p95_ms": ms(nlp_t, 95),
        "plan_nlp_targets": len(nlp_t) + nlp_fail,
        "plan_nlp_failed": nlp_fail,
        "plan_fast_cpu_median_ms": ms(fast_cpu, 50),
        "plan_fast_cpu_p95_ms": ms(fast_cpu, 95),
        "plan_nlp_cpu_median_ms": ms(nlp_cpu, 50),
        "plan_nlp_cpu_p95_ms": ms(nlp_cpu, 95),
        "plan_max_miss_m": float(max(misses)) if misses else float("nan"),
        "plan_load_avg_1min": float(os.getloadavg()[0]) if hasattr(os, "getloadavg") else -1.0,
    }


def run(quick: bool = False) -> dict[str, float]:
    """The plan figures: 1000 fast-path targets; 1000 NLP targets (100 with quick)."""
    return measure(1000, 100 if quick else 1000)
