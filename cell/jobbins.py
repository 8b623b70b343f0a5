"""Where a job's bins may stand: clear of the robot's base and of each other, walls and all.

Positions and sizes are a bin's inner floor footprint (centre x y, size x y) [m] in the
world frame W; its walls, `BIN_WALL_M` thick, stand outside that size (`cell.sim.bins`).
"""

from __future__ import annotations

import math
from collections.abc import Collection, Sequence
from typing import Any

from cell.jobschema import BIN_WALL_M

__all__ = [
    "BIN_HINTS",
    "MAX_BIN_DISTANCE_M",
    "ROBOT_BASE_CLEARANCE_M",
    "capacity_warnings",
    "millimetre_problem",
    "station_millimetres",
    "footprints_overlap",
    "light_item_warnings",
    "look_alike_warnings",
    "wide_item_warnings",
    "placement_problem",
    "places",
]

ROBOT_BASE_CLEARANCE_M = 0.25  # [m] no bin may come closer to the robot base than this
# [m] no bin's centre farther from the base (no throw reaches past a few metres; the bound
# the command line puts on a position, `cell.cli.guard`)
MAX_BIN_DISTANCE_M = 100.0
# What a bin's two vectors hold, said where one has another length (a height given to it).
BIN_HINTS = {
    "position_m": "x y of its centre: a bin stands on the floor, and the height of its "
    "opening, up to 1 m, is rim_height_m",
    "size_m": "its inner x y: its height is rim_height_m",
}


def places(policy: str, reach_m: float, b: Any, thrown: Collection[str] = ()) -> bool:
    """Does the cell place into bin `b` (else it throws): every bin under `policy: place`;
    under `auto`, a bin within `reach_m` (`limits.place_reach_m`) of the base [m] but one
    whose place pose the job's check finds out of the arm's reach (`thrown`, those bins'
    ids: `Job.thrown_bins`, `cell.jobcheck.job_problems`)."""
    near = math.hypot(*b.position) <= reach_m
    return policy == "place" or (policy == "auto" and near and b.id not in thrown)


def millimetre_problem(pos: Sequence[float], size: Sequence[float], rim: float) -> str:
    """What to say of a bin whose centre lies beyond MAX_BIN_DISTANCE_M of the base or
    whose rim stands over 1 m, read in metres (a position of [1600, 0], a rim of 150:
    written in millimetres?), naming what the fields that read as millimetres are in
    metres; "" where neither."""
    far = math.hypot(*pos)
    if far <= MAX_BIN_DISTANCE_M and rim <= 1.0:
        return ""
    said, metres = [], []
    if far > MAX_BIN_DISTANCE_M:
        said.append(f"its centre {far:,.0f} m from the base (at most {MAX_BIN_DISTANCE_M:g} m)")
        if ROBOT_BASE_CLEARANCE_M <= far / 1000 <= MAX_BIN_DISTANCE_M:
            metres.append(f"position_m [{pos[0] / 1000:g}, {pos[1] / 1000:g}]")
    if max(size) > 5.0 and (far > MAX_BIN_DISTANCE_M or rim > 1.0):
        metres.append(f"size_m [{size[0] / 1000:g}, {size[1] / 1000:g}]")
    if rim > 1.0:
        said.append(f"a rim {rim:g} m high (at most 1 m)")
        if BIN_WALL_M < rim / 1000 <= 1.0:
            metres.append(f"rim_height_m {rim / 1000:g}")
    mm = f"; written in millimetres? In metres: {', '.join(metres)}" if metres else ""
    return f"read in metres (a job's unit), the bin has {' and '.join(said)}{mm}"


