"""A release on the move in the PyBullet plant: the arm driven along a planned motion and
the latch opened at the planned instant while it moves (`cell.robot.moving_release`
plans the motion; this is the plant's side of it, which reads the bodies' states)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.errors import TrajectoryError

__all__ = ["SceneRelease", "release_in_scene"]


@dataclass(frozen=True)
class SceneRelease:
    """What the plant did at a release on the move.

    Attributes:
        t_latch_s: scene time the latch opened [s].
        t_planned_s: scene time the plan put it at [s].
        v_item_mps: the item's centre-of-mass velocity at the latch instant [m/s, W].
        v_ee_mps: the end-effector body's velocity at the item's centre then [m/s, W].
        released_at: the item's centre then [m, W].
        throw_done_s: time from the latch to the item's last contact with the
            end-effector, or to the end of the push if later [s].
    """

    t_latch_s: float
    t_planned_s: float
    v_item_mps: np.ndarray
    v_ee_mps: np.ndarray
    released_at: np.ndarray
    throw_done_s: float


def release_in_scene(scene: Any, ee: Any, motion: Any) -> SceneRelease:
    """Drive the arm along the motion in the scene and open the latch at the release
    instant while it moves; returns once the arm is at rest again (the item flies on).

    The arm must be at rest at motion.q_start with the item gripped. The motion's clock
    is set so that the release instant falls on a physics step: the latch then opens at
    the start of that step. Each step sets the arm to q(t) (`CellScene.set_arm_motion`)
    and the mount pulls the end-effector along.

    Raises:
        TrajectoryError: the item still touches the end-effector at the coast's end (the
            arm would brake with it still in the pads).
    """
    sc = ee.scene if scene is None else scene
    ldt = sc.launch_dt_s
    # The whole release runs at the launch's physics step, set while the arm is at rest:
    # the mount drags E a few steps' travel behind where it holds it (measured: ~4 steps),
    # so a change of step while the arm moves changes that lag at once and jolts E
    # (at a 0.25 m/s release: E at 0.9 m/s along the axis for a moment, and the item
    # slid in the pads and left 0.04 m/s faster). Each step sets the mount to q at the
    # step's end.
    sc.set_timestep(ldt)
    m = int(math.ceil(motion.t_release_s / ldt - 1e-9))
    t0 = sc.t + m * ldt - motion.t_release_s  # q(t − t0): the release after m steps
    sc.set_arm_motion(lambda t: motion.state(t - t0 + sc.dt_now)[0])
    try:
        sc.step(m)
        cl = sc.client
        item = ee.item
        p_item = sc.item_position(item)
        v_item = sc.item_velocity(item)[0]
        v_e, w_e = (np.asarray(x) for x in cl.getBaseVelocity(sc.ee_body))
        v_ee = v_e + np.cross(w_e, p_item - sc.ee_pose()[0])
        t_latch = sc.t
        ee.throw(keep_launch_step=True)
        done = sc.t - t_latch
        t_coast_end = t0 + motion.t_release_s + motion.coast.duration
        while sc.t < t_coast_end - 1e-9:
            sc.step()
            if cl.getContactPoints(bodyA=item.body, bodyB=sc.ee_body):
                done = sc.t - t_latch
        if cl.getContactPoints(bodyA=item.body, bodyB=sc.ee_body):
            raise TrajectoryError(
                f"the item still touches the end-effector {motion.coast.duration} s after the "
                "latch opened, when the arm starts to brake: lengthen the coast"
            )
        sc.set_timestep(sc.dt_s)
        sc.run_for(max(sc.dt_s, t0 + motion.duration_s - sc.t))
    finally:
        sc.set_arm_motion(None)
        sc.set_timestep(sc.dt_s)
    sc.set_arm(motion.q_end)
    return SceneRelease(t_latch, t0 + motion.t_release_s, v_item, v_ee, p_item, done)
