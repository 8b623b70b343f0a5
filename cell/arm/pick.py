"""The pick: the empty arm's approach, the kinematic pick and the physical pick by contact."""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np

from cell.arm.base import ArmBase
from cell.arm.joints import GRIP_DOWN, joint_gap
from cell.arm.kinematics import roll_of
from cell.errors import (
    GraspLost,
    IKFailed,
    TrajectoryError,
)
from cell.model.objects import ObjectParams

log = logging.getLogger(__name__)


class Pick(ArmBase):
    """The pick (a part of the arm; `cell.orchestrator.Orchestrator`)."""

    def _pick_kinematic(
        self, obj: ObjectParams, item: Any, stroke: float, side_yaw: float = 0.0
    ) -> np.ndarray:
        """The kinematic pick: the grip over the item, which is moved into it
        (PyBulletEndEffector.grasp) turned `side_yaw` [rad] about the grip's axis (the
        side it is gripped across, `cell.arm.grip_side`; `obj`: the item as gripped);
        returns the lift configuration."""
        q_pick, q_lift = self.over_item(item, stroke, obj)
        q0, t0 = self.q, self.scene.t
        if not self._approach(item, stroke, obj, q_pick):
            self.move([q_lift, q_pick])
        self._time_floor(q0, t0)
        self.ee.grasp(stroke, item, yaw_rad=side_yaw)
        self._carried = (obj, stroke)  # the item and its throw's stroke: what routes are for
        self._grip_stroke = stroke  # where the carriage holds it now (`_carry_stroke`)
        return q_lift

    def _approach(self, item: Any, stroke: float, obj: ObjectParams, q_pick: np.ndarray) -> bool:
        """The empty arm to the pick without stopping over it (`_approach_plan`); False
        when there is none, and nothing has moved."""
        traj, why = self._approach_plan(item, stroke, obj, q_pick)
        if traj is None:
            log.info("%s: over the lift instead", why)
            return False
        # no settle: the grasp that follows holds the arm still while the pads close
        self.follow(traj, q_pick, 0.0)
        return True

    def _approach_plan(
        self,
        item: Any,
        stroke: float,
        obj: ObjectParams,
        q_pick: np.ndarray,
        q_from: np.ndarray | None = None,
    ) -> tuple[Any, str]:
        """(the trajectory, "") of the empty arm from where it is (or `q_from`) to the pick
        without stopping over it: anywhere to the point the pads' length and PICK_OVER_CLEARANCE_M
        over the pick, then down the straight joint-space segment onto the item
        (`plan_approach`). Taken only if, until that point, the grip stays at least that
        high wherever it is over the station or within the grip's reach of it
        (`_keeps_over_station`); else (or when no IK or move is found) (None, why).
        Remembered until the next decision (`decide` clears it, as `_approach_s`): the
        decision times the approach the pick then takes, from the same configurations."""
        q0 = self.q if q_from is None else q_from
        p_item = self.scene.item_position(item)
        key = (
            *(np.asarray(q, float).tobytes() for q in (q0, q_pick)),
            p_item.tobytes(),
            stroke,
            obj,
            self._frame,
        )
        if key not in self._approach_plans:
            self._approach_plans[key] = self._plan_approach(p_item, stroke, obj, q_pick, q0)
        return self._approach_plans[key]

    def _plan_approach(
        self, p_item: np.ndarray, stroke: float, obj: ObjectParams, q_pick: np.ndarray, q0: Any
    ) -> tuple[Any, str]:
        """`_approach_plan` for the item at p_item [m, W], from q0 [rad], planned."""
        from cell.robot.motion import plan_approach

        over = self.scene.geometry.pad_length_m + self.tuning.pick_over_clearance_m
        try:
            tcp = self._tcp_for_item_centre(
                p_item + np.array([0, 0, over]), *GRIP_DOWN, stroke, obj
            )
            q_over = self.ik_frame(tcp, q_pick)
            if joint_gap(q_pick, q_over) > self.tuning.lift_max_dq_rad:  # another IK branch
                return None, "the point over the pick is on another IK branch"
            traj = plan_approach(
                q0,
                q_over,
                q_pick,
                self.robot,
                velocity_scale=self.speed_scale,
                acceleration_scale=self.speed_scale,
            )
        except (IKFailed, TrajectoryError) as exc:
            return None, f"no straight approach to the pick ({exc})"
        if not self._keeps_over_station(traj.parts[0], float(self.robot.tcp_pose(q_over)[0][2])):
            return None, "the approach to the pick dips over the station"
        return traj, ""

    def _approach_s(
        self,
        q_from: np.ndarray,
        over: tuple[np.ndarray, np.ndarray],
        stroke: float,
        obj: ObjectParams,
    ) -> float:
        """How long [s] the empty arm takes from rest at q_from [rad] to the pick of the
        presented item, `over` its (pick, lift) configurations: without stopping over it
        (`_approach_plan`), else through the lift (`_pick_kinematic`; jerk-limited
        rest-to-rest moves at the full limits, `move_time`). TrajectoryError or IKFailed
        where neither is found."""
        from cell.robot.motion import move_time

        q_pick, q_lift = over
        key = (
            *(np.asarray(q, float).tobytes() for q in (q_from, q_pick, q_lift)),
            self.scene.item_position(self._presented).tobytes(),
            stroke,
            obj,
            self._frame,
        )
        if key in self._approach_memo:  # until the next decision, as `_solve_ik`
            return self._approach_memo[key]
        approach, _ = self._approach_plan(self._presented, stroke, obj, q_pick, q_from)
        if approach is not None:
            t = float(approach.duration)
        else:
            t = move_time(q_from, q_lift, self.robot) + move_time(q_lift, q_pick, self.robot)
        self._approach_memo[key] = t
        return t

    def _spawn_at_station(self, index: int, obj: ObjectParams) -> Any:
        """The item, set down on the pick station at a random spot (± PICK_SCATTER_M) and
        yaw drawn from the job's seed and the item's index (reproducible); it settles while
        the arm comes over it (`_pick_once` waits for it to rest before the descent)."""
        rng = np.random.default_rng([self.job.seed, index])
        dx, dy = rng.uniform(-self.tuning.pick_scatter_m, self.tuning.pick_scatter_m, 2)
        yaw = float(rng.uniform(-math.pi, math.pi))
        item = self.scene.spawn_item(
            obj if obj.shape != "mesh" else obj.name, offset_xy=(dx, dy), yaw=yaw
        )
        self._run_for(0.05)  # let it settle on the station
        return item

    def _item_pose(self, item: Any) -> tuple[np.ndarray, np.ndarray]:
        """The item as the plant reports it: centre [m, W] and rotation matrix (3, 3)."""
        return self.scene.item_pose(item)

    @staticmethod
    def _grip_axes(
        obj: ObjectParams,
        rot: np.ndarray,
        heading: float,
        signed: bool,
        lean: float = 1.0,
        side_yaw: float = 0.0,
    ) -> tuple[float, float, list[float]]:
        """The grip for an item at rotation `rot` (its pose as the plant reports it):
        (elevation, azimuth [rad]) of the approach axis u, and the rolls [rad] about it
        that close the pads across the item's x axis turned `side_yaw` [rad] about its z
        (the side it is gripped across, `cell.arm.grip_side`: 0, its x; π/2, its y).

        The grip comes down the item's own axis (−z), so that an item resting tilted (a
        mesh on an uneven side) ends seated square on the carriage as the throw model
        assumes; straight down onto a sphere. `lean` < 1 turns the approach that fraction
        of the way from straight down to the item's axis (`_grip_plan`: where the full
        lean would put a pad on the station). Of the rolls the item's symmetry allows
        (a quarter turn for a square section, a half turn else; any for an upright
        cylinder), those that point the pads' axis (E's x) nearest the horizontal direction
        `heading` [rad] (`signed`: along it, else either way): the carry's heading is a
        throw's azimuth, E's x pointing the way that turns the grip up to the release's
        roll about E's y alone (or a place's bin). Then the pads' normal forces, not
        their friction alone, hold the item against the turn's and the carry's
        accelerations, which would swing it about the pads' axis.
        """
        from cell.frames import axis_frame

        vertical = np.array([0.0, 0.0, 1.0])
        up = vertical if obj.shape == "sphere" else rot[:, 2] / np.linalg.norm(rot[:, 2])
        up = (1.0 - lean) * vertical + lean * up
        u = -up / np.linalg.norm(up)
        if math.hypot(u[0], u[1]) < 1e-9:  # straight down (as ReleasePose reads it)
            elevation, azimuth = -math.pi / 2, 0.0
        else:
            elevation = math.asin(max(-1.0, min(1.0, float(u[2]))))
            azimuth = math.atan2(float(u[1]), float(u[0]))
        a0 = axis_frame(elevation, azimuth, 0.0)
        h = np.array([math.cos(heading), math.sin(heading), 0.0])
        if obj.shape in ("sphere", "cylinder"):  # any roll grips it: along the heading
            d = h - (h @ a0[:, 2]) * a0[:, 2]
            dirs = [d, -d]
        else:
            square = obj.shape == "cube" or (
                obj.shape == "cuboid" and abs(obj.size[0] - obj.size[1]) < 1e-9
            )
            n = 4 if square else 2
            angles = [side_yaw + k * 2 * math.pi / n for k in range(n)]
            dirs = [rot @ np.array([math.cos(a), math.sin(a), 0.0]) for a in angles]
            dirs = [d - (d @ u) * u for d in dirs]  # across the axis (a leaning grip's)

        def off(d: np.ndarray) -> float:  # angle between d's horizontal part and the heading
            ang = math.atan2(float(d[1]), float(d[0])) - heading
            return abs(math.remainder(ang, 2 * math.pi if signed else math.pi))

        best = min(off(d) for d in dirs)
        rolls = [
            math.atan2(float(a0[:, 1] @ d), float(a0[:, 0] @ d))
            for d in dirs
            if off(d) < best + 1e-6
        ]
        return elevation, azimuth, rolls

    def _grip_plan(
        self,
        obj: ObjectParams,
        item: Any,
        heading: float,
        signed: bool,
        opening: float,
        side_yaw: float = 0.0,
    ) -> tuple[np.ndarray, float, float, list[float], float]:
        """The item's centre [m, W] as the plant reports it, the grip's approach axis
        (elevation, azimuth) and rolls [rad] (`_grip_axes`), and the least standoff h_min
        [m] of the carriage's face from the item's top along the axis that keeps every pad
        corner (the pads open `opening` [m] from the axis) PAD_TIP_CLEARANCE_M above the
        station: down the item's axis if that lets the grip reach its top (h_min ≤ 0),
        else leaning less towards it (GRIP_LEANS), at most MAX_TILT_RAD from vertical."""
        from cell.frames import axis_frame

        geo = self.scene.geometry
        p, rot = self._item_pose(item)
        tilt = math.acos(max(-1.0, min(1.0, float(rot[2, 2]))))
        for lean in self.tuning.grip_leans:
            if lean * tilt > self.tuning.max_tilt_rad and lean > 0:
                continue
            elevation, azimuth, rolls = self._grip_axes(obj, rot, heading, signed, lean, side_yaw)
            u = axis_frame(elevation, azimuth)[:, 2]
            drop = max(  # lowest pad corner below the pads' tip line on the axis [m]
                (opening + geo.pad_thickness_m) * abs(f[2, 0]) + geo.pad_half_width_m * abs(f[2, 1])
                for f in (axis_frame(elevation, azimuth, r) for r in rolls)
            )
            floor = self.scene.pick_station_height + self.tuning.pad_tip_clearance_m + drop
            h_min = (floor - p[2]) / -u[2] - obj.size[2] / 2 + geo.pad_length_m
            if h_min <= 0 or lean == 0:
                break
        return p, elevation, azimuth, rolls, float(h_min)

    def _carry_heading(
        self, plan: Any, target: Any, q_release: np.ndarray | None
    ) -> tuple[float, bool]:
        """Where the pads' axis (E's x) should point while the item is carried, and whether
        its sense matters (see `_grip_axes`): for a throw, along the azimuth, the way the
        release's roll (0 or π, of q_release [rad]) turns up to about E's y alone; for a place,
        either way along the line from the station to the bin."""
        if plan is None:
            x0, y0 = self.scene.pick_station_xy
            return math.atan2(target.position[1] - y0, target.position[0] - x0), False
        # at the release, roll 0 puts E's x at (sin e cos a, sin e sin a, −cos e): turned
        # down about E's y it points back along the azimuth; roll π, forward
        assert q_release is not None
        roll = roll_of(self.robot, q_release, plan.elevation_rad, plan.azimuth_rad)
        return plan.azimuth_rad + math.pi - roll, True

    def _pick(
        self,
        obj: ObjectParams,
        item: Any,
        stroke: float,
        heading: float,
        signed: bool,
        side_yaw: float = 0.0,
    ) -> np.ndarray:
        """Pick the item off the station into the grip at `stroke` [m], by contact: returns
        the lift configuration the arm is at, the item held by friction between the pads.
        `heading` [rad], `signed`: where the pads' axis should point while it is carried
        (`_carry_heading`), as far as the item's symmetry allows. `side_yaw` [rad]: the
        side it is gripped across (`cell.arm.grip_side`; `obj` is the item as gripped).

        A grasp that fails (the pads close on nothing, the item slips out on the lift) is
        tried again while the item is still on the station, PICK_ATTEMPTS in all.

        Raises:
            GraspLost: (stage "grasp") every attempt failed, or the item left the station.
            IKFailed: no configuration reaches over the item.
        """
        for attempt in range(1, self.tuning.pick_attempts + 1):
            try:
                return self._pick_once(obj, item, stroke, (heading, signed), side_yaw)
            except GraspLost as exc:
                self.ee.let_go()
                self._run_for(0.1)  # the fingers open
                self._wait_at_rest(item)
                if attempt == self.tuning.pick_attempts or not self.scene.on_station(item):
                    raise GraspLost(
                        f"{exc} (pick attempt {attempt} of {self.tuning.pick_attempts})", "grasp"
                    ) from exc
                log.info("pick of %s failed (%s): trying again", obj.name or obj.shape, exc)
        raise AssertionError("unreachable")  # pragma: no cover

    def _pick_once(
        self,
        obj: ObjectParams,
        item: Any,
        stroke: float,
        toward: tuple[float, bool],
        side_yaw: float = 0.0,
    ) -> np.ndarray:
        """One pick: over the item (as the plant reports it) with the pads open and the
        spool wound to `stroke`, a guarded descent until the grip touches it, the pads
        closed by contact, and the lift; GraspLost when it did not come up in the grip."""
        from cell.catalogue import pad_width_m
        from cell.frames import axis_frame

        opening = min(
            pad_width_m(obj) / 2 + self.tuning.finger_clearance_m, self.scene.geometry.finger_open_m
        )
        self.ee.open_for_pick(stroke, opening)
        p, elevation, azimuth, rolls, h_min = self._grip_plan(obj, item, *toward, opening, side_yaw)

        def at(h: float) -> np.ndarray:
            """Where the item's centre would sit in the grip with the carriage's face h out
            from its top along the approach axis (h_min at least: the pads clear the station)."""
            return p - axis_frame(elevation, azimuth)[:, 2] * max(h, h_min)

        q_high, roll = self._ik_grip_any(
            at(self.tuning.lift_m), stroke, obj, elevation, azimuth, rolls
        )
        q_near = self._ik_grip(at(self.tuning.approach_m), stroke, obj, (elevation, azimuth, roll))
        self.move([q_high])
        # the carriage may still be on its way in from the last throw's end stop: the
        # grip goes down over the item only once it is at the stroke
        self.ee.wait_wound()
        self.move([q_near])
        # the item as the plant reports it now that it rests (a mesh may still have been
        # rocking when it was first seen): over it again if it moved, then a guarded
        # descent onto it
        self._wait_at_rest(item)
        if not self.scene.on_station(item):
            where = self.scene.item_position(item)
            raise GraspLost(
                f"{obj.name or obj.shape} is no longer on the pick station (its centre at "
                f"{', '.join(f'{v:.3f}' for v in where)} m)",
                "grasp",
            )
        aimed = (p, elevation, azimuth)
        p, elevation, azimuth, rolls, h_min = self._grip_plan(obj, item, *toward, opening, side_yaw)
        roll = min(rolls, key=lambda r: abs(math.remainder(r - roll, 2 * math.pi)))
        axes = (elevation, azimuth, roll)
        u0, u1 = (axis_frame(e, a)[:, 2] for e, a in (aimed[1:], axes[:2]))
        turned = math.acos(max(-1.0, min(1.0, float(u0 @ u1))))
        if np.linalg.norm(p - aimed[0]) > self.tuning.replan_m or turned > self.tuning.replan_rad:
            q_over = self._ik_grip(at(self.tuning.approach_m), stroke, obj, axes)
            if not np.allclose(q_over, self.q, atol=1e-6):
                self.move([q_over])
        q_from, q_to = self.q.copy(), self._ik_grip(at(-self.tuning.press_m), stroke, obj, axes)
        depth = float(np.linalg.norm(self.robot.tcp_pose(q_to)[0] - self.robot.tcp_pose(q_from)[0]))

        def along(d: float) -> np.ndarray:
            """The configuration d [m] down the descent's (near-straight) joint segment."""
            return q_from + (q_to - q_from) * (d / depth)

        touched = self._straight(
            q_to, depth / self.tuning.descent_mps, lambda: self.scene.ee_touches(item)
        )
        d_touch = touched * depth
        if touched < 1.0:
            # back to a hair over where it touched: the mount pulls E along behind the
            # flange (pressing on would squeeze the item onto the station with up to the
            # mount's force), and the item must be free to slide as the pads centre it
            d_touch -= float(np.linalg.norm(self.scene.ee_lag()))
            self._straight(along(max(0.0, d_touch - self.tuning.touch_gap_m)), 0.02)
        self.ee.close_on(item, yaw_rad=side_yaw)
        self._carried = (obj, stroke)
        self._grip_stroke = stroke
        # a short lift that shows whether the pads hold it (the move on starts at lift_m)
        held = at(0.0)  # where the grip holds it: lifted straight up from there
        self._lift_check(obj, item, stroke, axes, held, z0=p[2])
        return self._ik_grip(held + [0.0, 0.0, self.tuning.lift_m], stroke, obj, axes)

    def _lift_check(
        self,
        obj: ObjectParams,
        item: Any,
        stroke: float,
        axes: tuple[float, float, float],
        held: np.ndarray,
        z0: float,
    ) -> None:
        """A short lift (`lift_check_m` in `lift_check_s`) from `held` (the item's centre
        in the grip [m, W], its centre z0 [m] before) that shows whether the pads hold it;
        GraspLost when it did not come up with the grip."""
        lift_m = self.tuning.lift_check_m
        q_check = self._ik_grip(held + [0.0, 0.0, lift_m], stroke, obj, axes)
        self._straight(q_check, self.tuning.lift_check_s, smooth=True)
        self._run_for(0.05)
        z1 = float(self.scene.item_position(item)[2])
        if not self.ee.holds_item() or z1 - z0 < lift_m / 2:
            self.ee.item = None
            raise GraspLost(
                f"{obj.name or obj.shape} slipped out of the grip on the lift (its centre rose "
                f"{(z1 - z0) * 1000:.0f} mm of {lift_m * 1000:.0f}; pads touching it: "
                f"{sorted(self.ee.pads_touching(item)) or 'none'})",
                "grasp",
            )
