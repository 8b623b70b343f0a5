"""What a sort job asks of its arm, checked before anything runs (`cell.jobs.parse_job`
calls these; every problem goes into the one report the job is refused with).

* The pick station under a bin: the station's 0.24 m block and a bin's footprint share
  floor (`station_problems`).
* The pick station out of the arm's reach: inverse kinematics of the grip pointing down
  over the station's centre, at the lowest and the highest grip the job's items need
  (the shortest item gripped at the shortest stroke; the tallest at the longest), as the
  pick solves it (`reach_problems`; the lift over the pick is lowered where the arm
  does not reach it, `cell.arm.kinematics`).
* A bin placed into out of the arm's reach: every bin under `policy: place` (an error),
  those within `limits.place_reach_m` under `auto` (a warning: its items are thrown
  instead, `Job.thrown_bins`), IK of the
  grip pointing down over the place's own spot nearest the base (`place_spot`: the point
  of `cell.arm.spots.place_spots`' grid nearest the base, the grid kept the item's
  footprint and the pads from the walls as `cell.arm.place` keeps it, for the item sent
  there whose grid keeps farthest in), the tallest item bound there at the two heights
  the place takes it through (`cell.arm.place`): over the spot, its lowest point
  `ArmTuning.lift_m` or 5 cm over the rim (the higher) above the floor plate and the place
  clearance, and down on the floor plate. An arm whose grip points down only low (the
  Unitree Z1) or only high (the PR2) failed every place with the check passed while it
  tested one pose 5 cm over the rim; a bin whose point 3 cm in from its walls the arm
  reached while it missed every spot the place would use (0.30 m at (0, -0.90) m from a
  Panda, a cube50: its nearest spot missed by 2.5 mm) failed every item with `ik`.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Sequence
from functools import lru_cache
from typing import Any

import numpy as np

from cell.jobbins import ROBOT_BASE_CLEARANCE_M as _CLEAR_M

__all__ = [
    "STATION_HALF_M",
    "STROKE_RANGE_M",
    "extents_mismatch",
    "items_fit",
    "job_problems",
    "place_miss",
    "place_problems",
    "place_spot",
    "reach_problems",
    "station_problems",
    "tallest_m",
    "unsorted_warning",
]

STATION_HALF_M = 0.12  # [m] half the pick station's square top (cell.sim.scene_build)
STROKE_RANGE_M = (0.03, 0.11)  # [m] the strokes an item is gripped at (MODEL.md)
CHECKED_CUBE_M = 0.05  # [m] the cube a bin no item is sent to is checked for (its side)
OVER_RIM_M = 0.05  # [m] the item's lowest point over the rim, at least, over the spot


def station_problems(
    pick: Sequence[float], bins: Sequence[Any], where: dict[str, str]
) -> list[str]:
    """A bin whose footprint reaches under the pick station's block.

    Args:
        pick: the station's top centre (x, y, z) [m, W].
        bins: the job's BinSpecs.
        where: "bins[i]" / "pick_station" -> "file, line N".

    Returns:
        One message per bin under the station.
    """
    out = []
    for i, b in enumerate(bins):
        dx = abs(b.position[0] - pick[0]) - b.size[0] / 2
        dy = abs(b.position[1] - pick[1]) - b.size[1] / 2
        if dx < STATION_HALF_M and dy < STATION_HALF_M:
            out.append(
                f"{where.get(f'bins[{i}]', '?')}, bins[{i}].position_m: bin {b.id!r} "
                f"({b.size[0]:.2f} × {b.size[1]:.2f} m at ({b.position[0]:.2f}, "
                f"{b.position[1]:.2f})) is under the pick station, a {2 * STATION_HALF_M:.2f} m "
                f"block at ({pick[0]:.2f}, {pick[1]:.2f}) ({where.get('pick_station', '?')}): "
                "move the bin or the station apart"
            )
    return out


@lru_cache(maxsize=16)
def _farthest_m(robot: Any) -> float:
    """The farthest the arm's TCP gets from its base over 500 random configurations [m]
    (seeded), and 5 % more: a pose farther out is out of reach without a search."""
    qs = robot.random_configuration(np.random.default_rng(0), 500)
    return 1.05 * max(float(np.linalg.norm(robot.tcp_pose(q)[0])) for q in qs)


# [robot][the TCP position's bytes] -> `_reaches`' answer: a pose a check (or another
# check of the process: a job loaded again, the draw's `NearBins` then the load) asks
# again is not searched again (the search is seeded: the same answer)
_REACHED: weakref.WeakKeyDictionary[Any, dict[bytes, float]] = weakref.WeakKeyDictionary()
_REACHED_MAX = 4096  # answers kept per arm (a job asks a few dozen poses)


def _reaches(robot: Any, tcp: np.ndarray) -> float:
    """0 when the grip pointing down reaches TCP position `tcp` [m, W], else how far the
    nearest solution found misses it [m] (kept per arm and position: `_REACHED`).

    The search stops at the first seed that converges (`solutions=1`): whether one does,
    and the nearest miss where none does (every seed tried, then the polish), are those
    of the default search's three solutions, which only a success's configuration (not
    read here) depends on."""
    from cell.errors import IKFailed
    from cell.robot.ik import ReleasePose, solve_ik

    tcp = np.asarray(tcp, float)
    kept = _REACHED.setdefault(robot, {})
    key = tcp.tobytes()
    if key in kept:
        return kept[key]
    if len(kept) >= _REACHED_MAX:  # a long-lived process checking many jobs: bounded
        kept.clear()
    far = float(np.linalg.norm(tcp)) - _farthest_m(robot)
    if not far < 0.0:  # beyond any configuration (or not finite): no search
        miss = far if math.isfinite(far) else math.inf
    else:
        pose = ReleasePose(tcp, np.array([0.0, 0.0, -1.0]))
        try:
            solve_ik(robot, pose, robot.home, solutions=1)
            miss = 0.0
        except IKFailed as exc:
            err = getattr(exc, "position_error_m", None)
            miss = float(err) if err is not None else float("nan")
    kept[key] = miss
    return miss


def _tcp_z(centre_z: float, stroke: float, height: float) -> float:
    """The TCP's height [m] for the grip pointing down with the item's centre at
    centre_z, gripped at `stroke` (`cell.frames.tcp_for_item_centre`)."""
    from cell.sim.frames import EE_TO_TCP_M

    return centre_z - (EE_TO_TCP_M - stroke - height / 2)


def _reach_m(robot: Any, xy: Sequence[float], z: float) -> float:
    """How far out from the base, toward xy and at TCP height z, the arm reaches with the
    grip pointing down [m] (bisection on IK, to 1 cm, from the nearest of 0.15 m, 0.25 m,
    ... out it reaches: a Panda's grip points down at a low height only some way out; 0
    when none is): for the messages ("the arm reaches about ...")."""
    d = np.array([xy[0], xy[1]], float)
    d = d / (np.linalg.norm(d) or 1.0)

    def ok(r: float) -> bool:
        return _reaches(robot, np.array([d[0] * r, d[1] * r, z])) == 0.0

    hi = _farthest_m(robot)
    lo = next((float(r) for r in np.arange(0.15, hi, 0.1) if ok(float(r))), 0.0)
    if lo == 0.0:
        return 0.0
    while hi - lo > 0.01:
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


def _missed(miss: float) -> str:
    """How far the nearest IK solution missed a pose, in words."""
    if math.isfinite(miss):
        return f"missed by {miss * 1000:.0f} mm"
    return "farther than any configuration reaches"


def _inner(reach: float, here_m: float) -> bool:
    """Is a pose `here_m` [m] out that the arm misses nearer the base than its reach
    `reach` [m] there (`_reach_m`, to its 1 cm): a gap its joints' limits leave inside?"""
    return here_m < reach - 0.01


