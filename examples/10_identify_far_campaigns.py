"""10 — identification on campaigns from end-effectors far from the defaults (issue 61).

Each case draws a world whose band stiffnesses (Ke3, Ke2, Ke1) and push time dt are each
10-40 % off the defaults (random sign), with the default world's object factors or, for
the "unseen" cases, random ones (mass ±12 %, grip width ±3 %); a campaign of N throws of
the 14 thesis objects with the documented noise; identification on a stratified 80 %;
and prints, as JSON, per case: the held-out landing RMSE over the noise floor (the true
parameters' RMSE on the same held-out throws), the same on 3000 fresh throws of the world
(a steadier figure than the ~20 % held out), the training RMSE over the true parameters',
the objects kept at the catalogue and the determined parameter combinations.

Run: .venv/bin/python examples/10_identify_far_campaigns.py [N ...] [--seeds 0 1 2] [--unseen]
[--unseen-seeds 10 11 12] [--json PATH]. `--unseen-seeds` adds unseen cases of those seeds
to the same run; `--json PATH` writes the rows (with the command's arguments) to PATH as
well (docs/figures/identify_far.json, quoted by docs/identify_evidence.md).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace

import numpy as np

from cell.identify import identify
from cell.identify.report import heldout_split, predicted_landing
from cell.model import DEFAULT_EE
from cell.synth import Campaign, World, default_world, draw_campaign

OFFSET = (0.1, 0.4)  # [-] the range of each far parameter's relative offset from the default
HELD_OUT = 0.2  # [-] the fraction of a campaign held out of the identification
FRESH_N = 3000  # fresh throws of the same world to score the fit on


def far_world(seed: int, unseen: bool) -> World:
    """Stiffnesses and push time each 10-40 % off the defaults (random sign)."""
    rng = np.random.default_rng(1000 + seed)
    d = DEFAULT_EE
    f = 1 + rng.choice([-1.0, 1.0], 4) * rng.uniform(*OFFSET, 4)
    ee = replace(d, Ke3=f[0] * d.Ke3, Ke2=f[1] * d.Ke2, Ke1=f[2] * d.Ke1, dt=f[3] * d.dt)
    world = replace(default_world(), ee=ee)
    if unseen:
        objects = {}
        for oid, o in world.objects.items():
            m, s = rng.uniform(0.88, 1.12), rng.uniform(0.97, 1.03)
            size = (
                (o.size[0] * s, *o.size[1:])
                if o.shape not in ("cube", "sphere")
                else ((o.size[0] * s,) * 3)
            )
            if o.shape == "cylinder":
                size = (o.size[0] * s, o.size[0] * s, o.size[2])
            objects[oid] = replace(o, mass=o.mass * m, size=size)  # type: ignore[arg-type]
        world = replace(world, objects=objects)
    return world


def rmse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))


def case(n: int, seed: int, unseen: bool) -> dict[str, object]:
    world = far_world(seed, unseen)
    table = draw_campaign(world, Campaign(n=n), seed=seed)
    fit_idx, held_idx = heldout_split(table, HELD_OUT, seed=seed)
    fit, held = table.take(fit_idx), table.take(held_idx)
    t0 = time.perf_counter()
    result = identify(fit)
    seconds = time.perf_counter() - t0
    floor = rmse(world.true_landing(held), held.landed)
    after = rmse(predicted_landing(held, result.params), held.landed)
    fresh = draw_campaign(world, Campaign(n=FRESH_N), seed=seed + 100)
    fresh_floor = rmse(world.true_landing(fresh), fresh.landed)
    fresh_after = rmse(predicted_landing(fresh, result.params), fresh.landed)
    train = rmse(predicted_landing(fit, result.params), fit.landed)
    train_true = rmse(world.true_landing(fit), fit.landed)
    return {
        "n": n,
        "objects": len(set(table.text("object_id"))),
        "seed": seed,
        "unseen": unseen,
        "heldout_over_floor": round(after / floor, 4),
        "fresh3000_over_floor": round(fresh_after / fresh_floor, 4),
        "objects_kept": sum(c.kept for c in result.objects),
        "determined": result.n_params,
        "train_over_true": round(train / train_true, 4),
        "seconds": round(seconds, 2),
        "iterations": result.iterations,
    }


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("n", nargs="*", type=int, default=[300, 650, 865])
    p.add_argument("--seeds", nargs="*", type=int, default=[0])
    p.add_argument("--unseen", action="store_true")
    p.add_argument("--unseen-seeds", nargs="*", type=int, default=[])
    p.add_argument("--json", metavar="PATH", help="also write the rows as JSON to PATH")
    a = p.parse_args()
    cases = [(s, a.unseen) for s in a.seeds] + [(s, True) for s in a.unseen_seeds]
    rows = [
        case(n, s, unseen) for unseen in (False, True) for n in a.n for s, u in cases if u is unseen
    ]
    print(json.dumps(rows, indent=1))
    if a.json:
        doc = {
            "command": " ".join(["examples/10_identify_far_campaigns.py", *sys.argv[1:]]),
            "offset_range": list(OFFSET),
            "heldout_fraction": HELD_OUT,
            "fresh_throws": FRESH_N,
            "cases": rows,
        }
        with open(a.json, "w") as f:
            f.write(json.dumps(doc, indent=1) + "\n")


if __name__ == "__main__":
    main()
