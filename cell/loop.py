"""The item loop, written once: present → decide → pick → carry → release → observe → record.

Every way the cell handles an item goes through `ItemLoop`: the arm's sort job
(`cell.orchestrator.Orchestrator`), the drone's and the moving base's
(`cell.platforms.runner.PlatformRunner`) and the throw campaigns that calibrate the
scene (`cell.workflows.campaign`). The loop knows three seams and nothing of
PyBullet:

* a `Platform` (arm, drone, moving base, or a fixed release pose for a campaign)
  presents the item to its end-effector, decides what to do with it (place or throw,
  and the plan), grips it, carries the end-effector to the release pose and lets go;
* a `Plant` (the PyBullet cell, the kinematic plant of tests, a hardware cell later) keeps time, reports where
  an item is and observes its flight until it rests (`Outcome`);
* the end-effector is the platform's; a hardware one rides in step with the simulated
  one (`cell.endeffector.instep.InStep`).

The loop scores what the plant observed (`cell.results.scored`), records each throw with its
flight track in the store (`sorted_throw_record`), tells an observer, and accounts
time honestly: an item's cycle runs from the start of its pick to the start of the
next item's pick; `items_per_hour` counts only items at rest in their target bin.
Beside that simulated time, the loop measures each item's planning (`plan_s`): the wall
time [s] of its present → release other than the plant's stepping (the plant's
`step_wall_s`; a plant that does not count it has all the wall time counted), from which
the run's `items_per_hour_realtime` (`cell.results.realtime_cycles`).

A platform that `overlaps` (the arm) starts the next pick while a thrown item flies:
the plant steps the flying item with everything else and the loop scores it once it
rests (`land`: the loop hands it to the platform as a hook, which the arm's mover calls
after each move; no platform imports the loop). The seams are in `cell.seams`, the results
and the throw-log row in `cell.results`; this module re-exports both.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from dataclasses import replace as dc_replace
from typing import Any

import numpy as np

from cell.decision import Decision
from cell.errors import (
    CellError,
    HardwareError,
    InvalidInput,
)
from cell.jobs import ItemSpec, Job, check_order
from cell.model.objects import ObjectParams
from cell.results import (
    FAILURES,
    ItemResult,
    RunSummary,
    failure_of,
    landing,
    rate_per_hour,
    scored,
    sorted_throw_record,
    summarise,
)
from cell.seams import Places, Plant, Platform

__all__ = [  # and, for their callers, the seams, the results and the decision it uses
    "Decision",
    "FAILURES",
    "InFlight",
    "ItemLoop",
    "ItemResult",
    "Places",
    "Plant",
    "Platform",
    "RunSummary",
    "rate_per_hour",
]

log = logging.getLogger(__name__)


def _settling_in(f: InFlight, bin_id: str) -> bool:
    """Is `f` an item placed in bin `bin_id` that has not come to rest yet?"""
    return f.decision.action == "place" and f.base["target_bin"] == bin_id


# Outcome (or the NoLanding error) → (ItemResult, landing point [m, W]): how an item
# released is scored once the plant says where it came to rest
Score = Callable[[Any], tuple[ItemResult, Any]]


@dataclass
class InFlight:
    """A thrown (or placed) item the loop is not waiting for: `score(outcome)` makes its
    ItemResult (and records the throw) once the plant says where it came to rest.

    Attributes:
        base: the result's index, object_id and target_bin.
        obj: the item's parameters.
        item: the plant's item.
        decision: what the platform did with it.
        score: Outcome → (ItemResult, landing point [m, W]).
    """

    base: dict[str, Any]
    obj: ObjectParams
    item: Any
    decision: Decision
    score: Score

    @property
    def index(self) -> int:
        return int(self.base["index"])


# -- the loop --------------------------------------------------------------------------
class ItemLoop:
    """Runs a job's items through a platform in a plant.

    Args:
        job: the validated job (None for a campaign: `throw_to_plane` only).
        platform: the platform (see `Platform`).
        plant: the plant (see `Plant`).
        store: a throw-log store with `append(record, track=...)` (None: do not record).
        session: the session id written with every throw.
        observer: told of each item's start, release, flight and result
            (`cell.record.observer.RunObserver`), or None.
        wait_for: (obj, flying objs) → wait for these in-flight items to land before
            the next item starts (the arm's flywheel learns from its earlier throw).
        order: the order the job's items are taken in (`cell.jobs.ORDERS`: "job", as
            listed; "bins", bin by bin; `Job.expanded_items`).
        on_landed: (decision, obj, crossing) → told of each throw's observed crossing of
            its target's rim plane [m, W] (the arm's flywheel learns from it), or None.
    """

    def __init__(
        self,
        job: Job | None,
        platform: Platform,
        plant: Plant,
        *,
        store: Any = None,
        session: str = "",
        observer: Any = None,
        wait_for: Callable[[ObjectParams, ObjectParams], bool] | None = None,
        order: str = "job",
        on_landed: Callable[[Decision, ObjectParams, Any], None] | None = None,
    ) -> None:
        check_order(order)
        self._job = job
        self.order = order
        self.platform = platform
        self.plant = plant
        self.store = store
        self.session = session
        self.observer = observer
        self.wait_for = wait_for
        self.on_landed = on_landed
        self._flying: list[InFlight] = []  # thrown, not yet at rest
        self._scored: dict[int, ItemResult] = {}  # scored, by index, not yet reported
        self._flights: dict[int, tuple[Any, Any]] = {}  # (Outcome, landing) for the observer
        self._plan_s: dict[int, float] = {}  # each item's planning wall time [s], by index

    @property
    def job(self) -> Job:
        """The job (a campaign's loop has none)."""
        if self._job is None:
            raise InvalidInput("this item loop runs a campaign, not a job")
        return self._job

    # -- one item ----------------------------------------------------------------------
    def throw_to_plane(
        self, index: int, obj: ObjectParams, land_z: float
    ) -> tuple[Decision, tuple[float, float, float], np.ndarray]:
        """One throw of a campaign: present, decide, pick, carry and release as a sort
        item, then observe the flight only until it crosses the plane z = land_z [m] (a
        campaign needs the landing, not the rest); the item is then taken away.

        Returns:
            (the decision, the crossing (x [m], y [m], t [s] since release), the track
            (k, 4): t, x, y, z up to the crossing).

        Raises:
            NoLanding: the item did not cross the plane in free flight.
        """
        pf, pl = self.platform, self.plant
        item = pf.present(index, obj)
        d: Decision | None = None
        try:
            d = pf.decide(index, obj, None)
            pf.pick(d, obj, item)
            pf.carry(d, obj, item)
            pf.release(d)
            track = pl.tracker(item)
            cross = pl.watch_until_crossing(item, land_z)
            return d, cross, np.asarray(track.samples, float)
        finally:
            pf.finish(d)
            pl.remove_item(item)

    def run_item(self, index: int, spec: ItemSpec) -> ItemResult:
        """One item, waiting for it to come to rest. Its `cycle_time_s` is the plant's
        time from the start of its pick until it is scored."""
        t0 = self.plant.t
        res = self._timed_item(index, spec)
        if isinstance(res, InFlight):
            res = self._wait_for(res)
        if self.observer is not None and index in self._flights:
            self.observer.on_flight(index, *self._flights.pop(index))
        plan_s = self._plan_s.pop(index, math.nan)
        return dc_replace(res, cycle_time_s=self.plant.t - t0, plan_s=plan_s)

    def _stepping_s(self) -> float:
        """The wall time [s] the plant has spent stepping so far (its `step_wall_s`; 0
        for a plant that does not count it)."""
        return float(getattr(self.plant, "step_wall_s", 0.0))

    def _timed_item(self, index: int, spec: ItemSpec) -> ItemResult | InFlight:
        """`_item`, its planning wall time kept in `_plan_s`: the wall time of present →
        release less the plant's stepping meanwhile (everything the cell computes for the
        item: the decision, IK, the moves' paths, and the loop's own work)."""
        w0, s0 = time.perf_counter(), self._stepping_s()
        try:
            return self._item(index, spec)
        finally:
            wall = time.perf_counter() - w0
            self._plan_s[index] = max(0.0, wall - (self._stepping_s() - s0))

    def _item(self, index: int, spec: ItemSpec) -> ItemResult | InFlight:
        """present → decide → pick → carry → release; a throw comes back in flight."""
        obj = spec.obj
        target = self.job.bin(spec.bin)
        pf, t0 = self.platform, self.plant.t
        item = pf.present(index, obj)
        if self.observer is not None:
            self.observer.on_item_start(index, obj, target, item)
        base: dict[str, Any] = dict(
            index=index, object_id=obj.name or obj.shape, target_bin=spec.bin
        )
        decision: Decision | None = None
        flying: InFlight | None = None
        try:
            decision = pf.decide(index, obj, target)
            pf.pick(decision, obj, item)
            if decision.action == "place":
                # the bin's items at rest say where this one goes (its spot, on the carry)
                self._land_while(lambda: any(_settling_in(f, spec.bin) for f in self._flying))
            pf.carry(decision, obj, item)
            if decision.action == "place":
                score = self._place(base, decision, target, t0)
            else:
                score = self._throw(base, obj, item, decision, target, t0)
            flying = InFlight(base, obj, item, decision, score)
            if not pf.overlaps:
                return self._wait_for(flying)
            return flying
        except HardwareError:
            raise  # the end-effector failed: the run stops (torque off), not just this item
        except CellError as exc:
            log.info("item %d (%s) failed: %s", index, obj.name, exc)
            return ItemResult(
                **base,
                action="failed",
                failure=failure_of(exc),
                reason=f"{type(exc).__name__}: {exc}",
                cycle_time_s=self.plant.t - t0,
            )
        finally:
            pf.finish(decision)
            if flying is None:  # an item released is tidied once it is scored (_settle)
                self.plant.tidy(item)

    def _place(self, base: dict[str, Any], d: Decision, target: Any, t0: float) -> Score:
        """Release slowly and leave; the item, settling in the bin, is scored where it
        comes to rest (the score returned). The arm does not wait for it: a soft item rocks for up to 0.8 s
        (the demo's teddy), while a box rests before the pads are out of the bin."""
        if not isinstance(self.platform, Places):
            raise InvalidInput(f"the {self.platform.name} platform does not place items")
        self.platform.release(d)
        t_release = self.plant.t
        self.platform.after_place(d)
        bx, by = target.position

        def score(out: Any) -> tuple[ItemResult, Any]:
            err = math.hypot(out.rest_xyz[0] - bx, out.rest_xyz[1] - by)
            return scored(base, "place", d, out, target, err, t_release - t0), out.rest_xyz

        return score

    def _throw(
        self,
        base: dict[str, Any],
        obj: ObjectParams,
        item: Any,
        d: Decision,
        target: Any,
        t0: float,
    ) -> Score:
        """Open the latch at once; the item in flight is scored and recorded once it rests
        (the score returned)."""
        released_at = self.plant.item_position(item)
        # the point the throw was for: the bin's centre, or one clear of what it holds
        bx, by = target.position[:2] if d.goal_xy is None else d.goal_xy
        aim = (bx, by, target.rim_height)
        if self.observer is not None and not d.moving:
            self.observer.on_release(
                base["index"], d.plan, d.model_obj, d.ee_params, d.stroke_m, released_at, aim
            )
        at = self.platform.release(d)
        if at is not None:
            released_at = at
        if self.observer is not None and d.moving:
            self.observer.on_release(
                base["index"], d.plan, d.model_obj, d.ee_params, d.stroke_m, released_at, aim
            )
        t_release = self.plant.t
        pf = self.platform

        def score(out: Any) -> tuple[ItemResult, Any]:
            cross, land_z = landing(out, target.rim_height)
            err = math.hypot(cross[0] - bx, cross[1] - by)
            if land_z == target.rim_height and self.on_landed is not None:
                self.on_landed(d, obj, cross)
            throw_id = f"{self.session}-{base['index']:04d}"
            if self.store is not None:
                self.store.append(
                    sorted_throw_record(
                        self.session,
                        throw_id,
                        d.gripped or obj,  # the item as the pads held it
                        d.plan,
                        d.stroke_m,
                        released_at,
                        target,
                        out,
                        cross,
                        platform=pf.name,
                        rotor_rpm=pf.rotor_rpm,
                        land_z_m=land_z,
                    ),
                    track=out.track,
                )
            res = scored(base, "throw", d, out, target, err, t_release - t0, throw_id)
            return res, (cross[0], cross[1], land_z)

        return score

    # -- items in flight ---------------------------------------------------------------
    def _settle(self, f: InFlight, out: Any) -> ItemResult:
        """Score an item whose flight ended (`out`: its Outcome, or the NoLanding error)."""
        try:
            if isinstance(out, CellError):
                raise out
            res, landing = f.score(out)
            self._flights[f.index] = (out, landing)
        except CellError as exc:
            log.info("item %d (%s) failed: %s", f.index, f.obj.name, exc)
            res = ItemResult(
                **f.base,
                action="failed",
                failure=failure_of(exc),
                reason=f"{type(exc).__name__}: {exc}",
            )
        finally:
            self.plant.tidy(f.item)
        return res

    def _poll(self, f: InFlight) -> ItemResult | None:
        """The item's result once its flight has ended, else None (non-blocking)."""
        try:
            out = self.plant.outcome_if_settled(f.item, timeout_s=self.job.item_time_limit_s)
        except CellError as exc:
            return self._settle(f, exc)
        return None if out is None else self._settle(f, out)

    def _wait_for(self, f: InFlight) -> ItemResult:
        """Step the plant until the item's flight has ended; its result."""
        pl = self.plant
        pl.set_timestep(pl.dt_s)
        while (res := self._poll(f)) is None:
            pl.step()
        return res

    def land(self) -> None:
        """Score every item in flight that has come to rest (the platform calls this
        between its moves)."""
        for f in list(self._flying):
            res = self._poll(f)
            if res is not None:
                self._flying.remove(f)
                self._scored[f.index] = res

    def _land_while(self, flying: Callable[[], bool]) -> None:
        pl = self.plant
        pl.set_timestep(pl.dt_s)
        while flying():
            pl.step()
            self.land()

    def _land_kin(self, obj: ObjectParams) -> None:
        """Let in-flight items of the same kind as `obj` land first (`wait_for`)."""
        kin = self.wait_for
        if kin is not None:
            self._land_while(lambda: any(kin(obj, f.obj) for f in self._flying))

    def _land_all(self) -> None:
        """Step the plant until every thrown item has come to rest, scoring each."""
        self._land_while(lambda: bool(self._flying))

    # -- the run ---------------------------------------------------------------------
    def run(self, on_item: Callable[[ItemResult], None] | None = None) -> RunSummary:
        """Every item of the job, in the loop's `order`; `on_item` is called after each,
        in that order.

        With a platform that overlaps, the next pick starts as soon as an item is
        thrown, and the item is scored when it comes to rest. An item's `cycle_time_s`
        runs from the start of its pick to the start of the next one; the last
        item's, until everything thrown has come to rest.
        """
        t_wall = time.perf_counter()
        pl = self.plant
        starts: list[float] = []
        results: list[ItemResult] = []
        self._flying, self._scored, self._flights, self._plan_s = [], {}, {}, {}

        def emit(t_end: float | None = None) -> None:
            # t_end may be 0.0: a lone item that failed before the plant ran is still reported
            while (i := len(results)) in self._scored and (
                i + 1 < len(starts) or t_end is not None
            ):
                t_next = starts[i + 1] if i + 1 < len(starts) else float(t_end or pl.t)
                res = dc_replace(
                    self._scored.pop(i),
                    cycle_time_s=t_next - starts[i],
                    plan_s=self._plan_s.pop(i, math.nan),
                )
                results.append(res)
                if self.observer is not None:
                    if i in self._flights:
                        self.observer.on_flight(i, *self._flights.pop(i))
                    self.observer.on_item_done(res)
                if on_item is not None:
                    on_item(res)

        try:
            for i, spec in enumerate(self.job.expanded_items(self.order)):
                if self.wait_for is not None:
                    self._land_kin(spec.obj)
                starts.append(pl.t)
                emit()
                res = self._timed_item(i, spec)
                if isinstance(res, InFlight):
                    self._flying.append(res)
                else:
                    self._scored[i] = res
                self.land()
            self._land_all()
        except HardwareError:
            # the run stops; what was thrown before the fault still lands and is recorded
            self._land_all()
            emit(t_end=pl.t)
            raise
        except BaseException:
            emit(t_end=pl.t)  # report what was scored; an item still in flight is lost
            raise
        emit(t_end=pl.t)
        return summarise(results, time.perf_counter() - t_wall, self.plan_workers())

    def plan_workers(self) -> int:
        """The processes a decision is planned on (`cell.arm.fork`; 1: a platform without)."""
        return int(getattr(self.platform, "plan_workers", 1))
