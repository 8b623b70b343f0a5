"""The arm's motion for a release on the move: approach, run-in, coast, stop
(`plan_moving_release`)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cell.errors import InvalidInput, TrajectoryError
from cell.robot.carry import GripHold
from cell.robot.model import Robot
from cell.robot.motion import plan_stop, release_joint_velocity
from cell.robot.moving_coast import CoastTrajectory, grip_move
from cell.robot.trajectory import Trajectory, as_robot, joint_vector

COAST_S = 0.08  # [s] constant grip velocity after the latch opens (the item leaves ~60 ms)


RUN_IN_S = 0.05  # [s] constant grip velocity before it (the plant's mount settles)


# -- the motion --------------------------------------------------------------------
@dataclass(frozen=True)
class MovingReleaseMotion:
    """The arm's motion for a release on the move: approach, coast, stop (see
    `cell.robot.moving_release`).

    Attributes:
        q_start: where the arm starts, at rest [rad].
        q_release: configuration at the release [rad].
        dq_release: joint velocity at the release [rad/s].
        v_release: the grip centre's (the item's centre's) velocity at the release [m/s, W].
        approach: ruckig from rest at q_start to the run-in's start, at its velocity.
        run_in: the straight line at v_release that ends at (q_release, dq_release).
        coast: the straight line at v_release after the release.
        stop: ruckig from the coast's end to rest.
    """

    q_start: np.ndarray
    q_release: np.ndarray
    dq_release: np.ndarray
    v_release: np.ndarray
    approach: Trajectory
    run_in: Trajectory
    coast: Trajectory
    stop: Trajectory

    @property
    def t_release_s(self) -> float:
        """The release instant, from the start [s]: the latch opens then."""
        return float(self.approach.duration + self.run_in.duration)

    @property
    def duration_s(self) -> float:
        """From the start to rest again [s]."""
        return self.t_release_s + self.coast.duration + self.stop.duration

    @property
    def q_end(self) -> np.ndarray:
        """Where the arm comes to rest [rad]."""
        return self.stop.end_state()[0]

    def state(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q [rad], q̇ [rad/s], q̈ [rad/s²]) at t since the start (clamped to [0, duration])."""
        t1 = self.approach.duration
        t2 = t1 + self.run_in.duration
        t3 = t2 + self.coast.duration
        if t <= t1:
            return self.approach.sample(t)
        if t <= t2:
            return self.run_in.sample(t - t1)
        if t <= t3:
            return self.coast.sample(t - t2)
        return self.stop.sample(t - t3)


def plan_moving_release(
    robot: Robot | str,
    q_start: np.ndarray | Sequence[float],
    q_release: np.ndarray | Sequence[float],
    v_release: np.ndarray | Sequence[float],
    *,
    coast_s: float = COAST_S,
    run_in_s: float = RUN_IN_S,
    hold: GripHold | None = None,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
) -> MovingReleaseMotion:
    """Plan the arm's release on the move: from rest at q_start through q_release with
    the grip centre at v_release, then to rest.

    Args:
        robot: the arm (or its name).
        q_start: the start configuration, at rest [rad].
        q_release: the release configuration [rad].
        v_release: the grip centre's velocity at the release [m/s, W], shape (3,).
        coast_s: how long the grip keeps v_release after the release [s].
        run_in_s: how long it moves at v_release before the release [s] (the plant's
            end-effector, pulled by its mount, settles on the arm's velocity then).
        hold: what the pads hold the item with (`cell.robot.carry.GripHold`): the
            approach is slowed (acceleration and jerk scaled together) until the item's
            use of the grip stays within 1/CARRY_MARGIN (`grip_move`); None: full speed.
            Without it a fast approach slides the item along the pads, off the carriage,
            and the push then hits it from a gap (a harder launch than planned).
        velocity_scale: fraction of the joint velocity limits the approach uses; the
            release's joint velocity must be within them.
        acceleration_scale: fraction of the acceleration limits (approach and stop).

    Returns:
        The motion.

    Raises:
        InvalidInput: bad shapes, configurations outside the limits, a negative coast.
        TrajectoryError: the release velocity needs a joint above its (scaled) limit or is
            singular, or ruckig found no approach or stop within the limits.
    """
    rb = as_robot(robot)
    q0 = joint_vector(rb, q_start, "q_start")
    q1 = joint_vector(rb, q_release, "q_release")
    v = np.asarray(v_release, float).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise InvalidInput(f"v_release {v_release!r} must be three finite numbers [m/s]")
    if not (math.isfinite(coast_s) and coast_s > 0 and math.isfinite(run_in_s) and run_in_s > 0):
        raise InvalidInput(f"coast_s {coast_s!r} and run_in_s {run_in_s!r} must be > 0 s")
    dq1 = release_joint_velocity(q1, v, rb)
    ratio = float(np.max(np.abs(dq1) / (rb.limits.velocity * velocity_scale)))
    if ratio > 1.0:
        raise TrajectoryError(
            f"the release velocity needs {ratio:.2f}x the scaled joint velocity limits"
        )
    run_in = CoastTrajectory(rb, q1, v, run_in_s, ending=True)
    q_in, dq_in, _ = run_in.sample(0.0)
    approach = grip_move(
        rb,
        q0,
        q_in,
        dq_in,
        hold,
        velocity_scale=velocity_scale,
        acceleration_scale=acceleration_scale,
    )
    coast = CoastTrajectory(rb, q1, v, coast_s)
    qc, dqc, ddqc = coast.end_state()
    amax = rb.limits.acceleration * acceleration_scale
    stop = plan_stop(
        qc, dqc, rb, ddq0=np.clip(ddqc, -amax, amax), acceleration_scale=acceleration_scale
    )
    return MovingReleaseMotion(q0, q1, dq1, v, approach, run_in, coast, stop)
