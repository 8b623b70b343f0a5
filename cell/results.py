"""What became of the items of a run: each item's result and failure reason, the run's
summary (items per hour counts only items at rest in their bin), and the throw-log row of
a sort throw. The item loop (`cell.loop`) scores with these; `cell.loop` re-exports them.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from cell.errors import (
    CannotGrip,
    GraspLost,
    IKFailed,
    TrajectoryError,
    UnreachableTarget,
)
from cell.log.records import throw_record
from cell.model.objects import ObjectParams

__all__ = [
    "FAILURES",
    "ItemResult",
    "RunSummary",
    "WALL_CLOCK_KEYS",
    "cores",
    "failure_of",
    "landing",
    "missed_bin",
    "plan_figures",
    "rate_per_hour",
    "realtime_cycles",
    "scored",
    "sorted_throw_record",
    "summarise",
]

# Why an item did not end in its bin: one of these, always (ItemResult.failure).
FAILURES = (
    "unreachable",  # no release within the cell's bounds lands it in the bin
    "cannot_grip",  # too wide, too thin or too heavy for the pads, refused before the pick
    "grasp_failed",  # the fingers did not close on it
    "dropped_while_carried",  # it left the grip between the pick and the release
    "ik",  # no arm configuration or move reaches the planned pose
    "missed_bin",  # released, but it came to rest outside its bin
)


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
        plan_s: the wall time [s] the cell spent on this item other than stepping the
            plant: deciding and planning it (the throw's release search, IK, the moves'
            paths), and the loop's own work while it was handled (`cell.loop.ItemLoop`);
            NaN where it was not measured. A wall-clock figure: it differs run to run
            (`WALL_CLOCK_KEYS`).
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
    plan_s: float = math.nan


@dataclass(frozen=True)
class RunSummary:
    """The closing table of a run (JSON keys as `cell run --json`).

    `placed`, `thrown` and `failed` count the items by `ItemResult.action`: `failed`, those
    stopped before their release (the table's `not released`); the items not at rest in
    their bin, released or not, are `items - in_bin`, by reason in `failures`.

    The planning figures are wall-clock ones (`WALL_CLOCK_KEYS`): `plan_s_median`,
    `plan_s_p95`, `plan_s_max` [s] of the items' `plan_s`, on a machine of `cores`
    CPU cores (`cores`), a decision planned on `plan_workers` processes (1: serially;
    2: a branch forked, `cell.arm.fork`); `items_per_hour_realtime` counts the items in their bins per
    hour of the run's real-time cycles (`realtime_cycles`: planning not hidden behind
    the arm's previous move added), beside `items_per_hour` of simulated time.
    """

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
    plan_s_median: float = math.nan
    plan_s_p95: float = math.nan
    plan_s_max: float = math.nan
    items_per_hour_realtime: float = math.nan
    cores: int = 0
    plan_workers: int = 1

    def as_dict(self) -> dict[str, Any]:
        """Plain values, item results as a list of dicts."""
        d = asdict(self)
        d["results"] = [asdict(r) for r in self.results]
        return d


def rate_per_hour(in_bin: int, sim_time_s: float) -> float:
    """Items at rest in their bin per hour of `sim_time_s` [s] of arm time (0 with none):
    the `items_per_hour` of a run, a campaign and its floor (`cell.bench.bench_sort`)."""
    return 3600.0 * in_bin / sim_time_s if sim_time_s > 0 else 0.0


# The keys of `cell run --json` (and of `cell bench`'s figures) that are wall-clock
# measurements of this machine, not results of the job: they differ run to run, while
# everything else is the same bytes in any process (tests/test_same_result.py).
WALL_CLOCK_KEYS = (
    "wall_time_s",
    "plan_s",
    "plan_s_median",
    "plan_s_p95",
    "plan_s_max",
    "items_per_hour_realtime",
    "cores",
    "plan_workers",
)


def cores() -> int:
    """The CPU cores this process may run on (its affinity where the OS says, else
    `os.cpu_count()`): the machine the planning times were measured on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def realtime_cycles(cycles_s: Sequence[float], plans_s: Sequence[float]) -> list[float]:
    """The items' real-time cycles [s]: each item's simulated cycle, lengthened by the
    planning of the next item that the arm's motion does not hide.

    The model: the cell plans item n+1 on another core while the arm executes item n
    (the planner is one item ahead, as a real cell's would be: a plan needs the arm's
    pose after the previous item, which that item's plan gives). Item n's motion starts
    at S(n); the plan of item n+1, started then, is ready at S(n) + plan_s(n+1); item
    n+1's motion starts when both the arm is free and its plan is ready:

        S(n+1) = S(n) + max(cycle(n), plan_s(n+1))

    so item n's real-time cycle is max(cycle(n), plan_s(n+1)), the last item's its
    simulated cycle (no item after it). The first item's plan is hidden behind nothing:
    it is added to the first item's cycle, S(0) = plan_s(0). A plan not measured (NaN)
    counts as 0. Each real-time cycle is at least the simulated one, so the real-time
    rate is never above the simulated one. docs/realtime.md says more.

    Args:
        cycles_s: each item's simulated pick-to-pick cycle [s] (`ItemResult.cycle_time_s`).
        plans_s: each item's planning wall time [s] (`ItemResult.plan_s`), same length.
    """
    if len(cycles_s) != len(plans_s):
        raise ValueError(f"{len(cycles_s)} cycles but {len(plans_s)} planning times")
    if not plans_s:
        return []
    plans = [float(p) if math.isfinite(p) else 0.0 for p in plans_s]
    out = [max(float(c), nxt) for c, nxt in zip(cycles_s, [*plans[1:], 0.0], strict=True)]
    out[0] += plans[0]
    return out


def plan_figures(results: Sequence[ItemResult]) -> dict[str, float]:
    """{plan_s_median, plan_s_p95, plan_s_max} [s] of the items' measured `plan_s`
    (NaN each where none was measured)."""
    p = np.array([r.plan_s for r in results if math.isfinite(r.plan_s)], float)
    if not p.size:
        return {"plan_s_median": math.nan, "plan_s_p95": math.nan, "plan_s_max": math.nan}
    return {
        "plan_s_median": float(np.median(p)),
        "plan_s_p95": float(np.percentile(p, 95)),
        "plan_s_max": float(p.max()),
    }


def summarise(results: list[ItemResult], wall_time_s: float, plan_workers: int = 1) -> RunSummary:
    """The closing figures of a list of item results, planned on `plan_workers` processes
    per decision (`Orchestrator.plan_workers`; 1 for a platform that plans serially)."""
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
        **plan_figures(results),
        items_per_hour_realtime=rate_per_hour(
            in_bin,
            sum(realtime_cycles([r.cycle_time_s for r in results], [r.plan_s for r in results])),
        ),
        cores=cores(),
        plan_workers=plan_workers,
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


def missed_bin(
    bin_id: str | None,
    target_id: str,
    landing_error_m: float,
    *,
    rest_xyz: Sequence[float] | None = None,
    target: Any = None,
) -> tuple[str, str]:
    """(failure, reason) of a released item; both empty when it rests in its bin.

    With `rest_xyz` (where it came to rest [m, W]) and `target` (the job's bin: `position`,
    `size`, `rim_height`), an item at rest over the target's footprint but too high to be
    in it (on another item, on a wall) is said to be there, not "outside every bin".
    """
    if bin_id == target_id:
        return "", ""
    where = f"in bin {bin_id!r}" if bin_id else "outside every bin"
    if not bin_id and rest_xyz is not None and target is not None:
        x, y, z = (float(v) for v in rest_xyz[:3])
        (cx, cy), (sx, sy) = target.position, target.size
        if abs(x - cx) <= sx / 2 and abs(y - cy) <= sy / 2:
            where = (
                f"over bin {target_id!r} but too high to be in it (its centre {z:.3f} m up, "
                f"the rim {target.rim_height:.3f} m: on another item or on a wall)"
            )
    return (
        "missed_bin",
        f"came to rest {where}, not in {target_id!r} (landing error {landing_error_m:.3f} m)",
    )


def scored(
    base: dict[str, Any],
    action: str,
    d: Any,
    out: Any,
    target: Any,
    err: float,
    cycle_time_s: float,
    throw_id: str = "",
) -> ItemResult:
    """The result of a released item from where the plant says it came to rest (`out`, the
    plant's outcome), its decision `d` (`cell.decision.Decision`) and its landing error [m]."""
    failure, reason = missed_bin(
        out.bin_id, target.id, err, rest_xyz=getattr(out, "rest_xyz", None), target=target
    )
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
