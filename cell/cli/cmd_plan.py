"""`cell plan`: the release state σ* that lands an object on a target."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Iterator
from typing import Any

import numpy as np

from cell.cli.common import add_json_arg, add_object_args, add_vector_arg, object_from_args, report
from cell.cli.model_checks import (
    modelled,
    refuse_release_under_floor,
    refuse_under_floor,
    warn_if_light,
    warn_if_not_held,
    warn_if_stroke_not_held,
)
from cell.errors import InvalidInput, InvalidParameter
from cell.model.objects import ObjectParams
from cell.params import load_params


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "plan",
        help="plan a throw: target in, release pose, velocity and stroke out",
        description=(
            "Find the release state σ* (grip centre, base velocity, roll, elevation, azimuth, "
            "stroke) within the bounds that lands the object on the target, with the least "
            "stored band energy. Target z is the landing plane (a bin's rim height)."
        ),
    )
    add_vector_arg(
        p, "--target", "goal in the world frame [m]; Z is the landing plane's height", required=True
    )
    add_object_args(p)
    p.add_argument(
        "--method",
        choices=("auto", "fast", "nlp"),
        default="auto",
        help="fast inverse, full NLP, or fast with the NLP as fallback (auto)",
    )
    add_vector_arg(
        p,
        "--current",
        "current grip centre [m]: the fast path releases there (moved into --box, said)",
    )
    add_vector_arg(
        p,
        "--base-velocity",
        "a known base velocity at release [m/s] (default: fixed base)",
        metavar=("VX", "VY", "VZ"),
    )
    p.add_argument(
        "--moving-base",
        type=float,
        metavar="VMAX",
        help="let the NLP choose a base velocity with |v| ≤ VMAX per axis [m/s]",
    )
    p.add_argument(
        "--box",
        type=float,
        nargs=6,
        metavar=("XMIN", "YMIN", "ZMIN", "XMAX", "YMAX", "ZMAX"),
        help="release-point box [m] (0.2 -0.4 0.4 0.6 0.4 0.9)",
    )
    p.add_argument(
        "--elevation-range",
        type=float,
        nargs=2,
        metavar=("MIN", "MAX"),
        help="throw-axis elevation range [rad] (0 1.1345 = 0…65°)",
    )
    p.add_argument("--params", metavar="EE.yaml", help="parameter file (default: reference values)")
    add_json_arg(p, "the plan")
    p.set_defaults(func=run)


def _bounds(args: argparse.Namespace):
    from dataclasses import replace

    from cell.optimize import DEFAULT_BOUNDS

    b = DEFAULT_BOUNDS
    try:
        if args.box is not None:
            b = replace(b, position_min=tuple(args.box[:3]), position_max=tuple(args.box[3:]))
        if args.elevation_range is not None:
            b = replace(
                b, elevation_min=args.elevation_range[0], elevation_max=args.elevation_range[1]
            )
        if args.moving_base is not None:
            b = b.with_base_velocity(args.moving_base)
    except InvalidParameter as exc:
        raise InvalidInput(str(exc)) from None
    return b


def run(args: argparse.Namespace) -> int:
    from cell.optimize import plan_throw

    obj = object_from_args(args)
    refuse_under_floor("--target", args.target[2])
    if args.box is not None:
        refuse_release_under_floor("--box", args.box[2])
    if args.current is not None:
        refuse_release_under_floor("--current", args.current[2])
    mp = load_params(args.params)
    warn_if_not_held(mp, obj)
    warn_if_light(obj)
    if args.base_velocity is not None and args.moving_base is not None:
        raise InvalidInput("give either --base-velocity or --moving-base, not both")
    try:
        model, said = modelled(mp, obj)
        plan = plan_throw(
            model,
            tuple(args.target),
            mp.ee,
            _bounds(args),
            current=args.current,
            base_velocity=args.base_velocity,
            method=args.method,
        )
    except InvalidParameter as exc:
        raise InvalidInput(str(exc)) from None
    warn_if_stroke_not_held(mp, obj, plan.stroke_m)
    _say_current_moved(args.current, _bounds(args))
    _say_at_the_base(args.target)
    return report(args, plan.as_dict(), _text(plan, obj, said))


def _say_at_the_base(target: Any) -> None:
    """A warning where the target lies within ROBOT_BASE_CLEARANCE_M of the arm's base (the
    world frame's origin), where a job refuses a bin: the model flies through the arm."""
    from cell.jobbins import ROBOT_BASE_CLEARANCE_M

    r = math.hypot(target[0], target[1])
    if r < ROBOT_BASE_CLEARANCE_M:
        print(
            f"cell plan: warning: the target is {r:.2f} m from the arm's base (the world "
            f"frame's origin), within the {ROBOT_BASE_CLEARANCE_M} m a job keeps its bins "
            "from it; the model flies through the arm standing there",
            file=sys.stderr,
        )


def _say_current_moved(current: Any, bounds: Any) -> None:
    """A line on standard error where --current lies outside the release box: the fast path
    releases at the box's point nearest it, not there (`cell.optimize.plan_throw`)."""
    if current is None:
        return
    inside = bounds.clip_position(np.asarray(current, float))
    if np.allclose(inside, current, rtol=0.0, atol=1e-12):
        return
    at, to, lo, hi = (
        ", ".join(f"{v:.2f}" for v in p)
        for p in (current, inside, bounds.position_min, bounds.position_max)
    )
    print(
        f"cell plan: --current ({at}) m lies outside the release box (--box: ({lo}) to "
        f"({hi}) m); the fast path releases from its nearest point, ({to}) m, instead",
        file=sys.stderr,
    )


def _text(plan: Any, obj: ObjectParams, said: str = "") -> Iterator[str]:
    """The plan as a person reads it, line by line."""
    yield f"object        {plan.as_dict()['object_id']}  ({obj.mass:.3f} kg, {obj.shape})"
    if said:
        yield said
    yield (
        f"target        x = {plan.target_x_m:.4f} m, y = {plan.target_y_m:.4f} m "
        f"on z = {plan.land_z_m:.3f} m (world frame)"
    )
    yield (
        f"release at    x = {plan.x_m:.4f}, y = {plan.y_m:.4f}, z = {plan.z_m:.4f} m; "
        f"base velocity ({plan.vx_mps:.3f}, {plan.vy_mps:.3f}, {plan.vz_mps:.3f}) m/s"
    )
    yield (
        f"throw axis    elevation {plan.elevation_rad:.4f} rad ({math.degrees(plan.elevation_rad):.1f}°), "
        f"azimuth {plan.azimuth_rad:.4f} rad ({math.degrees(plan.azimuth_rad):.1f}°), "
        f"roll {plan.roll_rad:.4f} rad"
    )
    yield f"stroke        L_s = {plan.stroke_m:.5f} m"
    yield (
        f"predicted     lands at x = {plan.pred_x_m:.4f} m, y = {plan.pred_y_m:.4f} m; "
        f"miss {plan.miss_m * 1e3:.3f} mm"
    )
    yield f"flight time   {plan.t_flight_s:.4f} s (from the start of the push)"
    yield f"stored energy {plan.energy_j:.4f} J (both band halves)"
    yield f"method        {plan.method}"
