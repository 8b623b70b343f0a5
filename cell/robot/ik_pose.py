"""The release pose, the IK result and error types, the success tolerances and the pose error."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.errors import IKFailed, InvalidInput
from cell.robot.model import Robot, axis_frame

POSITION_TOL_M = 1e-3
"""Success tolerance on the grip-centre position [m]."""

AXIS_TOL_RAD = math.radians(0.5)
"""Success tolerance on the throw axis (and the roll, when fixed) [rad]."""


class IKNoSolution(IKFailed):
    """No seed reached the pose; carries the best residual found.

    Attributes:
        position_error_m: best position error [m].
        axis_error_rad: axis error of that attempt [rad].
        q_best: the configuration of that attempt [rad].
    """

    def __init__(
        self, message: str, position_error_m: float, axis_error_rad: float, q_best: np.ndarray
    ) -> None:
        super().__init__(message)
        self.position_error_m = position_error_m
        self.axis_error_rad = axis_error_rad
        self.q_best = q_best

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickled with its attributes (a planning branch's answer, `cell.arm.fork`)."""
        args = (str(self), self.position_error_m, self.axis_error_rad, self.q_best)
        return (type(self), args)


@dataclass(frozen=True)
class ReleasePose:
    """Where the grip centre must be and where the throw axis must point.

    Attributes:
        position: grip centre p in W [m], shape (3,).
        axis: throw axis u in W (unit), shape (3,).
        roll: rotation about u [rad] of ee_tcp relative to `axis_frame(e, a, 0)`, or None
            to leave it free.
    """

    position: np.ndarray
    axis: np.ndarray
    roll: float | None = None

    def __post_init__(self) -> None:
        p = np.asarray(self.position, dtype=float).reshape(-1)
        u = np.asarray(self.axis, dtype=float).reshape(-1)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise InvalidInput(f"release position must be 3 finite numbers [m], got {p!r}")
        n = float(np.linalg.norm(u)) if u.shape == (3,) else 0.0
        if not (math.isfinite(n) and n > 1e-9):
            raise InvalidInput(f"throw axis must be a nonzero 3-vector, got {u!r}")
        if self.roll is not None and not math.isfinite(self.roll):
            raise InvalidInput(f"roll must be finite [rad] or None, got {self.roll!r}")
        object.__setattr__(self, "position", p)
        object.__setattr__(self, "axis", u / n)

    @classmethod
    def from_angles(
        cls,
        position: np.ndarray | tuple[float, float, float],
        elevation: float,
        azimuth: float,
        roll: float | None = None,
    ) -> ReleasePose:
        """The pose from MODEL.md's elevation e and azimuth a [rad]:
        u = (cos e cos a, cos e sin a, sin e)."""
        u = axis_frame(elevation, azimuth)[:, 2]
        return cls(np.asarray(position, dtype=float), u, roll)

    @property
    def elevation(self) -> float:
        """e = asin(u_z) [rad]."""
        return math.asin(max(-1.0, min(1.0, float(self.axis[2]))))

    @property
    def azimuth(self) -> float:
        """a = atan2(u_y, u_x) [rad] (0 for a vertical axis)."""
        if math.hypot(self.axis[0], self.axis[1]) < 1e-12:
            return 0.0
        return math.atan2(float(self.axis[1]), float(self.axis[0]))

    def rotation(self) -> np.ndarray:
        """The full target orientation of ee_tcp (roll 0 when free), shape (3, 3)."""
        return axis_frame(self.elevation, self.azimuth, self.roll or 0.0)


@dataclass(frozen=True)
class IKResult:
    """A converged IK solution.

    Attributes:
        q: arm configuration [rad], shape (n,).
        position_error_m: |p(q) - p| [m].
        axis_error_rad: angle between ee_tcp's z and u [rad].
        roll_error_rad: roll error [rad] (0 when the roll is free).
        iterations: DLS iterations spent over all seeds.
        seeds_tried: seeds started.
    """

    q: np.ndarray
    position_error_m: float
    axis_error_rad: float
    roll_error_rad: float
    iterations: int
    seeds_tried: int


def _log3(r: np.ndarray) -> np.ndarray:
    """Rotation vector of a rotation matrix [rad], shape (3,)."""
    return np.array(_log3_floats(r))


def _log3_floats(r: np.ndarray) -> tuple[float, float, float]:
    """`_log3`'s rotation vector [rad] as three floats."""
    # the trace and the skew part from the nine entries as floats (the same IEEE sums and
    # differences numpy's scalars make, in np.trace's order; a tenth of the time); the
    # scaling too (numpy's float-times-array is the same product, entry by entry)
    f = r.ravel().tolist()
    c = max(-1.0, min(1.0, ((f[0] + f[4] + f[8]) - 1.0) / 2.0))
    th = math.acos(c)
    v0, v1, v2 = f[7] - f[5], f[2] - f[6], f[3] - f[1]
    if th < 1e-8:
        return 0.5 * v0, 0.5 * v1, 0.5 * v2
    if math.pi - th < 1e-6:
        # Near π the antisymmetric part vanishes: take the axis from the symmetric part.
        b = (r + np.eye(3)) / 2.0
        k = int(np.argmax(np.diag(b)))
        ax = b[:, k] / math.sqrt(max(b[k, k], 1e-12))
        w0, w1, w2 = (th * ax / np.linalg.norm(ax)).tolist()
        return w0, w1, w2
    s = th / (2.0 * math.sin(th))
    return s * v0, s * v1, s * v2


def _cross(z: np.ndarray, u: np.ndarray) -> np.ndarray:
    """z × u, shape (3,), from the entries as floats: the same IEEE products and differences
    as numpy's scalars make, a third of the time (the descent asks for it every iteration)."""
    z0, z1, z2 = z.tolist()
    u0, u1, u2 = u.tolist()
    return np.array([z1 * u2 - z2 * u1, z2 * u0 - z0 * u2, z0 * u1 - z1 * u0])


def _axis_angle(z: np.ndarray, u: np.ndarray) -> float:
    """The angle [rad] between z and u: `_axis_error`'s, without its rotation vector."""
    c = _cross(z, u)
    return math.atan2(math.sqrt(float(c @ c)), float(z @ u))


def _axis_error(z: np.ndarray, u: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, float]:
    """Rotation vector that turns z onto u (perpendicular to both) and its angle [rad]."""
    c = _cross(z, u)
    s = math.sqrt(float(c @ c))
    th = math.atan2(s, float(z @ u))
    if s > 1e-12:
        return th * c / s, th
    return (th * x if th > 1.0 else np.zeros(3)), th


def pose_error(robot: Robot, q: np.ndarray, pose: ReleasePose) -> tuple[float, float, float]:
    """How far configuration q puts the grip centre from a release pose.

    Args:
        robot: the arm.
        q: configuration [rad], shape (n,).
        pose: the target.

    Returns:
        (position error [m], axis error [rad], roll error [rad]; 0 when the roll is free).
    """
    p, r = robot.tcp_pose(q)
    ep = float(np.linalg.norm(pose.position - p))
    _, th = _axis_error(r[:, 2], pose.axis, r[:, 0])
    roll = 0.0
    if pose.roll is not None:
        roll = float(np.linalg.norm(_log3(pose.rotation() @ r.T)))
    return ep, th, roll
