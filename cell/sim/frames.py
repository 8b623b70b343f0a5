"""Frames, mount and poses of the scene's arm and end-effector (world frame W: z up).

E is the end-effector frame: on the base plate face, +z the throw axis, x
across the grip. It lies FLANGE_TO_EE_M along z from robots/throwing_ee's
`ee_base` (the origin of its `ee_band_joint`), which each arm's mount file puts
on the arm's flange (the Panda's `panda_link8` at Rz(FLANGE_YAW_RAD)); the TCP
`ee_tcp` is at z = EE_TO_TCP_M in E. These numbers are read from the
description (robots/throwing_ee/throwing_ee.urdf, robots/panda_throwing/mount.yaml),
not repeated here.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from cell.errors import InvalidParameter, MissingDependency
from cell.frames import axis_frame, quat_from_matrix
from cell.sim.bins import BinSpec

__all__ = [
    "FLANGE_TO_EE_M",
    "FLANGE_YAW_RAD",
    "EE_TO_TCP_M",
    "MOUNT_FORCE_N",
    "PANDA_READY",
    "DEFAULT_BINS",
    "panda_urdf",
    "ee_pose_for_item_centre",
    "item_behind_ee_m",
    "release_orientation",
    "quat_from_matrix",
]


def _joint_z(root: ET.Element, name: str, path: Path) -> float:
    """The z of a joint's origin in its parent link [m] (the description's joints along z)."""
    for j in root.iter("joint"):
        if j.get("name") == name:
            o = j.find("origin")
            xyz = [float(v) for v in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()]
            if len(xyz) != 3 or xyz[0] or xyz[1]:
                raise InvalidParameter(f"{path}: joint {name!r} must sit on ee_base's z axis")
            return xyz[2]
    raise InvalidParameter(f"{path}: no joint {name!r}")


def _description() -> tuple[float, float, float, tuple[float, ...]]:
    from cell.robot.composite import end_effector_urdf, load_mount

    path = end_effector_urdf()
    root = ET.parse(path).getroot()
    plate = _joint_z(root, "ee_band_joint", path)  # the stroke's zero: the plate face
    tcp = _joint_z(root, "ee_tcp_joint", path)
    panda = load_mount("panda")
    return plate, round(tcp - plate, 12), panda.mount_rpy[2], panda.home


FLANGE_TO_EE_M, EE_TO_TCP_M, FLANGE_YAW_RAD, PANDA_READY = _description()
"""[m] ee_base (on the flange) to E, the base plate face; [m] E to the TCP `ee_tcp`;
[rad] E's yaw on the Panda's flange (its mount file); [rad] the Panda's ready
configuration (its mount file's home)."""
MOUNT_FORCE_N = 1000.0  # [N] most the mount constraint exerts (EE + item at ~100 m/s^2)
DEFAULT_BINS = (
    BinSpec("near", (0.45, 0.45), (0.3, 0.3), 0.12),
    BinSpec("mid", (1.3, 0.3), (0.4, 0.4), 0.15),
    BinSpec("far", (1.9, -0.4), (0.5, 0.5), 0.2),
)


def panda_urdf() -> Path:
    """The Panda's URDF from example-robot-data (pybullet_data's as a fallback).

    Raises:
        MissingDependency: neither is installed.
    """
    import sysconfig

    base = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share"
    p = base / "example-robot-data" / "robots" / "panda_description" / "urdf" / "panda.urdf"
    if p.is_file():
        return p
    try:
        import pybullet_data
    except ImportError:
        raise MissingDependency("the arm needs example-robot-data or pybullet") from None
    q = Path(pybullet_data.getDataPath()) / "franka_panda" / "panda.urdf"
    if q.is_file():
        return q
    raise MissingDependency("no Panda URDF: pip install example-robot-data")


release_orientation = axis_frame
"""Orientation of E whose +z is the throw axis u(e, a) [MODEL.md], rolled by `roll`
(`cell.frames.axis_frame`: with roll 0 the grip's x axis lies in the vertical plane of
the throw, the lower finger carrying the item's weight). Rotation matrix of E in W."""


def item_behind_ee_m(stroke_m: float, obj: Any) -> float:
    """How far along the throw axis the gripped item's centre of mass sits from E [m]:
    on the carriage's face at the stroke, L_s + size_z / 2."""
    return float(stroke_m) + float(obj.size[2]) / 2


def ee_pose_for_item_centre(
    centre: Sequence[float] | np.ndarray,
    elevation: float,
    azimuth: float,
    stroke_m: float,
    obj: Any,
    roll: float = 0.0,
) -> tuple[list[float], list[float]]:
    """The pose of E that puts the gripped item's centre of mass at `centre` [m, W] with
    the throw axis along u(e, a) and the roll of `cell.frames.axis_frame`: every
    platform's release pose (the arm's scene, the drone, the moving base, a campaign).

    Returns:
        (position [m], quaternion x y z w) of E in W.
    """
    r = release_orientation(elevation, azimuth, roll)
    pos = np.asarray(centre, float) - r[:, 2] * item_behind_ee_m(stroke_m, obj)
    return [float(v) for v in pos], quat_from_matrix(r)
