"""Joint limits of an arm: position and velocity from its URDF, acceleration and jerk from
its mount description (robots/<mount>/mount.yaml; the URDFs carry no such limits — the
Panda's are Franka's datasheet values, the UR5's a documented choice, see the READMEs).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cell.errors import InvalidInput

__all__ = ["JointLimits"]


@dataclass(frozen=True)
class JointLimits:
    """Per-joint limits of an arm, all arrays of shape (n,).

    Attributes:
        lower: lower position limits [rad].
        upper: upper position limits [rad].
        velocity: velocity limits [rad/s] (symmetric).
        acceleration: acceleration limits [rad/s²] (symmetric).
        jerk: jerk limits [rad/s³] (symmetric).
    """

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray

    @property
    def dof(self) -> int:
        """Number of joints."""
        return int(self.lower.shape[0])

    def check_position(self, q: np.ndarray, name: str = "q", tol: float = 1e-9) -> None:
        """Raise if a configuration is outside the position limits.

        Args:
            q: configuration, shape (n,) [rad].
            name: what to call it in the message.
            tol: tolerance [rad].

        Raises:
            InvalidInput: wrong shape, not finite, or outside the limits (the message names
                the joint, its value and its range).
        """
        q = np.asarray(q, dtype=float)
        if q.shape != (self.dof,) or not np.all(np.isfinite(q)):
            raise InvalidInput(f"{name} must be {self.dof} finite joint values, got {q!r}")
        bad = np.flatnonzero((q < self.lower - tol) | (q > self.upper + tol))
        if bad.size:
            i = int(bad[0])
            raise InvalidInput(
                f"{name}[{i}] = {q[i]:.4f} rad is outside joint {i + 1}'s range "
                f"[{self.lower[i]:.4f}, {self.upper[i]:.4f}] rad"
            )

    def check_velocity(self, dq: np.ndarray, name: str = "dq") -> None:
        """Raise if a joint velocity is not within the velocity limits.

        Args:
            dq: joint velocity, shape (n,) [rad/s].
            name: what to call it in the message.

        Raises:
            InvalidInput: wrong shape, not finite or above a limit.
        """
        dq = np.asarray(dq, dtype=float)
        if dq.shape != (self.dof,) or not np.all(np.isfinite(dq)):
            raise InvalidInput(f"{name} must be {self.dof} finite joint velocities, got {dq!r}")
        bad = np.flatnonzero(np.abs(dq) > self.velocity)
        if bad.size:
            i = int(bad[0])
            raise InvalidInput(
                f"{name}[{i}] = {dq[i]:.4f} rad/s exceeds joint {i + 1}'s velocity limit "
                f"{self.velocity[i]:.4f} rad/s"
            )
