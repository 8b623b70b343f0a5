"""The end-effector in the PyBullet cell (cell.sim), behind the EndEffector interface.

* The physical pick (the arm's, cell.orchestrator): `open_for_pick(L_s)` opens the
  fingers and winds the spool to L_s while the arm moves over the item; the arm
  lowers the grip onto the item resting on the station; `close_on(item)` closes the
  fingers on it by contact with the band's grip force f_g, and from then on friction
  alone holds it. Nothing moves the item but its contacts.
* `grasp(L_s)`: the kinematic pick (calibration campaigns, the platforms): the item
  is moved into the open grip and seated on the hoop at L_s (latch engaged); the
  fingers close on it as above.
* `set_stroke(L_s)`: the spool winds or unwinds at `spool_speed_mps`.
* `throw()`: the latch lets go; the band law drives the carriage, which pushes
  the item (sub-stepped at the scene's launch step) until the carriage hits its
  end stop; the item flies on. Its launch velocity is never set.
* `place()`: the spool unwinds at `place_speed_mps`; the carriage lowers the item
  until it touches something, then the fingers open (`cell.sim.scene_arm.ee_pose_for_place`
  gives a pose for it). Items shorter than the finger pads (cube30, the flat
  rocks) are let go when the pads meet the surface and drop the difference.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from cell.catalogue import pad_width_m
from cell.endeffector.base import EndEffector, EndEffectorStatus
from cell.errors import GraspLost, InvalidInput, InvalidParameter
from cell.model.params import G
from cell.sim.band import BAND_JOINT, FINGER_LEFT, FINGER_RIGHT, BandReading
from cell.sim.items import Item

__all__ = ["PLACE_DROP_M", "PLACE_SPEED_MPS", "PyBulletEndEffector"]

log = logging.getLogger(__name__)

_STALL_M = 0.002  # [m] carriage lag behind the spool that means it is blocked
# A place sets the item down no harder than a drop from PLACE_DROP_M: the carriage
# follows the spool within a step, and the item touches down at the unwinding speed
# (measured in the scene for cube50, cuboid_c, cyl70, cube30, sphere40, teddy and duck
# at 0.04-0.3 m/s: touchdown speed = unwinding speed to 1 mm/s), so the unwinding speed
# is that of a free fall from PLACE_DROP_M, v = sqrt(2 g h) = 0.198 m/s. Its place
# takes 0.20 s from 20 mm over the floor instead of 0.59 s at 0.04 m/s (a 0.08 mm drop);
# where the items came to rest did not change (within 0.2 mm).
PLACE_DROP_M = 0.002
PLACE_SPEED_MPS = math.sqrt(2.0 * G * PLACE_DROP_M)
FINGERS = (FINGER_LEFT, FINGER_RIGHT)
GRIP_BUILD_S = 0.02  # [s] the closed pads' grip builds up this long before the item is lifted
PLACE_OPENING_M = 0.005  # [m] a place opens each pad this far outside the item's width


class PyBulletEndEffector(EndEffector):
    """The simulated end-effector of a `cell.sim.CellScene`.

    Args:
        scene: the scene whose end-effector this drives.
        spool_speed_mps: carriage speed when winding or unwinding [m/s].
        place_speed_mps: carriage speed while placing [m/s]: the item's touchdown speed
            (PLACE_SPEED_MPS, a drop from PLACE_DROP_M).
        close_time_s: time given to the fingers to close [s] (the physical pick: at most,
            they stop on the item sooner).
    """

    def __init__(
        self,
        scene: object,
        *,
        spool_speed_mps: float = 0.1,
        place_speed_mps: float = PLACE_SPEED_MPS,
        close_time_s: float = 0.15,
    ) -> None:
        from cell.sim.scene import CellScene

        if not isinstance(scene, CellScene):
            raise InvalidInput("PyBulletEndEffector needs a cell.sim.CellScene")
        for name, v in (("spool_speed_mps", spool_speed_mps), ("place_speed_mps", place_speed_mps)):
            if not v > 0:
                raise InvalidParameter(f"{name}={v} must be > 0 m/s")
        self.scene = scene
        self.band = scene.band
        self.spool_speed_mps = spool_speed_mps
        self.place_speed_mps = place_speed_mps
        self.close_time_s = close_time_s
        self.item: Item | None = None
        self.grip_yaw_rad = 0.0  # the grip's turn about the item held (`across`)
        self._grasp_stroke_m = 0.0
        self.last_released: Item | None = None

    # -- helpers ---------------------------------------------------------------
    def _check_stroke(self, stroke_m: float) -> None:
        ee = self.band.ee
        if not (ee.stroke_min - 1e-9 <= stroke_m <= ee.stroke_max + 1e-9):
            raise InvalidParameter(
                f"stroke {stroke_m:.4f} m outside the end-effector's range "
                f"{ee.stroke_min:.3f} … {ee.stroke_max:.3f} m"
            )

    def _wind_to(self, stroke_m: float, speed_mps: float) -> None:
        sc = self.scene
        sc.set_timestep(sc.dt_s)
        self.band.wind_target_m = None
        s = self.band.stroke_cmd_m
        n = max(1, int(abs(stroke_m - s) / (speed_mps * sc.dt_s)))
        for k in range(1, n + 1):
            self.band.stroke_cmd_m = s + (stroke_m - s) * k / n
            sc.step()

    def reading(self) -> BandReading:
        """The band now: stretch, forces, latch (law at the current configuration)."""
        return self.band.reading()

    def pick_candidate(self) -> Item:
        """The item to grasp: the newest item resting on the pick station.

        Raises:
            InvalidInput: none is there.
        """
        sc = self.scene
        x0, y0 = sc.pick_station_xy
        for it in reversed(sc.items):
            p, _ = sc.client.getBasePositionAndOrientation(it.body)
            on_top = abs(p[0] - x0) < 0.15 and abs(p[1] - y0) < 0.15
            if on_top and sc.pick_station_height < p[2] < sc.pick_station_height + 0.25:
                return it
        raise InvalidInput("no item on the pick station to grasp (spawn one first)")

    # -- the physical pick -------------------------------------------------------
    def open_for_pick(self, stroke_m: float, opening_m: float | None = None) -> None:
        """Get ready to pick at stroke L_s [m]: the fingers open (each to `opening_m` from
        the axis [m], None: their widest) and the spool winds to L_s at `spool_speed_mps`,
        both over the next physics steps while the arm moves (`wait_wound` waits for it).

        Raises:
            InvalidParameter: stroke or opening out of range.
            InvalidInput: already holding an item.
        """
        self._check_stroke(stroke_m)
        widest = self.scene.geometry.finger_open_m
        if opening_m is not None and not 0 < opening_m <= widest:
            raise InvalidParameter(f"finger opening {opening_m} m outside 0 … {widest} m")
        self._check_empty()
        self.band.fingers_closing = False
        self.band.open_to_m = opening_m
        self.band.wind(stroke_m, self.spool_speed_mps)

    def wait_wound(self, tolerance_m: float = 5e-4, timeout_s: float = 2.0) -> float:
        """Step until the spool has wound to its target and the carriage is there (within
        `tolerance_m`); returns the time waited [s]."""
        sc = self.scene
        sc.set_timestep(sc.dt_s)
        t0 = sc.t
        while sc.t - t0 < timeout_s and (
            self.band.winding() or abs(self.band.position() - self.band.stroke_cmd_m) > tolerance_m
        ):
            sc.step()
        return sc.t - t0

    def pads_touching(self, item: Item) -> set[str]:
        """Which pads ("left", "right") touch the item now (the plant's contacts)."""
        cl = self.scene.client
        links = {int(c[3]) for c in cl.getContactPoints(bodyA=self.scene.ee_body, bodyB=item.body)}
        return {n for n, j in (("left", FINGER_LEFT), ("right", FINGER_RIGHT)) if j in links}

    def close_on(self, item: Item, yaw_rad: float = 0.0) -> None:
        """Close the fingers on the item between the open pads, at the stroke the carriage is
        at (the arm holds the grip over the item): they close by contact with the band's
        grip force f_g, and from then on friction alone holds the item. `yaw_rad`: the
        grip turned that far about the item's z from its x axis (0: across its size x;
        π/2: across its size y, `cell.arm.grip_side`).

        Raises:
            InvalidInput: already holding an item.
            GraspLost: (stage "grasp") the pads did not both close on the item, or its
                centre is not between them.
        """
        self._check_empty()
        sc = self.scene
        sc.set_timestep(sc.dt_s)
        stroke_m = self.band.position()
        self.grip_yaw_rad = float(yaw_rad)
        self.band.fingers_closing = True
        self._close_fingers()
        touching = self.pads_touching(item)
        if len(touching) < 2 or not self._in_grip(item, stroke_m):
            opening = self.band.width()
            self.band.fingers_closing = False
            raise GraspLost(
                f"the fingers did not close on item {item.obj.name or item.body} "
                f"(width {self.across(item)[0] * 1000:.0f} mm; pads closed to "
                f"{opening * 1000:.0f} mm, "
                f"touching it: {sorted(touching) or 'none'})",
                "grasp",
            )
        self._hold(item, stroke_m)

    def _check_empty(self) -> None:
        """InvalidInput when an item is held already (a grasp takes one at a time)."""
        if self.item is not None:
            raise InvalidInput("already holding an item: place or throw it first")

    def _hold(self, item: Item, stroke_m: float) -> None:
        """From now on `item` is held, gripped at stroke L_s [m] (`holds_item`)."""
        self.item = item
        self._grasp_stroke_m = stroke_m

    def _held(self, action: str) -> Item:
        """The item in the grip, which `action` ("throw", "place") lets go of.

        Raises:
            InvalidInput: no item in the grip.
        """
        if self.item is None:
            raise InvalidInput(f"{action}: no item in the grip")
        return self.item

    def _close_fingers(self) -> None:
        """Step while the closing fingers move (close_time_s at most: they stop on the item,
        or on each other), then GRIP_BUILD_S for the grip to build up."""
        sc, cl = self.scene, self.scene.client
        t0 = sc.t
        while sc.t - t0 < self.close_time_s:
            sc.step()
            moving = max(abs(cl.getJointState(sc.ee_body, j)[1]) for j in FINGERS)
            if sc.t - t0 > 0.01 and moving < 0.01:
                break
        sc.run_for(GRIP_BUILD_S)

    def let_go(self) -> None:
        """Open the fingers and forget the item (a pick that failed, before a retry)."""
        self.band.fingers_closing = False
        self.item = None

    # -- the interface ---------------------------------------------------------
    def grasp(self, stroke_m: float, item: Item | None = None, yaw_rad: float = 0.0) -> None:
        """Take `item` (default: the one on the pick station) into the grip at stroke L_s [m],
        turned `yaw_rad` [rad] about the grip's axis (0: its size x across the pads; π/2:
        its size y, `cell.arm.grip_side`).

        Raises:
            InvalidParameter: stroke out of range.
            InvalidInput: already holding an item, or nothing to grasp.
            SimulationError: the fingers did not close on the item.
        """
        self._check_stroke(stroke_m)
        self._check_empty()
        it = item if item is not None else self.pick_candidate()
        sc, cl = self.scene, self.scene.client
        sc.set_timestep(sc.dt_s)
        self.grip_yaw_rad = float(yaw_rad)
        self.band.reset(stroke_m, self.across(it)[0] / 2 + 0.003)
        self.band.fingers_closing = False
        e_pos, e_orn = cl.getBasePositionAndOrientation(sc.ee_body)
        centre = stroke_m + it.obj.size[2] / 2 + 5e-4
        turn = [0.0, 0.0, math.sin(yaw_rad / 2), math.cos(yaw_rad / 2)]
        pos, orn = cl.multiplyTransforms(e_pos, e_orn, [0, 0, centre], turn)
        cl.resetBasePositionAndOrientation(it.body, pos, orn)
        # While the fingers close, the item is seated on the hoop, as the approach
        # presses the hoop onto the item resting on the station; then friction holds it.
        seat = cl.createConstraint(
            sc.ee_body,
            BAND_JOINT,
            it.body,
            -1,
            cl.JOINT_FIXED,
            [0, 0, 0],
            [0, 0, centre - stroke_m],
            [0, 0, 0],
            parentFrameOrientation=turn,  # the item turned in the grip as set above
        )
        cl.changeConstraint(seat, maxForce=50.0)
        self.band.fingers_closing = True
        try:
            self._close_fingers()
        finally:
            cl.removeConstraint(seat)
        sc.run_for(0.01)
        if not self._in_grip(it, stroke_m):
            raise GraspLost(
                f"the fingers did not close on item {it.obj.name or it.body} "
                f"(width {self.across(it)[0]:.3f} m)",
                "grasp",
            )
        self._hold(it, stroke_m)

    def holds_item(self) -> bool:
        """The item taken by `grasp` is still held: between the closed pads, or (if it
        slid along them while carried) still touching both pads."""
        if self.item is None:
            return False
        if self._in_grip(self.item, self._grasp_stroke_m):
            return True
        cl = self.scene.client
        touching = {
            c[4] for c in cl.getContactPoints(bodyA=self.item.body, bodyB=self.scene.ee_body)
        }
        return {FINGER_LEFT, FINGER_RIGHT} <= touching

    def across(self, it: Item) -> tuple[float, float]:
        """The item's (width across the pads, depth along them) [m] as gripped: its sizes x
        and y, swapped where the grip is turned a quarter turn about it (`grip_yaw_rad`)."""
        if abs(math.sin(self.grip_yaw_rad)) > 0.5:
            return it.obj.size[1], it.obj.size[0]
        return it.obj.size[0], it.obj.size[1]

    def _in_grip(self, it: Item, stroke_m: float) -> bool:
        """The fingers stopped on the item and its centre is between them."""
        cl, ee = self.scene.client, self.scene.ee_body
        e_p, e_o = cl.getBasePositionAndOrientation(ee)
        inv = cl.invertTransform(e_p, e_o)
        p, _ = cl.multiplyTransforms(*inv, *cl.getBasePositionAndOrientation(it.body))
        width, depth = self.across(it)
        half = width / 2
        reach = float(np.linalg.norm(it.obj.size))
        opening = [cl.getJointState(ee, j)[0] for j in (FINGER_LEFT, FINGER_RIGHT)]
        # closed (not jammed open) on something (not on each other), the item's centre
        # between the pads
        return (
            max(opening) < half + 0.002
            and min(opening) > 1e-3
            and abs(p[0]) < half
            and abs(p[1]) < depth / 2
            and stroke_m < p[2] < stroke_m + reach
        )

    def set_stroke(self, stroke_m: float) -> None:
        """Wind or unwind the spool to L_s [m] with the latch engaged.

        Raises:
            InvalidParameter: stroke out of range.
        """
        self._check_stroke(stroke_m)
        if not self.band.latched:
            self.band.reset(self.band.position(), self.band.width() / 2)
        self._wind_to(stroke_m, self.spool_speed_mps)
        if self.item is not None:  # the carriage took the item with it
            self._grasp_stroke_m = stroke_m

    def throw(self, *, keep_launch_step: bool = False) -> None:
        """Disengage the latch; returns once the carriage has hit its end stop.

        Args:
            keep_launch_step: stay at the launch's physics step afterwards (a release on
                the move, `cell.robot.moving_release`: the mount drags E a few steps'
                travel behind the arm, so a change of step while the arm moves jolts E,
                and the item may still touch the pads).

        Raises:
            InvalidInput: no item in the grip.
        """
        item = self._held("throw")
        sc = self.scene
        sc.set_timestep(sc.launch_dt_s)
        sc.refresh_contacts(item)  # the pads' contacts as they are now (see there)
        sc.track(item)
        self.band.wind_target_m = None
        self.band.latched = False
        stop = sc.geometry.end_stop_m - 1e-3
        t_end = sc.t + 0.2
        while sc.t < t_end and self.band.position() < stop:
            sc.step()
        sc.run_for(0.01)  # let the carriage settle on its stop and the item clear the pads
        if not keep_launch_step:
            sc.set_timestep(sc.dt_s)
        self.last_released, self.item = self.item, None

    def place(self) -> None:
        """Unwind at `place_speed_mps`; the fingers open once the item touches down, each
        PLACE_OPENING_M outside the item's gripped width (not to their widest: in a bin,
        the widest pads reach 8.4 cm from the axis and met the wall of a 0.30 m tote
        beside an item set down 1 cm clear of it).

        Raises:
            InvalidInput: no item in the grip.
        """
        item = self._held("place")
        sc = self.scene
        sc.set_timestep(sc.dt_s)
        tr = sc.track(item)
        self.band.wind_target_m = None
        end = sc.geometry.end_stop_m - 0.002
        step_m = self.place_speed_mps * sc.dt_s
        blocked = False
        while self.band.stroke_cmd_m < end and tr.touchdown is None and not blocked:
            self.band.stroke_cmd_m = min(end, self.band.stroke_cmd_m + step_m)
            sc.step()
            # the carriage stalls when the pads (longer than a flat item) meet the surface
            blocked = self.band.stroke_cmd_m - self.band.position() > _STALL_M
        if tr.touchdown is None:
            log.warning(
                "place: the item had not touched down when the fingers opened (%s)",
                "the pads met the surface first" if blocked else "end of the stroke",
            )
        self.band.stroke_cmd_m = self.band.position()
        widest = sc.geometry.finger_open_m
        turned = abs(math.sin(self.grip_yaw_rad)) > 0.5
        width = self.across(item)[0] if turned else pad_width_m(item.obj)
        self.band.open_to_m = min(widest, width / 2 + PLACE_OPENING_M)
        self.band.fingers_closing = False
        sc.run_for(0.1)
        self.last_released, self.item = self.item, None

    def stroke(self) -> float:
        """The carriage position, i.e. the measured stroke L_s [m]."""
        return self.band.position()

    def status(self) -> EndEffectorStatus:
        """Stroke, latch, holding, and the band's forces in `detail`."""
        r = self.band.reading()
        return EndEffectorStatus(
            stroke_m=r.position_m,
            latch_engaged=r.latched,
            holding=self.item is not None,
            detail=(
                f"stretch {r.stretch_m:.4f} m, push {r.push_n:.3f} N, grip {r.grip_n:.3f} N, "
                f"width {r.width_m:.4f} m"
            ),
        )

    def held_offset_m(self) -> np.ndarray:
        """Held item's centre of mass in the end-effector frame E [m], shape (3,).

        Raises:
            InvalidInput: no item held.
        """
        if self.item is None:
            raise InvalidInput("no item held")
        cl = self.scene.client
        e_p, e_o = cl.getBasePositionAndOrientation(self.scene.ee_body)
        inv = cl.invertTransform(e_p, e_o)
        p, _ = cl.multiplyTransforms(*inv, *cl.getBasePositionAndOrientation(self.item.body))
        return np.asarray(p)