def _out(reach: float, here_m: float, for_bin: bool = True) -> str:
    """How far out the grip pointing down reaches at a height, in words; `here_m` is how
    far out the pose missed lies [m]: nearer than `reach`, the gap is an inner one (the
    joints' limits keep the grip from pointing down that close to the base)."""
    if reach <= 0.0:
        return "the arm's grip pointing down does not get there at that height"
    if _inner(reach, here_m):
        return (
            f"the arm's grip pointing down reaches about {reach:.2f} m out at that height, "
            "but not this near the base (its joints' limits)"
        )
    if for_bin and _too_near(reach):
        return (
            f"the arm's grip pointing down reaches about {reach:.2f} m out at that height, "
            f"nearer the base than a bin may stand ({_CLEAR_M} m)"
        )
    return f"the arm's grip pointing down reaches about {reach:.2f} m out at that height"


def _too_near(reach: float) -> bool:
    """Does the grip pointing down reach out at a height only where no bin may stand
    (`cell.jobbins.ROBOT_BASE_CLEARANCE_M`: a bin's nearest wall at least that far out)?
    An arm hung from the ceiling over the floor's bins: no bin closer places."""
    return 0.0 < reach < _CLEAR_M


def _whither(reach: float, here_m: float) -> str:
    """Where to move a station the grip pointing down misses, in words (`_out`'s cases)."""
    if reach <= 0.0:  # nowhere out at that height
        return "to a height the grip reaches pointing down (`cell reach --elevation -1.5708`)"
    return "farther out" if _inner(reach, here_m) else "within that"


