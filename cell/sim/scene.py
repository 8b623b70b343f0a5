"""The PyBullet cell: floor, arm with the throwing end-effector, pick station, bins, items.

World frame W: z up, the floor is z = 0, the arm's base at `robot_base_xyz`.
The end-effector is a multibody of its own, loaded from its description
(robots/throwing_ee/throwing_ee.urdf, the file the planner's composite includes;
cell.sim.mechanism reads its numbers), held at its mount pose by a fixed constraint
whose target follows the arm's flange (`panda_link8`; frames in cell.sim.frames);
without an arm (`robot=None`) the target is set directly with `hold_ee` (calibration
campaigns do this: the end-effector held kinematically at the release pose).
The arm is kinematic (joint positions are set, not simulated) and has no
collisions: its motion is the planner's business, the scene checks what
happens to the items.

Time stepping: `dt_s` (default 1 ms) in general, `launch_dt_s` (0.25 ms)
while the band pushes, so the ~10-30 ms push is resolved by 40+ sub-steps.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from cell.errors import InvalidInput, InvalidParameter, MissingDependency, NoLanding
from cell.model.objects import ObjectParams
from cell.model.params import DEFAULT_EE, EndEffectorParams, G
from cell.sim.band import BAND_JOINT, FINGER_LEFT, FINGER_RIGHT, BandDrive
from cell.sim.bins import BinSpec, build_bin, which_bin
from cell.sim.drag import apply_drag
from cell.sim.frames import (
    DEFAULT_BINS,
    EE_TO_TCP_M,
    FLANGE_TO_EE_M,
    FLANGE_YAW_RAD,
    MOUNT_FORCE_N,
    PANDA_READY,
    ee_pose_for_item_centre,
    panda_urdf,
    quat_from_matrix,
    release_orientation,
)
from cell.sim.items import Item, spawn_item
from cell.sim.mechanism import DRIVEN_JOINTS, EEGeometry, load_ee_geometry
from cell.sim.settle import Outcome, Tracker, crossing

# the frame constants and helpers are re-exported for callers that import them from here
__all__ = [
    "CellScene",
    "DEFAULT_BINS",
    "EE_TO_TCP_M",
    "FLANGE_TO_EE_M",
    "FLANGE_YAW_RAD",
    "PANDA_READY",
    "panda_urdf",
    "release_orientation",
]

log = logging.getLogger(__name__)


@contextlib.contextmanager
def _quiet_c_output(keep_stderr: bool = False) -> Iterator[None]:
    """Silence what C code writes to file descriptors 1 and 2 (2 kept if `keep_stderr`).

    PyBullet prints a banner on import ("pybullet build time") and on every connect
    ("argv[0]="), once per scene: 13 times in a sort job, 34 in a calibration. They are
    not the command's output (`cell calibrate --json` prints JSON on stdout) and say
    nothing to its user, so they go to /dev/null at the file-descriptor level, which is
    where C code writes. A GUI connect keeps stderr: its X server errors are worth seeing.
    """
    import ctypes

    libc = ctypes.CDLL(None)
    fds = (1,) if keep_stderr else (1, 2)
    sys.stdout.flush()
    sys.stderr.flush()
    libc.fflush(None)
    saved = [os.dup(fd) for fd in fds]
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        for fd in fds:
            os.dup2(null, fd)
        yield
    finally:
        libc.fflush(None)  # C stdio buffers what PyBullet printed: out before the fds are back
        for fd, old in zip(fds, saved, strict=True):
            os.dup2(old, fd)
            os.close(old)
        os.close(null)


class CellScene:
    """The simulated cell.

    Args:
        robot: "panda" or None (end-effector only, held with `hold_ee`).
        bins: the open bins.
        gui: open PyBullet's GUI instead of DIRECT.
        dt_s: physics step outside the launch [s].
        launch_dt_s: physics step during the launch push [s].
        band: the band law the plant obeys (MODEL.md parameters).
        pick_station_xy: centre of the pick station [m, W].
        pick_station_height: its top surface height [m].
        robot_base_xyz: the arm's base position [m, W].

    Raises:
        InvalidParameter: a bad step, an unknown robot, or an end-effector description
            (robots/throwing_ee/throwing_ee.urdf) that is not the mechanism the scene drives.
    """

    def __init__(
        self,
        robot: str | None = "panda",
        bins: Sequence[BinSpec] = DEFAULT_BINS,
        *,
        gui: bool = False,
        dt_s: float = 1e-3,
        launch_dt_s: float = 2.5e-4,
        band: EndEffectorParams = DEFAULT_EE,
        pick_station_xy: tuple[float, float] = (0.45, -0.4),
        pick_station_height: float = 0.2,
        robot_base_xyz: tuple[float, float, float] = (0.0, 0.0, 0.0),
    ) -> None:
        if not (0 < launch_dt_s <= dt_s <= 0.01):
            raise InvalidParameter(
                f"time steps dt_s={dt_s}, launch_dt_s={launch_dt_s} s: need 0 < launch ≤ dt ≤ 0.01"
            )
        from cell.robot.composite import MOUNTS

        if robot is not None and robot not in MOUNTS:
            raise InvalidParameter(f"robot {robot!r}: valid are {sorted(MOUNTS)} or None")
        ids = [b.id for b in bins]
        if len(set(ids)) != len(ids):
            raise InvalidParameter(f"bin ids must be unique, got {ids}")
        with _quiet_c_output(keep_stderr=gui):  # PyBullet's banners (import, connect)
            try:
                import pybullet
                import pybullet_data
                from pybullet_utils.bullet_client import BulletClient
            except ImportError:
                raise MissingDependency("the scene needs pybullet: pip install pybullet") from None
            self.client = BulletClient(connection_mode=pybullet.GUI if gui else pybullet.DIRECT)
        cl = self.client
        self.dt_s = dt_s
        self.launch_dt_s = launch_dt_s
        self._dt_now = dt_s
        cl.setGravity(0, 0, -G)
        cl.setPhysicsEngineParameter(fixedTimeStep=dt_s, numSolverIterations=60)
        cl.setAdditionalSearchPath(pybullet_data.getDataPath())
        self.floor = int(cl.loadURDF("plane.urdf"))
        cl.changeDynamics(self.floor, -1, lateralFriction=0.6, restitution=0.1)
        self.t = 0.0
        self.bins = tuple(bins)
        self.bin_bodies = {b.id: build_bin(cl, b) for b in self.bins}
        self.pick_station_xy = pick_station_xy
        self.pick_station_height = pick_station_height
        half = [0.12, 0.12, pick_station_height / 2]
        self.pick_station = int(
            cl.createMultiBody(
                0,
                cl.createCollisionShape(cl.GEOM_BOX, halfExtents=half),
                cl.createVisualShape(cl.GEOM_BOX, halfExtents=half, rgbaColor=[0.5, 0.4, 0.3, 1]),
                [pick_station_xy[0], pick_station_xy[1], pick_station_height / 2],
            )
        )
        self.ee_body, self.geometry = self._load_end_effector()
        self.band = BandDrive(cl, self.ee_body, band, self.geometry)
        self._mount = cl.createConstraint(
            self.ee_body, -1, -1, -1, cl.JOINT_FIXED, [0, 0, 0], [0, 0, 0], [0, 0, 1.0]
        )
        cl.changeConstraint(self._mount, maxForce=MOUNT_FORCE_N)
        self._mount_pose: tuple[list[float], list[float]] = ([0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0])
        self._arm_motion: Callable[[float], Sequence[float]] | None = None
        self.items: list[Item] = []
        self._trackers: dict[int, Tracker] = {}
        self._kept: set[int] = set()  # items left resting in a bin (see `keep`)
        self.arm: int | None = None
        self.arm_joints: list[int] = []
        self._flange = -1
        self.robot = robot
        self.robot_base_xyz = tuple(float(v) for v in robot_base_xyz)  # [m, W]
        self.ready_q: tuple[float, ...] = ()
        if robot is not None:
            self._load_arm(robot, robot_base_xyz)

    # -- construction ----------------------------------------------------------
    def _load_end_effector(self) -> tuple[int, EEGeometry]:
        """The end-effector's body from its description, E at (0, 0, 1) m until mounted,
        and the geometry read from the same file.

        PyBullet puts the body's base frame at `ee_base`'s inertial frame, which the
        description puts at E (the plate face); loadURDF places the link frame, so the
        base is then set to E's pose.
        """
        from cell.robot.composite import end_effector_urdf

        cl = self.client
        path = end_effector_urdf()
        geometry = load_ee_geometry(path)
        body = int(cl.loadURDF(str(path), [0, 0, 1.0]))
        cl.resetBasePositionAndOrientation(body, [0, 0, 1.0], [0, 0, 0, 1])
        names = [
            cl.getJointInfo(body, j)[1].decode() for j in (BAND_JOINT, FINGER_LEFT, FINGER_RIGHT)
        ]
        if names != list(DRIVEN_JOINTS):
            raise InvalidParameter(
                f"{path}: PyBullet numbers its joints {names} where the scene drives "
                f"{list(DRIVEN_JOINTS)}: keep the joints in that order in the file"
            )
        return body, geometry

    def _load_arm(self, robot: str, base_xyz: tuple[float, float, float]) -> None:
        """The arm from the composite URDF Pinocchio plans with (robots/<arm>_throwing):
        kinematic and collision-free; its end-effector links are hidden, and the
        physically driven end-effector body follows its `ee_base` link, so the mount
        (flange offset and yaw) is the mount file's, as in the planner's model."""
        from cell.robot.composite import composite_urdf, load_mount

        spec = load_mount(robot)
        cl = self.client
        with _quiet_c_output(keep_stderr=True):
            arm = int(cl.loadURDF(str(composite_urdf(robot)), list(base_xyz), useFixedBase=True))
        joints = {cl.getJointInfo(arm, j)[1].decode(): j for j in range(cl.getNumJoints(arm))}
        links = {cl.getJointInfo(arm, j)[12].decode(): j for j in range(cl.getNumJoints(arm))}
        self.arm = arm
        self.arm_joints = [joints[n] for n in spec.arm_joints]
        self._flange = links["ee_base"]
        for j in range(-1, cl.getNumJoints(arm)):
            cl.setCollisionFilterGroupMask(arm, j, 0, 0)  # kinematic, collision-free
        for name, j in links.items():
            if name.startswith("ee_"):  # drawn by the driven end-effector body instead
                cl.changeVisualShape(arm, j, rgbaColor=[0, 0, 0, 0])
        self.ready_q = tuple(float(v) for v in spec.home)
        self.set_arm(self.ready_q, teleport=True)

    # -- the arm and the end-effector's mount ----------------------------------
    def set_arm(self, q: Sequence[float], *, teleport: bool = False) -> None:
        """Set the arm's joint positions [rad]; the end-effector follows its mount.

        Args:
            q: joint positions [rad].
            teleport: move the end-effector (and a held item) there at once
                instead of letting the mount constraint pull it over the next steps.

        Raises:
            InvalidInput: no arm in this scene, or not one value per arm joint.
        """
        if self.arm is None:
            raise InvalidInput("this scene has no arm (robot=None): use hold_ee")
        if len(q) != len(self.arm_joints):
            raise InvalidInput(
                f"arm configuration needs {len(self.arm_joints)} values, got {len(q)}"
            )
        cl = self.client
        for j, v in zip(self.arm_joints, q, strict=True):
            cl.resetJointState(self.arm, j, float(v))
        st = cl.getLinkState(self.arm, self._flange, computeForwardKinematics=True)
        # E, the base plate's face, lies FLANGE_TO_EE_M along ee_base's z
        pos, orn = cl.multiplyTransforms(st[4], st[5], [0, 0, FLANGE_TO_EE_M], [0, 0, 0, 1])
        self.hold_ee(pos, orn, teleport=teleport)

    def set_arm_motion(self, q_of_t: Callable[[float], Sequence[float]] | None) -> None:
        """Drive the arm on every physics step by q = q_of_t(t) [rad], t the scene time [s].

        This lets the arm keep moving while the end-effector acts (a release
        with the arm in motion: set it, then `throw`). None stops it.

        Raises:
            InvalidInput: no arm in this scene.
        """
        if q_of_t is not None and self.arm is None:
            raise InvalidInput("this scene has no arm (robot=None): use hold_ee")
        self._arm_motion = q_of_t

    def follow(self, q_samples: Sequence[Sequence[float]], dt_s: float) -> None:
        """Move the arm through joint samples [rad] taken every dt_s [s], stepping the physics.

        Between samples the joints are interpolated linearly at every physics
        step, so the mount constraint drags the end-effector (and the item it
        grips) smoothly, with the arm's real velocity. Stops any `set_arm_motion`.

        Raises:
            InvalidInput: no arm, or a sample of the wrong size.
            InvalidParameter: dt_s shorter than the physics step.
        """
        if dt_s < self.dt_s:
            raise InvalidParameter(
                f"sample period {dt_s} s is below the physics step {self.dt_s} s"
            )
        if self.arm is None:
            raise InvalidInput("this scene has no arm (robot=None): use hold_ee")
        self._arm_motion = None
        self.set_timestep(self.dt_s)
        n = max(1, int(round(dt_s / self.dt_s)))
        cl = self.client
        q_prev = np.asarray([cl.getJointState(self.arm, j)[0] for j in self.arm_joints])
        for q in q_samples:
            q_next = np.asarray(q, float)
            for k in range(1, n + 1):
                self.set_arm(q_prev + (q_next - q_prev) * k / n)
                self.step()
            q_prev = q_next

    def hold_ee(
        self, position: Sequence[float], orientation: Sequence[float], *, teleport: bool = False
    ) -> None:
        """Hold the end-effector frame E at a pose [m, quaternion x y z w, W].

        With teleport, E and the item it holds jump there (the item keeps its
        pose relative to E); otherwise the mount constraint pulls E over.
        """
        cl = self.client
        pos, orn = [float(v) for v in position], [float(v) for v in orientation]
        if teleport:
            old_p, old_o = cl.getBasePositionAndOrientation(self.ee_body)
            inv_p, inv_o = cl.invertTransform(old_p, old_o)
            held = self.held_bodies()
            moved = [it.body for it in self.items if it.body in held]
            rel = {
                b: cl.multiplyTransforms(inv_p, inv_o, *cl.getBasePositionAndOrientation(b))
                for b in moved
            }
            cl.resetBasePositionAndOrientation(self.ee_body, pos, orn)
            for b, (rp, ro) in rel.items():
                cl.resetBasePositionAndOrientation(b, *cl.multiplyTransforms(pos, orn, rp, ro))
        self._mount_pose = (pos, orn)
        cl.changeConstraint(
            self._mount,
            jointChildPivot=pos,
            jointChildFrameOrientation=orn,
            maxForce=MOUNT_FORCE_N,
        )

    def ee_collides_with_station(self, collide: bool) -> None:
        """Let the end-effector collide with the pick station (the physical pick), or not
        (a kinematic pick moves the item into the grip: the pads, longer than a flat item,
        must not jam on the station's top while the fingers close). It collides by default."""
        cl = self.client
        for link in range(-1, cl.getNumJoints(self.ee_body)):
            cl.setCollisionFilterPair(self.ee_body, self.pick_station, link, -1, int(collide))

    def ee_lag(self) -> np.ndarray:
        """Where the mount holds the end-effector frame E minus where E is [m, W], shape (3,):
        E lags the arm's flange while the mount constraint pulls it along."""
        p, _ = self.client.getBasePositionAndOrientation(self.ee_body)
        return np.asarray(self._mount_pose[0], float) - np.asarray(p, float)

    def held_bodies(self) -> set[int]:
        """Item bodies in contact with the end-effector."""
        return {int(c[2]) for c in self.client.getContactPoints(bodyA=self.ee_body)} - {
            self.ee_body
        }

    def ee_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """The end-effector frame E now: position [m, W] and rotation matrix, shape (3, 3)."""
        p, o = self.client.getBasePositionAndOrientation(self.ee_body)
        return np.asarray(p), np.asarray(self.client.getMatrixFromQuaternion(o)).reshape(3, 3)

    def ee_pose_for_release(
        self,
        p0: Sequence[float],
        elevation: float,
        azimuth: float,
        stroke_m: float,
        obj: ObjectParams,
        roll: float = 0.0,
    ) -> tuple[list[float], list[float]]:
        """The pose of E that puts the gripped item's centre of mass at p0 [m, W].

        The item's centre sits at z = L_s + size_z/2 in E, on the throw axis.

        Returns:
            (position [m], quaternion x y z w) of E in W.
        """
        return ee_pose_for_item_centre(p0, elevation, azimuth, stroke_m, obj, roll)

    def ee_pose_for_place(
        self,
        point_xy: Sequence[float],
        surface_z: float,
        obj: ObjectParams,
        stroke_m: float,
        *,
        clearance_m: float = 0.02,
        yaw: float = 0.0,
    ) -> tuple[list[float], list[float]]:
        """The pose of E pointing down that holds the grip's lowest point `clearance_m` above a surface.

        With E's +z down, the item's bottom is at L_s + size_z along it and the
        pad ends at L_s + pad length; the lower of the two is put at the
        clearance (the TCP is EE_TO_TCP_M along +z from E). `place` then lowers
        the item by up to (end stop − L_s), so keep clearance_m small.

        Args:
            point_xy: where to set the item down [m, W].
            surface_z: height of the surface (a bin's floor plate top) [m].
            obj: the held item.
            stroke_m: the stroke it is held at [m].
            clearance_m: gap between the item's bottom and the surface [m].
            yaw: rotation of the grip about the vertical [rad].

        Returns:
            (position [m], quaternion x y z w) of E in W.
        """
        r = release_orientation(-np.pi / 2, 0.0, yaw)
        lowest = max(obj.size[2], self.geometry.pad_length_m)  # item bottom or pad ends
        z = surface_z + clearance_m + stroke_m + lowest
        return [float(point_xy[0]), float(point_xy[1]), float(z)], quat_from_matrix(r)

    # -- items -----------------------------------------------------------------
    def spawn_item(
        self,
        what: str | ObjectParams,
        *,
        at_pick_station: bool = True,
        position: Sequence[float] | None = None,
        orientation: Sequence[float] = (0.0, 0.0, 0.0, 1.0),
        offset_xy: Sequence[float] = (0.0, 0.0),
        yaw: float = 0.0,
        gap_m: float = 1e-3,
    ) -> Item:
        """Add an item: on the pick station (dropped onto any item already there), or at a pose.

        Args:
            what: catalogue id or object parameters.
            at_pick_station: put it on the pick station (ignored when position is given).
            position: centre of mass [m, W].
            orientation: quaternion (x, y, z, w) [W] (ignored on the pick station).
            offset_xy: on the pick station: where from the station's centre [m, W].
            yaw: on the pick station: the item's turn about the vertical [rad].
            gap_m: on the pick station: how high over its top the item's box is set [m]
                (0: resting on it, for a box, a cylinder or a sphere).
        """
        from cell.sim.items import resolve_object

        obj, _ = resolve_object(what)
        if position is None:
            if not at_pick_station:
                raise InvalidInput("spawn_item: give a position or at_pick_station=True")
            position = (
                self.pick_station_xy[0] + float(offset_xy[0]),
                self.pick_station_xy[1] + float(offset_xy[1]),
                self._station_top() + obj.size[2] / 2 + gap_m,
            )
            orientation = (0.0, 0.0, float(np.sin(yaw / 2)), float(np.cos(yaw / 2)))
        item = spawn_item(self.client, what, position, orientation)
        self.items.append(item)
        return item

    def item_position(self, item: Item) -> np.ndarray:
        """The item's centre of mass now [m, W]."""
        p, _ = self.client.getBasePositionAndOrientation(item.body)
        return np.asarray(p, float)

    def item_pose(self, item: Item) -> tuple[np.ndarray, np.ndarray]:
        """The item's centre of mass [m, W] and rotation matrix (3, 3) [W] now."""
        p, o = self.client.getBasePositionAndOrientation(item.body)
        rot = np.asarray(self.client.getMatrixFromQuaternion(o), float).reshape(3, 3)
        return np.asarray(p, float), rot

    def item_aabb(self, item: Item) -> tuple[np.ndarray, np.ndarray]:
        """The item's axis-aligned bounding box now: (lowest, highest corner) [m, W]."""
        lo, hi = self.client.getAABB(item.body)
        return np.asarray(lo, float), np.asarray(hi, float)

    def item_velocity(self, item: Item) -> tuple[np.ndarray, np.ndarray]:
        """The item's linear [m/s, W] and angular [rad/s, W] velocity now."""
        v, w = self.client.getBaseVelocity(item.body)
        return np.asarray(v, float), np.asarray(w, float)

    def ee_touches(self, item: Item) -> bool:
        """The end-effector touches the item or the pick station (the plant's contacts)."""
        return any(
            c[8] < 0.0
            for body in (item.body, self.pick_station)
            for c in self.client.getContactPoints(bodyA=self.ee_body, bodyB=body)
        )

    def pick_station_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The pick station's axis-aligned bounding box: (lowest, highest) corner [m, W]."""
        lo, hi = self.client.getAABB(self.pick_station)
        return np.asarray(lo, float), np.asarray(hi, float)

    def on_station(self, item: Item) -> bool:
        """The item rests on the pick station (its centre over it, not far above it)."""
        p = self.item_position(item)
        x0, y0 = self.pick_station_xy
        h = self.pick_station_height
        return abs(p[0] - x0) < 0.12 and abs(p[1] - y0) < 0.12 and h < p[2] < h + max(item.obj.size)

    def tidy(self, item: Item) -> None:
        """Bins keep what lands in them, as real bins do (later items land on earlier
        ones); an item anywhere else (on the floor, still on the station, in the grip) is
        taken away, as an operator would."""
        if self.in_bin(item) is not None:
            self.keep(item)
        else:
            self.remove_item(item)

    def _station_top(self) -> float:
        """Height above which a new item fits on the pick station (over any item resting
        there; not over one flying past, which is still being tracked) [m]."""
        top = self.pick_station_height
        x0, y0 = self.pick_station_xy
        for it in self.items:
            if it.body in self._trackers or it.body in self._kept:
                continue
            p, _ = self.client.getBasePositionAndOrientation(it.body)
            if abs(p[0] - x0) < 0.15 and abs(p[1] - y0) < 0.15 and p[2] > top - 0.05:
                top = max(top, p[2] + float(np.linalg.norm(it.obj.size)) / 2)
        return top

    def remove_item(self, item: Item) -> None:
        """Take an item out of the scene."""
        self.client.removeBody(item.body)
        self.items = [i for i in self.items if i.body != item.body]
        self._trackers.pop(item.body, None)
        self._kept.discard(item.body)

    # -- what the bins hold ----------------------------------------------------
    def in_bin(self, item: Item) -> str | None:
        """The bin the item's centre lies in now, below its rim + half the item's largest
        extent (as `watch_until_rest` scores it), or None."""
        pos, _ = self.client.getBasePositionAndOrientation(item.body)
        return which_bin(pos, self.bins, above_rim_m=max(item.obj.size) / 2)

    def keep(self, item: Item) -> None:
        """Leave an item resting where it is: a bin keeps what lands in it.

        It stays a body of the scene (later items land on it and may knock it about),
        but is no longer tracked nor given the drag law (a resting or nudged item moves
        at well under 1 m/s, where drag is below 0.1 % of its weight), and Bullet puts it
        to sleep until something touches it: piles of items awake in the bins would
        make every physics step several times slower (their contacts are solved at
        every step with 60 solver iterations).
        """
        cl = self.client
        self._trackers.pop(item.body, None)
        self._kept.add(item.body)
        cl.changeDynamics(item.body, -1, activationState=cl.ACTIVATION_STATE_ENABLE_SLEEPING)
        cl.changeDynamics(item.body, -1, activationState=cl.ACTIVATION_STATE_SLEEP)

    def kept_items(self, bin_id: str | None = None) -> list[Item]:
        """Items left in the scene by `keep` (those whose centre lies in `bin_id`, if given)."""
        kept = [it for it in self.items if it.body in self._kept]
        return kept if bin_id is None else [it for it in kept if self.in_bin(it) == bin_id]

    def bin_spec(self, bin_id: str) -> BinSpec:
        """The bin of that id; InvalidInput naming the scene's bins when there is none."""
        spec = next((b for b in self.bins if b.id == bin_id), None)
        if spec is None:
            raise InvalidInput(f"no bin {bin_id!r} in the scene; bins: {[b.id for b in self.bins]}")
        return spec

    def which_bin(self, point: Sequence[float]) -> str | None:
        """The id of the bin a point lies in (see cell.sim.bins.which_bin), or None."""
        return which_bin(point, self.bins)

    # -- stepping --------------------------------------------------------------
    def set_timestep(self, dt_s: float) -> None:
        """Change the physics step [s] (the launch uses a shorter one)."""
        if dt_s != self._dt_now:
            self.client.setPhysicsEngineParameter(fixedTimeStep=dt_s)
            self._dt_now = dt_s

    @property
    def dt_now(self) -> float:
        """The physics step in use now [s] (`dt_s`, or `launch_dt_s` during a launch)."""
        return self._dt_now

    def step(self, n: int = 1) -> None:
        """Advance n physics steps: band law, drag on every item, then the physics."""
        cl = self.client
        for _ in range(n):
            if self._arm_motion is not None:
                self.set_arm(self._arm_motion(self.t))
            self.band.apply(self._dt_now)
            for it in self.items:
                if it.body not in self._kept:
                    apply_drag(cl, it.body, it.drag_c)
            cl.stepSimulation()
            self.t += self._dt_now
            for body, tr in self._trackers.items():
                pos, _ = cl.getBasePositionAndOrientation(body)
                vel, spin = cl.getBaseVelocity(body)
                tr.sample(
                    self.t, pos, np.asarray(vel), np.asarray(spin), cl.getContactPoints(bodyA=body)
                )

    def refresh_contacts(self, item: Item) -> None:
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
        cl = self.client
        links = range(-1, cl.getNumJoints(self.ee_body))
        for link in links:
            cl.setCollisionFilterPair(self.ee_body, item.body, link, -1, 0)
        self.step()
        for link in links:
            cl.setCollisionFilterPair(self.ee_body, item.body, link, -1, 1)

    def run_for(self, seconds: float) -> None:
        """Step for a duration [s] at the current step."""
        self.step(max(1, int(round(seconds / self._dt_now))))

    def track(self, item: Item) -> Tracker:
        """Start recording an item's track (release time = now)."""
        tr = Tracker(item.body, self.ee_body, self.t)
        self._trackers[item.body] = tr
        return tr

    def tracker(self, item: Item) -> Tracker:
        """The item's active tracker (started by `track`, or by a throw or place).

        Raises:
            InvalidInput: the item is not being tracked.
        """
        tr = self._trackers.get(item.body)
        if tr is None:
            raise InvalidInput(f"item {item.obj.name or item.body} is not being tracked")
        return tr

    def watch_until_crossing(
        self, item: Item, land_z: float, *, timeout_s: float = 4.0
    ) -> tuple[float, float, float]:
        """Step until the item's centre of mass crosses z = land_z going down.

        Returns:
            (x [m], y [m], t [s] since release) of the crossing (see Outcome.crossing).

        Raises:
            NoLanding: it touched down first, or the timeout passed.
        """
        self.set_timestep(self.dt_s)
        tr = self._trackers.get(item.body) or self.track(item)
        t_end = self.t + timeout_s
        try:
            while self.t < t_end:
                self.step()
                z = tr.samples[-1][3]
                if z <= land_z and tr.samples[-2][3] > z:
                    return crossing(np.asarray(tr.samples), land_z)
                if tr.touchdown is not None:
                    break
        finally:
            self._trackers.pop(item.body, None)
        raise NoLanding(
            f"item {item.obj.name or item.body} did not cross z = {land_z:.3f} m in free flight"
        )

    def watch_until_rest(self, item: Item, *, timeout_s: float = 6.0) -> Outcome:
        """Step until the item rests (or the timeout) and report where it went.

        Tracking starts at the last `track` call (the end-effector's throw and
        place start it at release), else now.

        Raises:
            NoLanding: the item never touched anything but the end-effector.
        """
        self.set_timestep(self.dt_s)
        tr = self._trackers.get(item.body) or self.track(item)
        t_end = self.t + timeout_s
        while not tr.at_rest and self.t < t_end and not self._fell_out(tr):
            self.step()
        return self._end_watch(item, tr, timeout_s)

    def outcome_if_settled(self, item: Item, *, timeout_s: float = 6.0) -> Outcome | None:
        """Where a tracked item went, once it rests or `timeout_s` after its release; None
        while it is still moving. Lets the loop go on with the next item while this one
        flies (the physics steps it with everything else); its track is the same as
        `watch_until_rest` would have recorded.

        Raises:
            InvalidInput: the item is not being tracked.
            NoLanding: it never touched anything but the end-effector.
        """
        tr = self.tracker(item)
        if tr.at_rest or self.t >= tr.t0 + timeout_s or self._fell_out(tr):
            return self._end_watch(item, tr, timeout_s)
        return None

    @staticmethod
    def _fell_out(tr: Tracker) -> bool:
        return bool(tr.samples) and tr.samples[-1][3] < -1.0  # fell out of the world

    def _end_watch(self, item: Item, tr: Tracker, timeout_s: float) -> Outcome:
        self._trackers.pop(item.body, None)
        if tr.touchdown is None:
            raise NoLanding(
                f"item {item.obj.name or item.body} never touched down in {timeout_s} s"
            )
        out = tr.outcome(None)
        return Outcome(
            touchdown_xyz=out.touchdown_xyz,
            touchdown_speed=out.touchdown_speed,
            touchdown_body=out.touchdown_body,
            rest_xyz=out.rest_xyz,
            bin_id=which_bin(out.rest_xyz, self.bins, above_rim_m=max(item.obj.size) / 2),
            rested=out.rested,
            t_touchdown=out.t_touchdown,
            t_rest=out.t_rest,
            track=out.track,
        )

    # -- output ----------------------------------------------------------------
    def snapshot(self, path: str | Path, **camera: Any) -> Path:
        """Render the scene headless (TinyRenderer) to a PNG; camera keywords as cell.sim.snapshot.render."""
        from cell.sim.snapshot import render, save_png

        return save_png(render(self.client, **camera), path)

    def close(self) -> None:
        """Disconnect from the physics server."""
        try:
            self.client.disconnect()
        except Exception:  # noqa: BLE001 - already disconnected
            log.debug("scene already closed")

    def __enter__(self) -> CellScene:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
