"""Frames, mount and poses of the scene's arm and end-effector (world frame W: z up).

E is the end-effector frame: on the base plate face, +z the throw axis, x
across the grip. It sits on the Panda's flange (`panda_link8`) at
Rz(FLANGE_YAW_RAD) · translate(0, 0, FLANGE_TO_EE_M), i.e. on the base plate
face of robots/throwing_ee's `ee_base` as robots/panda_throwing/mount.yaml
mounts it; the TCP `ee_tcp` is at z = EE_TO_TCP_M in E.
"""

from __future__ import annotations

import math
from pathlib import Path

from cell.errors import MissingDependency
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
    "release_orientation",
    "quat_from_matrix",
]

FLANGE_TO_EE_M = 0.015  # [m] flange (panda_link8) to E (the base plate face) along z
FLANGE_YAW_RAD = -math.pi / 4  # [rad] E's yaw on the flange, as robots/panda_throwing/mount.yaml
EE_TO_TCP_M = 0.13  # [m] E to the TCP `ee_tcp` (0.145 m from the flange, robots/throwing_ee)
MOUNT_FORCE_N = 1000.0  # [N] most the mount constraint exerts (EE + item at ~100 m/s^2)
PANDA_READY = (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785)  # [rad]
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
