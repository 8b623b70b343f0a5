"""The item loop, written once: present → decide → pick → carry → release → observe → record.

Every way the cell handles an item goes through `ItemLoop`: the arm's sort job
(`cell.orchestrator.Orchestrator`), the drone's and the moving base's
(`cell.platforms.runner.PlatformRunner`) and the throw campaigns that calibrate the
scene (`cell.workflows.campaign`). The loop knows three seams and nothing of
PyBullet:

* a `Platform` (arm, drone, moving base, or a fixed release pose for a campaign)
  presents the item to its end-effector, decides what to do with it (place or throw,
  and the plan), grips it, carries the end-effector to the release pose and lets go;
* a `Plant` (the PyBullet cell now, a hardware cell later) keeps time, reports where
  an item is and observes its flight until it rests (`Outcome`);
* the end-effector is the platform's; a hardware one rides in step with the simulated
  one (`cell.endeffector.instep.InStep`).

The loop scores what the plant observed (`missed_bin`), records each throw with its
flight track in the store (`sorted_throw_record`), tells an observer, and accounts
time honestly: an item's cycle runs from the start of its pick to the start of the
next item's pick; `items_per_hour` counts only items at rest in their target bin.

A platform that `overlaps` (the arm) starts the next pick while a thrown item flies:
the plant steps the flying item with everything else and the loop scores it once it
rests (`land`, which the platform calls between its moves).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from dataclasses import replace as dc_replace
from typing import Any, Protocol, runtime_checkable

import numpy as np

from cell.decision import Decision
from cell.errors import (
    CannotGrip,
    CellError,
    GraspLost,
    HardwareError,
    IKFailed,
    InvalidInput,
    TrajectoryError,
    UnreachableTarget,
)
from cell.jobs import ItemSpec, Job, check_order
from cell.log.records import throw_record
from cell.model.objects import ObjectParams

__all__ = [
    "FAILURES",
    "Decision",
    "InFlight",
    "ItemLoop",
    "ItemResult",
    "Plant",
    "Places",
    "Platform",
    "RunSummary",
    "failure_of",
    "landing",
    "missed_bin",
    "rate_per_hour",
    "sorted_throw_record",
    "summarise",
]

log = logging.getLogger(__name__)

# Why an item did not end in its bin: one of these, always (ItemResult.failure).
FAILURES = (
    "unreachable",  # no release within the cell's bounds lands it in the bin
    "cannot_grip",  # too wide, too thin or too heavy for the pads, refused before the pick
    "grasp_failed",  # the fingers did not close on it
    "dropped_while_carried",  # it left the grip between the pick and the release
    "ik",  # no arm configuration or move reaches the planned pose
    "missed_bin",  # released, but it came to rest outside its bin
)


# -- the seams -------------------------------------------------------------------------
class Plant(Protocol):
    """What the loop needs of the cell it runs in (`cell.sim.CellScene` is one)."""

    @property
    def t(self) -> float:
        """The plant's clock [s]."""
        ...

    dt_s: float

    def set_timestep(self, dt_s: float) -> None: ...
    def step(self, n: int = 1) -> None: ...
    def item_position(self, item: Any) -> np.ndarray:
        """The item's centre of mass now [m, W]."""
        ...

    def watch_until_rest(self, item: Any, *, timeout_s: float = 6.0) -> Any:
        """Observe the released item until it rests: its `Outcome`."""
        ...

    def outcome_if_settled(self, item: Any, *, timeout_s: float = 6.0) -> Any | None:
        """The released item's `Outcome` once it rests, else None (non-blocking)."""
        ...

    def tidy(self, item: Any) -> None:
        """Keep an item at rest in a bin there; take any other away."""
        ...

    def remove_item(self, item: Any) -> None:
        """Take an item away."""
        ...

    def tracker(self, item: Any) -> Any:
        """The released item's track so far (`samples`: t, x, y, z)."""
        ...

    def watch_until_crossing(
        self, item: Any, land_z: float, *, timeout_s: float = 4.0
    ) -> tuple[float, float, float]:
        """Observe the released item until it crosses z = land_z going down: (x, y, t)."""
        ...