def station_millimetres(pick: Sequence[float]) -> str:
    """What to say of a pick station whose top lies beyond MAX_BIN_DISTANCE_M of the base,
    read in metres (`[450, -400, 200]`: written in millimetres?), with it in metres where
    that is within the bound; "" where it lies nearer."""
    far = math.hypot(*pick)
    if far <= MAX_BIN_DISTANCE_M:
        return ""
    metres = ", ".join(f"{v / 1000:g}" for v in pick)
    mm = f"; written in millimetres? In metres: [{metres}]" if far / 1000 <= 2.0 else ""
    return (
        f"read in metres (a job's unit), the pick table's top lies {far:,.0f} m from the "
        f"base (at most {MAX_BIN_DISTANCE_M:g} m){mm}"
    )


def footprints_overlap(pos_a: Any, size_a: Any, pos_b: Any, size_b: Any) -> bool:
    """Whether two axis-aligned bin footprints (centre [x, y] m, size [x, y] m) share area."""
    return all(abs(pos_a[k] - pos_b[k]) < (size_a[k] + size_b[k]) / 2 for k in (0, 1))


def placement_problem(
    bid: str, pos: Sequence[float], size: Sequence[float], bins: Sequence[Any]
) -> str:
    """What is wrong with bin `bid` at `pos` of `size` beside the `bins` before it (each
    with .id, .position, .size), "" if nothing: a wall nearer the base than
    ROBOT_BASE_CLEARANCE_M (the nearest point of its walls, not a circle round it), a
    footprint overlapping another's, or walls meeting another's."""
    near = math.hypot(*(max(abs(pos[k]) - size[k] / 2 - BIN_WALL_M, 0.0) for k in (0, 1)))
    if near < ROBOT_BASE_CLEARANCE_M:
        return (
            f"the bin's nearest wall is {near:.3f} m from the robot base at the origin; "
            f"keep every bin at least {ROBOT_BASE_CLEARANCE_M} m away"
        )
    outer = [s + 2 * BIN_WALL_M for s in size]
    for other in bins:
        where = (
            f"(footprints {tuple(size)} m at {tuple(pos)} and {tuple(other.size)} m at "
            f"{tuple(other.position)}"
        )
        # footprints that only touch (within rounding: 0.85 - 0.55 < 0.3) meet at the walls
        if footprints_overlap(pos, [s - 1e-9 for s in size], other.position, other.size):
            return (
                f"bin {bid!r} overlaps bin {other.id!r} {where}); an item landing in one "
                "would be scored in the other: move them apart"
            )
        if footprints_overlap(pos, outer, other.position, [s + 2 * BIN_WALL_M for s in other.size]):
            return (
                f"the walls of bin {bid!r} meet those of bin {other.id!r} {where}, each walled "
                f"{BIN_WALL_M} m thick outside its size): leave at least {2 * BIN_WALL_M:g} m "
                "between their footprints"
            )
    return ""


def capacity_warnings(job: Any) -> tuple[str, ...]:
    """A warning for each bin the job's items (those sorted: `Job.expanded_items`) cannot
    all fit in: their boxes' volume over the bin's inside up to its rim (its floor plate,
    `BIN_WALL_M` thick, taken off). Boxes never pack the whole of it, so past 1 the later
    items rest on the others above the rim, not in the bin."""
    filled: dict[str, float] = {}
    count: dict[str, int] = {}
    for it in job.expanded_items():
        filled[it.bin] = filled.get(it.bin, 0.0) + math.prod(it.obj.size)
        count[it.bin] = count.get(it.bin, 0) + 1
    out = []
    for b in job.bins:
        inside = b.size[0] * b.size[1] * (b.rim_height - BIN_WALL_M)
        if b.id in filled and filled[b.id] > inside:
            n = count[b.id]
            sent = f"{n} items whose boxes take" if n > 1 else "1 item whose box takes"
            rests = (
                "the later ones will come to rest on the others, above the rim"
                if n > 1
                else "it will stand above the rim"
            )
            out.append(
                f"{job.path}: bin {b.id!r} is sent {sent} {filled[b.id]:.3g} m³, "
                f"{filled[b.id] / inside:.3g} times the {inside:.3g} m³ inside it up to its "
                f"rim: {rests} (`missed_bin`); widen or deepen the bin"
                + (", or split the items between bins" if n > 1 else "")
            )
    return tuple(out)