def _move(reach: float, here_m: float) -> str:
    """Where to move a bin whose place pose the arm misses (`_out`'s cases), in words;
    none where the grip does not point down at that height at all (the Z1 over a bin: the
    carry lifts the item `ArmTuning.lift_m` over the floor plate at least)."""
    if reach <= 0.0 or (_too_near(reach) and not _inner(reach, here_m)):
        return ""  # not at that height anywhere a bin may stand: no other spot helps
    return f"move the bin {'farther out' if _inner(reach, here_m) else 'closer'}, or "


def _fmt(v: Any) -> str:
    return "(" + ", ".join(f"{x:.2f}" for x in v) + ")"


def reach_problems(
    robot_ref: str,
    pick: Sequence[float],
    bins: Sequence[Any],
    items: Sequence[Any],
    placed: Sequence[int],
    where: dict[str, str],
) -> list[str]:
    """The pick station and the bins placed into that the arm does not reach.

    Args:
        robot_ref: the arm (a name under robots/ or a mount file: `cell.robot.mount`).
        pick: the station's top centre (x, y, z) [m, W].
        bins: the job's BinSpecs.
        items: the job's ItemSpecs.
        placed: the indices of the bins the job places into.
        where: "bins[i]" / "pick_station" / "cell" -> "file, line N".

    Returns:
        One message per pose the arm does not reach, naming the field and what would do.
    """
    from cell.robot.model import load_robot

    robot = load_robot(robot_ref)
    heights = [float(it.obj.size[2]) for it in items] or [0.05]
    out: list[str] = []
    centre_lo = pick[2] + min(heights) / 2
    centre_hi = pick[2] + max(heights) / 2
    checks = (
        (_tcp_z(centre_lo, STROKE_RANGE_M[0], min(heights)), "the shortest item gripped"),
        (_tcp_z(centre_hi, STROKE_RANGE_M[1], max(heights)), "the tallest item gripped"),
    )
    for z, what in checks:
        tcp = np.array([pick[0], pick[1], z])
        miss = _reaches(robot, tcp)
        if miss == 0.0:
            continue
        reach = _reach_m(robot, pick, z)
        r_pick = math.hypot(pick[0], pick[1])
        out.append(
            f"{where.get('pick_station', where.get('cell', '?'))}, pick_station.position_m: "
            f"the {robot.name} arm does not reach the pick station at {_fmt(pick)} m "
            f"({what}: the grip pointing down with its TCP at {_fmt(tcp)} m, "
            f"{_missed(miss)}); the station's centre is "
            f"{r_pick:.2f} m from the base and "
            f"{_out(reach, r_pick, for_bin=False)}: move the station {_whither(reach, r_pick)}, "
            "or choose another arm"
        )
        break
    return out + place_problems(robot, bins, items, placed, where)


def place_problems(
    robot: Any,
    bins: Sequence[Any],
    items: Sequence[Any],
    placed: Sequence[int],
    where: dict[str, str],
) -> list[str]:
    """The bins placed into (indices `placed`) that the arm (`cell.robot.model.Robot`) does
    not reach with the grip pointing down over the place's spot nearest the base
    (`place_spot`), one message a bin."""
    return [m for _, m in _place_misses(robot, bins, items, placed, where, thrown=False)]


def place_miss(robot: Any, b: Any, tall_m: float, xy: Sequence[float]) -> tuple[float, np.ndarray]:
    """How far the nearest IK solution misses placing an item `tall_m` high into bin `b`
    (0 when the arm reaches both heights the place takes it through over the spot `xy`
    [m, W], `place_spot`, `_place_centres_z`), and the TCP position missed [m, W]."""
    miss, tcp = 0.0, np.zeros(3)
    for centre_z in _place_centres_z(b.rim_height, tall_m):
        tcp = np.array([xy[0], xy[1], _tcp_z(centre_z, STROKE_RANGE_M[0], tall_m)])
        miss = _reaches(robot, tcp)
        if miss != 0.0:
            break
    return miss, tcp


def tallest_m(b: Any, items: Sequence[Any]) -> float:
    """The height [m] of the tallest item the job sends to bin `b` (5 cm when none)."""
    return max((it.obj.size[2] for it in items if it.bin == b.id), default=CHECKED_CUBE_M)