class Platform(Protocol):
    """A platform carries the end-effector: the arm, a drone, a moving base, or the fixed
    release poses of a campaign. Each step may raise a CellError: the item fails with
    its reason (`failure_of`) and the run goes on; a HardwareError stops the run."""

    name: str  # "arm", "drone" or "mobile": the throw log's `platform`
    overlaps: bool  # may start the next item while a thrown one flies
    rotor_rpm: float  # the drone's rotor speed in the throw log (0 for the others)

    def present(self, index: int, obj: ObjectParams) -> Any:
        """Have the plant present the item for the grasp; the plant's item."""
        ...

    def decide(self, index: int, obj: ObjectParams, target: Any) -> Decision:
        """Place or throw, and the plan."""
        ...

    def pick(self, decision: Decision, obj: ObjectParams, item: Any) -> None:
        """Grip the item (the end-effector holds it at `decision.stroke_m`)."""
        ...

    def carry(self, decision: Decision, obj: ObjectParams, item: Any) -> None:
        """Take the end-effector to the release pose, the item still held (GraspLost)."""
        ...

    def release(self, decision: Decision) -> np.ndarray | None:
        """Open the latch: slowly for a place, at once for a throw. A release on the move
        returns the item's centre at the latch [m, W]; None: where it was held."""
        ...

    def finish(self, decision: Decision | None) -> None:
        """The item is done with (scored, or failed): let go of anything of it."""
        ...


@runtime_checkable
class Places(Protocol):
    """A platform that places items as well as throwing them (the arm): after the latch
    has let a placed item down, it leaves the bin."""

    def after_place(self, decision: Decision) -> None:
        """After a placed item is let go: leave the bin."""
        ...


# -- results ---------------------------------------------------------------------------
def failure_of(exc: BaseException) -> str:
    """The FAILURES entry for an error that stopped an item before its release."""
    if isinstance(exc, UnreachableTarget):
        return "unreachable"
    if isinstance(exc, CannotGrip):
        return "cannot_grip"
    if isinstance(exc, GraspLost):
        return "grasp_failed" if exc.stage == "grasp" else "dropped_while_carried"
    if isinstance(exc, (IKFailed, TrajectoryError)):
        return "ik"
    return "missed_bin"


@dataclass(frozen=True)
class ItemResult:
    """What became of one item.

    Attributes:
        index: item number in the job (0-based).
        object_id: catalogue id (or ad-hoc name).
        target_bin: where the job wanted it.
        action: "place", "throw" or "failed".
        failure: why it is not in its bin, one of FAILURES ("" when it is).
        reason: the full message of that failure ("" when there is none).
        bin_id: the bin it came to rest in ("" for none).
        in_bin: True when that is the target bin.
        landing_error_m: throws: distance of the crossing of the rim plane from the
            point the throw was for (the bin's centre, or the point of it clear of
            what the bin holds: cell.arm.spots.throw_spot); places: distance
            of the rest point from the bin centre [m].
        stroke_m: commanded stroke at release [m] (NaN for failures before planning).
        delta_stroke_m: learned correction ΔL_s included in stroke_m [m].
        cycle_time_s: simulated time for this item [s] (see the module docstring).
        throw_id: the log id of the throw ("" for places and failures).
        moving: the latch opened while the platform moved (a release on the move).
    """

    index: int
    object_id: str
    target_bin: str
    action: str
    failure: str = ""
    reason: str = ""
    bin_id: str = ""
    in_bin: bool = False
    landing_error_m: float = math.nan
    stroke_m: float = math.nan
    delta_stroke_m: float = 0.0
    cycle_time_s: float = 0.0
    throw_id: str = ""
    moving: bool = False


@dataclass(frozen=True)
class RunSummary:
    """The closing table of a run (JSON keys as `cell run --json`)."""

    items: int
    placed: int
    thrown: int
    failed: int
    in_bin: int
    in_bin_rate: float
    mean_landing_error_m: float
    p95_landing_error_m: float
    mean_cycle_time_s: float
    items_per_hour: float
    sim_time_s: float
    wall_time_s: float
    results: list[ItemResult] = field(default_factory=list)
    failures: dict[str, int] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """Plain values, item results as a list of dicts."""
        d = asdict(self)
        d["results"] = [asdict(r) for r in self.results]
        return d


