"""The joint trajectory type both planners return, and a limit check over samples."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from itertools import chain
from typing import Any

import numpy as np

from cell.errors import InvalidInput
from cell.robot.model import Robot, load_robot

__all__ = [
    "POSITION_TOL_RAD",
    "RuckigTrajectory",
    "ToppraTrajectory",
    "Trajectory",
    "as_robot",
    "check_limits",
    "joint_vector",
]

POSITION_TOL_RAD = 1e-6
"""Tolerance on the joint position limits [rad]."""


class Trajectory(ABC):
    """A joint trajectory q(t) for t in [0, duration].

    Sampling outside [0, duration] clamps t to the interval (the planned end state; a move
    ending with nonzero velocity needs its own follow-up trajectory to stop).

    Attributes:
        duration: total time [s].
        dof: number of joints.
        kind: "toppra" or "ruckig".
    """

    duration: float
    dof: int
    kind: str

    @abstractmethod
    def _eval(self, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Joint state at one time.

        Args:
            t: time since the start [s].

        Returns:
            (q [rad], dq [rad/s], ddq [rad/s²]), each shape (dof,).
        """
        q, dq, ddq = self.sample_many(np.array([t], dtype=float))
        return q[0], dq[0], ddq[0]

    def sample_many(self, ts: np.ndarray | Sequence[float]) -> tuple[np.ndarray, ...]:
        """Joint states at many times.

        Args:
            ts: times since the start [s], shape (k,).

        Returns:
            (q [rad], dq [rad/s], ddq [rad/s²]), each shape (k, dof).
        """
        t = np.clip(np.asarray(ts, dtype=float).reshape(-1), 0.0, self.duration)
        return self._eval(t)

    def positions(self, ts: np.ndarray | Sequence[float]) -> np.ndarray:
        """The joint positions [rad] at many times [s], shape (k, dof): `sample_many`'s
        first array (a move that can give them alone does so: `RuckigTrajectory`)."""
        return self.sample_many(ts)[0]

    def end_state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, dq, ddq) at t = duration."""
        return self.sample(self.duration)


class ToppraTrajectory(Trajectory):
    """A toppra parameterisation (spline through the waypoints), from `plan_path`."""

    def __init__(self, traj: Any, dof: int) -> None:
        self._traj = traj
        self.duration = float(traj.duration)
        self.dof = dof
        self.kind = "toppra"

    def _eval(self, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        from toppra.parametrizer import ParametrizeConstAccel

        from cell.robot.toppra_bulk import const_accel_states

        if isinstance(self._traj, ParametrizeConstAccel) and ts.size > 0:
            # `plan_path`'s: the same states, the parameterisation evaluated once
            q, dq, ddq = const_accel_states(self._traj, ts)
        else:
            q, dq, ddq = self._traj(ts), self._traj(ts, 1), self._traj(ts, 2)
        return np.atleast_2d(q), np.atleast_2d(dq), np.atleast_2d(ddq)


class RuckigTrajectory(Trajectory):
    """A ruckig move, from `plan_move` or `plan_stop`."""

    def __init__(self, traj: Any, dof: int) -> None:
        self._traj = traj
        self.duration = float(traj.duration)
        self.dof = dof
        self.kind = "ruckig"

    def _eval(self, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        # ruckig answers each instant with three lists of floats: read them all into one
        # array at once (`np.fromiter`) rather than row by row, which cost twice ruckig's
        # own evaluation; the same floats, laid out as before, (3, k, dof) C-contiguous
        k, n = ts.size, self.dof
        flat = np.fromiter(
            chain.from_iterable(chain.from_iterable(map(self._traj.at_time, ts.tolist()))),
            float,
            count=3 * k * n,
        )
        out = np.ascontiguousarray(flat.reshape(k, 3, n).transpose(1, 0, 2))
        return out[0], out[1], out[2]

    def positions(self, ts: np.ndarray | Sequence[float]) -> np.ndarray:
        """`sample_many`'s positions alone: the same floats (ruckig's positions at the same
        clipped times), without reading its velocities and accelerations."""
        return self._positions(np.clip(np.asarray(ts, dtype=float).reshape(-1), 0.0, self.duration))

    def _positions(self, ts: np.ndarray) -> np.ndarray:
        """The positions [rad] at the times ts [s], shape (k, dof), as `_eval`'s."""
        at = self._traj.at_time
        flat = np.fromiter(
            chain.from_iterable(at(t)[0] for t in ts.tolist()), float, count=ts.size * self.dof
        )
        return flat.reshape(ts.size, self.dof)

    def stays_within(
        self,
        max_acceleration: np.ndarray,
        lower: np.ndarray,
        upper: np.ndarray,
        n: int = 16,
        most: int = 160,
    ) -> bool:
        """True where the move provably keeps every joint within [lower, upper] [rad]
        (each shape (dof,)); False where that is not shown (a joint's sample outside, or
        more than `most` samples needed): `position_bounds` then says.

        Between two samples dt apart a joint whose |q̈| ≤ A has its maximum either at a
        sample or where q̇ = 0, within A·dt²/8 of the higher sample (and so its minimum);
        A is the larger of `max_acceleration` [rad/s²] and the move's start acceleration
        (ruckig keeps within the limits, first bringing down an acceleration beyond them).
        An interval that this does not clear is halved, down to the joints' limits
        sampled at the start of a move from rest (where the arm waits at a limit). n
        samples to begin with, evenly spread, the ends included. Where it is True, every
        position ruckig gives within the move, and so `position_bounds`'s, lies within
        [lower, upper] (with 1e-12 rad of the bounds left for ruckig's rounding)."""
        if self.duration <= 0.0:
            q0 = np.asarray(self._traj.at_time(0.0)[0], dtype=float)
            return bool(np.all(q0 >= lower) and np.all(q0 <= upper))
        acc = np.maximum(max_acceleration, np.abs(self._traj.at_time(0.0)[2]))
        acc = acc * (1.0 + 1e-9) / 8.0
        top, bottom = np.asarray(upper) - 1e-12, np.asarray(lower) + 1e-12
        ts = np.linspace(0.0, self.duration, n)
        q = self._positions(ts)
        if np.any(q > upper) or np.any(q < lower):
            return False
        ta, tb, qa, qb = ts[:-1], ts[1:], q[:-1], q[1:]
        taken = n
        while True:
            slack = ((tb - ta) ** 2)[:, None] * acc
            out = (np.maximum(qa, qb) + slack > top) | (np.minimum(qa, qb) - slack < bottom)
            left = np.flatnonzero(out.any(axis=1))
            if left.size == 0:
                return True
            taken += left.size
            if taken > most:
                return False
            ta, tb, qa, qb = ta[left], tb[left], qa[left], qb[left]
            tm = 0.5 * (ta + tb)
            qm = self._positions(tm)
            if np.any(qm > upper) or np.any(qm < lower):
                return False
            ta, tb = np.r_[ta, tm], np.r_[tm, tb]
            qa, qb = np.r_[qa, qm], np.r_[qm, qb]

    def position_bounds(
        self,
        max_acceleration: np.ndarray,
        n: int = 400,
        within: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """(min, max) position of each joint over the move [rad], each shape (dof,).

        ruckig 0.19.4's own `position_extrema` is wrong for time-synchronised profiles (it
        missed a maximum by 36 mm in a check), so the extrema are found by sampling and then
        refined: between samples dt apart a joint with |ddq| ≤ a passes its sampled values
        by at most a·dt²/8 (the velocity is zero at a true extremum), so every sampled local
        extremum within that margin of the sampled extreme is refined by a ternary search
        over its two neighbouring intervals.

        Args:
            max_acceleration: per-joint acceleration bound [rad/s²], shape (dof,).
            n: samples.
            within: (lower, upper) [rad], each shape (dof,): a joint's extremum is refined
                only where refining could take it past these (its sampled extremum within
                the margin of them); elsewhere the sampled one is returned, which lies
                inside them as the refined one does. None: every joint refined.

        Returns:
            (minimum, maximum), each shape (dof,).
        """
        if self.duration <= 0.0:
            q0 = np.asarray(self._traj.at_time(0.0)[0], dtype=float)
            return q0.copy(), q0.copy()
        ts = np.linspace(0.0, self.duration, n)
        q = self._positions(ts)
        slack = np.asarray(max_acceleration, dtype=float) * (ts[1] - ts[0]) ** 2 / 8
        lo, hi = q.min(axis=0), q.max(axis=0)
        for j in range(self.dof):
            for sign, ext in ((1.0, hi), (-1.0, lo)):
                if within is not None and (
                    hi[j] + slack[j] <= within[1][j]
                    if sign > 0
                    else lo[j] - slack[j] >= within[0][j]
                ):
                    continue  # the refined extremum cannot pass the bound either
                f = sign * q[:, j]
                pad = np.r_[-np.inf, f, -np.inf]
                peaks = np.flatnonzero((f >= pad[:-2]) & (f >= pad[2:]) & (f >= f.max() - slack[j]))
                for k in peaks.tolist():
                    a, b = float(ts[max(k - 1, 0)]), float(ts[min(k + 1, n - 1)])
                    for _ in range(40):
                        m1, m2 = a + (b - a) / 3, b - (b - a) / 3
                        g1 = sign * self._traj.at_time(m1)[0][j]
                        g2 = sign * self._traj.at_time(m2)[0][j]
                        a, b = (m1, b) if g1 < g2 else (a, m2)
                    best = self._traj.at_time((a + b) / 2)[0][j]
                    ext[j] = max(ext[j], best) if sign > 0 else min(ext[j], best)
        return lo, hi


def as_robot(robot: Robot | str) -> Robot:
    """The Robot itself, or the one of that name."""
    return load_robot(robot) if isinstance(robot, str) else robot


def joint_vector(robot: Robot, v: np.ndarray | Sequence[float], name: str) -> np.ndarray:
    """v as a finite float array of shape (dof,); InvalidInput naming `name` otherwise."""
    a = np.asarray(v, dtype=float).reshape(-1)
    if a.shape != (robot.dof,) or not np.all(np.isfinite(a)):
        raise InvalidInput(f"{name} must be {robot.dof} finite joint values, got {v!r}")
    return a


def check_limits(
    traj: Trajectory, robot: Robot | str, n: int = 2001, rtol: float = 1e-6
) -> dict[str, float]:
    """The worst use of each limit over a densely sampled trajectory.

    Args:
        traj: the trajectory.
        robot: the robot whose limits apply.
        n: samples over [0, duration].
        rtol: relative tolerance (1.0 + rtol counts as within).

    Returns:
        {"velocity", "acceleration", "position_margin_rad"}: the largest |dq|/v_max and
        |ddq|/a_max over joints and samples, and the smallest distance to a position limit
        [rad] (negative = outside).
    """
    rb = as_robot(robot)
    q, dq, ddq = traj.sample_many(np.linspace(0.0, traj.duration, n))
    lim = rb.limits
    return {
        "velocity": float(np.max(np.abs(dq) / lim.velocity)),
        "acceleration": float(np.max(np.abs(ddq) / lim.acceleration)),
        "position_margin_rad": float(min(np.min(q - lim.lower), np.min(lim.upper - q))),
    }
