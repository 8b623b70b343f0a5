"""The launches the pads release cleanly, and whether the cell can sort an item at all
(`check_sortable`).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Collection
from typing import Any

import numpy as np

from cell.arm.grip_limits import (
    MIN_THROW_STROKE_RANGE_M,
    grip_bounds,
)
from cell.errors import (
    CannotGrip,
    UnreachableTarget,
)
from cell.jobschema import PLACE_REACH_M
from cell.model.objects import ObjectParams
from cell.params import ModelParams

log = logging.getLogger(__name__)


# A launch slower than this [m/s] (the model's launch speed) is thrown flat, with the throw
# axis at most SLOW_LAUNCH_MAX_ELEVATION_RAD up. Measured in the scene (ad-hoc items
# 30-171 g): launched at 0.58-0.84 m/s at 35-60°, items fell back onto the pads (reach 17-66 %
# short of the model's, or no landing); at 10° a 100 g box launched at 0.72 m/s landed within
# 3 % of the model, and at 1.0 m/s and faster the model's reach holds at every elevation.
LAUNCH_SPEED_MIN_MPS = 1.0


SLOW_LAUNCH_MAX_ELEVATION_RAD = math.radians(20.0)


def clean_launch(speed_mps: float, elevation_rad: float) -> bool:
    """Does an item launched at `speed_mps` [m/s] with the throw axis at `elevation_rad`
    leave the pads as the model has it (fast enough, or flat enough not to fall back)?"""
    return speed_mps >= LAUNCH_SPEED_MIN_MPS or elevation_rad <= SLOW_LAUNCH_MAX_ELEVATION_RAD


def launch_stroke_limit(
    params: ModelParams,
    obj: ObjectParams,
    elevation_max_rad: float,
    model_obj: ObjectParams | None = None,
) -> float:
    """The longest stroke [m] at which the model launches `obj` at LAUNCH_SPEED_MIN_MPS
    or faster at every elevation up to `elevation_max_rad` (the steepest is the slowest),
    `obj` as the plan models it (`model_obj`; default `params.model_object(obj)`).

    Raises:
        UnreachableTarget: even the shortest stroke launches it slower (too heavy to
            throw steeply); the message says what the cell can do instead.
    """
    from cell.model.throw import longest_stroke_launching

    ee, name = params.ee, obj.name or obj.shape
    modelled = params.model_object(obj) if model_obj is None else model_obj
    s_max = longest_stroke_launching(ee, modelled, LAUNCH_SPEED_MIN_MPS, elevation_max_rad)
    if s_max is None or s_max < ee.stroke_min + MIN_THROW_STROKE_RANGE_M:
        raise UnreachableTarget(
            f"{name} ({obj.mass * 1000:.0f} g) is too heavy to throw steeply: the band "
            f"launches it slower than {LAUNCH_SPEED_MIN_MPS:.1f} m/s at every stroke, and a "
            "slow steep launch falls back onto the pads; place it in a bin within reach, or "
            "sort it by hand"
        )
    return s_max


def plan_clean(
    params: ModelParams, obj: ObjectParams, model_obj: ObjectParams, goal: Any, bounds: Any
) -> Any:
    """`plan_facing` within the launches the pads release cleanly (`clean_launch`): the
    planner's throw when it is one; else the same goal thrown flat (a slow launch at most
    SLOW_LAUNCH_MAX_ELEVATION_RAD up); else at strokes that launch at least
    LAUNCH_SPEED_MIN_MPS (`launch_stroke_limit`).

    Raises:
        UnreachableTarget: no clean launch within the bounds lands on the goal.
    """
    from dataclasses import replace as dc_replace

    from cell.optimize.plan import plan_facing

    plan = plan_facing(model_obj, goal, params.ee, bounds)
    if clean_launch(launch_speed_mps(params, model_obj, plan), plan.elevation_rad):
        return plan
    flat = dc_replace(
        bounds,
        elevation_min=min(bounds.elevation_min, SLOW_LAUNCH_MAX_ELEVATION_RAD),
        elevation_max=min(bounds.elevation_max, SLOW_LAUNCH_MAX_ELEVATION_RAD),
    )
    try:
        return plan_facing(model_obj, goal, params.ee, flat)
    except UnreachableTarget:
        pass
    s_fast = launch_stroke_limit(params, obj, bounds.elevation_max, model_obj)
    if bounds.stroke_max is not None:  # a cap the bounds already have (the grip's)
        s_fast = min(s_fast, bounds.stroke_max)
    return plan_facing(model_obj, goal, params.ee, grip_bounds(bounds, params, s_fast))


def launch_speed_mps(params: ModelParams, model_obj: ObjectParams, plan: Any) -> float:
    """The model's launch speed [m/s] of a static throw plan (the push and the ride)."""
    from cell.model.throw import launch_state

    return float(np.linalg.norm(launch_state(plan.to_batch(model_obj), params.ee)[1][0]))


def check_sortable(
    params: ModelParams,
    obj: ObjectParams,
    bin_spec: Any,
    *,
    policy: str = "auto",
    place_reach_m: float = PLACE_REACH_M,
    bounds: Any = None,
    sides: list[Any] | None = None,
    thrown_bins: Collection[str] = (),
) -> None:
    """Raise CannotGrip or UnreachableTarget when the cell cannot sort `obj` into the
    bin: the pads hold it across none of its sides (`cell.arm.grip_side`), or (for a
    throw) none briskly (`throw_sides`), or no release within the bounds lands it there, across any side that holds, by
    the planner's model of the scene. `sides`: what `holding_sides(params, obj)` gave,
    where the caller has it (`cell.jobgen.sortable_bins`: once an item, not once a bin).
    A bin placed into (`cell.jobbins.places`: `thrown_bins`, the job's `Job.thrown_bins`,
    are thrown into under `auto` though near) is not checked here but by the job's load."""
    from cell.arm.grip_side import holding_sides, throw_sides
    from cell.jobbins import places

    if sides is None:
        sides = holding_sides(params, obj)
    if places(policy, place_reach_m, bin_spec, thrown_bins):
        return
    sides = throw_sides(sides, obj, params)
    err: Exception | None = None
    for side in sides:
        e = side_throw_error(params, side, bin_spec, bounds, obj.name or obj.shape)
        if e is None:
            return
        err = err or e
    assert err is not None
    if bin_spec.id in thrown_bins:  # the reason it is thrown, not placed, said too
        raise type(err)(
            f"{str(err).rstrip('.')}; the bin is within limits.place_reach_m, but the arm "
            "cannot place into it either (its place pose is out of reach: the job's warning)"
        ) from None
    raise err


def side_throw_error(
    params: ModelParams, side: Any, bin_spec: Any, bounds: Any = None, name: str = ""
) -> Exception | None:
    """Why no throw gripped across `side` (a `cell.arm.grip_side.GripSide`) lands in
    `bin_spec` by the planner's model within `bounds` (`ThrowBounds`, default: the
    planner's) and the strokes the pads hold it at (None: a throw does)."""
    from cell.optimize.bounds import ThrowBounds

    goal = (*bin_spec.position, bin_spec.rim_height)
    b = bounds or ThrowBounds()
    try:
        if b.stroke_max is None or side.stroke_max_m < b.stroke_max:
            b = grip_bounds(b, params, side.stroke_max_m, name or side.obj.name or side.obj.shape)
        plan_clean(params, side.obj, params.model_object(side.obj), goal, b)
    except (CannotGrip, UnreachableTarget) as exc:
        return exc
    return None