def rate_per_hour(in_bin: int, sim_time_s: float) -> float:
    """Items at rest in their bin per hour of `sim_time_s` [s] of arm time (0 with none):
    the `items_per_hour` of a run, a campaign and its floor (`cell.bench.bench_sort`)."""
    return 3600.0 * in_bin / sim_time_s if sim_time_s > 0 else 0.0


def summarise(results: list[ItemResult], wall_time_s: float) -> RunSummary:
    """The closing figures of a list of item results."""
    n = len(results)
    errs = np.array([r.landing_error_m for r in results if np.isfinite(r.landing_error_m)])
    cyc = np.array([r.cycle_time_s for r in results])
    sim_time = float(np.sum([r.cycle_time_s for r in results]))
    in_bin = sum(r.in_bin for r in results)
    return RunSummary(
        items=n,
        placed=sum(r.action == "place" for r in results),
        thrown=sum(r.action == "throw" for r in results),
        failed=sum(r.action == "failed" for r in results),
        in_bin=in_bin,
        in_bin_rate=in_bin / n if n else 0.0,
        mean_landing_error_m=float(errs.mean()) if errs.size else math.nan,
        p95_landing_error_m=float(np.percentile(errs, 95)) if errs.size else math.nan,
        mean_cycle_time_s=float(cyc.mean()) if cyc.size else math.nan,
        items_per_hour=rate_per_hour(in_bin, sim_time),
        sim_time_s=sim_time,
        wall_time_s=wall_time_s,
        results=list(results),
        failures={k: c for k in FAILURES if (c := sum(r.failure == k for r in results))},
    )


def sorted_throw_record(
    session: str,
    throw_id: str,
    obj: ObjectParams,
    plan: Any,
    stroke_m: float,
    released_at: np.ndarray,
    target: Any,
    out: Any,
    cross: Any,
    *,
    platform: str = "arm",
    rotor_rpm: float = 0.0,
    land_z_m: float | None = None,
) -> dict[str, Any]:
    """The throw-log row of a sort throw: the release as planned and observed, the
    crossing of the landing plane (the target bin's rim plane unless `land_z_m` says
    otherwise, see `landing`), and which bin it came to rest in."""
    return throw_record(
        throw_id,
        obj,
        stroke_m=stroke_m,
        position_m=released_at,
        elevation_rad=plan.elevation_rad,
        azimuth_rad=plan.azimuth_rad,
        roll_rad=plan.roll_rad,
        base_velocity_mps=(plan.vx_mps, plan.vy_mps, plan.vz_mps),
        platform=platform,
        rotor_rpm=rotor_rpm,
        land_z_m=target.rim_height if land_z_m is None else land_z_m,
        landed_xy_m=cross[:2],
        session=session,
        time_s=time.time(),
        t_flight_s=float(cross[2]),
        target_bin=target.id,
        bin_id=out.bin_id or "",
    )


def landing(out: Any, rim_z: float) -> tuple[tuple[float, float, float], float]:
    """Where a thrown item landed: ((x [m], y [m], t [s] since release), plane z [m]).

    The crossing of the target's rim plane going down (MODEL.md's landing); when the
    track never goes below that plane (it came down on the pile a low-rimmed bin holds,
    or on something else as high), the touchdown, on the plane of its height.
    """
    from cell.errors import NoLanding

    try:
        return out.crossing(rim_z), rim_z
    except NoLanding:
        x, y, z = out.touchdown_xyz
        return (float(x), float(y), float(out.t_touchdown)), float(z)


def missed_bin(bin_id: str | None, target_id: str, landing_error_m: float) -> tuple[str, str]:
    """(failure, reason) of a released item; both empty when it rests in its bin."""
    if bin_id == target_id:
        return "", ""
    where = f"in bin {bin_id!r}" if bin_id else "outside every bin"
    return (
        "missed_bin",
        f"came to rest {where}, not in {target_id!r} (landing error {landing_error_m:.3f} m)",
    )


