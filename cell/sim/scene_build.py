"""Building the PyBullet cell: connecting, the pick station, the end-effector's body and
the arm's (see `cell.sim.scene`)."""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any

from cell.errors import InvalidParameter, MissingDependency
from cell.model.params import G
from cell.sim.band import BAND_JOINT, FINGER_LEFT, FINGER_RIGHT
from cell.sim.bins import BinSpec
from cell.sim.frames import MOUNT_FORCE_N
from cell.sim.mechanism import DRIVEN_JOINTS, EEGeometry, load_ee_geometry
from cell.sim.quiet import quiet_c_output


def check_settings(
    robot: str | None, bins: Sequence[BinSpec], dt_s: float, launch_dt_s: float
) -> None:
    """InvalidParameter for a bad time step, an unknown robot or repeated bin ids."""
    if not (0 < launch_dt_s <= dt_s <= 0.01):
        raise InvalidParameter(
            f"time steps dt_s={dt_s}, launch_dt_s={launch_dt_s} s: need 0 < launch ≤ dt ≤ 0.01"
        )
    from cell.robot.mount import load_mount

    if robot is not None:
        try:
            load_mount(robot)
        except InvalidParameter:
            raise
        except ValueError as exc:  # an unknown name or a missing file
            raise InvalidParameter(f"{exc}; or None (the end-effector alone)") from None
    ids = [b.id for b in bins]
    if len(set(ids)) != len(ids):
        raise InvalidParameter(f"bin ids must be unique, got {ids}")


def connect(gui: bool) -> tuple[Any, str]:
    """A PyBullet client (GUI or DIRECT) with its banners silenced, and pybullet_data's
    path; MissingDependency without pybullet."""
    with quiet_c_output(keep_stderr=gui):  # PyBullet's banners (import, connect)
        try:
            import pybullet
            import pybullet_data
            from pybullet_utils.bullet_client import BulletClient
        except ImportError:
            raise MissingDependency("the scene needs pybullet: pip install pybullet") from None
        client = _client_class(BulletClient)(
            connection_mode=pybullet.GUI if gui else pybullet.DIRECT
        )
    return client, pybullet_data.getDataPath()


@functools.cache
def _client_class(base: type) -> type:
    """pybullet_utils' BulletClient that keeps each function it binds to its client (and
    each constant it reads): BulletClient builds a new functools.partial at every call
    (`__getattr__`), three million times in a scene test's throws; the same functions,
    the same client id."""

    class Client(base):  # type: ignore[valid-type,misc]
        def __getattr__(self, name: str) -> Any:
            attribute = super().__getattr__(name)
            if name != "disconnect":  # a bound function, or one of pybullet's constants
                self.__dict__[name] = attribute
            return attribute

    return Client


def pick_station_body(cl: Any, xy: tuple[float, float], height: float) -> int:
    """The pick station: a fixed 0.24 m square block centred at xy [m, W], its top at
    `height` [m]."""
    half = [0.12, 0.12, height / 2]
    return int(
        cl.createMultiBody(
            0,
            cl.createCollisionShape(cl.GEOM_BOX, halfExtents=half),
            cl.createVisualShape(cl.GEOM_BOX, halfExtents=half, rgbaColor=[0.5, 0.4, 0.3, 1]),
            [xy[0], xy[1], height / 2],
        )
    )


def load_end_effector(cl: Any) -> tuple[int, EEGeometry]:
    """The end-effector's body from its description, E at (0, 0, 1) m until mounted,
    and the geometry read from the same file.

    PyBullet puts the body's base frame at `ee_base`'s inertial frame, which the
    description puts at E (the plate face); loadURDF places the link frame, so the
    base is then set to E's pose.
    """
    from cell.robot.composite import end_effector_urdf

    path = end_effector_urdf()
    geometry = load_ee_geometry(path)
    body = int(cl.loadURDF(str(path), [0, 0, 1.0]))
    cl.resetBasePositionAndOrientation(body, [0, 0, 1.0], [0, 0, 0, 1])
    names = [cl.getJointInfo(body, j)[1].decode() for j in (BAND_JOINT, FINGER_LEFT, FINGER_RIGHT)]
    if names != list(DRIVEN_JOINTS):
        raise InvalidParameter(
            f"{path}: PyBullet numbers its joints {names} where the scene drives "
            f"{list(DRIVEN_JOINTS)}: keep the joints in that order in the file"
        )
    return body, geometry


