"""Sort jobs on the drone and moving-base platforms (`platform: drone | mobile`).

`PlatformRunner` is the platform of the item loop (`cell.loop.ItemLoop`) for a
drone or a moving base, as `cell.orchestrator.Orchestrator` is the arm's: the same
per-item results, throw records with their flight tracks, and closing summary
(`RunSummary`, the `cell run --json` keys). Every item is thrown (neither platform
places).

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

from cell.errors import InvalidInput, JobError
from cell.jobs import Job
from cell.loop import Decision, ItemLoop, ItemResult, RunSummary
from cell.model.objects import ObjectParams
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
        from cell.endeffector.factory import make_in_step
        from cell.params import scene_params_path
        from cell.sim import BinSpec

        if job.platform not in ("drone", "mobile"):
            raise InvalidInput(
                f"{job.path}: cell.platform {job.platform!r}: this runner is for drone or mobile"
            )
        if end_effector is not None:
            raise InvalidInput(
                f"{job.path}: a hardware end-effector rides the arm only, not the {job.platform}"
            )
        if job.policy == "place":
            raise JobError(
                f"{job.path}: policy 'place': the {job.platform} throws every item, it places "
                "none; give policy throw (or auto), or cell.platform arm to place"
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
        self.effector = make_in_step(self.scene)  # the plant's end-effector, by the factory
        self.ee = self.effector.sim
        self.name = job.platform
        self.rotor_rpm = job.rotor_rpm if job.platform == "drone" else 0.0
        self.loop = ItemLoop(job, self, self.scene, store=store, session=self.session)
        try:
            self._check_reach()
        except JobError:
            self.scene.close()  # a refused job leaves nothing open
            raise

    def _check_reach(self) -> None:
        """Refuse the job before any item moves if the pads cannot hold an item (across
        its x, as the loader puts it in the grip; `grip_refusal`) or its bin is beyond
        every throw the platform can make with it (the plan `decide` makes in the run, here
        once an item line): every such line in one report, as the arm's jobs are
        (`Orchestrator._check_job`)."""
        from cell.arm.grip_limits import grip_refusal
        from cell.errors import UnreachableTarget
        from cell.yamltree import Errors

        errors = Errors(self.job.path)
        for spec in self.job.items:
            name = spec.obj.name or spec.obj.shape
            why = grip_refusal(self.params, spec.obj)  # gripped across x, as the loader does
            if why:
                errors.add(
                    JobError(
                        f"{self.job.path}, line {spec.line}: item {name} "
                        f"({spec.obj.mass * 1000:.0f} g) cannot be held: {why}; sort it by hand"
                    )
                )
                continue
            try:
                self.decide(0, spec.obj, self.job.bin(spec.bin))
            except UnreachableTarget as exc:
                errors.add(
                    JobError(
                        f"{self.job.path}, line {spec.line}: item {name} to bin {spec.bin!r}: "
                        f"{str(exc).rstrip('.')}; move bin {spec.bin!r} within the reach "
                        "above, or send the item to another bin"
                    )
                )
        errors.raise_all()

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

    # -- the platform's steps (cell.loop.Platform) -------------------------------
    overlaps = False  # the next item is loaded once this one rests
    name: str  # the job's platform ("drone" or "mobile"), set at construction
    rotor_rpm: float  # the drone's rotor speed (0 for the moving base)

    def present(self, index: int, obj: ObjectParams) -> Any:
        """The item at the pick station (the loader takes it into the grip)."""
        return self.scene.spawn_item(obj if obj.shape != "mesh" else obj.name)

    def decide(self, index: int, obj: ObjectParams, target: Any) -> Decision:
        """Throw (neither platform places): the drone's plan corrected for the downwash,
        or the moving base's with its velocity at the job's speed toward the target."""
        model_obj = self.params.model_object(obj)
        goal = np.array([*target.position, target.rim_height])
        if self.mobile is None:
            plan, _ = self.plan_drone(model_obj, goal)
        else:
            plan = self.mobile.plan(model_obj, goal, self.params.ee, free_velocity=False)
        return Decision("throw", plan.stroke_m, plan, model_obj=model_obj, ee_params=self.params.ee)

    def pick(self, d: Decision, obj: ObjectParams, item: Any) -> None:
        """The loader puts the item into the grip with the end-effector at its release
        pose (drone), or at the start of the base's drive (mobile)."""
        plan = d.plan
        if self.mobile is None:
            self.scene.hold_at_release(plan.elevation_rad, plan.azimuth_rad, plan.stroke_m, obj)
        else:
            drive = self.mobile.arrival(plan)
            self.scene.start_drive(drive, plan.elevation_rad, plan.azimuth_rad, plan.stroke_m, obj)
        self.effector.grasp(plan.stroke_m, item)

    def carry(self, d: Decision, obj: ObjectParams, item: Any) -> None:
        """The drone hovers at the release point; the base drives to it, arriving with
        the planned velocity (the latch opens while it moves)."""
        if self.mobile is not None:
            self.scene.drive_to_release()

    def release(self, d: Decision) -> None:
        """Open the latch at once."""
        self.effector.throw()

    def finish(self, d: Decision | None) -> None:
        """The base stops; nothing is held any more."""
        if self.mobile is not None:
            self.scene.stop_drive()
        self.ee.item = None

    # -- the run -------------------------------------------------------------------

    def run(self, on_item: Callable[[ItemResult], None] | None = None) -> RunSummary:
        """Throw every item of the job; `on_item` is called after each (progress)."""
        return self.loop.run(on_item)

    def close(self) -> None:
        """Close the scene."""
        self.scene.close()
