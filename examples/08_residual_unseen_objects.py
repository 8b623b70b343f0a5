"""Residual learning of ΔL_s, end to end (thesis chapter 5), in a synthetic world.

1. Draw an identification campaign of the 14 thesis objects in a world whose band
   stretches more round curved objects than the model knows (κ · width), and write
   it as a throw log.
2. Table 5.1: hold out two objects at a time, train SVR, random forest and MLP on
   the rest, report the ΔL_s MSE and the held-out landing RMSE before and after.
3. Train the SVR residual on every object, and save it (what `cell learn` does).
4. Thesis §5.3: throw the 7 unseen objects (2 primitives, 5 meshes) 5 times each at
   set targets, with the model's stroke L_s and with L_s + ΔL_s, and plot the
   landings around the targets.

    python examples/08_residual_unseen_objects.py OUT_DIR [--quick] [--kappa 0.1] [--identify]

Without --identify the world's parameters are the model's (only the stretch is
missing from the model). With --identify the world's η_ee and η_o are perturbed
(`cell.synth.default_world`) and the model is what `cell identify` fits to the
campaign: the thesis' chain, identification first, the residual on top.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

from cell.log import write_throws_csv
from cell.model import DEFAULT_EE
from cell.params import load_params
from cell.residual import round_robin, shape_stretch_hook, targeted_throws, unseen_ids
from cell.residual.model import train_residual, training_data
from cell.residual.plot import plot_table51, plot_targeted
from cell.synth import Campaign, NoiseModel, World, default_world, draw_campaign


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path, help="output folder")
    ap.add_argument("--quick", action="store_true", help="280 throws and small grids")
    ap.add_argument("--kappa", type=float, default=0.1, help="extra stretch per width [m/m]")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--identify", action="store_true", help="perturbed world, identified model")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    # Landing noise 0.5% of the reach along the throw (the thesis' arm repeats to 8%).
    noise = NoiseModel(along_rel=0.005, across_rel=0.0025, floor_m=0.003)
    if args.identify:
        world = dataclasses.replace(default_world(noise), predict=shape_stretch_hook(args.kappa))
    else:
        world = World(ee=DEFAULT_EE, noise=noise, predict=shape_stretch_hook(args.kappa))
    n = 280 if args.quick else 865
    grid = "small" if args.quick else "full"
    table = draw_campaign(world, Campaign(n=n, stroke_m=(0.04, 0.10)), seed=args.seed)
    write_throws_csv(table, args.out / "throws.csv")

    model_ee, model_objects = DEFAULT_EE, None
    if args.identify:
        from cell.cli import main as cell_main

        params = args.out / "params.yaml"
        cell_main(["identify", str(args.out / "throws.csv"), "-o", str(params), "--holdout", "0"])
        mp = load_params(params)
        model_ee = mp.ee  # the residual is learned against the CAD η_o an unseen object has
    t0 = time.perf_counter()
    data = training_data(table, model_ee, objects=model_objects)
    rr = round_robin(data, grid=grid, seed=args.seed)
    print(f"Table 5.1 ({n} throws, {len(rr['svr'].folds)} folds, {time.perf_counter() - t0:.0f} s)")
    print(f"{'learner':8s} {'ΔL_s MSE [mm²]':>20s} {'held-out landing RMSE [m]':>28s}")
    for name, s in rr.items():
        print(
            f"{name:8s} {s.dls_mse_mean:10.4f} ± {s.dls_mse_std:<8.4f} "
            f"{s.heldout_rmse_before_m:12.4f} -> {s.heldout_rmse_after_m:.4f}"
        )
    (args.out / "table51.json").write_text(
        json.dumps({k: v.as_dict() for k, v in rr.items()}, indent=2, default=str)
    )
    plot_table51(rr, args.out / "table51.png")

    summary = {}
    for learner in ("svr", "rf", "mlp"):
        model = train_residual(data, learner=learner, grid=grid, seed=args.seed)
        if learner == "svr":
            model.save(args.out / "residual.skops")
        tt = targeted_throws(
            world, model, unseen_ids(), model_ee=model_ee, throws_per_object=5, seed=args.seed + 1
        )
        summary[learner] = {
            "rmse_before_m": tt.rmse(False),
            "rmse_after_m": tt.rmse(True),
            "per_object": tt.per_object(),
            "clipped": int(tt.clipped.sum()),
        }
        print(
            f"unseen objects, {learner}: landing RMSE {tt.rmse(False):.4f} m -> {tt.rmse(True):.4f} m"
        )
        if learner == "svr":
            for oid, r in tt.per_object().items():
                print(f"   {oid:14s} {r['rmse_before_m']:.4f} -> {r['rmse_after_m']:.4f} m")
            plot_targeted(tt, args.out / "unseen_targets.png")
    (args.out / "unseen.json").write_text(json.dumps(summary, indent=2))
    print(
        f"wrote {args.out}/throws.csv, residual.skops, table51.*, unseen_targets.png, unseen.json"
    )


if __name__ == "__main__":
    main()