def place_spot(b: Any, objs: Sequence[Any]) -> tuple[tuple[float, float], str, float]:
    """The place's own spot nearest the base in bin `b` (a `cell.jobs.BinSpec`) for the
    items `objs` (ObjectParams) sent there, and the item it is for: of each item's grid
    (`cell.arm.spots.floor_grid`, as `place_spots` lays it out, kept half its footprint and
    the place's wall margin, `place_wall_margin_m`, from the walls), the point nearest the
    base; of those, the one farthest from the base (x, y) [m, W], the item's name and how
    far in from the walls that grid is kept [m]. A place tries that point
    when its first spots are out of reach (`cell.arm.place.Place.spots_to_try`); where the
    arm does not reach it, it reaches none nearer. Whether the housing goes below the rim
    (its margin, `housing_below_rim`) is taken at the shortest stroke (`STROKE_RANGE_M`,
    the TCP lowest, as the poses checked); a place carries at `ArmTuning.pick_stroke_m`
    (45 mm) or shorter, its housing at most 15 mm higher. No item: a 5 cm cube's (its mass
    is read by nothing here)."""
    from cell.arm.spots import floor_grid, footprint_radius, housing_below_rim, place_wall_margin_m
    from cell.model.objects import ObjectParams
    from cell.sim.bins import BinSpec
    from cell.sim.mechanism import DEFAULT_GEOMETRY

    spec = BinSpec(b.id, tuple(b.position), tuple(b.size), b.rim_height)  # type: ignore[arg-type]
    cube = (CHECKED_CUBE_M,) * 3
    best: tuple[float, tuple[float, float], str, float] | None = None
    for o in objs or [ObjectParams("cube", 0.1, cube, f"{CHECKED_CUBE_M * 100:.0f} cm cube")]:
        h = float(o.size[2])
        tcp_z = _tcp_z(_place_centres_z(b.rim_height, h)[1], STROKE_RANGE_M[0], h)
        low = housing_below_rim(DEFAULT_GEOMETRY, tcp_z, b.rim_height)
        r, wall = footprint_radius(o), place_wall_margin_m(DEFAULT_GEOMETRY, o, low)
        xy = min(floor_grid(spec, r, wall), key=lambda p: math.hypot(*p))
        if best is None or math.hypot(*xy) > best[0]:
            best = (math.hypot(*xy), xy, o.name or f"ad hoc {o.shape}", r + wall)
    assert best is not None
    return best[1], best[2], best[3]


def _place_misses(
    robot: Any,
    bins: Sequence[Any],
    items: Sequence[Any],
    placed: Sequence[int],
    where: dict[str, str],
    *,
    thrown: bool,
) -> list[tuple[int, str]]:
    """(index, message) for each bin of `placed` the arm cannot place into; the message
    ends with what would do (`thrown`: that `auto` throws its items instead)."""
    out: list[tuple[int, str]] = []
    for i in placed:
        b = bins[i]
        xy, what, inset = place_spot(b, [it.obj for it in items if it.bin == b.id])
        miss, tcp = place_miss(robot, b, tallest_m(b, items), xy)
        if miss == 0.0:
            continue
        reach = _reach_m(robot, xy, float(tcp[2]))
        r_bin = math.hypot(xy[0], xy[1])
        if thrown:
            move = _move(reach, r_bin).removesuffix(", or ")
            tail = (
                "under policy auto its items are thrown into it instead (a throw is planned "
                "for each, as into a bin beyond limits.place_reach_m)"
                + (f"; to have them placed, {move}" if move else "")
            )
        else:
            tail = (
                f"{_move(reach, r_bin)}have its items thrown (policy: auto with "
                f"limits.place_reach_m below {math.hypot(*b.position):.2f} m)"
            )
        out.append(
            (
                i,
                f"{where.get(f'bins[{i}]', '?')}, bins[{i}].position_m: the {robot.name} arm "
                f"cannot place into bin {b.id!r}: the grip pointing down over the place's "
                f"spot nearest the base, {_fmt(xy)} m (for a {what}: its footprint and the "
                f"gripper's margin, {inset * 1000:.0f} mm, from the walls), TCP at "
                f"{_fmt(tcp)} m, is out of reach "
                f"({_missed(miss)}; "
                f"{_out(reach, r_bin)}): {tail}",
            )
        )
    return out


def _place_centres_z(rim_m: float, tall_m: float) -> tuple[float, float]:
    """The heights [m, W] of an item's centre (`tall_m` high) a place into a bin with its
    rim at `rim_m` takes it through (`cell.arm.place`): over the spot, then down on the
    floor plate, each with the place clearance under it."""
    from cell.arm.tuning import ArmTuning
    from cell.jobschema import BIN_WALL_M

    t = ArmTuning()
    down = BIN_WALL_M + tall_m / 2 + t.place_clearance_m
    return (down + max(t.lift_m, rim_m + OVER_RIM_M), down)


