"""`cell throw`: one throw with the model, from the command line."""

from __future__ import annotations

import argparse
from collections.abc import Iterator
from typing import Any

import numpy as np

from cell.catalogue import catalogue
from cell.cli.common import (
    add_axis_args,
    add_json_arg,
    add_object_args,
    add_vector_arg,
    object_from_args,
    report,
)
from cell.cli.model_checks import (
    modelled,
    refuse_release_under_floor,
    refuse_under_floor,
    warn_if_light,
    warn_if_not_held,
    warn_if_stroke_not_held,
)
from cell.model import ObjectParams, ThrowBatch, band_state, predict_landing
from cell.params import load_params


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "throw", help="predict one throw: landing, flight time, launch speed, energy"
    )
    add_object_args(p)
    p.add_argument("--list", action="store_true", help="list the catalogue objects and exit")
    p.add_argument("--stroke", type=float, default=0.06, metavar="M", help="stroke L_s [m] (0.06)")
    add_vector_arg(
        p, "--at", "release grip centre in the world frame [m] (0 0 0.6)", default=(0.0, 0.0, 0.6)
    )
    add_axis_args(p)
    add_vector_arg(
        p,
        "--base-velocity",
        "end-effector velocity at release [m/s]",
        default=(0.0, 0.0, 0.0),
        metavar=("VX", "VY", "VZ"),
    )
    p.add_argument(
        "--land-z", type=float, default=0.0, metavar="M", help="landing plane height [m]"
    )
    p.add_argument("--params", metavar="EE.yaml", help="parameter file (default: reference values)")
    add_json_arg(p, "the prediction")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if args.list:
        for name, e in catalogue().items():
            o = e.params
            print(
                f"{name:16s} {o.shape:9s} {o.mass:6.3f} kg  "
                f"{o.size[0]:.3f} x {o.size[1]:.3f} x {o.size[2]:.3f} m  [{e.set}]"
            )
        return 0
    obj = object_from_args(args)
    refuse_under_floor("--land-z", args.land_z)
    refuse_release_under_floor("--at", args.at[2])
    mp = load_params(args.params)
    warn_if_not_held(mp, obj)
    warn_if_stroke_not_held(mp, obj, args.stroke)
    warn_if_light(obj)
    model, said = modelled(mp, obj)
    batch = ThrowBatch.single(
        model,
        stroke=args.stroke,
        position=tuple(args.at),
        elevation=args.elevation,
        azimuth=args.azimuth,
        base_velocity=tuple(args.base_velocity),
        land_z=args.land_z,
    )
    land = predict_landing(batch, mp.ee)
    band = band_state(args.stroke, model.width, mp.ee)
    out = {
        "object": obj.name or obj.shape,
        "model_mass_kg": model.mass,
        "stroke_m": args.stroke,
        "landed_x_m": float(land.x[0]),
        "landed_y_m": float(land.y[0]),
        "land_z_m": args.land_z,
        "t_flight_s": float(land.t_flight[0]),
        "launch_speed_mps": float(np.linalg.norm(land.launch_velocity[0])),
        "band_stretch_m": float(band.stretch),
        "push_force_n": float(band.push),
        "grip_force_n": float(band.grip),
        "stored_energy_j": float(band.energy),
    }
    return report(args, out, _text(out, obj, args.land_z, said))


def _text(out: dict[str, Any], obj: ObjectParams, land_z: float, said: str) -> Iterator[str]:
    """The prediction as a person reads it, line by line."""
    yield f"object        {out['object']}  ({obj.mass:.3f} kg, {obj.shape})"
    if said:
        yield said
    yield (
        f"lands at      x = {out['landed_x_m']:.4f} m, y = {out['landed_y_m']:.4f} m "
        f"on z = {land_z:.3f} m (world frame)"
    )
    yield f"flight time   {out['t_flight_s']:.4f} s (from the start of the push)"
    yield f"launch speed  {out['launch_speed_mps']:.3f} m/s"
    yield (
        f"band          stretch ΔL = {out['band_stretch_m']:.5f} m, push f_o = "
        f"{out['push_force_n']:.3f} N, grip f_g = {out['grip_force_n']:.3f} N"
    )
    yield f"stored energy {out['stored_energy_j']:.4f} J (both band halves)"
