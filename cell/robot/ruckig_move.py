"""A jerk-limited move planned by ruckig and checked against the joint position limits
(`_ruckig`, which `cell.robot.motion`'s planners call), and the same move remembered for
an approach that plans it again (`_ruckig_kept`)."""

from __future__ import annotations

import math

import numpy as np

from cell.errors import TrajectoryError
from cell.robot.kept import Kept, array_key
from cell.robot.model import Robot
from cell.robot.trajectory import POSITION_TOL_RAD, RuckigTrajectory, Trajectory


def _ruckig(
    rb: Robot,
    p0: np.ndarray,
    v0: np.ndarray,
    a0: np.ndarray,
    p1: np.ndarray,
    v1: np.ndarray,
    vmax: np.ndarray,
    amax: np.ndarray,
    jmax: np.ndarray,
    *,
    velocity_interface: bool,
    phase: bool = False,
) -> Trajectory:
    from ruckig import ControlInterface, InputParameter, Result, Ruckig, Synchronization
    from ruckig import Trajectory as RTrajectory

    n = rb.dof
    lim = rb.limits
    inp = InputParameter(n)
    if velocity_interface:
        inp.control_interface = ControlInterface.Velocity
    if phase:  # all joints on one profile: a straight joint-space line where ruckig can
        inp.synchronization = Synchronization.Phase
    inp.current_position = p0.tolist()
    inp.current_velocity = v0.tolist()
    inp.current_acceleration = a0.tolist()
    inp.target_position = p1.tolist()
    inp.target_velocity = v1.tolist()
    inp.target_acceleration = [0.0] * n
    inp.max_velocity = vmax.tolist()
    inp.max_acceleration = amax.tolist()
    inp.max_jerk = jmax.tolist()
    raw = RTrajectory(n)
    try:
        result = Ruckig(n).calculate(inp, raw)
    except RuntimeError as exc:
        raise TrajectoryError(f"ruckig rejected the move: {exc}") from None
    except ValueError as exc:
        # a result code ruckig's Python binding cannot name (its enum lacks -101, the
        # duration beyond ruckig's numerical range: limits far too slow for the move)
        raise TrajectoryError(
            f"ruckig found no trajectory ({exc}; a move longer than ruckig can time, "
            "from limits far too slow for it?)"
        ) from None
    if result != Result.Working and result != Result.Finished:
        raise TrajectoryError(f"ruckig found no trajectory (result {result})")
    traj = RuckigTrajectory(raw, n)
    lower, upper = lim.lower - POSITION_TOL_RAD, lim.upper + POSITION_TOL_RAD
    at_rest = not velocity_interface and not np.any(a0) and np.all(np.abs(v0) <= vmax)
    if at_rest and _within_by_speed(p0, p1, vmax, traj.duration, lower, upper):
        bad = np.zeros(0, dtype=int)  # no joint can reach a limit: nothing to sample
    elif traj.stays_within(amax, lower, upper):
        # shown within on a few samples: `position_bounds`'s 400 would find it so as well
        bad = np.zeros(0, dtype=int)
    else:
        lo, hi = traj.position_bounds(amax, within=(lower, upper))
        bad = np.flatnonzero((lo < lower) | (hi > upper))
    if bad.size:
        i = int(bad[0])
        raise TrajectoryError(
            f"the jerk-limited move passes joint {i + 1}'s position limit: it spans "
            f"[{lo[i]:.4f}, {hi[i]:.4f}] rad, the range is [{lim.lower[i]:.4f}, "
            f"{lim.upper[i]:.4f}] rad (start velocity {v0[i]:.3f}, target velocity "
            f"{v1[i]:.3f} rad/s): lower the velocities or move the target inwards"
        )
    if not math.isfinite(traj.duration):
        raise TrajectoryError("ruckig returned a trajectory of infinite duration")
    return traj


def _within_by_speed(
    p0: np.ndarray,
    p1: np.ndarray,
    vmax: np.ndarray,
    duration_s: float,
    lower: np.ndarray,
    upper: np.ndarray,
) -> bool:
    """Can no joint of a move from p0 to p1 [rad] in duration_s [s], never faster than
    vmax [rad/s], leave [lower, upper] [rad]? At time t a joint is within vmax·t of p0 and
    within vmax·(T − t) of p1, so never further up than (p0 + p1 + vmax·T) / 2, nor
    further down than (p0 + p1 − vmax·T) / 2 (with margins over ruckig's own rounding:
    1e-6 of vmax, 1e-7 rad). Where both are within the limits, `_ruckig` need not sample
    the move (`RuckigTrajectory.position_bounds`): it would find it within them. Only for
    a move that starts without acceleration and within vmax, whose target is a position
    (ruckig keeps such a move within vmax)."""
    if not math.isfinite(duration_s):
        return False
    reach = np.asarray(vmax, float) * (1.0 + 1e-6) * duration_s + 1e-7
    mid = p0 + p1
    return bool(np.all((mid + reach) / 2.0 <= upper) and np.all((mid - reach) / 2.0 >= lower))


# `_ruckig`'s moves by the bytes of everything they depend on: the states, the limits
# (velocity, acceleration and jerk given; the position limits the robot's), and the
# interface and synchronisation; a move that failed by its error's message. `plan_approach`
# plans the same moves again and again: the descent from the point over a pick to the
# pick (`cell.arm.pick`: from every release the search tries, the same 6 descents) and
# the move there from one release at rest; 1,044 of the 3,232 moves of tune layout 2's
# first 10 items. ruckig is deterministic, so a move remembered is the move it plans;
# nothing writes into one (a trajectory is sampled, never changed). Bounded: cleared when
# full.
_KEPT: Kept[Trajectory] = Kept(512, TrajectoryError)


def _ruckig_kept(
    rb: Robot,
    p0: np.ndarray,
    v0: np.ndarray,
    a0: np.ndarray,
    p1: np.ndarray,
    v1: np.ndarray,
    vmax: np.ndarray,
    amax: np.ndarray,
    jmax: np.ndarray,
    *,
    velocity_interface: bool,
    phase: bool = False,
) -> Trajectory:
    """`_ruckig`'s move, planned once for the same arguments and position limits: the
    same trajectory object, or the same TrajectoryError (by its message)."""
    lim = rb.limits
    key = bytes((velocity_interface, phase)) + array_key(
        p0, v0, a0, p1, v1, vmax, amax, jmax, lim.lower, lim.upper
    )
    return _KEPT.get(
        key,
        lambda: _ruckig(
            rb,
            p0,
            v0,
            a0,
            p1,
            v1,
            vmax,
            amax,
            jmax,
            velocity_interface=velocity_interface,
            phase=phase,
        ),
    )
