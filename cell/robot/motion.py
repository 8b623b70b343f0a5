"""Joint trajectories: toppra along a geometric path, ruckig for jerk-limited moves.

Two planners, one result type:

- `plan_path` (toppra 0.6): the time-optimal parameterisation of a cubic spline through
  joint waypoints (pick → lift → pre-release), at rest at both ends, under the joint
  velocity and acceleration limits; where the spline would overshoot a joint limit, one
  that keeps to the shape-preserving cubic through the waypoints (`spline_path`).
- `plan_move` (ruckig 0.19): a jerk-limited, time-optimal move from one joint state to
  another, which may end with a nonzero joint velocity (a release while moving: the
  thesis §4.2's secondary trajectory reaching the gripper's pose with nonzero velocity).
- `plan_approach` (ruckig): an empty arm's move to a configuration over a pick that it
  passes without stopping, on into a straight joint-space descent to the pick.

Limits come from the robot description (`Robot.limits`: URDF position and velocity limits,
acceleration and jerk limits from robots/<mount>/mount.yaml). Both planners check the result
against the position limits and raise TrajectoryError rather than return something unsafe:
a spline may overshoot between waypoints, and ruckig 0.19.4 ignores position limits (its
own `position_extrema` is unreliable too, so the extrema are searched on samples).

`plan_path` is in `cell.robot.path_plan`, the spline it follows in `cell.robot.spline`;
both are re-exported here.
"""

from __future__ import annotations

import weakref
from collections.abc import Sequence

import numpy as np

from cell.errors import InvalidInput, TrajectoryError
from cell.robot.model import Robot
from cell.robot.path_plan import _check_scales, plan_path
from cell.robot.ruckig_move import _ruckig, _ruckig_kept
from cell.robot.spline import monotone_samples, spline_path
from cell.robot.trajectory import (
    POSITION_TOL_RAD,
    Trajectory,
    as_robot,
    check_limits,
    joint_vector,
)

__all__ = [
    "ChainTrajectory",
    "Trajectory",
    "check_limits",
    "monotone_samples",
    "move_time",
    "plan_approach",
    "plan_move",
    "plan_path",
    "plan_stop",
    "release_joint_velocity",
    "spline_path",
]


def plan_move(
    q0: np.ndarray | Sequence[float],
    dq0: np.ndarray | Sequence[float] | None,
    q1: np.ndarray | Sequence[float],
    dq1: np.ndarray | Sequence[float] | None,
    robot: Robot | str,
    *,
    ddq0: np.ndarray | Sequence[float] | None = None,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
    jerk_scale: float = 1.0,
) -> Trajectory:
    """Jerk-limited, time-optimal move between joint states (ruckig), all joints in sync.

    Args:
        q0: start configuration [rad], shape (dof,).
        dq0: start joint velocity [rad/s] (None: at rest).
        q1: target configuration [rad], shape (dof,).
        dq1: target joint velocity [rad/s] (None: at rest); nonzero for a release while
            moving. Must be within the (scaled) velocity limits.
        robot: the robot (or its name).
        ddq0: start joint acceleration [rad/s²] (None: zero). The target acceleration is 0.
        velocity_scale: fraction of the velocity limits to use, in (0, 1].
        acceleration_scale: fraction of the acceleration limits, in (0, 1].
        jerk_scale: fraction of the jerk limits, in (0, 1].

    Returns:
        A Trajectory that ends exactly at (q1, dq1) with zero acceleration.

    Raises:
        InvalidInput: bad shapes, a configuration outside the limits, a velocity above its
            limit, or a scale outside (0, 1].
        TrajectoryError: ruckig found no trajectory, or the move would pass a joint's
            position limit (checked from the exact position extrema).
    """
    rb = as_robot(robot)
    n = rb.dof
    _check_scales(
        velocity_scale=velocity_scale, acceleration_scale=acceleration_scale, jerk_scale=jerk_scale
    )
    zero = np.zeros(n)
    p0 = joint_vector(rb, q0, "q0")
    p1 = joint_vector(rb, q1, "q1")
    v0 = zero if dq0 is None else joint_vector(rb, dq0, "dq0")
    v1 = zero if dq1 is None else joint_vector(rb, dq1, "dq1")
    a0 = zero if ddq0 is None else joint_vector(rb, ddq0, "ddq0")
    lim = rb.limits
    lim.check_position(p0, "q0", tol=POSITION_TOL_RAD)
    lim.check_position(p1, "q1", tol=POSITION_TOL_RAD)
    vmax = lim.velocity * velocity_scale
    amax = lim.acceleration * acceleration_scale
    jmax = lim.jerk * jerk_scale
    for name, v in (("dq0", v0), ("dq1", v1)):
        bad = np.flatnonzero(np.abs(v) > vmax * (1 + 1e-9))
        if bad.size:
            i = int(bad[0])
            raise InvalidInput(
                f"{name}[{i}] = {v[i]:.4f} rad/s exceeds joint {i + 1}'s velocity limit "
                f"{vmax[i]:.4f} rad/s"
            )
    return _ruckig(rb, p0, v0, a0, p1, v1, vmax, amax, jmax, velocity_interface=False)