def _settling_in(f: InFlight, bin_id: str) -> bool:
    """Is `f` an item placed in bin `bin_id` that has not come to rest yet?"""
    return f.decision.action == "place" and f.base["target_bin"] == bin_id


def _scored(
    base: dict[str, Any],
    action: str,
    d: Decision,
    out: Any,
    target: Any,
    err: float,
    cycle_time_s: float,
    throw_id: str = "",
) -> ItemResult:
    """The result of a released item from where the plant says it came to rest."""
    failure, reason = missed_bin(out.bin_id, target.id, err)
    return ItemResult(
        **base,
        action=action,
        bin_id=out.bin_id or "",
        in_bin=out.bin_id == target.id,
        failure=failure,
        reason=reason,
        landing_error_m=err,
        stroke_m=d.stroke_m,
        delta_stroke_m=d.delta_stroke_m,
        cycle_time_s=cycle_time_s,
        throw_id=throw_id,
        moving=d.moving,
    )


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
    score: Callable[[Any], tuple[ItemResult, Any]]

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
        res = self._item(index, spec)
        if isinstance(res, InFlight):
            res = self._wait_for(res)
        if self.observer is not None and index in self._flights:
            self.observer.on_flight(index, *self._flights.pop(index))
        return dc_replace(res, cycle_time_s=self.plant.t - t0)

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
                flying = self._place(base, obj, item, decision, target, t0)
            else:
                flying = self._throw(base, obj, item, decision, target, t0)
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

    def _place(
        self,
        base: dict[str, Any],
        obj: ObjectParams,
        item: Any,
        d: Decision,
        target: Any,
        t0: float,
    ) -> InFlight:
        """Release slowly and leave; the item, settling in the bin, is scored where it
        comes to rest. The arm does not wait for it: a soft item rocks for up to 0.8 s
        (the demo's teddy), while a box rests before the pads are out of the bin."""
        if not isinstance(self.platform, Places):
            raise InvalidInput(f"the {self.platform.name} platform does not place items")
        self.platform.release(d)
        t_release = self.plant.t
        self.platform.after_place(d)
        bx, by = target.position

        def score(out: Any) -> tuple[ItemResult, Any]:
            err = math.hypot(out.rest_xyz[0] - bx, out.rest_xyz[1] - by)
            return _scored(base, "place", d, out, target, err, t_release - t0), out.rest_xyz

        return InFlight(base, obj, item, d, score)

    def _throw(
        self,
        base: dict[str, Any],
        obj: ObjectParams,
        item: Any,
        d: Decision,
        target: Any,
        t0: float,
    ) -> InFlight:
        """Open the latch at once; the item in flight, scored and recorded once it rests."""
        released_at = self.plant.item_position(item)
        if self.observer is not None and not d.moving:
            self.observer.on_release(
                base["index"], d.plan, d.model_obj, d.ee_params, d.stroke_m, released_at
            )
        at = self.platform.release(d)
        if at is not None:
            released_at = at
        if self.observer is not None and d.moving:
            self.observer.on_release(
                base["index"], d.plan, d.model_obj, d.ee_params, d.stroke_m, released_at
            )
        t_release = self.plant.t
        # the point the throw was for: the bin's centre, or one clear of what it holds
        bx, by = target.position[:2] if d.goal_xy is None else d.goal_xy
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
                        obj,
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
            res = _scored(base, "throw", d, out, target, err, t_release - t0, throw_id)
            return res, (cross[0], cross[1], land_z)

        return InFlight(base, obj, item, d, score)

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
        self._flying, self._scored, self._flights = [], {}, {}

        def emit(t_end: float | None = None) -> None:
            # t_end may be 0.0: a lone item that failed before the plant ran is still reported
            while (i := len(results)) in self._scored and (
                i + 1 < len(starts) or t_end is not None
            ):
                t_next = starts[i + 1] if i + 1 < len(starts) else float(t_end or pl.t)
                res = dc_replace(self._scored.pop(i), cycle_time_s=t_next - starts[i])
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
                res = self._item(i, spec)
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
        return summarise(results, time.perf_counter() - t_wall)
