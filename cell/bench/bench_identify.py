"""Identification time on a thesis-sized synthetic campaign (865 throws of 14 objects)."""

from __future__ import annotations

import time

import numpy as np

from cell.identify import identify
from cell.identify.report import heldout_split
from cell.synth import Campaign, default_world, draw_campaign


def run(quick: bool = False) -> dict[str, float]:
    """Time `identify` on all throws of the default campaign (300 with quick), and report
    the held-out landing RMSE of a second fit on 80 % against the noise floor.

    identify_s is wall time; identify_cpu_s the process's CPU time, which a machine
    shared with other work inflates less.
    """
    n = 300 if quick else 865
    world = default_world()
    table = draw_campaign(world, Campaign(n=n), seed=0)
    t0, c0 = time.perf_counter(), time.process_time()
    full = identify(table)
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    fit_idx, held_idx = heldout_split(table, 0.2, seed=0)
    part = identify(table.take(fit_idx))
    held = table.take(held_idx)
    pred = held.to_batch(objects=part.params.objects)
    from cell.model.throw import predict_landing

    xy = predict_landing(pred, part.params.ee, strict=False, check_stroke=False).xy
    obs = held.landed
    rmse = float(np.sqrt(np.mean(np.sum((xy - obs) ** 2, axis=1))))
    floor = float(np.sqrt(np.mean(np.sum((world.true_landing(held) - obs) ** 2, axis=1))))
    return {
        "identify_s": round(seconds, 3),
        "identify_cpu_s": round(cpu, 3),
        "identify_throws": n,
        "identify_objects": len(set(table.text("object_id"))),
        "identify_iterations": full.iterations,
        "identify_heldout_rmse_m": round(rmse, 4),
        "identify_noise_floor_m": round(floor, 4),
        "identify_heldout_over_floor": round(rmse / floor, 3),
    }