def light_item_warnings(job: Any) -> tuple[str, ...]:
    """A warning for each item line thrown (not placed: `cell.arm.launch`'s rule) whose
    mass is under the lightest catalogue object's, the lightest the throw model is
    calibrated on: it misses where it is aimed. Measured in the scene (25 mm cubes
    thrown 1.5 m, `tasks`-like layout): missed by 0.75 m at 0.2 g, 0.36 m at 1 g, 0.24 m at
    2 g, 0.13 m at 5 g, 0.065 m at 10 g, 0.04 m at 20 g. Placed, an item is not affected."""
    from cell.catalogue import catalogue

    lightest = min(catalogue().items(), key=lambda kv: kv[1].params.mass)
    m_min = lightest[1].params.mass
    out = []
    for it in job.items:
        b = job.bin(it.bin)
        if not places(job.policy, job.place_reach_m, b, job.thrown_bins) and it.obj.mass < m_min:
            out.append(
                f"{job.path}, line {it.line}, mass_kg: {it.obj.mass:g} kg is lighter than the "
                f"lightest object the throw model is calibrated on ({lightest[0]}, {m_min:g} "
                f"kg): thrown to bin {it.bin!r}, it will miss where it is aimed (25 mm cubes "
                "thrown 1.5 m missed by 0.24 m at 2 g, 0.13 m at 5 g); under policy auto, a "
                "bin within limits.place_reach_m that the arm reaches has it placed"
            )
    return tuple(out)


def calibrated_width_m() -> float:
    """[m] The widest grip the throw model is calibrated on: `cell calibrate --adhoc` fits
    the mass rule (`cell.params`) to items `cell.jobgen` draws (`adhoc_plan`), up to its
    widest extent, 90 mm; the catalogue's widest is 70 mm (cyl70, sphere70)."""
    from cell.jobgen import LayoutRanges

    return float(LayoutRanges.adhoc_extent_m[1])


def wide_item_warnings(job: Any) -> tuple[str, ...]:
    """A warning for each item line thrown (not placed: `places`) that a throw may grip
    across a side wider than the throw model is calibrated on (`calibrated_width_m`): a
    side the pads hold briskly (`cell.arm.grip_side.throw_sides`) where no narrower side
    held briskly gives a throw into the bin by the model (the planner takes a narrower
    one where it does: `GripSideChoice._throw_side`). There the
    model extrapolates, and the scene's pads still squeeze an item wider than 85 mm as it
    slides out of them at the carriage's end stop (the band is not slack there), which
    the model does not have: a light one lands short. Measured in the scene (boxes
    [a, 0.03, 0.1] thrown at a stroke of 0.09 m, 25 deg up, from 0.7 m; the model put
    them 1.19-1.27 m out at 30 g): 30 g boxes 100, 110, 120 mm across 0.11, 0.24, 0.39 m
    short of the model, 90 g ones 0.03, 0.09, 0.24 m; 90 mm within 0.03 m. A warning
    only. The pads' hold is the job's parameter file's (the scene's calibrated one by
    default)."""
    from cell.arm.grip_side import grip_sides
    from cell.catalogue import pad_width_m

    widest = calibrated_width_m()
    params: Any = False  # loaded at the first wide item (None: unreadable, said by the run)
    out = []
    for it in job.items:
        b = job.bin(it.bin)
        if places(job.policy, job.place_reach_m, b, job.thrown_bins):
            continue
        # the arm may turn the grip to either side; the other platforms grip across x
        sides = [s for _, s in grip_sides(it.obj)][: None if job.platform == "arm" else 1]
        if all(pad_width_m(s) <= widest + 1e-9 for s in sides):
            continue
        if params is False:
            params = _job_params(job)
        thrown = [pad_width_m(s) for s in sides if _throw_side(params, s)]
        held = [w for w in thrown if w > widest + 1e-9]
        if not held:
            continue
        w = max(held)
        narrow = [w for w in thrown if w <= widest + 1e-9]
        if narrow and params is not None and _narrow_reaches(params, sides, b, widest):
            continue  # the planner throws it across the narrower side
        though = (
            ""
            if not narrow
            else f" (though the {min(narrow) * 1000:.0f} mm side holds: the planner takes it "
            "where a throw across it reaches the bin, which the parameter file, unread, "
            "does not tell)"
            if params is None
            else f" (its {min(narrow) * 1000:.0f} mm side, which the planner takes where a "
            "throw across it is found, gives no throw into the bin by the model)"
        )
        out.append(
            f"{job.path}, line {it.line}, size_m: {w * 1000:.0f} mm across the pads is wider "
            f"than the widest grip the throw model is calibrated on ({widest * 1000:.0f} mm): "
            f"thrown to bin {it.bin!r} gripped across it{though}, the item may land short "
            "of where it is aimed: the pads still squeeze an item over 85 mm wide as it "
            "leaves them, which the model does not have (30 g boxes 100, 110 and 120 mm "
            "across landed 0.11, 0.24 and 0.39 m short of a 1.2-1.3 m throw in the scene); "
            "under policy auto, a bin within limits.place_reach_m that the arm reaches has "
            "it placed"
        )
    return tuple(out)


