"""Sort jobs on the drone and moving-base platforms (`platform: drone | mobile`).

`PlatformRunner` runs a job in the PyBullet cell with the same per-item
results and closing summary as the arm's `cell.orchestrator.Orchestrator`
(`RunSummary`, the `cell run --json` keys), so `cell run` can hand a job with
another platform to it. Every item is thrown (neither platform places).

* drone: the end-effector hangs under the iris hovering at the job's height
  (`DroneScene`); a loader puts each item into the grip (the grasp); the throw
  is planned from the fixed release point under the drone with the nominal
  planner, then the aim point is corrected until the downwash model
  (`predict_drone_landing`, the job's rotor speed, `DEFAULT_DRONE_LAW`) lands
  on the bin; the scene blows the same downwash on the flying item.
* mobile: a mobile base drives the end-effector (`MovingBaseScene`); the
  release state is planned with the base velocity at the job's speed toward
  the target (`MobilePlatform.plan`), the base drives from rest along the
  ruckig trajectory to the release point, arriving with that velocity, and
  the latch opens while it moves.

Time accounting as the arm's (cell.orchestrator): `cycle_time_s` is simulated
time from the item's loading to the start of the next item's, the wait for
the item to come to rest included. The loading itself is instantaneous here
(the item appears in the grip at the release pose): a drone's trip back to a
loading station is not simulated, so its rate is an upper bound.
"""

from __future__ import annotations

import logging
import math
import uuid
from collections.abc import Callable
from typing import Any

import numpy as np

from cell.errors import CellError, HardwareError, InvalidInput
from cell.jobs import ItemSpec, Job
from cell.model.objects import ObjectParams
from cell.orchestrator import failure_of, missed_bin, sorted_throw_record
from cell.params import ModelParams, load_params
from cell.platforms.downwash import DEFAULT_DRONE_LAW, DownwashLaw, predict_drone_landing
from cell.platforms.mobile import MobilePlatform

__all__ = ["DRONE_BOUNDS_ELEVATION_RAD", "PlatformRunner"]

log = logging.getLogger(__name__)

DRONE_BOUNDS_ELEVATION_RAD = (math.radians(-45.0), math.radians(60.0))  # [rad]
_AIM_ITERS = 6  # aim-point corrections for the downwash
_AIM_TOL_M = 2e-3  # [m] predicted miss at which the correction stops


