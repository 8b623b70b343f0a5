"""A sound reach test: a grip pose whose last joint's origin lies farther from the first
joint's origin than any configuration puts it, so IK cannot solve it (any roll).

The chain from the first joint's origin O1 [m, W] to the last joint's origin (the joint
ee_tcp hangs from) is a sum of the joints' fixed translations t_i, each turned by the
joints before it. Turning about the first joint's axis (through O1) keeps the distance
from O1, so |p_last - O1| ≤ the sum over the rest. Where the joints after the first turn
about parallel axes (direction n: a UR's shoulder, elbow and first wrist joint), the
components along n of their translations never change and add as numbers, their parts
across n at most as lengths: |A| ≤ √((Σ n·t_i)² + (Σ |t_i⊥|)²); the joints after that run
add their translations' lengths. An exact bound (the triangle inequality), loose where
the axes are not parallel (the Panda's).

Given a pose (the grip centre p and its axis u, ee_tcp's +z; any roll about u), the last
joint's origin lies on a circle: p + (v·e_z) u at a radius |v_⊥|, v the last joint's
origin seen from ee_tcp (in ee_tcp's frame). A configuration IK accepts is within
`tol_position_m` and `tol_axis_rad` of the pose, which moves that circle by at most
tol_position_m + |v|·tol_axis_rad: the margin added before a pose is refused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cell.robot.model import Robot

# axes this close to parallel (|cross| of unit vectors) are taken as one direction; a
# run is then bounded as parallel only where they are exactly so in the model (UR: 0)
PARALLEL_EPS = 1e-12


@dataclass(frozen=True)
class ReachBound:
    """The bound for one arm: O1 [m, W], the farthest the last joint's origin gets
    from it [m], and v (the last joint's origin in ee_tcp's frame) [m]."""

    origin: np.ndarray
    reach_m: float
    v: np.ndarray

    def refuses(self, position: np.ndarray, axis: np.ndarray, tol_m: float, tol_rad: float) -> bool:
        """True where no configuration puts ee_tcp within tol_m [m] of `position` [m, W]
        with its +z within tol_rad [rad] of `axis` (unit, W), at any roll."""
        v_z = float(self.v[2])
        r_perp = math.hypot(float(self.v[0]), float(self.v[1]))
        centre = np.asarray(position, float) + v_z * np.asarray(axis, float)
        margin = tol_m + float(np.linalg.norm(self.v)) * tol_rad
        return float(np.linalg.norm(centre - self.origin)) - r_perp > self.reach_m + margin


def _axis_local(robot: Robot, j: int) -> np.ndarray | None:
    """Joint j's axis in its own frame (unit), or None where it is not a revolute joint
    about a fixed axis."""
    name = robot.model.joints[j].shortname()
    unit = {"JointModelRX": 0, "JointModelRY": 1, "JointModelRZ": 2}
    if name in unit:
        a = np.zeros(3)
        a[unit[name]] = 1.0
        return a
    if name == "JointModelRevoluteUnaligned":
        a = np.array(robot.model.joints[j].extract().axis, float)
        return a / np.linalg.norm(a)
    return None


def reach_bound(robot: Robot) -> ReachBound | None:
    """The arm's `ReachBound`, or None where the model is not a serial chain of revolute
    joints ending at ee_tcp's joint (no bound: nothing refused)."""
    import pinocchio as pin

    model = robot.model
    last = int(model.frames[robot.tcp_frame].parentJoint)
    if last < 2 or any(int(model.parents[j]) != j - 1 for j in range(1, last + 1)):
        return None
    axes = [_axis_local(robot, j) for j in range(1, last + 1)]
    if any(a is None for a in axes):
        return None
    data = model.createData()
    pin.forwardKinematics(model, data, np.asarray(robot.home, float))
    origin = np.array(data.oMi[1].translation, float)
    # the run of joints from the second whose axes stay parallel to its (n in frame j)
    n = np.asarray(axes[1], float)  # joint 2's axis in its frame
    along, across, rest = 0.0, 0.0, 0.0
    t12 = np.array(model.jointPlacements[2].translation, float)
    n1 = np.array(model.jointPlacements[2].rotation, float) @ n  # n in joint 1's frame
    along += float(n1 @ t12)
    across += float(np.linalg.norm(t12 - (n1 @ t12) * n1))
    parallel = True
    for j in range(2, last):
        t = np.array(model.jointPlacements[j + 1].translation, float)
        if parallel:
            along += float(n @ t)
            across += float(np.linalg.norm(t - (n @ t) * n))
            n_next = np.array(model.jointPlacements[j + 1].rotation, float).T @ n
            if np.linalg.norm(np.cross(n_next, np.asarray(axes[j], float))) > PARALLEL_EPS:
                parallel = False  # joint j+1 turns about another axis: lengths from here
            n = n_next
        else:
            rest += float(np.linalg.norm(t))
    reach = math.hypot(along, across) + rest
    f = model.frames[robot.tcp_frame].placement  # ee_tcp in the last joint's frame
    v = -np.array(f.rotation, float).T @ np.array(f.translation, float)
    return ReachBound(origin=origin, reach_m=reach, v=v)


def bound_of(robot: Robot) -> ReachBound | None:
    """`reach_bound(robot)`, made once per Robot (kept on it)."""
    if "_reach_bound" not in robot.__dict__:
        robot.__dict__["_reach_bound"] = reach_bound(robot)
    found: ReachBound | None = robot.__dict__["_reach_bound"]
    return found
