"""Pure functions of joint configurations [rad] that the arm's parts share: gaps, distinct
waypoints, how long a chain of moves takes, the spline a route follows and how far it
twists the grip (of an arm's kinematic model, `cell.robot.model.Robot`).
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np

from cell.model.objects import ObjectParams

log = logging.getLogger(__name__)


def joint_gap(qa: np.ndarray, qb: np.ndarray) -> float:
    """The largest joint move between two configurations [rad]."""
    return float(np.max(np.abs(np.asarray(qb) - np.asarray(qa))))


def distinct_waypoints(waypoints: list[np.ndarray]) -> list[np.ndarray]:
    """The waypoints [rad] without those equal to the one before (a spline needs distinct
    knots): the first, then each that moves a joint more than 1e-9 rad from its predecessor."""
    return [waypoints[0]] + [
        w for a, w in zip(waypoints, waypoints[1:], strict=False) if joint_gap(a, w) > 1e-9
    ]


GRIP_DOWN = (-math.pi / 2, 0.0)  # (elevation, azimuth) [rad] of the throw axis pointing down


# Where a carry starts, for planning it before the pick (`Orchestrator._departure`): the
# pick's configuration [rad], the item's centre there [m, W] (None: not known), the item and
# the stroke it is held at [m].
PickState = tuple[np.ndarray, np.ndarray | None, ObjectParams, float]


def plan_time(trajs: list[Any], settle_s: float) -> float:
    """How long [s] `move` takes along `_move_plan`'s trajectories: their durations and a
    settle of `settle_s` [s] at each stop between them."""
    return sum(float(t.duration) for t in trajs) + settle_s * (len(trajs) - 1)


def clip(v: float, lim: float) -> float:
    return max(-lim, min(lim, v))


def spline_within_limits(robot: Any, waypoints: list[np.ndarray], n: int) -> np.ndarray | None:
    """n configurations [rad] evenly along the cubic spline through the distinct
    `waypoints` (`cell.robot.motion.spline_path` without limits: the path a move
    follows whatever its timing), or None when they are fewer than two or that spline
    leaves `robot`'s joint limits: such a route is not chosen (a move along one, the last
    resort of `Routes._departure`, follows the shape-preserving path instead)."""
    from cell.robot.motion import spline_path

    keep = distinct_waypoints(waypoints)
    if len(keep) < 2:
        return None
    qs = np.asarray(spline_path(keep)(np.linspace(0.0, 1.0, n)))
    lim = robot.limits
    if np.any(qs < lim.lower - 1e-6) or np.any(qs > lim.upper + 1e-6):
        return None
    return qs


def twist(robot: Any, waypoints: list[np.ndarray], samples: int) -> float:
    """How far [rad] `robot`'s grip turns off the one rotation that takes it from the first
    waypoint's orientation to the last's, at most along the spline through the
    `waypoints` (the path a carry follows, checked at `samples` configurations): 0 for a
    swing about one fixed axis.

    The twist-free swing's waypoints are solved in the frame the release swings up
    from (`Kinematics._pick_frame`), but a grip pointing down is solved at azimuth 0
    (`ReleasePose` keeps the axis, which has no azimuth there): on random layout 4 a
    sphere's swing to a bin behind the arm turned its grip 74° off that rotation and
    its wrist 3.4 rad, where the spline between the ends turned it 27° and took
    1.0 s against 2.5 s."""
    from scipy.spatial.transform import Rotation

    from cell.robot.motion import spline_path

    keep = distinct_waypoints(waypoints)
    if len(keep) < 2:
        return 0.0
    lim = robot.limits
    qs = np.asarray(spline_path(keep, lim.lower, lim.upper)(np.linspace(0, 1, samples)))
    rots = [robot.tcp_pose(q)[1] for q in qs]
    # the axis of the one rotation between the ends (its sign does not matter here)
    rotvec = Rotation.from_matrix(rots[-1] @ rots[0].T).as_rotvec()
    angle = float(np.linalg.norm(rotvec))
    # no turn between the ends: any turn of the throw axis on the way is a twist
    k = rots[0][:, 2] if angle < 1e-6 else rotvec / angle
    v = rots[0].T @ k
    return max(math.acos(max(-1.0, min(1.0, float((r @ v) @ k)))) for r in rots)
