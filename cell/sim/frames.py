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

import numpy as np

from cell.errors import MissingDependency
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


def release_orientation(elevation: float, azimuth: float, roll: float = 0.0) -> np.ndarray:
    """Orientation of E whose +z is the throw axis u(e, a) [MODEL.md], rolled by `roll`.

    E = Rz(azimuth) · Ry(π/2 − elevation) · Rz(roll); with roll 0 the grip's x
    axis lies in the vertical plane of the throw (the lower finger carries the
    item's weight).

    Returns:
        Rotation matrix of E in W, shape (3, 3).
    """

    def rz(t: float) -> np.ndarray:
        c, s = math.cos(t), math.sin(t)
        return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])

    b = math.pi / 2 - elevation
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1.0, 0], [-math.sin(b), 0, math.cos(b)]])
    return rz(azimuth) @ ry @ rz(roll)


def quat_from_matrix(r: np.ndarray) -> list[float]:
    """Quaternion (x, y, z, w) of a rotation matrix."""
    from scipy.spatial.transform import Rotation

    return [float(v) for v in Rotation.from_matrix(r).as_quat()]
