"""Moving the arm's end-effector in the scene: following joint samples, teleporting E with
what it holds, refreshing the pads' contacts, and E's pose for setting an item down."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from cell.errors import InvalidInput, InvalidParameter
from cell.model.objects import ObjectParams
from cell.sim.frames import FLANGE_TO_EE_M, quat_from_matrix, release_orientation
from cell.sim.items import Item
from cell.sim.mechanism import EEGeometry

if TYPE_CHECKING:
    from cell.sim.scene import CellScene


def follow(scene: CellScene, q_samples: Sequence[Sequence[float]], dt_s: float) -> None:
    """Move the arm through joint samples [rad] taken every dt_s [s], stepping the physics.

    Between samples the joints are interpolated linearly at every physics
    step, so the mount constraint drags the end-effector (and the item it
    grips) smoothly, with the arm's real velocity. Stops any `set_arm_motion`.

    Raises:
        InvalidInput: no arm, or a sample of the wrong size.
        InvalidParameter: dt_s shorter than the physics step.
    """
    if dt_s < scene.dt_s:
        raise InvalidParameter(f"sample period {dt_s} s is below the physics step {scene.dt_s} s")
    if scene.arm is None:
        raise InvalidInput("this scene has no arm (robot=None): use hold_ee")
    scene._arm_motion = None
    scene.set_timestep(scene.dt_s)
    n = max(1, int(round(dt_s / scene.dt_s)))
    cl = scene.client
    q_prev = np.asarray([cl.getJointState(scene.arm, j)[0] for j in scene.arm_joints])
    for q in q_samples:
        q_next = np.asarray(q, float)
        for k in range(1, n + 1):
            scene.set_arm(q_prev + (q_next - q_prev) * k / n)
            scene.step()
        q_prev = q_next


def pose_arm(
    cl: Any, arm: int, joints: Sequence[int], flange: int, q: Sequence[float]
) -> tuple[Sequence[float], Sequence[float]]:
    """Set the kinematic arm's joint positions q [rad] and return where its mount holds the
    end-effector frame E: position [m, W] and quaternion (x, y, z, w). E, the base plate's
    face, lies FLANGE_TO_EE_M along the `ee_base` link's z."""
    # a row of an array as Python floats at once (the same values `float` gives each)
    for j, v in zip(joints, q.tolist() if isinstance(q, np.ndarray) else q, strict=True):
        cl.resetJointState(arm, j, float(v))
    st = cl.getLinkState(arm, flange, computeForwardKinematics=True)
    return cl.multiplyTransforms(st[4], st[5], _EE_OFFSET, _NO_TURN)  # type: ignore[no-any-return]


# E from the `ee_base` link's frame: FLANGE_TO_EE_M along its z, unturned
_EE_OFFSET = (0.0, 0.0, FLANGE_TO_EE_M)
_NO_TURN = (0.0, 0.0, 0.0, 1.0)


def teleport_ee(scene: CellScene, pos: list[float], orn: list[float]) -> None:
    """Move E to a pose [m, quaternion x y z w, W] at once, with the items it holds (each
    keeps its pose relative to E)."""
    cl = scene.client
    old_p, old_o = cl.getBasePositionAndOrientation(scene.ee_body)
    inv_p, inv_o = cl.invertTransform(old_p, old_o)
    held = scene.held_bodies()
    moved = [it.body for it in scene.items if it.body in held]
    rel = {
        b: cl.multiplyTransforms(inv_p, inv_o, *cl.getBasePositionAndOrientation(b)) for b in moved
    }
    cl.resetBasePositionAndOrientation(scene.ee_body, pos, orn)
    for b, (rp, ro) in rel.items():
        cl.resetBasePositionAndOrientation(b, *cl.multiplyTransforms(pos, orn, rp, ro))


def refresh_contacts(scene: CellScene, item: Item) -> None:
    """Drop the cached contacts between the end-effector and `item`, then step once at
    the current step: Bullet makes them anew, with the normals the bodies have now.

    Why: for a cylinder or a mesh (GJK pairs) Bullet keeps each contact point with
    the normal it was made with, in world axes. While the pads hold an item and the
    arm turns the end-effector, the points stay (nothing slides) but their normals
    do not turn: after a carry they were measured 30-40° off the pads' faces, and at
    the launch they wedged a cylinder against one pad (it left at 0.2 m/s instead of
    3.2 m/s). Filtering the pair out for one step empties the cache; the item is
    unsupported for that one step (it falls g·dt²/2, under a micrometre).
    """
    cl = scene.client
    links = range(-1, cl.getNumJoints(scene.ee_body))
    for link in links:
        cl.setCollisionFilterPair(scene.ee_body, item.body, link, -1, 0)
    scene.step()
    for link in links:
        cl.setCollisionFilterPair(scene.ee_body, item.body, link, -1, 1)


def ee_pose_for_place(
    point_xy: Sequence[float],
    surface_z: float,
    obj: ObjectParams,
    stroke_m: float,
    geometry: EEGeometry,
    *,
    clearance_m: float = 0.02,
    yaw: float = 0.0,
) -> tuple[list[float], list[float]]:
    """The pose of E pointing down that holds the grip's lowest point `clearance_m` above a
    surface.

    With E's +z down, the item's bottom is at L_s + size_z along it and the
    pad ends at L_s + pad length; the lower of the two is put at the
    clearance (the TCP is EE_TO_TCP_M along +z from E). `place` then lowers
    the item by up to (end stop − L_s), so keep clearance_m small.

    Args:
        point_xy: where to set the item down [m, W].
        surface_z: height of the surface (a bin's floor plate top) [m].
        obj: the held item.
        stroke_m: the stroke it is held at [m].
        geometry: the end-effector's (the length of its pads).
        clearance_m: gap between the item's bottom and the surface [m].
        yaw: rotation of the grip about the vertical [rad].

    Returns:
        (position [m], quaternion x y z w) of E in W.
    """
    r = release_orientation(-np.pi / 2, 0.0, yaw)
    lowest = max(obj.size[2], geometry.pad_length_m)  # item bottom or pad ends
    z = surface_z + clearance_m + stroke_m + lowest
    return [float(point_xy[0]), float(point_xy[1]), float(z)], quat_from_matrix(r)