def load_arm(
    cl: Any, robot: str, base_xyz: tuple[float, float, float], *, visuals: bool = True
) -> tuple[int, list[int], int, tuple[float, ...]]:
    """The arm from the composite URDF Pinocchio plans with (robots/<arm>_throwing):
    kinematic and collision-free; its end-effector links are hidden, and the
    physically driven end-effector body follows its `ee_base` link, so the mount
    (flange offset and yaw) is the mount file's, as in the planner's model. Without
    `visuals` its visual shapes are not loaded (the Panda's Collada meshes: 0.3 s of
    CPU a scene), which only a picture of the scene needs (`show_arm`).

    Returns:
        (the arm's body, its joints' indices, `ee_base`'s link index, the ready
        configuration [rad]).
    """
    from cell.robot.composite import composite_urdf, load_mount

    spec = load_mount(robot)
    with quiet_c_output(keep_stderr=True):
        flags = 0 if visuals else cl.URDF_IGNORE_VISUAL_SHAPES
        arm = int(
            cl.loadURDF(str(composite_urdf(robot)), list(base_xyz), useFixedBase=True, flags=flags)
        )
    joints = {cl.getJointInfo(arm, j)[1].decode(): j for j in range(cl.getNumJoints(arm))}
    links = {cl.getJointInfo(arm, j)[12].decode(): j for j in range(cl.getNumJoints(arm))}
    for j in range(-1, cl.getNumJoints(arm)):
        cl.setCollisionFilterGroupMask(arm, j, 0, 0)  # kinematic, collision-free
    for name, value in spec.held_joints:  # as the planner's model holds them (the rest at 0)
        cl.resetJointState(arm, joints[name], float(value))
    for name, j in links.items() if visuals else ():
        if name.startswith("ee_"):  # drawn by the driven end-effector body instead
            cl.changeVisualShape(arm, j, rgbaColor=[0, 0, 0, 0])
    return (
        arm,
        [joints[n] for n in spec.arm_joints],
        links["ee_base"],
        tuple(float(v) for v in spec.home),
    )


def show_arm(scene: Any) -> None:
    """Give a `CellScene`'s arm its visual shapes if the scene was built without them
    (DIRECT): the arm is loaded again with them, at the joint positions [rad] it has now (a
    new body id in `scene.arm`). The arm is kinematic and collides with nothing, so this
    changes no step of the physics."""
    if scene.arm is None or scene._arm_visuals or scene.robot is None:
        return
    cl, arm, joints = scene.client, scene.arm, scene.arm_joints
    q = [cl.getJointState(arm, j)[0] for j in joints]
    cl.removeBody(arm)
    x, y, z = scene.robot_base_xyz
    new_arm, new_joints, flange, _ = load_arm(cl, scene.robot, (x, y, z), visuals=True)
    for j, v in zip(new_joints, q, strict=True):
        cl.resetJointState(new_arm, j, float(v))
    scene.arm, scene.arm_joints, scene._flange = new_arm, new_joints, flange
    scene._arm_visuals = True


def build_floor(cl: Any, data_path: str, dt_s: float) -> int:
    """Gravity, the physics step [s] and the floor plane (z = 0, W); returns its body."""
    cl.setGravity(0, 0, -G)
    cl.setPhysicsEngineParameter(fixedTimeStep=dt_s, numSolverIterations=60)
    cl.setAdditionalSearchPath(data_path)
    floor = int(cl.loadURDF("plane.urdf"))
    cl.changeDynamics(floor, -1, lateralFriction=0.6, restitution=0.1)
    return floor


def mount_constraint(cl: Any, ee_body: int) -> int:
    """The fixed constraint that holds the end-effector frame E at its mount pose (its
    target follows the arm's flange, `CellScene.hold_ee`); returns its id."""
    c = int(
        cl.createConstraint(ee_body, -1, -1, -1, cl.JOINT_FIXED, [0, 0, 0], [0, 0, 0], [0, 0, 1.0])
    )
    cl.changeConstraint(c, maxForce=MOUNT_FORCE_N)
    return c
