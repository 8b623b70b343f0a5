"""`cell bench sort`: the cell on sort jobs it has never seen.

Each layout is a job drawn by `cell.jobgen.random_job` (seed = the campaign's
seed + the layout's index, arms alternating over `robots`), run in its own
PyBullet scene by the same orchestrator as `cell run`. A layout is one unit of
work: `run_layout` is a plain function of a picklable unit, so a campaign can be
split over processes or a Ray cluster and gives the same figures as the serial
run.

Figures (`summarise_layouts`):
    in_bin_rate            items at rest in their target bin / items, with a 95 %
                           Wilson interval (in_bin_rate_lo, in_bin_rate_hi);
    in_bin_rate_unseen     the same over items never used in calibration (catalogue
                           sets other than thesis14, and ad-hoc items);
    items_per_hour         items at rest in their bin per simulated hour of arm time;
    floor_items_per_hour   with `--floor`: the same in-bin count over the cycles with
                           each approach and throw's carry one direct move at the arm's
                           full limits, the carry as fast as the grip holds the item
                           along it (`Orchestrator._time_floor`): the rate were the
                           routes free, a floor of the cycle, not a rate the cell reaches;
    items, layouts, failures (count per cell.orchestrator.FAILURES reason);
    failures_by_object     per reason, which objects failed so and how often
                           (`failures_by_object`: where to look first);
    per_layout             each layout's own figures (`per_layout`).

Two sets of layouts (`LAYOUT_SETS`, `cell bench sort --set`): `tune`, the seeds the
cell's constants may be chosen on (the arm's constants were chosen on seeds 0–19), and
`test`, a disjoint range of seeds no choice is made on (from 1000): the figure a user
should expect on jobs the cell has never seen is the `test` set's.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Any

import yaml

from cell.loop import rate_per_hour

__all__ = [
    "LAYOUT_SETS",
    "LayoutUnit",
    "first_seed",
    "failures_by_object",
    "floor_figures",
    "layout_units",
    "per_layout",
    "refused_at_draw",
    "run_layout",
    "summarise_layouts",
    "wilson_interval",
]


LAYOUT_SETS: dict[str, tuple[int, int]] = {"tune": (0, 1000), "test": (1000, 2**32)}
"""The seeds of each set of layouts, [first, end): `tune` may be looked at to choose a
constant, `test` never is (`random_job` takes seeds below 2³²)."""


def first_seed(layout_set: str, layouts: int, seed: int | None = None) -> int:
    """The first seed of `layouts` layouts of a set: `seed`, or the set's first.

    Raises:
        InvalidInput: an unknown set, or seeds seed … seed + layouts − 1 not all in it.
    """
    from cell.errors import InvalidInput

    if layout_set not in LAYOUT_SETS:
        raise InvalidInput(f"--set {layout_set!r}: give one of {', '.join(LAYOUT_SETS)}")
    lo, end = LAYOUT_SETS[layout_set]
    first = lo if seed is None else seed
    if not (lo <= first and first + layouts <= end):
        other = [n for n, (a, b) in LAYOUT_SETS.items() if a <= first < b and n != layout_set]
        hint = f" (seed {first} is in the {other[0]} set: --set {other[0]})" if other else ""
        raise InvalidInput(
            f"--seed {first} --layouts {layouts}: the {layout_set} set's seeds are "
            f"{lo}–{end - 1}; give a first seed from {lo} to {end - layouts}{hint}"
        )
    return first


@dataclass(frozen=True)
class LayoutUnit:
    """One layout of a campaign: which job to draw and run.

    Attributes:
        seed: the job's seed (cell job random --seed).
        robot: the arm.
        learn: correct the planner from each observed landing during the run.
        max_items: run only the first items of the job (0: all of them).
        speed_scale: fraction of the arm's joint limits its moves use (Orchestrator).
        turn: release throws turned toward the pick station (`cell run --turn-release`, on
            by default).
        floor: also time each approach and throw's carry as one direct move
            (`Orchestrator.floors`): each item's `floor_cycle_s`.
        cycle_search: each throw's release chosen by its cycle (`cell run --cycle-search`,
            on by default).
        order: the order the items are taken in (`cell run --order`: "job" or "bins").
        plan_workers: processes a throw's plan uses (`Orchestrator`'s; None: its default).
            On Ray workers 1 (`cell bench sort --workers 2`): the layouts already keep both
            cores busy, and a Ray worker runs threads of its own, where a fork is unsafe.
    """

    seed: int
    robot: str = "panda"
    learn: bool = False
    max_items: int = 0
    speed_scale: float = 1.0
    turn: bool = True
    floor: bool = False
    cycle_search: bool = True
    order: str = "job"
    plan_workers: int | None = None


def layout_units(
    n: int,
    seed: int,
    robots: tuple[str, ...] = ("panda",),
    learn: bool = False,
    max_items: int = 0,
    speed_scale: float = 1.0,
    turn: bool = True,
    floor: bool = False,
    cycle_search: bool = True,
    order: str = "job",
    plan_workers: int | None = None,
) -> list[LayoutUnit]:
    """The campaign's layouts: seeds seed … seed + n − 1, arms taken in turn."""
    return [
        LayoutUnit(
            seed + i,
            robots[i % len(robots)],
            learn,
            max_items,
            speed_scale,
            turn,
            floor,
            cycle_search,
            order,
            plan_workers,
        )
        for i in range(n)
    ]


