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

`CellScene` delegates its parts to modules of functions: its construction
(`cell.sim.scene_build`), the end-effector's moves (`cell.sim.scene_arm`), the station and
the kept items (`cell.sim.station`) and watching a released item (`cell.sim.watch`).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from cell.errors import InvalidInput
from cell.model.objects import ObjectParams
from cell.model.params import DEFAULT_EE, EndEffectorParams
from cell.sim import scene_arm, station, watch
from cell.sim import snapshot as snapshot_png
from cell.sim.band import BandDrive
from cell.sim.bins import BinSpec, build_bin, which_bin
from cell.sim.drag import apply_drag
from cell.sim.frames import (
    DEFAULT_BINS,
    EE_TO_TCP_M,
    FLANGE_TO_EE_M,
    FLANGE_YAW_RAD,
    MOUNT_FORCE_N,
    PANDA_READY,
    panda_urdf,
    release_orientation,
)
from cell.sim.items import Item, spawn_item
from cell.sim.scene_build import (
    build_floor,
    check_settings,
    connect,
    load_arm,
    load_end_effector,
    mount_constraint,
    pick_station_body,
    show_arm,
)
from cell.sim.settle import Outcome, Tracker

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
        check_settings(robot, bins, dt_s, launch_dt_s)
        self.client, data_path = connect(gui)
        cl = self.client
        self.dt_s = dt_s
        self.launch_dt_s = launch_dt_s
        self._dt_now = dt_s
        self.floor = build_floor(cl, data_path, dt_s)
        self.t = 0.0
        # the wall time [s] spent stepping the physics and setting the arm along its
        # moves (`step`, `set_arm`): the item loop's planning time is the rest (`plan_s`)
        self.step_wall_s = 0.0
        self._stepping = 0  # nesting depth of the calls counted in step_wall_s
        self.bins = tuple(bins)
        self.bin_bodies = {b.id: build_bin(cl, b) for b in self.bins}
        self.pick_station_xy = pick_station_xy
        self.pick_station_height = pick_station_height
        self.pick_station = pick_station_body(cl, pick_station_xy, pick_station_height)
        self.ee_body, self.geometry = load_end_effector(cl)
        self.band = BandDrive(cl, self.ee_body, band, self.geometry)
        self._mount = mount_constraint(cl, self.ee_body)
        self._mount_pose: tuple[Sequence[float], ...] = ((0.0, 0.0, 1.0), (0.0, 0.0, 0.0, 1.0))
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
        # the arm's visual shapes only where they are seen: in the GUI, or once a picture
        # or a recording asks for them (`show_arm`); they change no step of the physics
        self._arm_visuals = gui
        if robot is not None:
            self.arm, self.arm_joints, self._flange, self.ready_q = load_arm(
                cl, robot, robot_base_xyz, visuals=gui
            )
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
        t0 = time.perf_counter()
        self._stepping += 1
        try:
            pos, orn = scene_arm.pose_arm(self.client, self.arm, self.arm_joints, self._flange, q)
            if teleport:
                self.hold_ee(pos, orn, teleport=True)
            else:  # PyBullet's tuples of floats: `hold_ee`'s own, without its copies
                self._hold(pos, orn)
        finally:
            self._count_wall(t0)

    def _count_wall(self, t0: float) -> None:
        """Leave a call counted in `step_wall_s` that began at perf_counter() = t0 [s]:
        only the outermost call adds its wall time."""
        self._stepping -= 1
        if self._stepping == 0:
            self.step_wall_s += time.perf_counter() - t0

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
        """Move the arm through joint samples [rad] taken every dt_s [s], stepping the
        physics; `cell.sim.scene_arm.follow`."""
        scene_arm.follow(self, q_samples, dt_s)

    def hold_ee(
        self, position: Sequence[float], orientation: Sequence[float], *, teleport: bool = False
    ) -> None:
        """Hold the end-effector frame E at a pose [m, quaternion x y z w, W].

        With teleport, E and the item it holds jump there (the item keeps its
        pose relative to E); otherwise the mount constraint pulls E over.
        """
        pos, orn = [float(v) for v in position], [float(v) for v in orientation]
        if teleport:
            scene_arm.teleport_ee(self, pos, orn)
        self._hold(pos, orn)

    def _hold(self, pos: Sequence[float], orn: Sequence[float]) -> None:
        """`hold_ee` without a teleport, for a position [m, W] and quaternion (x, y, z, w)
        already of floats: the mount's target set there."""
        self._mount_pose = (pos, orn)
        self.client.changeConstraint(self._mount, jointChildPivot=pos,
                                     jointChildFrameOrientation=orn, maxForce=MOUNT_FORCE_N)  # fmt: skip

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
            position, orientation = station.drop_pose(self, obj, offset_xy, yaw, gap_m)
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
        """Leave an item resting where it is: a bin keeps what lands in it (untracked,
        asleep until touched); `cell.sim.station.keep`."""
        station.keep(self, item)

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
        t0 = time.perf_counter()
        self._stepping += 1
        try:
            apply_band, step_physics = self.band.apply, cl.stepSimulation
            for _ in range(n):
                if self._arm_motion is not None:
                    self.set_arm(self._arm_motion(self.t))
                dt = self._dt_now
                apply_band(dt)
                self._item_forces()
                step_physics()
                self.t += dt
                if self._trackers:  # none while nothing is tracked
                    watch.sample_trackers(self)
        finally:
            self._count_wall(t0)

    def _item_forces(self) -> None:
        """The forces on the items for the next physics step: air drag on every item but
        those kept in a bin (`cell.sim.drag.apply_drag`)."""
        cl, kept = self.client, self._kept
        for it in self.items:
            if it.body not in kept:
                apply_drag(cl, it.body, it.drag_c)

    def refresh_contacts(self, item: Item) -> None:
        """Drop the cached contacts between the end-effector and `item`, then step once;
        `cell.sim.scene_arm.refresh_contacts`."""
        scene_arm.refresh_contacts(self, item)

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
        """Step until the item's centre of mass crosses z = land_z going down: (x [m],
        y [m], t [s] since release); `cell.sim.watch.watch_until_crossing`."""
        return watch.watch_until_crossing(self, item, land_z, timeout_s=timeout_s)

    def watch_until_rest(self, item: Item, *, timeout_s: float = 6.0) -> Outcome:
        """Step until the item rests (or the timeout) and report where it went;
        `cell.sim.watch.watch_until_rest`."""
        return watch.watch_until_rest(self, item, timeout_s=timeout_s)

    def outcome_if_settled(self, item: Item, *, timeout_s: float = 6.0) -> Outcome | None:
        """Where a tracked item went once it rests or `timeout_s` after its release, None
        while it still moves; `cell.sim.watch.outcome_if_settled`."""
        return watch.outcome_if_settled(self, item, timeout_s=timeout_s)

    # -- output ----------------------------------------------------------------
    def show_arm(self) -> None:
        """The arm given its visual shapes if built without them (`scene_build.show_arm`)."""
        show_arm(self)

    def render(self, **camera: Any) -> np.ndarray:
        """The scene as an RGB image (h, w, 3), headless; camera keywords as `snapshot.render`."""
        self.show_arm()
        return snapshot_png.render(self.client, **camera)

    def snapshot(self, path: str | Path, **camera: Any) -> Path:
        """The scene rendered (`render`) to a PNG at `path`."""
        return snapshot_png.save_png(self.render(**camera), path)

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


def item_xyz(scene: CellScene, item: Item) -> tuple[float, float, float]:
    """The item's centre of mass now [m, W], as PyBullet's tuple of floats: a flight
    loop's read every step, without an array made (`CellScene.item_position`'s values)."""
    return scene.client.getBasePositionAndOrientation(item.body)[0]


def item_linear_xyz(scene: CellScene, item: Item) -> tuple[float, float, float]:
    """The item's linear velocity now [m/s, W], as PyBullet's tuple of floats
    (`CellScene.item_velocity`'s first)."""
    return scene.client.getBaseVelocity(item.body)[0]