class ChainTrajectory(Trajectory):
    """Trajectories one after the other, each starting in the state the one before ends in.

    Args:
        parts: the trajectories, in order (at least one).
    """

    def __init__(self, parts: Sequence[Trajectory]) -> None:
        if not parts:
            raise InvalidInput("ChainTrajectory needs at least one trajectory")
        self.parts = list(parts)
        self.dof = self.parts[0].dof
        self.kind = "+".join(p.kind for p in self.parts)
        self._starts = np.cumsum([0.0] + [p.duration for p in self.parts])
        self.duration = float(self._starts[-1])

    def _eval(self, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        out = np.empty((3, ts.size, self.dof))
        k = np.clip(np.searchsorted(self._starts, ts, side="right") - 1, 0, len(self.parts) - 1)
        for i, part in enumerate(self.parts):
            sel = np.flatnonzero(k == i)
            if sel.size:
                q, dq, ddq = part.sample_many(ts[sel] - self._starts[i])
                out[0, sel], out[1, sel], out[2, sel] = q, dq, ddq
        return out[0], out[1], out[2]


def _approach_points(
    rb: Robot, *qs: np.ndarray | Sequence[float]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q0, q_over and q_to [rad] as joint vectors, each checked against the position limits."""
    p0 = joint_vector(rb, qs[0], "q0")
    pm = joint_vector(rb, qs[1], "q_over")
    p1 = joint_vector(rb, qs[2], "q_to")
    lim = rb.limits
    for name, q in (("q0", p0), ("q_over", pm), ("q_to", p1)):
        lim.check_position(q, name, tol=POSITION_TOL_RAD)
    return p0, pm, p1


APPROACH_SPEED_FRACTIONS = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5)
"""Joint speeds over the approach point tried by `plan_approach`, as fractions of the
fastest the descent's joint-space direction allows (0: at rest there)."""


def plan_approach(
    q0: np.ndarray | Sequence[float],
    q_over: np.ndarray | Sequence[float],
    q_to: np.ndarray | Sequence[float],
    robot: Robot | str,
    *,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
    fractions: Sequence[float] = APPROACH_SPEED_FRACTIONS,
) -> ChainTrajectory:
    """The quickest jerk-limited move from rest at q0 through q_over to rest at q_to whose
    last part, from q_over on, runs along the straight joint-space segment to q_to.

    The arm passes q_over moving along that segment (at one of `fractions` of the fastest
    speed its direction allows, whichever ends soonest), then a phase-synchronised ruckig
    move, every joint on one profile, takes it along the segment to rest at q_to. An empty
    arm's approach to a pick: anywhere to the point over the item, then straight down
    onto it, without stopping in between.

    Args:
        q0: start configuration, at rest [rad], shape (dof,).
        q_over: the configuration passed on the way [rad], shape (dof,).
        q_to: the end configuration, at rest [rad], shape (dof,).
        robot: the robot (or its name).
        velocity_scale: fraction of the velocity limits to use, in (0, 1].
        acceleration_scale: fraction of the acceleration limits, in (0, 1].
        fractions: speeds over q_over to try, each in [0, 1].

    Returns:
        A ChainTrajectory of two ruckig moves (to q_over, then along the segment to q_to).

    Raises:
        InvalidInput: bad shapes or scales, a configuration outside the limits, or q_over
            equal to q_to.
        TrajectoryError: no speed gives a move within the limits whose last part stays
            on the segment.
    """
    rb = as_robot(robot)
    _check_scales(velocity_scale=velocity_scale, acceleration_scale=acceleration_scale)
    p0, pm, p1 = _approach_points(rb, q0, q_over, q_to)
    lim = rb.limits
    seg = p1 - pm
    length = float(np.linalg.norm(seg))
    if length < 1e-9:
        raise InvalidInput("plan_approach: q_over is q_to, there is no segment to descend")
    u = seg / length
    vmax = lim.velocity * velocity_scale
    amax = lim.acceleration * acceleration_scale
    jmax = lim.jerk
    with np.errstate(divide="ignore"):
        s_max = float(np.min(np.where(np.abs(u) > 0, vmax / np.abs(u), np.inf)))
    zero = np.zeros(rb.dof)
    best: ChainTrajectory | None = None
    err: Exception | None = None
    for f in fractions:
        if not (0.0 <= f <= 1.0):
            raise InvalidInput(f"plan_approach: speed fraction {f} outside [0, 1]")
        v = u * s_max * f
        try:
            # the same moves as `_ruckig`'s, remembered: an approach to the same pick from
            # another start descends the same way (`cell.robot.ruckig_move._KEPT`)
            first = _ruckig_kept(
                rb, p0, zero, zero, pm, v, vmax, amax, jmax, velocity_interface=False
            )
            down = _ruckig_kept(
                rb, pm, v, zero, p1, zero, vmax, amax, jmax, velocity_interface=False, phase=True
            )
        except TrajectoryError as exc:
            err = exc
            continue
        if not _on_segment(down, pm, u):
            err = TrajectoryError(f"the descent at speed fraction {f} leaves the segment")
            continue
        if best is None or first.duration + down.duration < best.duration:
            best = ChainTrajectory([first, down])
    if best is None:
        raise TrajectoryError(f"no approach through q_over: {err}")
    return best


# Whether a descent `_ruckig_kept` remembered keeps to its segment, by the descent: a
# remembered one is the move of one (start, target) pair, so of one segment.
_ON_SEGMENT: weakref.WeakKeyDictionary[Trajectory, bool] = weakref.WeakKeyDictionary()


def _on_segment(down: Trajectory, pm: np.ndarray, u: np.ndarray) -> bool:
    """Does the descent `down` from pm [rad] keep to the joint-space line along the unit
    vector u (within POSITION_TOL_RAD at 41 instants)? Phase synchronisation may fall
    back to time synchronisation: then it is off the line."""
    on = _ON_SEGMENT.get(down)
    if on is None:
        qs = down.sample_many(np.linspace(0.0, down.duration, 41))[0] - pm
        off = qs - np.outer(qs @ u, u)
        on = not float(np.max(np.linalg.norm(off, axis=1))) > POSITION_TOL_RAD
        _ON_SEGMENT[down] = on
    return on


def plan_stop(
    q0: np.ndarray | Sequence[float],
    dq0: np.ndarray | Sequence[float],
    robot: Robot | str,
    *,
    ddq0: np.ndarray | Sequence[float] | None = None,
    acceleration_scale: float = 1.0,
    jerk_scale: float = 1.0,
) -> Trajectory:
    """Jerk-limited, time-optimal stop from a moving state (ruckig's velocity interface).

    The follow-up of a release while moving: the arm brakes to rest wherever the limits
    let it, all joints reaching zero velocity together.

    Args:
        q0: configuration at the start of the stop [rad], shape (dof,).
        dq0: joint velocity [rad/s] (within the velocity limits).
        robot: the robot (or its name).
        ddq0: joint acceleration [rad/s²] (None: zero).
        acceleration_scale: fraction of the acceleration limits, in (0, 1].
        jerk_scale: fraction of the jerk limits, in (0, 1].

    Returns:
        A Trajectory ending at rest.

    Raises:
        InvalidInput: bad shapes, a configuration outside the limits, a velocity above its
            limit, or a scale outside (0, 1].
        TrajectoryError: the stop would pass a joint's position limit.
    """
    rb = as_robot(robot)
    _check_scales(acceleration_scale=acceleration_scale, jerk_scale=jerk_scale)
    zero = np.zeros(rb.dof)
    p0 = joint_vector(rb, q0, "q0")
    v0 = joint_vector(rb, dq0, "dq0")
    a0 = zero if ddq0 is None else joint_vector(rb, ddq0, "ddq0")
    rb.limits.check_position(p0, "q0", tol=POSITION_TOL_RAD)
    rb.limits.check_velocity(v0, "dq0")
    lim = rb.limits
    return _ruckig(
        rb,
        p0,
        v0,
        a0,
        p0,
        zero,
        lim.velocity,
        lim.acceleration * acceleration_scale,
        lim.jerk * jerk_scale,
        velocity_interface=True,
    )


def release_joint_velocity(
    q: np.ndarray | Sequence[float],
    v_tcp: np.ndarray | Sequence[float],
    robot: Robot | str,
    *,
    omega: np.ndarray | Sequence[float] | None = None,
    rtol: float = 1e-6,
) -> np.ndarray:
    """Joint velocity that moves the grip centre at a given velocity (the release velocity).

    Solves J(q) dq = [v; ω] in the least-squares, minimum-norm sense (the Panda has one
    redundant joint), with the angular velocity ω zero by default so the throw axis does not
    turn at release.

    Args:
        q: release configuration [rad], shape (dof,).
        v_tcp: grip-centre velocity in W [m/s], shape (3,).
        robot: the robot (or its name).
        omega: angular velocity of ee_tcp in W [rad/s], shape (3,) (None: zero).
        rtol: admissible twist residual relative to max(1, |twist|).

    Returns:
        dq [rad/s], shape (dof,).

    Raises:
        InvalidInput: bad shapes or q outside the limits.
        TrajectoryError: the twist is not achievable at q (singular), or it needs a joint
            faster than its velocity limit (the message names the joint and the factor).
    """
    rb = as_robot(robot)
    qa = joint_vector(rb, q, "q")
    rb.limits.check_position(qa, "q", tol=POSITION_TOL_RAD)
    v = np.asarray(v_tcp, dtype=float).reshape(-1)
    w = np.zeros(3) if omega is None else np.asarray(omega, dtype=float).reshape(-1)
    if v.shape != (3,) or w.shape != (3,) or not np.all(np.isfinite(np.r_[v, w])):
        raise InvalidInput(f"v_tcp and omega must be 3 finite numbers each, got {v!r}, {w!r}")
    twist = np.concatenate([v, w])
    jac = rb.tcp_jacobian(qa)
    dq = np.linalg.lstsq(jac, twist, rcond=1e-10)[0]
    res = float(np.linalg.norm(jac @ dq - twist))
    if res > rtol * max(1.0, float(np.linalg.norm(twist))):
        raise TrajectoryError(
            f"the release twist {np.round(twist, 4).tolist()} is not achievable at this "
            f"configuration (residual {res:.3g}; the arm is near a singularity)"
        )
    ratio = np.abs(dq) / rb.limits.velocity
    i = int(np.argmax(ratio))
    if ratio[i] > 1.0:
        raise TrajectoryError(
            f"a grip-centre velocity of {np.linalg.norm(v):.3f} m/s needs joint {i + 1} at "
            f"{dq[i]:.3f} rad/s, {ratio[i]:.2f}x its limit {rb.limits.velocity[i]:.3f} rad/s"
        )
    return dq


def move_time(
    q0: np.ndarray | Sequence[float], q1: np.ndarray | Sequence[float], robot: Robot | str
) -> float:
    """Duration of a jerk-limited rest-to-rest move [s] (ruckig, full limits).

    Raises:
        InvalidInput: see plan_move.
        TrajectoryError: see plan_move.
    """
    return plan_move(q0, None, q1, None, robot).duration
