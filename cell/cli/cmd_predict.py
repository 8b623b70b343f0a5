"""`cell predict`: predicted landings for every row of a throw log."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from cell.cli.common import plural
from cell.errors import LogFormatError
from cell.log import read_throws_csv, write_throws_csv
from cell.log.table import RANGES
from cell.model import predict_landing
from cell.params import load_params

# [m/s] a launch faster than any the log may record (its velocities' range, RANGES) is
# the push model out of its domain (an item of a gram or less at a short stroke: the model
# drives it with the band's whole force, the carriage's mass not in it), not a flight
MAX_LAUNCH_SPEED_MPS = RANGES["vx_mps"][1]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("predict", help="add predicted landings to a throw log (docs/throw_log.md)")
    p.add_argument("throws", help="throws.csv")
    p.add_argument(
        "-o",
        "--output",
        required=True,
        help="output CSV: the log plus pred_x_m, pred_y_m, pred_t_flight_s",
    )
    p.add_argument("--params", metavar="EE.yaml", help="parameter file (default: reference values)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    table = read_throws_csv(args.throws)
    mp = load_params(args.params)
    batch = _as_planned(table, table.to_batch(objects=mp.objects), mp)
    bad = batch.stroke_out_of_range(mp.ee)
    if bad.size:
        i = int(bad[0])
        raise LogFormatError(
            args.throws,
            i + 1,
            "stroke_m",
            f"L_s = {batch.stroke[i]} m is outside the end-effector's range "
            f"{mp.ee.stroke_min} … {mp.ee.stroke_max} m",
        )
    if mp.effects:
        # a parameter file may switch identified effects on: predictions then include them
        from cell.model.effects_apply import predict_with_effects

        land = predict_with_effects(
            batch, mp.ee, mp.effects, rotor_rpm=table.num("rotor_rpm"), strict=False
        )
    else:
        land = predict_landing(batch, mp.ee, strict=False, check_stroke=False)
    speed = np.linalg.norm(land.launch_velocity, axis=1)
    fast = np.flatnonzero(~(speed <= MAX_LAUNCH_SPEED_MPS))
    if fast.size:
        i = int(fast[0])
        raise LogFormatError(
            args.throws,
            i + 1,
            "mass_kg",
            f"throw {table.data['throw_id'][i]}: the end-effector model launches "
            f"{batch.mass[i]:g} kg at {speed[i]:.3g} m/s at the stroke {batch.stroke[i]:g} m, "
            f"faster than the {MAX_LAUNCH_SPEED_MPS:g} m/s a log's velocities may be: the "
            "model (the band's force on the item alone) is beyond its domain for an item "
            "this light at this stroke",
        )
    if not land.landed.all():
        i = int(np.flatnonzero(~land.landed)[0])
        z0, zl = float(batch.position[i, 2]), float(batch.land_z[i])
        # blame the column a user most likely got wrong: a release below the floor (z = 0 in
        # the world frame) is the release height's fault, otherwise the landing plane's
        column, hint = (
            (
                "z_m",
                f"the release height z_m = {z0} m is below the floor (z = 0) and the plane {zl} m",
            )
            if z0 < 0.0 <= zl
            else (
                "land_z_m",
                f"the landing plane z = {zl} m is above the whole flight (released at z = {z0} m)",
            )
        )
        raise LogFormatError(
            args.throws,
            i + 1,
            column,
            f"throw {table.data['throw_id'][i]} never crosses its landing plane while "
            f"descending: {hint}",
        )
    out = table.with_columns(
        {"pred_x_m": land.x, "pred_y_m": land.y, "pred_t_flight_s": land.t_flight}
    )
    write_throws_csv(out, args.output)
    print(f"predicted {plural(len(table), 'throw')} -> {args.output}")
    return 0


def _as_planned(table: Any, batch: Any, params: Any) -> Any:
    """`batch` with each row's object as `cell run` models it with `params`
    (`ModelParams.model_object`): a catalogue object the file identifies by its identified
    η_o, turned as the row was gripped; any other by the file's mass rule (an effective
    mass). Without the rule, rows of objects the file does not list keep their logged
    mass (as `to_batch` gave them). The cell's own ad-hoc throws were predicted with their
    logged mass: 0.06-0.75 m from where they landed, against 0.00-0.07 m so."""
    from dataclasses import replace

    from cell.errors import CellError
    from cell.model.objects import SHAPES, ObjectParams

    if params.mass_rule is None and not params.objects:
        return batch
    mass, size = batch.mass.copy(), batch.size.copy()
    logged_mass = table.num("mass_kg")
    logged_size = np.stack([table.num(f"size_{k}_m") for k in "xyz"], -1)
    for j, oid in enumerate(table.data["object_id"]):
        try:
            obj = ObjectParams(
                SHAPES[int(batch.shape[j])],
                float(logged_mass[j]),
                (float(logged_size[j, 0]), float(logged_size[j, 1]), float(logged_size[j, 2])),
                name=str(oid),
            )
        except (CellError, ValueError):  # a row the catalogue's types cannot hold: as read
            continue
        model = params.model_object(obj)
        mass[j], size[j] = model.mass, model.size
    return replace(batch, mass=mass, size=size)