def run_layout(unit: LayoutUnit) -> dict[str, Any]:
    """Draw and run one layout; plain values only (JSON- and pickle-safe).

    Returns:
        {"seed", "robot", "wall_time_s", "sim_time_s", "refused" (the job's
        up-front refusal message, "" when it ran), "items": [{object_id, unseen,
        action, in_bin, failure, reason, landing_error_m, cycle_time_s, moving, and
        with `unit.floor` floor_cycle_s: the cycle with its approach and throw's carry
        as one direct move each}, ...]}.
    """

    from cell.parallel import one_blas_thread

    # One BLAS thread, as on a Ray worker (OMP_NUM_THREADS=1): the same floating-point
    # sums everywhere, so a layout gives the same result serially and on any worker; scipy's
    # OpenBLAS too, which the first layout of a process would otherwise load after the limit.
    with one_blas_thread():
        return _run_layout(unit)


def _run_layout(unit: LayoutUnit) -> dict[str, Any]:
    from cell.catalogue import catalogue
    from cell.errors import JobError
    from cell.jobgen import CALIBRATION_SET, random_job
    from cell.jobs import parse_job
    from cell.orchestrator import Orchestrator

    t0 = time.perf_counter()
    refused: list[str] = []  # kinds drawn that no bin could take, drawn again
    doc = random_job(unit.seed, unit.robot, refused=refused)
    name = f"<random layout {unit.seed}>"
    cat = catalogue()
    out: dict[str, Any] = {
        "seed": unit.seed,
        "robot": unit.robot,
        "speed_scale": unit.speed_scale,
        "refused": "",
        "refused_at_draw": refused,
        "kinds_drawn": len(doc["items"]) + len(refused),
        "items": [],
    }
    try:  # a layout its arm cannot sort (the station out of its reach) is refused, not the run
        job = parse_job(yaml.safe_dump(doc, sort_keys=False), name)
        if unit.max_items:
            job = replace(job, max_items=unit.max_items)
        orch = Orchestrator(
            job,
            learn=unit.learn,
            speed_scale=unit.speed_scale,
            turn_release=unit.turn,
            cycle_search=unit.cycle_search,
            floor=unit.floor,
            order=unit.order,
            plan_workers=unit.plan_workers,
        )
    except JobError as exc:
        out["refused"] = str(exc)
        out["wall_time_s"] = time.perf_counter() - t0
        out["sim_time_s"] = 0.0
        return out
    try:
        summary = orch.run()
    finally:
        orch.close()
    for r in summary.results:
        oid = r.object_id
        out["items"].append(
            {
                "object_id": oid,
                "unseen": oid not in cat or cat[oid].set != CALIBRATION_SET,
                "action": r.action,
                "in_bin": bool(r.in_bin),
                "failure": r.failure,
                "reason": r.reason,
                "landing_error_m": float(r.landing_error_m),
                "cycle_time_s": float(r.cycle_time_s),
                "moving": bool(r.moving),
                "plan_s": float(r.plan_s),  # wall time (cell.results.WALL_CLOCK_KEYS)
            }
        )
        if unit.floor:
            spent, floor = orch.floors.get(r.index, (0.0, 0.0))
            out["items"][-1]["floor_cycle_s"] = float(r.cycle_time_s) - spent + floor
    out["sim_time_s"] = float(summary.sim_time_s)
    out["wall_time_s"] = time.perf_counter() - t0
    return out


