"""The reachable range of an object, and the error for a target outside it."""

from __future__ import annotations

import math

import numpy as np

from cell.errors import UnreachableTarget
from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams
from cell.model.throw import predict_landing
from cell.optimize.bounds import ThrowBounds
from cell.optimize.verify import sigma_batch

__all__ = ["reach_range", "unreachable_error"]


def reach_range(
    obj: ObjectParams,
    ee: EndEffectorParams,
    bounds: ThrowBounds,
    release: np.ndarray,
    land_z: float,
) -> tuple[float, float]:
    """(smallest, largest) horizontal reach [m] from a release point onto z = land_z.

    Over the bounds' candidate elevations at the two stroke limits (the reach
    falls with the stroke), with a fixed base. NaN, NaN if nothing lands.
    """
    elev = bounds.elevations()
    s_lo, s_hi = bounds.stroke_range(ee)
    n = len(elev)
    sig = np.zeros((2 * n, 10))
    sig[:, 0:3] = release
    sig[:, 7] = np.r_[elev, elev]
    sig[:, 9] = np.r_[np.full(n, s_lo), np.full(n, s_hi)]
    land = predict_landing(sigma_batch(obj, sig, land_z), ee, strict=False)
    if not land.landed.any():
        return float("nan"), float("nan")
    reach = np.hypot(land.x - release[0], land.y - release[1])[land.landed]
    return float(reach.min()), float(reach.max())


def unreachable_error(
    obj: ObjectParams,
    target: np.ndarray,
    ee: EndEffectorParams,
    bounds: ThrowBounds,
    release: np.ndarray,
    detail: str,
) -> UnreachableTarget:
    lo, hi = reach_range(obj, ee, bounds, release, float(target[2]))
    dist = math.hypot(target[0] - release[0], target[1] - release[1])
    name = obj.name or f"the {obj.mass:.3f} kg {obj.shape}"
    s_lo, s_hi = bounds.stroke_range(ee)
    where = (
        f"from ({release[0]:.2f}, {release[1]:.2f}, {release[2]:.2f}) m at elevations "
        f"{math.degrees(bounds.elevation_min):.0f}…{math.degrees(bounds.elevation_max):.0f}° "
        f"and strokes {s_lo:.3f}…{s_hi:.3f} m"
    )
    if math.isnan(lo):
        reach = f"{name} never comes down onto z = {target[2]:.3f} m {where}"
    else:
        reach = f"{name} reaches {lo:.2f} … {hi:.2f} m onto z = {target[2]:.3f} m {where}"
    near = bounds.clip_position(np.array([target[0], target[1], bounds.position_max[2]]))
    if not np.allclose(near, release):
        _, hi_box = reach_range(obj, ee, bounds, near, float(target[2]))
        if not math.isnan(hi_box):
            d_box = math.hypot(target[0] - near[0], target[1] - near[1])
            reach += (
                f"; from the box point nearest the target, ({near[0]:.2f}, {near[1]:.2f}, "
                f"{near[2]:.2f}) m, {d_box:.2f} m away, it reaches at most {hi_box:.2f} m"
            )
    err = UnreachableTarget(
        f"target ({target[0]:.3f}, {target[1]:.3f}, {target[2]:.3f}) m is out of reach: it lies "
        f"{dist:.2f} m from the release point; {reach}. {detail}"
    )
    err.reach_range = (lo, hi)  # type: ignore[attr-defined]
    return err
