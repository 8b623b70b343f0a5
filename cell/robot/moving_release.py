"""Release on the move: the arm throws while its end-effector moves (issue 16).

The moving base's formulation (cell.platforms.mobile) applied to the arm: the grip
centre moves at a velocity v_rel [m/s, W] at the release, the launch is the band's push
along the throw axis plus v_rel (σ's base velocity vx_mps, vy_mps, vz_mps), and the arm
arrives at the release configuration with the joint velocity that gives v_rel.

The motion, one joint trajectory q(t) (`MovingReleaseMotion`):

1. approach: ruckig from rest at q_start to the run-in's first state, at its velocity
   and zero acceleration (`grip_move`: slowed until the pads hold the item, see
   `cell.robot.carry`; a fast approach slid the item off the carriage). Ruckig's
   non-zero target states: `calculate` returns a trajectory whose state at t = duration
   is the target exactly (tested); past the duration `at_time` goes on with the
   target's acceleration (pantor/ruckig#59), so what follows is planned separately; and
   with a target velocity the move may overshoot the target position on the way
   (moveit/moveit#3376): `plan_move` checks the position extrema against the limits.
2. run-in: RUN_IN_S on the straight line at v_rel, the axis fixed (resolved rate,
   q̇ = J⁺ [v_rel; 0], `CoastTrajectory`), ending at (q_rel, q̇_rel), q̇_rel =
   J(q_rel)⁺ [v_rel; 0] (`release_joint_velocity`: the grip's angular velocity held at
   zero, so the throw axis does not turn and every point of the end-effector, the
   item's centre included, moves at v_rel). The latch opens at its end: the release
   instant `t_release_s`.
3. coast: COAST_S more on the line at v_rel while the band pushes the item out (it
   leaves the carriage ~35 ms after the latch, `leave_time_s`).
4. stop: ruckig's velocity interface brakes from the coast's end to rest (`plan_stop`).

The landing (`predict_moving_landing`): the model's launch for the plan made static,
taken in the end-effector's frame (inertial while it moves at v_rel), then v_rel added
to the velocity and v_rel × `leave_time_s` to the position, and the model's flight.
`predict_landing` with σ's base velocity (the moving base's use) carries the item only
the push's fitted ee.dt (~9 ms) along and lands 10-20 mm short at 0.5-0.75 m/s.

`plan_moving_throw` plans the release for an item and a bin with v_rel given (the
static plan's release point, the stroke and azimuth polished to land on the goal),
`choose_release` tries a few v_rel and keeps the soonest (by the cycle, or by the time
to the release) or the static release when none is sooner, and `cell.sim.release.release_in_scene` runs
a motion in the PyBullet cell and opens the latch at the planned instant while the arm
moves.

The parts: `cell.robot.moving_coast` (the coast and `grip_move`), `cell.robot.moving_motion`
(`plan_moving_release`), `cell.robot.moving_throw` (`plan_moving_throw`) and
`cell.robot.moving_landing` (`predict_moving_landing`); this module chooses between the
releases and re-exports their names.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.errors import IKFailed, InvalidInput, TrajectoryError, UnreachableTarget
from cell.frames import tcp_for_item_centre
from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams
from cell.robot.carry import GripHold
from cell.robot.model import Robot
from cell.robot.motion import move_time
from cell.robot.moving_coast import CoastTrajectory, grip_move, throw_axis
from cell.robot.moving_landing import leave_time_s, predict_moving_landing
from cell.robot.moving_motion import COAST_S, RUN_IN_S, MovingReleaseMotion, plan_moving_release
from cell.robot.moving_throw import IK, MovingThrow, _default_ik, plan_moving_throw
from cell.robot.trajectory import as_robot, joint_vector

__all__ = [
    "COAST_S",
    "RUN_IN_S",
    "CoastTrajectory",
    "MovingReleaseMotion",
    "MovingThrow",
    "ReleaseChoice",
    "choose_release",
    "grip_move",
    "leave_time_s",
    "plan_moving_release",
    "plan_moving_throw",
    "predict_moving_landing",
    "throw_axis",
]


SETTLE_S = 0.0  # [s] the static release's wait at the release pose (as the orchestrator's)
DEFAULT_SPEEDS_MPS = (0.25, 0.5, 0.75, 1.0)  # candidate grip speeds at release [m/s]


@dataclass(frozen=True)
class ReleaseChoice:
    """The planner's choice between the static release and the moving ones.

    Attributes:
        moving: the chosen moving throw, or None when the static release is faster.
        static_q: the static release configuration [rad].
        static_to_release_s: the static move's duration to the release [s] (ruckig,
            rest to rest, within the grip as `grip_move`, then SETTLE_S).
        static_cycle_s: that, the push (COAST_S) and the move back to q_start [s].
        candidates: (v_release, MovingThrow or the reason it was refused) tried.
    """

    moving: MovingThrow | None
    static_q: np.ndarray
    static_to_release_s: float
    static_cycle_s: float
    candidates: list[tuple[np.ndarray, MovingThrow | str]]

    @property
    def saved_s(self) -> float:
        """Cycle time the moving release saves over the static one [s] (0 if static)."""
        return 0.0 if self.moving is None else self.static_cycle_s - self.moving.cycle_s

    @property
    def saved_to_release_s(self) -> float:
        """Time to the release the moving release saves over the static one [s]."""
        if self.moving is None:
            return 0.0
        return self.static_to_release_s - self.moving.motion.t_release_s


def release_directions(
    robot: Robot, static_plan: Any, q_start: np.ndarray, q_static: np.ndarray
) -> list[np.ndarray]:
    """Unit directions [W] a release velocity is tried along: the throw axis (all of the
    speed goes into the launch), the straight swing of the grip centre from q_start to
    the release, their bisector, and the grip centre's direction at the end of the
    joint-space straight line from q_start (J(q_rel) (q_rel − q_start): the way a
    synchronised move arrives)."""
    u = throw_axis(static_plan.elevation_rad, static_plan.azimuth_rad)
    swing = robot.tcp_pose(q_static)[0] - robot.tcp_pose(q_start)[0]
    arrive = robot.tcp_jacobian(q_static)[:3] @ (q_static - q_start)
    out = [u]
    for d in (swing, (u + swing / max(np.linalg.norm(swing), 1e-12)), arrive):
        if np.linalg.norm(d) > 1e-6:
            out.append(d / np.linalg.norm(d))
    return out


def _static_release(
    rb: Robot,
    obj: ObjectParams,
    sp: Any,
    q0: np.ndarray,
    solve: IK,
    hold: GripHold | None,
    kw: dict[str, Any],
) -> tuple[np.ndarray, float, float]:
    """The static release's configuration [rad], its time from q0 to the latch (the move
    within the grip + SETTLE_S) [s] and its cycle (that + COAST_S + the move back) [s]."""
    tcp = tcp_for_item_centre(
        [sp.x_m, sp.y_m, sp.z_m], sp.elevation_rad, sp.azimuth_rad, sp.stroke_m, obj
    )
    q_static = solve(tcp, sp.elevation_rad, sp.azimuth_rad)
    t_static = grip_move(rb, q0, q_static, None, hold, gentle=True, **kw).duration + SETTLE_S
    static_cycle = t_static + COAST_S + move_time(q_static, q0, rb)
    return q_static, t_static, static_cycle


def choose_release(
    robot: Robot | str,
    obj: ObjectParams,
    static_plan: Any,
    q_start: np.ndarray | Sequence[float],
    ee: EndEffectorParams,
    *,
    bounds: Any = None,
    ik: IK | None = None,
    hold: GripHold | None = None,
    speeds_mps: Sequence[float] = DEFAULT_SPEEDS_MPS,
    directions: Sequence[np.ndarray] | None = None,
    criterion: str = "cycle",
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
) -> ReleaseChoice:
    """Choose between the static release and a moving one by cycle time.

    The cycle is from rest at q_start (the lift pose) through the release to rest back
    at q_start: static = rest-to-rest move to the release + SETTLE_S + the push
    (COAST_S) + the move back; moving = approach + run-in + coast + stop + the move back
    (ruckig for all). Each moving candidate lands on the goal by the model
    (`predict_moving_landing` within MISS_TOL, so within the bin) and is within the
    joint limits all along; the soonest wins if it is sooner than the static release.

    Args:
        robot, obj, static_plan, q_start, ee, bounds, ik, hold: see `plan_moving_throw`
            (both releases' approaches are kept within the grip by `hold`).
        speeds_mps: grip speeds at the release tried [m/s].
        directions: unit directions tried [W]; default `release_directions`.
        criterion: "cycle" (out and back, as above) or "release" (the time from the
            start to the latch: the next pick's move then starts from wherever the arm
            stopped, and is left out).
        velocity_scale, acceleration_scale: fractions of the joint limits used.

    Returns:
        The ReleaseChoice.

    Raises:
        IKFailed: no configuration for the static release pose.
    """
    rb = as_robot(robot)
    q0 = joint_vector(rb, q_start, "q_start")
    solve = ik or _default_ik(rb, q0)
    sp = static_plan
    kw: dict[str, Any] = dict(velocity_scale=velocity_scale, acceleration_scale=acceleration_scale)
    q_static, t_static, static_cycle = _static_release(rb, obj, sp, q0, solve, hold, kw)
    dirs = release_directions(rb, sp, q0, q_static) if directions is None else directions
    if criterion not in ("cycle", "release"):
        raise InvalidInput(f"criterion {criterion!r}: give 'cycle' or 'release'")

    def key(mt: MovingThrow) -> float:
        return mt.cycle_s if criterion == "cycle" else mt.motion.t_release_s

    cands: list[tuple[np.ndarray, MovingThrow | str]] = []
    best: MovingThrow | None = None
    bar = static_cycle if criterion == "cycle" else t_static
    for d in dirs:
        # speeds in rising order: a direction is left once a speed is refused or no
        # sooner than the one before it (in the cell's measurements the time rises, or the
        # joint limits refuse, monotonically with the speed along a direction)
        last = math.inf
        for s in sorted(speeds_mps):
            v = s * np.asarray(d, float)
            try:
                mt = plan_moving_throw(
                    rb, obj, sp, v, q0, ee, bounds=bounds, ik=solve, hold=hold, **kw
                )
            except (UnreachableTarget, IKFailed, TrajectoryError) as exc:
                cands.append((v, f"{type(exc).__name__}: {exc}"))
                break
            cands.append((v, mt))
            if best is None or key(mt) < key(best):
                best = mt
            if key(mt) >= min(last, bar):
                break
            last = key(mt)
    if best is not None and key(best) >= bar:
        best = None
    return ReleaseChoice(best, q_static, t_static, static_cycle, cands)
