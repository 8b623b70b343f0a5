"""The grip's moves for a release on the move: the coast along a straight line at constant
velocity (`CoastTrajectory`) and the move to it within the grip (`grip_move`)."""

from __future__ import annotations

import logging
import math

import numpy as np
from numpy.linalg import _umath_linalg  # type: ignore[attr-defined]

from cell.errors import TrajectoryError
from cell.frames import axis_frame
from cell.robot.carry import GripHold
from cell.robot.model import Robot
from cell.robot.motion import plan_move
from cell.robot.trajectory import Trajectory

log = logging.getLogger(__name__)


_COAST_H = 1e-3  # [s] the coast's integration step (RK4) and sample period

_lstsq = _umath_linalg.lstsq


def throw_axis(elevation: float, azimuth: float) -> np.ndarray:
    """The throw axis u(e, a) in W, shape (3,): `cell.frames.axis_frame`'s z."""
    return axis_frame(elevation, azimuth)[:, 2]


# -- the coast ---------------------------------------------------------------------
class CoastTrajectory(Trajectory):
    """The grip centre on a straight line at a constant velocity, the axis fixed.

    q̇ = J(q)⁺ [v; 0] integrated with RK4 every _COAST_H from q0; between samples the
    state is the cubic Hermite interpolant of (q, q̇), q̈ its derivative.

    Args:
        robot: the arm.
        q0: configuration at the start (with `ending`, at the end) [rad], shape (dof,).
        v: grip-centre velocity [m/s, W], shape (3,).
        duration: the coast's length [s].
        ending: the line ends at q0 (a run-in to the release) instead of starting there.

    Raises:
        TrajectoryError: a joint leaves its position or velocity limit on the way.
    """

    def __init__(
        self, robot: Robot, q0: np.ndarray, v: np.ndarray, duration: float, *, ending: bool = False
    ) -> None:
        self.dof = robot.dof
        self.kind = "coast"
        self.duration = float(duration)
        sign = -1.0 if ending else 1.0  # a run-in is integrated backwards from its end
        twist = np.concatenate([sign * np.asarray(v, float), np.zeros(3)])[:, None]

        def rate(q: np.ndarray) -> np.ndarray:
            # np.linalg.lstsq(J, twist, rcond=1e-10)[0]: the gufunc it calls (LAPACK's
            # gelsd), called directly, bit for bit (tests/test_coast_rate.py), without
            # its checks and copies, which took 40 % of its time (~30,000 calls on tune
            # layout 2's throws)
            return _lstsq(robot.tcp_jacobian(q), twist, 1e-10, signature="ddd->ddid")[0][:, 0]

        n = max(1, int(math.ceil(self.duration / _COAST_H)))
        h = self.duration / n
        qs = [np.asarray(q0, float)]
        dqs = [rate(qs[0])]
        for _ in range(n):
            q = qs[-1]
            k1 = dqs[-1]
            k2 = rate(q + h / 2 * k1)
            k3 = rate(q + h / 2 * k2)
            k4 = rate(q + h * k3)
            qn = q + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            qs.append(qn)
            dqs.append(rate(qn))
        self._ts = np.linspace(0.0, self.duration, n + 1)
        self._qs = np.array(qs)
        self._dqs = np.array(dqs)
        if ending:
            self._qs, self._dqs = self._qs[::-1].copy(), -self._dqs[::-1]
        lim = robot.limits
        if np.any(self._qs < lim.lower) or np.any(self._qs > lim.upper):
            raise TrajectoryError("the coast after the release leaves a joint's position range")
        if np.any(np.abs(self._dqs) > lim.velocity):
            raise TrajectoryError("the coast after the release needs a joint above its velocity")

    def _eval(self, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        h = self._ts[1] - self._ts[0]
        i = np.clip(((ts - self._ts[0]) / h).astype(int), 0, len(self._ts) - 2)
        s = ((ts - self._ts[i]) / h)[:, None]
        p0, p1 = self._qs[i], self._qs[i + 1]
        m0, m1 = self._dqs[i] * h, self._dqs[i + 1] * h
        s2, s3 = s * s, s * s * s
        q = (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * p1
        q += (s3 - s2) * m1
        dq = ((6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * m0 + (-6 * s2 + 6 * s) * p1) / h
        dq += (3 * s2 - 2 * s) * m1 / h
        ddq = ((12 * s - 6) * p0 + (6 * s - 4) * m0 + (-12 * s + 6) * p1 + (6 * s - 2) * m1) / (
            h * h
        )
        return q, dq, ddq


def grip_move(
    robot: Robot,
    q0: np.ndarray,
    q1: np.ndarray,
    dq1: np.ndarray | None,
    hold: GripHold | None,
    *,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
    iterations: int = 6,
    gentle: bool = False,
) -> Trajectory:
    """Ruckig from rest at q0 to (q1, dq1), the fastest whose use of the grip stays within
    1/CARRY_MARGIN (`cell.robot.carry.grip_use`): bisection on a factor s that scales the
    acceleration and jerk limits. None for `hold`: the move at the given scales.

    With `gentle`, a move whose path asks too much of the grip at any speed (it turns a
    hanging item) is made at GENTLE_SCALE of the limits instead, as `plan_carry` does.

    Raises:
        TrajectoryError: no move at all (see plan_move), or (without `gentle`) the grip
            cannot hold the item even at the slowest factor tried (2 % of the limits).
    """
    from cell.robot.carry import CARRY_MARGIN, grip_use

    def attempt(s: float) -> tuple[Trajectory, float]:
        tr = plan_move(
            q0,
            None,
            q1,
            dq1,
            robot,
            velocity_scale=velocity_scale,
            acceleration_scale=acceleration_scale * s,
            jerk_scale=s,
        )
        return tr, (0.0 if hold is None else grip_use(tr, robot, hold))

    bound = 1.0 / CARRY_MARGIN
    best = attempt(1.0)
    if best[1] <= bound:
        return best[0]
    lo, hi = 0.0, 1.0
    found: Trajectory | None = None
    for _ in range(iterations):
        mid = max(0.02, 0.5 * (lo + hi))
        tr, use = attempt(mid)
        if use <= bound:
            lo, found = mid, tr
        else:
            hi = mid
    if found is None and gentle:
        from cell.robot.carry import GENTLE_SCALE

        log.info("no speed keeps the move within the grip: moving at %.0f %%", 100 * GENTLE_SCALE)
        return attempt(GENTLE_SCALE)[0]
    if found is None:
        raise TrajectoryError(
            f"no ruckig move to the release keeps the item in the grip (use {best[1]:.2f} "
            f"at full speed, above {bound:.2f} even at {100 * max(0.02, hi):.0f} %)"
        )
    return found
