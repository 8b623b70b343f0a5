"""Carrying an item without letting it slip: the grip's limit on the arm's motion.

The pads hold an item of mass m with a friction force of at most F = 2 μ f_g(L_s, a)
(`cell.model.grip`). In the end-effector's frame the item feels the specific force
f = a_c − g, a_c the acceleration of its centre of mass c in the world frame W and g
gravity (0, 0, −9.81) m/s²; it stays put while m |f| ≤ F. So the grip sets a bound
on |a_c − g| [m/s²], the same for every direction (the pads' normal direction is
held by the band, the two in-plane directions by friction: bounding the magnitude is
the conservative union).

`plan_carry` finds the fastest toppra path through the waypoints whose |a_c − g|
stays under that bound: it time-scales the path (velocity limits × √s, acceleration
limits × s, so that a uniform slow-down of the same path scales every acceleration by
s, centripetal terms included) by bisection on s, evaluating a_c exactly from the
joint state with Pinocchio (a_c = a_o + α × r + ω × (ω × r), o the grip centre).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from cell.errors import TrajectoryError
from cell.model.params import G
from cell.robot.model import Robot
from cell.robot.trajectory import Trajectory

__all__ = [
    "CARRY_MARGIN",
    "carry_specific_force_limit",
    "item_accelerations",
    "peak_specific_force",
    "plan_carry",
]

# The grip's static friction force over what a carry may ask of it. Measured in the scene
# (tests/test_carry.py): accelerated, the pads hold 0.74-0.78 of what they hold at rest
# (a 30 mm box at 0.06 m stroke held at 0.74 of the static limit, slid 15 mm at 0.80).
CARRY_MARGIN = 1.35
_GRAVITY = np.array([0.0, 0.0, -G])


def carry_specific_force_limit(
    hold_mass_kg: float, item_mass_kg: float, margin: float = CARRY_MARGIN
) -> float:
    """The largest |a_c − g| [m/s²] the grip holds an item at.

    Args:
        hold_mass_kg: the heaviest item the grip holds against gravity alone at this
            stroke and width (`cell.model.grip.holding_mass_kg`) [kg]: F = hold · g.
        item_mass_kg: the carried item's mass [kg].
        margin: F over the largest force a carry may ask of the pads (≥ 1).
    """
    if item_mass_kg <= 0.0:
        return math.inf
    return hold_mass_kg * G / (item_mass_kg * margin)


def item_accelerations(
    robot: Robot,
    qs: np.ndarray,
    dqs: np.ndarray,
    ddqs: np.ndarray,
    offset_tcp_m: Sequence[float] = (0.0, 0.0, 0.0),
) -> np.ndarray:
    """World accelerations [m/s², W] of a point fixed in the ee_tcp frame.

    Args:
        robot: the arm.
        qs, dqs, ddqs: joint states, each shape (k, dof) [rad, rad/s, rad/s²].
        offset_tcp_m: the point in ee_tcp coordinates [m] (the item's centre of mass).

    Returns:
        Shape (k, 3).
    """
    import pinocchio as pin

    m, d, f = robot.model, robot.data, robot.tcp_frame
    r_local = np.asarray(offset_tcp_m, float)
    out = np.empty((len(qs), 3))
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    for i, (q, dq, ddq) in enumerate(zip(qs, dqs, ddqs, strict=True)):
        pin.forwardKinematics(m, d, q, dq, ddq)
        pin.updateFramePlacements(m, d)
        a_o = np.array(pin.getFrameClassicalAcceleration(m, d, f, lwa).linear)
        spatial_a = pin.getFrameAcceleration(m, d, f, lwa)
        w = np.array(pin.getFrameVelocity(m, d, f, lwa).angular)
        alpha = np.array(spatial_a.angular)
        r = d.oMf[f].rotation @ r_local
        out[i] = a_o + np.cross(alpha, r) + np.cross(w, np.cross(w, r))
    return out


def peak_specific_force(
    traj: Trajectory,
    robot: Robot,
    offset_tcp_m: Sequence[float] = (0.0, 0.0, 0.0),
    n: int = 201,
) -> float:
    """The largest |a_c − g| [m/s²] along a trajectory, sampled at n instants."""
    ts = np.linspace(0.0, traj.duration, n)
    qs, dqs, ddqs = traj.sample_many(ts)
    acc = item_accelerations(robot, qs, dqs, ddqs, offset_tcp_m)
    return float(np.max(np.linalg.norm(acc - _GRAVITY, axis=1)))


def plan_carry(
    waypoints_q: Sequence[np.ndarray],
    robot: Robot,
    specific_force_max: float,
    *,
    offset_tcp_m: Sequence[float] = (0.0, 0.0, 0.0),
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
    iterations: int = 6,
) -> tuple[Trajectory, float]:
    """The fastest path through the waypoints that keeps the item in the grip.

    Args:
        waypoints_q: joint waypoints [rad] (the first is where the arm is).
        robot: the arm.
        specific_force_max: the bound on |a_c − g| [m/s²] (`carry_specific_force_limit`).
        offset_tcp_m: the item's centre of mass in ee_tcp coordinates [m].
        velocity_scale, acceleration_scale: the fastest scales to try, in (0, 1].
        iterations: bisection steps on the time scale s.

    Returns:
        (the trajectory, its peak |a_c − g| [m/s²]).

    Raises:
        TrajectoryError: not even a slow path keeps |a_c − g| under the bound (the grip
            cannot hold the item against gravity alone), or toppra fails.
    """
    from cell.robot.motion import plan_path

    if specific_force_max <= G:
        raise TrajectoryError(
            f"the grip holds {specific_force_max:.2f} m/s² of specific force, less than "
            f"gravity's {G:.2f}: the item cannot be carried"
        )

    def attempt(s: float) -> tuple[Trajectory, float]:
        tr = plan_path(
            waypoints_q,
            robot,
            velocity_scale=velocity_scale * math.sqrt(s),
            acceleration_scale=acceleration_scale * s,
        )
        return tr, peak_specific_force(tr, robot, offset_tcp_m)

    best = attempt(1.0)
    if best[1] <= specific_force_max:
        return best
    lo, hi = 0.0, 1.0  # s = lo is slow enough (the limit at rest is gravity's G < bound)
    slowest = 0.02
    for _ in range(iterations):
        mid = max(slowest, 0.5 * (lo + hi))
        tr, peak = attempt(mid)
        if peak <= specific_force_max:
            lo, best = mid, (tr, peak)
        else:
            hi = mid
    if best[1] > specific_force_max:
        tr, peak = attempt(slowest)
        if peak > specific_force_max:
            raise TrajectoryError(
                f"even at {slowest:.0%} of the limits the carry asks {peak:.2f} m/s² of a grip "
                f"that holds {specific_force_max:.2f} m/s²"
            )
        best = (tr, peak)
    return best
