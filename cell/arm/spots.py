"""Where in a bin the arm sets an item down or aims a throw: the arm's place planning.

The plant only reports what the bin holds (`kept_items`, `item_position`, `item_aabb`) and
the bin's shape (`bin_spec`); the choice of a spot is the arm's. Each spot is a point of a
grid on the bin's floor (world frame W, metres), clear of what the bin already holds.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from cell.model.objects import ObjectParams
from cell.sim.bins import BinSpec

__all__ = [
    "SPOT_GRID",
    "THROW_CLEARANCE_M",
    "THROW_WALL_MARGIN_M",
    "clear_spots",
    "floor_grid",
    "footprint_radius",
    "housing_below_rim",
    "kept_circles",
    "place_spots",
    "place_wall_margin_m",
    "throw_spot",
]

THROW_CLEARANCE_M = 0.01  # [m] a throw's aim from an item the bin holds (throw_spot)
THROW_WALL_MARGIN_M = 0.03  # [m] a throw's aim from a wall when it is moved (throw_spot)
SPOT_GRID = 7  # candidates per side of a bin's floor (place_spots, throw_spot)
WALL_CLEAR_M = 0.01  # [m] the open pads (or the housing) kept this far from a bin's walls


def housing_below_rim(geometry: Any, tcp_z: float, rim_m: float) -> bool:
    """Is the housing of the end-effector (`cell.sim.mechanism.EEGeometry`) below a bin's
    rim (at `rim_m` [m]) + 1 cm with the grip pointing down and the TCP at height tcp_z [m]?"""
    return tcp_z + geometry.housing_to_tcp_m < rim_m + 0.01


def place_wall_margin_m(geometry: Any, obj: ObjectParams, housing_low: bool) -> float:
    """How far from a bin's walls a place keeps the item's footprint [m] (`place_spots`'s
    wall_margin_m): the pads that open beside the item (PLACE_OPENING_M) and 1 cm (5 mm: an
    open pad still met a tote's wall as the grip rose out of it); where the housing goes down
    below the rim (`housing_low`, a deep bin), 1 cm beyond the circle about its sides as
    well: its sides are wider than the pads (random layout 17: seven items placed into a
    0.25 m rim bin were knocked out of the grip as the housing met the bin's walls)."""
    from cell.endeffector.pybullet_backend import PLACE_OPENING_M

    pads = PLACE_OPENING_M + geometry.pad_thickness_m + WALL_CLEAR_M
    if housing_low:
        r_item = max(obj.size[0], obj.size[1]) / 2
        pads = max(pads, geometry.housing_radius_m + WALL_CLEAR_M - r_item)
    return float(pads)


def floor_grid(
    spec: BinSpec, r_m: float, wall_m: float, grid: int = SPOT_GRID
) -> list[tuple[float, float]]:
    """The grid x grid candidate spots (x, y) [m, W] of a bin's floor, kept `r_m` (half the
    item's footprint) plus `wall_m` [m] from its walls (`clear_spots`)."""
    hx = max(spec.size_xy[0] / 2 - r_m - wall_m, 0.0)
    hy = max(spec.size_xy[1] / 2 - r_m - wall_m, 0.0)
    c, s = np.cos(spec.yaw), np.sin(spec.yaw)
    return [
        (
            float(spec.center_xy[0] + c * x - s * y),
            float(spec.center_xy[1] + s * x + c * y),
        )
        for x in np.linspace(-hx, hx, grid)
        for y in np.linspace(-hy, hy, grid)
    ]


def kept_circles(plant: Any, bin_id: str) -> list[tuple[np.ndarray, float, float]]:
    """The items at rest in a bin, each as the circle that holds its footprint however it
    lies: its bounding box's centre [m, W] (3,), the half diagonal of its horizontal
    extent [m] and its top's height [m]."""
    out = []
    for it in plant.kept_items(bin_id):
        lo, hi = plant.item_aabb(it)
        out.append(((lo + hi) / 2, float(np.hypot(*(hi - lo)[:2])) / 2, float(hi[2])))
    return out


def footprint_radius(obj: ObjectParams) -> float:
    """The radius [m] of the circle that holds an item's footprint (its first two sizes)
    however it is turned about the vertical: half the footprint's diagonal."""
    return float(np.hypot(obj.size[0], obj.size[1])) / 2


def place_spots(
    plant: Any,
    bin_id: str,
    obj: ObjectParams,
    *,
    margin_m: float = 0.01,
    wall_margin_m: float | None = None,
    grid: int = SPOT_GRID,
) -> list[tuple[float, float, float]]:
    """Where in a bin of `plant` (a `cell.sim.CellScene`) to set an item down, clear of
    what the bin already holds: every candidate, best first (for a spot the arm does not
    reach, the next).

    Candidates are a grid x grid of points on the bin's floor, kept half the item's
    footprint plus `margin_m` from the walls. Of those that clear every item resting
    in the bin (footprints as circles of half the largest extent, plus the margin),
    the one nearest the bin's centre comes first (the centre itself in an empty bin);
    when none is clear, the one with the most room, on top of what lies under it.

    Args:
        plant: the scene (`bin_spec`, `kept_items`, `item_position`).
        bin_id: the bin.
        obj: the item to set down.
        margin_m: clearance from other items [m], and from the walls unless…
        wall_margin_m: … this is given [m] (room for the pads that open beside it).
        grid: candidates per side.

    Returns:
        [(x [m], y [m], z [m]) in W, ...]: the spots and the height of the surface under
        each (the floor plate's top, or the top of the items there).

    Raises:
        InvalidInput: no such bin.
    """
    spec = plant.bin_spec(bin_id)
    # each footprint as the circle that holds it, whatever way it is turned: an item
    # resting in the bin, its bounding box's (as `throw_spot`); the one set down, half its
    # footprint's diagonal. With half the largest side each, a 220 g tetrapack (63 x 40 x
    # 110 mm) set down beside another, lying, met it on the way down and left the pads
    # (issue 59)
    kept = kept_circles(plant, bin_id)
    held = [(c, r) for c, r, _ in kept]
    tops = [top for _, _, top in kept]
    wall = margin_m if wall_margin_m is None else wall_margin_m
    r_new = footprint_radius(obj)
    out = []
    for (x, y), room in clear_spots(spec, obj, held, margin_m, wall, grid, r_new_m=r_new):
        z = spec.wall
        if room < margin_m:  # crowded: on top of what lies under it
            for (p, r), top in zip(held, tops, strict=True):
                if np.hypot(x - p[0], y - p[1]) < r + r_new + margin_m:
                    z = max(z, top)
        out.append((x, y, float(z)))
    return out


def throw_spot(
    plant: Any,
    bin_id: str,
    obj: ObjectParams,
    *,
    margin_m: float = THROW_CLEARANCE_M,
    wall_margin_m: float = THROW_WALL_MARGIN_M,
    grid: int = SPOT_GRID,
    source_xy: Sequence[float] | None = None,
) -> tuple[float, float]:
    """Where in a bin of `plant` to aim a throw: the centre, unless the bin holds items
    there.

    Every item resting in the bin is an obstacle, its footprint the circle about its
    bounding box plus `margin_m`: a throw that lands on an item at rest bounces off
    that item's edges and faces, not off the floor, and out of a bin whose rim the
    pile nears. The aim is the grid point nearest the centre clear of every
    obstacle, kept half the thrown item's footprint plus `wall_margin_m` from the
    walls; of points as near, the one farthest from `source_xy` (the thrown item
    flies on past the aim as it descends: away from the obstacle that made it move);
    when none is clear, the one with the most room.

    Measured: an item standing above the rim turned a 60 mm cylinder out of a 55 mm
    rim bin (0.22-0.25 m off); of four 60 mm cubes thrown at a 121 mm rim bin, the
    three thrown onto the first bounced out (random layout 18: 19 → 22 of 27 items
    counting all). Counting only items whose top rose above the thrown item's
    underside, or whose top would put the thrown item stacked on them above the rim,
    kept 35 and 34 of random layout 6's 40 items in their bins; counting all, 39.

    Args:
        plant: the scene (`bin_spec`, `kept_items`, `item_aabb`, `robot_base_xyz`).
        bin_id: the bin.
        obj: the item to throw.
        margin_m: clearance from an obstacle [m].
        wall_margin_m: clearance from the walls [m] (the spread of the landings).
        grid: candidates per side.
        source_xy: where the throw comes from (x, y) [m] in W; None: the arm's base.

    Returns:
        (x [m], y [m]) in W: the point of the rim plane to aim at.

    Raises:
        InvalidInput: no such bin.
    """
    spec = plant.bin_spec(bin_id)
    held = [(c, r) for c, r, _ in kept_circles(plant, bin_id)]
    if not held:
        return float(spec.center_xy[0]), float(spec.center_xy[1])
    source = plant.robot_base_xyz[:2] if source_xy is None else source_xy
    xy, _ = clear_spots(spec, obj, held, margin_m, wall_margin_m, grid, source)[0]
    return xy


def clear_spots(
    spec: BinSpec,
    obj: ObjectParams,
    held: list[tuple[np.ndarray, float]],
    margin_m: float,
    wall_m: float,
    grid: int,
    source_xy: Sequence[float] | None = None,
    r_new_m: float | None = None,
) -> list[tuple[tuple[float, float], float]]:
    """The grid points of a bin's floor, each with its room [m] from every (centre,
    radius) in `held`, best first: those with `margin_m` of room, nearest the centre
    first (of points as near, the farthest from `source_xy`, if given), then the
    others, most room first. Points keep half the item's footprint plus `wall_m` from
    the walls (`r_new_m`: the radius [m] of its footprint's circle; default half its
    larger side)."""
    r_new = max(obj.size[0], obj.size[1]) / 2 if r_new_m is None else r_new_m
    cands = floor_grid(spec, r_new, wall_m, grid)

    def room(xy: tuple[float, float]) -> float:
        return min(
            (float(np.hypot(xy[0] - p[0], xy[1] - p[1])) - r - r_new for p, r in held),
            default=np.inf,
        )

    def nearness(xy: tuple[float, float]) -> tuple[float, float]:
        off = round(float(np.hypot(xy[0] - spec.center_xy[0], xy[1] - spec.center_xy[1])), 6)
        if source_xy is None:
            return off, 0.0
        return off, -float(np.hypot(xy[0] - source_xy[0], xy[1] - source_xy[1]))

    scored = [(xy, room(xy)) for xy in cands]
    clear = sorted((c for c in scored if c[1] >= margin_m), key=lambda c: nearness(c[0]))
    crowded = sorted((c for c in scored if c[1] < margin_m), key=lambda c: -c[1])
    return clear + crowded