def job_problems(
    job: Any, where: dict[str, str], reach: bool = True
) -> tuple[list[str], list[str], frozenset[str]]:
    """What the job asks of its arm that it cannot do: a bin under the station, and (with
    `reach`, once nothing else is wrong) the station and the bins placed into out of the
    arm's reach, and an arm that cannot turn its throw axis up to level where the job
    throws (`cell.jobtilt`).

    A bin out of place reach is an error under `policy: place`; under `auto` (the cell
    places into a bin within `limits.place_reach_m`) its items are thrown instead, with a
    warning: the job's `Job.thrown_bins` (`cell.jobbins.places`), which the run's
    decisions and its check that every item can be sorted (`cell.arm.launch`) read.

    Args:
        job: the job (`cell.jobs.Job`, on the arm platform).
        where: "cell", "pick_station", "bins[i]" -> "file, line N".
        reach: check the arm's reach (IK) too.

    Returns:
        (errors, warnings, the ids of the bins within place reach `auto` throws into).
    """
    out = station_problems(job.pick_position, job.bins, where)
    warnings: list[str] = []
    thrown: set[str] = set()
    if reach and not out:
        chosen = [
            i
            for i, b in enumerate(job.bins)
            if job.policy == "auto" and math.hypot(*b.position) <= job.place_reach_m
        ]
        forced = list(range(len(job.bins))) if job.policy == "place" else []
        out += reach_problems(job.robot, job.pick_position, job.bins, job.items, forced, where)
        from cell.jobbins import places
        from cell.jobtilt import tilt_problems
        from cell.robot.model import load_robot

        robot = load_robot(job.robot)
        for i, m in _place_misses(robot, job.bins, job.items, chosen, where, thrown=True):
            warnings.append(m)
            thrown.add(job.bins[i].id)
        sent = {it.bin for it in job.items}
        throws = [
            i
            for i, b in enumerate(job.bins)
            if b.id in sent and not places(job.policy, job.place_reach_m, b, thrown)
        ]
        out += tilt_problems(robot, job.bins, throws, where)
    return out, warnings, frozenset(thrown)


def extents_mismatch(shape: str, size: Sequence[float]) -> str:
    """Why a sphere's or a cylinder's extents do not say one item ("" when they do): the
    scene builds a sphere and a cylinder of diameter size_m[0] (cell.sim.items), the planner
    holds all three extents."""
    same = {"sphere": (0, 1, 2), "cylinder": (0, 1)}.get(shape, ())
    if all(math.isclose(size[k], size[0], rel_tol=1e-3) for k in same):
        return ""
    what = (
        "a sphere's three extents are its diameter"
        if shape == "sphere"
        else "a cylinder's x and y extents are its diameter, z its length"
    )
    return (
        f"{list(size)} m: {what}; the scene would build a {shape} "
        f"{size[0] * 1000:.0f} mm across and the planner hold another"
    )


def items_fit(path: str, items: Sequence[Any], bins: Sequence[Any]) -> list[str]:
    """An error for each item narrower nowhere than its bin's opening: a box's (cylinder's,
    sphere's) narrowest width is its smallest extent, and it cannot come to rest inside a
    bin whose narrower side is less than that. Meshes are not checked (a mesh may be
    narrower than its box's smallest extent)."""
    by_id = {b.id: b for b in bins}
    out = []
    for it in items:
        b = by_id.get(it.bin)
        if b is None or it.obj.shape == "mesh":
            continue
        narrowest, opening = min(it.obj.size), min(b.size)
        if narrowest > opening:
            out.append(
                f"{path}, line {it.line}: item {it.obj.name} to bin {b.id!r}: its narrowest "
                f"extent, {narrowest * 1000:.0f} mm, is wider than the bin's opening, "
                f"{opening * 1000:.0f} mm across: it cannot come to rest inside; widen the "
                "bin or send the item to another bin"
            )
    return out


def unsorted_warning(job: Any) -> tuple[str, ...]:
    """A warning when limits.max_items leaves items of the job unsorted."""
    listed = sum(it.count for it in job.items)
    if listed <= job.max_items:
        return ()
    return (
        f"{job.path}: limits.max_items is {job.max_items} and the job lists {listed} items: "
        f"the first {job.max_items} are sorted, {listed - job.max_items} are left unsorted",
    )