def wilson_interval(k: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """95 % Wilson score interval of a proportion k/n (0, 1 when n = 0)."""
    if n == 0:
        return 0.0, 1.0
    p = k / n
    den = 1 + z * z / n
    mid = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return max(0.0, mid - half), min(1.0, mid + half)


def summarise_layouts(layouts: list[dict[str, Any]]) -> dict[str, Any]:
    """The campaign's figures (flat JSON) from `run_layout` results."""
    from cell.bench.bench_realtime import realtime_figures
    from cell.orchestrator import FAILURES

    items = [it for lay in layouts for it in lay["items"]]
    n = len(items)
    k = sum(it["in_bin"] for it in items)
    unseen = [it for it in items if it["unseen"]]
    ku = sum(it["in_bin"] for it in unseen)
    sim = sum(lay["sim_time_s"] for lay in layouts)
    lo, hi = wilson_interval(k, n)
    ulo, uhi = wilson_interval(ku, len(unseen))
    errs = sorted(it["landing_error_m"] for it in items if math.isfinite(it["landing_error_m"]))
    return {
        "layouts": len(layouts),
        "layouts_refused": sum(bool(lay["refused"]) for lay in layouts),
        "robots": ",".join(sorted({lay["robot"] for lay in layouts})),
        "items": n,
        "in_bin": k,
        "in_bin_rate": k / n if n else 0.0,
        "in_bin_rate_lo": lo,
        "in_bin_rate_hi": hi,
        "items_unseen": len(unseen),
        "in_bin_rate_unseen": ku / len(unseen) if unseen else 0.0,
        "in_bin_rate_unseen_lo": ulo,
        "in_bin_rate_unseen_hi": uhi,
        "items_per_hour": rate_per_hour(k, sim),
        **realtime_figures(layouts),
        **floor_figures(items),
        "median_landing_error_m": errs[len(errs) // 2] if errs else math.nan,
        "sim_time_s": sim,
        "wall_time_s": sum(lay["wall_time_s"] for lay in layouts),
        "failures": {f: c for f in FAILURES if (c := sum(it["failure"] == f for it in items))},
        "failures_by_object": failures_by_object(items),
        "thrown": sum(it["action"] == "throw" for it in items),
        **refused_at_draw(layouts),
        "released_moving": sum(bool(it.get("moving")) for it in items),
        **repeat_figures(layouts),
        "per_layout": per_layout(layouts),
    }


def floor_figures(items: list[dict[str, Any]]) -> dict[str, float]:
    """{floor_items_per_hour, floor_sim_time_s} over items that have a `floor_cycle_s`
    (`run_layout` with `floor`): the items in their bins per hour of those cycles; {}
    when any item lacks one (a campaign run without the floor)."""
    if not items or any("floor_cycle_s" not in it for it in items):
        return {}
    sim = sum(float(it["floor_cycle_s"]) for it in items)
    k = sum(it["in_bin"] for it in items)
    return {"floor_items_per_hour": rate_per_hour(k, sim), "floor_sim_time_s": sim}


def refused_at_draw(layouts: list[dict[str, Any]]) -> dict[str, Any]:
    """What the campaign's rate leaves out: the kinds of item (an object and its count)
    drawn for the layouts that no bin could take by the planner's model (the pads cannot
    hold them, or no bin is within their reach), which `random_job` drew again. {
    kinds_drawn, kinds_refused_at_draw, refused_at_draw_by_object: {object: times}, most
    frequent first}."""
    from collections import Counter

    counts = Counter(k for lay in layouts for k in lay.get("refused_at_draw", []))
    return {
        "kinds_drawn": sum(int(lay.get("kinds_drawn", 0)) for lay in layouts),
        "kinds_refused_at_draw": sum(counts.values()),
        "refused_at_draw_by_object": dict(sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))),
    }