def _narrow_reaches(params: Any, sides: list[Any], bin_spec: Any, widest: float) -> bool:
    """Does a throw gripped across one of `sides` no wider than `widest` [m], held briskly,
    land in `bin_spec` by the planner's model (`cell.arm.launch.side_throw_error`)?"""
    from cell.arm.grip_limits import grip_strokes
    from cell.arm.grip_side import GripSide
    from cell.arm.launch import side_throw_error
    from cell.catalogue import pad_width_m

    for s in sides:
        s_max, brisk = grip_strokes(params, s)
        if s_max is None or not brisk or pad_width_m(s) > widest + 1e-9:
            continue
        if side_throw_error(params, GripSide(0.0, s, s_max), bin_spec) is None:
            return True
    return False


def _throw_side(params: Any, side: Any) -> bool:
    """May a throw grip the item across `side` (as gripped)? The pads open that wide and
    hold it briskly there (`cell.arm.grip_side.throw_sides`), by `params`; where the
    job's parameters do not load (None), whether the pads open that wide."""
    from cell.arm.grip_limits import as_gripped, grip_strokes
    from cell.sim.mechanism import DEFAULT_GEOMETRY

    if params is None:
        return as_gripped(side).width <= 2 * DEFAULT_GEOMETRY.finger_open_m
    return grip_strokes(params, side)[1]


def _job_params(job: Any) -> Any:
    """The job's model parameters (its `cell.params`, else the scene's calibrated file), or
    None where they do not load (the run refuses the file, saying why)."""
    from cell.errors import CellError
    from cell.params import load_params, scene_params_path

    try:
        return load_params(job.params or scene_params_path())
    except CellError:
        return None


def look_alike_warnings(job: Any) -> tuple[str, ...]:
    """A warning for each two bins whose ids are one text to the eye but not the same id
    (`cell.yamltree.look_alike`: `near` and the full-width `ｎear`), or differ only in
    case (`near` and `Near`): both are bins, and an item sent to one is not sent to the
    other."""
    from cell.yamltree import look_alike

    out = []
    ids = [b.id for b in job.bins]
    for i, a in enumerate(ids):
        for b in ids[i + 1 :]:
            how = look_alike(b, a)
            if how:
                out.append(
                    f"{job.path}: bins {a!r} and {b!r} look alike but are two bins ({b!r} "
                    f"holds {how}); an item sent to one is not sent to the other"
                )
            elif a != b and a.casefold() == b.casefold():  # `near` and `Near`
                out.append(
                    f"{job.path}: bins {a!r} and {b!r} differ only in case, and are two bins "
                    "(an id is matched as written); an item sent to one is not sent to the other"
                )
    return tuple(out)