class PlatformRunner:
    """Runs a sort job whose platform is a drone or a moving base.

    Args:
        job: the validated job (`platform: drone` or `mobile`).
        gui: show PyBullet's GUI.
        store: a throw-log store with `append(record)` (None: do not record).
        session: the session id written with every throw.
        params: model parameters for planning; default: the job's `cell.params`,
            else the scene's calibrated parameter file.
        law: the downwash law (drone): default `DEFAULT_DRONE_LAW`.
        end_effector: must be None (hardware end-effectors ride the arm only).

    Raises:
        InvalidInput: the job's platform is the arm, or a hardware end-effector is given.
    """

    def __init__(
        self,
        job: Job,
        *,
        gui: bool = False,
        store: Any = None,
        session: str = "",
        params: ModelParams | None = None,
        law: DownwashLaw = DEFAULT_DRONE_LAW,
        end_effector: Any = None,
    ) -> None:
        from cell.endeffector.pybullet_backend import PyBulletEndEffector
        from cell.orchestrator import scene_params_path
        from cell.sim import BinSpec

        if job.platform not in ("drone", "mobile"):
            raise InvalidInput(
                f"{job.path}: cell.platform {job.platform!r}: this runner is for drone or mobile"
            )
        if end_effector is not None:
            raise InvalidInput(
                f"{job.path}: a hardware end-effector rides the arm only, not the {job.platform}"
            )
        self.job = job
        self.params = params or load_params(job.params or scene_params_path())
        self.store = store
        self.session = session or f"run-{uuid.uuid4().hex[:8]}"
        self.law = law
        bins = [BinSpec(b.id, b.position, b.size, b.rim_height) for b in job.bins]
        kw: dict[str, Any] = dict(
            bins=bins,
            gui=gui,
            pick_station_xy=job.pick_position[:2],
            pick_station_height=max(job.pick_position[2], 0.05),
        )
        if job.platform == "drone":
            from cell.platforms.drone import DroneScene

            self.scene: Any = DroneScene(job.hover_height_m, job.rotor_rpm, law, **kw)
            self.mobile: MobilePlatform | None = None
        else:
            from cell.platforms.mobile_scene import MovingBaseScene

            self.scene = MovingBaseScene(**kw)
            self.mobile = MobilePlatform(job.base_speed_mps)
        self.ee = PyBulletEndEffector(self.scene)

    # -- planning ----------------------------------------------------------------
    def plan_drone(self, obj: ObjectParams, goal: np.ndarray) -> tuple[Any, np.ndarray]:
        """The drone's throw plan for a goal (x, y, rim z) and its predicted landing (x, y).

        The nominal plan from the release point under the drone, then the aim
        point moved by the downwash model's miss until it lands on the goal.

        Raises:
            UnreachableTarget: no throw from under the drone reaches the goal.
        """
        from cell.optimize import ThrowBounds, plan_throw
        from cell.platforms.drone import scene_exit_distance_m

        drone = self.scene.drone
        p0 = drone.release_point
        bounds = ThrowBounds(
            position_min=tuple(p0),
            position_max=tuple(p0),
            elevation_min=DRONE_BOUNDS_ELEVATION_RAD[0],
            elevation_max=DRONE_BOUNDS_ELEVATION_RAD[1],
            release_height=float(p0[2]),
            release_radius=0.0,
        )
        ee = self.params.ee
        aim = np.asarray(goal, float).copy()
        plan = plan_throw(obj, aim, ee, bounds, current=p0)
        xy = np.array([plan.pred_x_m, plan.pred_y_m])
        for _ in range(_AIM_ITERS):
            land = predict_drone_landing(
                plan.to_batch(obj),
                ee,
                drone.rotor_rpm,
                drone.rotor_centre,
                self.law,
                exit_distance_m=scene_exit_distance_m(plan.stroke_m, self.scene.geometry),
                strict=False,
            )
            xy = land.xy[0]
            miss = goal[:2] - xy
            if not np.all(np.isfinite(miss)) or float(np.linalg.norm(miss)) < _AIM_TOL_M:
                break
            aim[:2] += miss
            plan = plan_throw(obj, aim, ee, bounds, current=p0)
        return plan, xy

    # -- one item ----------------------------------------------------------------
    def run_item(self, index: int, spec: ItemSpec) -> Any:
        """Load, plan, release, observe and record one item; returns its ItemResult
        (cycle time: to the moment the next item can be loaded)."""
        from dataclasses import replace as dc_replace

        t0 = self.scene.t
        res = self._run_item(index, spec)
        return dc_replace(res, cycle_time_s=self.scene.t - t0)

    def _run_item(self, index: int, spec: ItemSpec) -> Any:
        from cell.orchestrator import ItemResult

        obj = spec.obj
        target = self.job.bin(spec.bin)
        sc = self.scene
        t0 = sc.t
        item = sc.spawn_item(obj if obj.shape != "mesh" else obj.name)
        base: dict[str, Any] = dict(
            index=index, object_id=obj.name or obj.shape, target_bin=spec.bin
        )
        model_obj = self.params.model_object(obj)
        goal = np.array([*target.position, target.rim_height])
        try:
            if self.mobile is None:
                plan, _ = self.plan_drone(model_obj, goal)
                sc.hold_at_release(plan.elevation_rad, plan.azimuth_rad, plan.stroke_m, obj)
                self.ee.grasp(plan.stroke_m, item)
                released_at = np.asarray(sc.client.getBasePositionAndOrientation(item.body)[0])
                self.ee.throw()
            else:
                plan = self.mobile.plan(model_obj, goal, self.params.ee, free_velocity=False)
                drive = self.mobile.arrival(plan)
                sc.start_drive(drive, plan.elevation_rad, plan.azimuth_rad, plan.stroke_m, obj)
                self.ee.grasp(plan.stroke_m, item)
                sc.drive_to_release()
                released_at = np.asarray(sc.client.getBasePositionAndOrientation(item.body)[0])
                self.ee.throw()
            t_release = sc.t
            out = sc.watch_until_rest(item, timeout_s=self.job.item_time_limit_s)
            cross = out.crossing(target.rim_height)
            err = math.hypot(cross[0] - goal[0], cross[1] - goal[1])
            throw_id = f"{self.session}-{index:04d}"
            if self.store is not None:
                self.store.append(
                    sorted_throw_record(
                        self.session,
                        throw_id,
                        obj,
                        plan,
                        plan.stroke_m,
                        released_at,
                        target,
                        out,
                        cross,
                        platform=self.job.platform,
                        rotor_rpm=self.job.rotor_rpm if self.job.platform == "drone" else 0.0,
                    ),
                    track=out.track,
                )
            return ItemResult(
                **base,
                action="throw",
                bin_id=out.bin_id or "",
                in_bin=out.bin_id == target.id,
                failure=missed_bin(out.bin_id, target.id, err)[0],
                reason=missed_bin(out.bin_id, target.id, err)[1],
                landing_error_m=err,
                stroke_m=plan.stroke_m,
                cycle_time_s=t_release - t0,
                throw_id=throw_id,
            )
        except HardwareError:
            raise  # the end-effector failed: the run stops (torque off), not just this item
        except CellError as exc:
            log.info("item %d (%s) failed: %s", index, obj.name, exc)
            self.ee.item = None
            return ItemResult(
                **base,
                action="failed",
                failure=failure_of(exc),
                reason=f"{type(exc).__name__}: {exc}",
                cycle_time_s=sc.t - t0,
            )
        finally:
            if self.mobile is not None:
                sc.stop_drive()
            if sc.in_bin(item) is not None:
                sc.keep(item)  # bins keep what lands in them
            else:
                sc.remove_item(item)

    # -- the run -------------------------------------------------------------------
    def run(self, on_item: Callable[[Any], None] | None = None) -> Any:
        """Throw every item of the job; `on_item` is called after each (progress).

        Returns:
            The `cell.orchestrator.RunSummary`.
        """
        from cell.orchestrator import run_items

        return run_items(self.job, self.run_item, on_item)

    def close(self) -> None:
        """Close the scene."""
        self.scene.close()