def failures_by_object(items: list[dict[str, Any]]) -> dict[str, dict[str, int]]:
    """{reason: {object_id: count}} over the failed items, each reason's objects most
    frequent first (ties by name), in the order of cell.orchestrator.FAILURES."""
    from collections import Counter

    from cell.orchestrator import FAILURES

    out: dict[str, dict[str, int]] = {}
    for reason in FAILURES:
        counts = Counter(it["object_id"] for it in items if it["failure"] == reason)
        if counts:
            out[reason] = dict(sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])))
    return out


def per_layout(layouts: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Each layout's own figures, in campaign order: which layouts the campaign's rate and
    time come from. {seed, robot, items, in_bin, sim_time_s, items_per_hour, the
    median cycle [s] of its items, its slowest item (object and cycle [s]), refused}."""
    rows = []
    for lay in layouts:
        items = lay["items"]
        k = sum(it["in_bin"] for it in items)
        sim = float(lay["sim_time_s"])
        cycles = sorted(float(it["cycle_time_s"]) for it in items)
        slow = max(items, key=lambda it: float(it["cycle_time_s"]), default=None)
        rows.append(
            {
                "seed": lay["seed"],
                "robot": lay["robot"],
                "items": len(items),
                "in_bin": k,
                "sim_time_s": sim,
                "items_per_hour": rate_per_hour(k, sim),
                **floor_figures(items),
                "median_cycle_s": cycles[len(cycles) // 2] if cycles else math.nan,
                "slowest_item": slow["object_id"] if slow else "",
                "slowest_cycle_s": float(slow["cycle_time_s"]) if slow else math.nan,
                "refused": bool(lay["refused"]),
            }
        )
    return rows


def repeat_figures(layouts: list[dict[str, Any]]) -> dict[str, Any]:
    """How an object's second throw in a layout lands against its first (the flywheel's
    measure; without `--learn` the baseline): the pairs' count, the median landing error
    of the first and of the second throws [m], and the share of pairs whose second lands
    closer."""
    pairs: list[tuple[float, float]] = []
    for lay in layouts:
        first: dict[str, float] = {}
        done: set[str] = set()
        for it in lay["items"]:
            oid, err = it["object_id"], it["landing_error_m"]
            if it["action"] != "throw" or not math.isfinite(err) or oid in done:
                continue
            if oid in first:
                pairs.append((first[oid], err))
                done.add(oid)
            else:
                first[oid] = err
    a = sorted(p[0] for p in pairs)
    b = sorted(p[1] for p in pairs)
    return {
        "repeat_pairs": len(pairs),
        "repeat_first_median_error_m": a[len(a) // 2] if a else math.nan,
        "repeat_second_median_error_m": b[len(b) // 2] if b else math.nan,
        "repeat_second_closer_rate": (
            sum(q < p for p, q in pairs) / len(pairs) if pairs else math.nan
        ),
    }
