"""`plan_path`: toppra's time-optimal parameterisation of a spline through joint
waypoints, at rest at both ends."""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import Any

import numpy as np

from cell.errors import InvalidInput, TrajectoryError
from cell.robot.model import Robot
from cell.robot.spline import spline_path
from cell.robot.toppra_bulk import propose_gridpoints
from cell.robot.trajectory import (
    POSITION_TOL_RAD,
    ToppraTrajectory,
    Trajectory,
    as_robot,
    check_limits,
    joint_vector,
)

log = logging.getLogger(__name__)


def _check_scales(**scales: float) -> None:
    """InvalidInput naming the first limit scale outside (0, 1]."""
    for name, s in scales.items():
        if not (0.0 < s <= 1.0):
            raise InvalidInput(f"{name} must be in (0, 1], got {s}")


def _distinct_waypoints(
    rb: Robot, waypoints_q: Sequence[np.ndarray] | np.ndarray
) -> list[np.ndarray]:
    """The waypoints [rad] checked against the joint limits, repeats dropped (≥ 2 left)."""
    wps = [joint_vector(rb, w, f"waypoint {i}") for i, w in enumerate(waypoints_q)]
    if len(wps) < 2:
        raise InvalidInput(f"plan_path needs at least 2 waypoints, got {len(wps)}")
    for i, w in enumerate(wps):
        rb.limits.check_position(w, name=f"waypoint {i}", tol=POSITION_TOL_RAD)
    # Drop repeated waypoints: a zero-length segment has no path parameter.
    keep = [wps[0]] + [
        w for a, w in zip(wps, wps[1:], strict=False) if np.linalg.norm(w - a) > 1e-9
    ]
    if len(keep) < 2:
        raise InvalidInput("plan_path waypoints are all the same configuration: nothing to do")
    return keep


def _spline_within(rb: Robot, keep: list[np.ndarray]) -> Any:
    """The spline through the distinct waypoints; TrajectoryError if it leaves the limits."""
    path = spline_path(keep, rb.limits.lower, rb.limits.upper)
    # Sample the geometric path itself: where no spline keeps within the limits (a waypoint
    # on a limit, the path turning back there), it leaves them.
    qs = path(np.linspace(0.0, 1.0, 400))
    lo = np.min(qs - rb.limits.lower)
    hi = np.min(rb.limits.upper - qs)
    if min(lo, hi) < -POSITION_TOL_RAD:
        raise TrajectoryError(
            f"the spline through the {len(keep)} waypoints leaves the joint limits by "
            f"{-min(lo, hi):.4f} rad between waypoints; add intermediate waypoints"
        )
    return path


# toppra's joint-limit constraints by their limits' bytes: building one formats its limits
# into a description string (1.6 ms a pair, more than toppra's own planning of a short
# path's grid takes); nothing in them changes once built. Bounded: cleared when full.
_LIMIT_CONSTRAINTS: dict[bytes, tuple[Any, Any]] = {}
_LIMIT_CONSTRAINTS_MAX = 256


def _joint_limits(vlim: np.ndarray, alim: np.ndarray) -> tuple[Any, Any]:
    """toppra's joint velocity and acceleration (interpolated) constraints for the limits
    vlim and alim, each shape (dof, 2) [rad/s, rad/s²], built once for those limits."""
    import toppra.constraint as constraint

    key = vlim.tobytes() + alim.tobytes()
    found = _LIMIT_CONSTRAINTS.get(key)
    if found is None:
        if len(_LIMIT_CONSTRAINTS) >= _LIMIT_CONSTRAINTS_MAX:
            _LIMIT_CONSTRAINTS.clear()
        found = (
            constraint.JointVelocityConstraint(vlim),
            constraint.JointAccelerationConstraint(
                alim, discretization_scheme=constraint.DiscretizationType.Interpolation
            ),
        )
        _LIMIT_CONSTRAINTS[key] = found
    return found


def plan_path(
    waypoints_q: Sequence[np.ndarray] | np.ndarray,
    robot: Robot | str,
    *,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
    constraints: Sequence[Any] = (),
) -> Trajectory:
    """Time-optimal trajectory along a spline through joint waypoints, at rest at both ends.

    The path is a cubic spline through the waypoints, with the path parameter at each
    waypoint proportional to the cumulative joint-space distance; where that spline
    overshoots a joint limit, the spline that keeps to the shape-preserving cubic through
    them (`spline_path`). Limits are scaled by
    `*_scale`, then tightened by 2 % (toppra's constant-acceleration parameterisation
    overshoots slightly); the result is sampled and, if it still exceeds a limit, planned
    again with tighter margins.

    Args:
        waypoints_q: k ≥ 2 configurations [rad], each shape (dof,).
        robot: the robot (or its name).
        velocity_scale: fraction of the velocity limits to use, in (0, 1].
        acceleration_scale: fraction of the acceleration limits to use, in (0, 1].
        constraints: more toppra path constraints, besides the joint limits (the grip's
            on a carry, `cell.robot.carry.grip_constraint`).

    Returns:
        A Trajectory starting at the first waypoint and stopping at the last.

    Raises:
        InvalidInput: fewer than two waypoints, a bad shape, a waypoint outside the joint
            limits, or a scale outside (0, 1].
        TrajectoryError: toppra found no parameterisation, or the spline leaves the joint
            limits between waypoints.
    """
    import toppra.algorithm as algo

    rb = as_robot(robot)
    _check_scales(velocity_scale=velocity_scale, acceleration_scale=acceleration_scale)
    keep = _distinct_waypoints(rb, waypoints_q)
    q_start = keep[0]
    path = _spline_within(rb, keep)
    vmax = rb.limits.velocity * velocity_scale
    amax = rb.limits.acceleration * acceleration_scale
    # toppra's own gridpoints (its TOPPRA's defaults), proposed once for every margin
    grid = propose_gridpoints(path, max_err_threshold=1e-3, min_nb_points=100)
    for margin in (0.98, 0.95, 0.9, 0.8):
        pc_vel, pc_acc = _joint_limits(
            np.c_[-vmax * margin, vmax * margin], np.c_[-amax * margin, amax * margin]
        )
        inst = algo.TOPPRA(
            [pc_vel, pc_acc, *constraints],
            path,
            gridpoints=grid,
            # the solver toppra would choose (its first available), named: choosing it
            # looks for the others' packages on every call (0.5 ms a plan)
            solver_wrapper="seidel",
            parametrizer="ParametrizeConstAccel",
        )
        raw = inst.compute_trajectory(0.0, 0.0)
        if raw is None:
            raise TrajectoryError(
                f"toppra found no time parameterisation through {len(keep)} waypoints "
                f"(from {np.round(q_start, 3).tolist()} rad); the path may pass a point where "
                "the limits admit no motion"
            )
        traj = ToppraTrajectory(raw, rb.dof)
        use = check_limits(traj, rb, n=501)
        if use["velocity"] <= velocity_scale * (1 + 1e-6) and use[
            "acceleration"
        ] <= acceleration_scale * (1 + 1e-6):
            return traj
        log.debug("toppra margin %.2f exceeded the limits (%s); retrying", margin, use)
    raise TrajectoryError(f"toppra's trajectory exceeded the limits even at 80 % of them: {use}")
