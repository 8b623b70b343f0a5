"""Frames and quaternions, written once: the throw-axis frame and its roll convention.

The throw-axis frame (world frame W: z up) is

    R(e, a, roll) = Rz(a) · Ry(π/2 − e) · Rz(roll),

whose third column is the throw axis u = (cos e cos a, cos e sin a, sin e) (MODEL.md,
`cell.model.throw.throw_axis`). With roll 0 its x axis, across the grip (the pads, the
band), lies in the vertical plane of the throw, pointing down for e > 0: the lower pad
carries the item's weight. Every user of a roll follows this: the arm's IK (`ee_tcp`),
the PyBullet scene's end-effector frame E, the drone and mobile scenes, the rigid-body
model's object frame, and the `roll_rad` column of a throw log.

Quaternions come in two orders, each named: `quat_from_matrix` gives (x, y, z, w), as
PyBullet takes them; the `_wxyz` functions work in (w, x, y, z), as the rigid-body model
integrates them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = [
    "axis_frame",
    "matrix_from_quat_wxyz",
    "quat_exp_wxyz",
    "quat_from_matrix",
    "quat_mul_wxyz",
    "quat_wxyz_from_matrix",
    "rot_z",
    "tcp_for_item_centre",
]


def rot_z(angle: float) -> np.ndarray:
    """Rotation by `angle` [rad] about z, shape (3, 3)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def axis_frame(elevation: float, azimuth: float, roll: float = 0.0) -> np.ndarray:
    """The throw-axis frame R(e, a, roll) = Rz(a) · Ry(π/2 − e) · Rz(roll) in W.

    Args:
        elevation: e [rad].
        azimuth: a [rad].
        roll: rotation about the throw axis [rad]; 0 puts x (across the grip) in the
            vertical plane of the throw.

    Returns:
        Rotation matrix, shape (3, 3); its third column is the throw axis u.
    """
    b = math.pi / 2 - elevation
    c, s = math.cos(b), math.sin(b)
    ry = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    return rot_z(azimuth) @ ry @ rot_z(roll)


def quat_from_matrix(r: np.ndarray) -> list[float]:
    """Quaternion (x, y, z, w) of a rotation matrix (PyBullet's order)."""
    from scipy.spatial.transform import Rotation

    return [float(v) for v in Rotation.from_matrix(r).as_quat()]


def matrix_from_quat_wxyz(q: np.ndarray) -> np.ndarray:
    """Rotation matrix of a unit quaternion (w, x, y, z), shape (3, 3)."""
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def quat_wxyz_from_matrix(r: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation matrix, shape (4,)."""
    tr = np.trace(r)
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    else:
        i = int(np.argmax(np.diag(r)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = math.sqrt(1.0 + r[i, i] - r[j, j] - r[k, k]) * 2
        q = [0.0, 0.0, 0.0, 0.0]
        q[0] = (r[k, j] - r[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (r[j, i] + r[i, j]) / s
        q[1 + k] = (r[k, i] + r[i, k]) / s
    qa = np.array(q)
    return qa / np.linalg.norm(qa)


def quat_mul_wxyz(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a · b of quaternions (w, x, y, z)."""
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ]
    )


def quat_exp_wxyz(omega: np.ndarray, h: float) -> np.ndarray:
    """The rotation by the angular velocity omega [rad/s] over h [s], as (w, x, y, z)."""
    angle = float(np.linalg.norm(omega)) * h
    if angle < 1e-12:
        return np.array([1.0, *(0.5 * h * omega)])
    axis = omega / np.linalg.norm(omega)
    return np.array([math.cos(angle / 2), *(math.sin(angle / 2) * axis)])


def tcp_for_item_centre(
    centre: Sequence[float] | np.ndarray,
    elevation: float,
    azimuth: float,
    stroke_m: float,
    obj: Any,
) -> np.ndarray:
    """The TCP (`ee_tcp`) position [m, W] that puts the gripped item's centre of mass at
    `centre` (an `ObjectParams`' centre, gripped at stroke L_s = `stroke_m` [m]) with the
    throw axis along u(e, a): what the arm's IK aims at. EE_TO_TCP_M, the TCP's height in
    E, is read from the end-effector's description (`cell.sim.frames`)."""
    from cell.sim.frames import EE_TO_TCP_M

    u = axis_frame(elevation, azimuth)[:, 2]
    return np.asarray(centre, float) + u * (EE_TO_TCP_M - stroke_m - obj.size[2] / 2)
