"""One docs/throw_log.md row from what a throw was: the one place rows are built."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from cell.model.objects import ObjectParams

__all__ = ["object_columns", "throw_record"]


def object_columns(obj: ObjectParams) -> dict[str, Any]:
    """A throw-log row's object columns, as the object gives them: object_id (its catalogue
    id), shape, mass_kg [kg] and size_x_m, size_y_m, size_z_m [m]."""
    return {
        "object_id": obj.name,
        "shape": obj.shape,
        "mass_kg": obj.mass,
        "size_x_m": obj.size[0],
        "size_y_m": obj.size[1],
        "size_z_m": obj.size[2],
    }


def throw_record(
    throw_id: str,
    obj: ObjectParams,
    *,
    stroke_m: float,
    position_m: Sequence[float] | np.ndarray,
    elevation_rad: float,
    azimuth_rad: float,
    roll_rad: float = 0.0,
    base_velocity_mps: Sequence[float] | np.ndarray = (0.0, 0.0, 0.0),
    platform: str = "arm",
    rotor_rpm: float = 0.0,
    land_z_m: float,
    landed_xy_m: Sequence[float] | np.ndarray | None = None,
    **extra: Any,
) -> dict[str, Any]:
    """A throw-log row (docs/throw_log.md columns, SI units, world frame W).

    Args:
        throw_id: unique id.
        obj: the object thrown (its id, shape, mass and extents are logged).
        stroke_m: stroke L_s at release [m].
        position_m: grip centre at release [m, W].
        elevation_rad, azimuth_rad, roll_rad: throw axis and roll at release [rad].
        base_velocity_mps: end-effector velocity at release [m/s, W].
        platform: arm, mobile or drone.
        rotor_rpm: rotor speed of a drone [rpm].
        land_z_m: height of the plane the landing is measured on [m].
        landed_xy_m: observed landing point on that plane [m, W]; None leaves it empty.
        **extra: optional and extra columns (session, time_s, t_flight_s, ...).
    """
    vx, vy, vz = (float(v) for v in base_velocity_mps)
    row: dict[str, Any] = {
        "throw_id": throw_id,
        "object_id": obj.name or obj.shape,
        "shape": obj.shape,
        "mass_kg": float(obj.mass),
        "size_x_m": float(obj.size[0]),
        "size_y_m": float(obj.size[1]),
        "size_z_m": float(obj.size[2]),
        "stroke_m": float(stroke_m),
        "x_m": float(position_m[0]),
        "y_m": float(position_m[1]),
        "z_m": float(position_m[2]),
        "elevation_rad": float(elevation_rad),
        "azimuth_rad": float(azimuth_rad),
        "roll_rad": float(roll_rad),
        "vx_mps": vx,
        "vy_mps": vy,
        "vz_mps": vz,
        "platform": platform,
        "rotor_rpm": float(rotor_rpm),
        "land_z_m": float(land_z_m),
        "landed_x_m": "" if landed_xy_m is None else float(landed_xy_m[0]),
        "landed_y_m": "" if landed_xy_m is None else float(landed_xy_m[1]),
    }
    row.update(extra)
    return row
