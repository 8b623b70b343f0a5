"""A bin's rim too low to keep a thrown item: the job's load-time warning.

A thrown item lands moving: it slides or rolls across the bin's floor plate into a wall.
A wall whose top stands lower above the plate than the item's centre of mass rests (half
its smallest extent: a sphere's radius, a box on its largest face) meets the item under
its centre, where it trips a box over it or lifts a ball onto it, and the faster the
item arrives the likelier it goes over. Measured in the scene (docs/HISTORY.md, 2026-12-02,
branch `robjob65`): a sphere40 (20 mm radius) thrown 2.5 m rolled out of a 0.40 m bin
with a 0.02 m rim (a 10 mm wall), and stayed in one with a 0.03 m rim; a cube50 thrown 4 m
slid out of a 0.50 m bin with a 0.02 m rim, landed 0.011 m from its aim; thrown 1.6 and
2.5 m it stayed in. A warning only: no decision changes. A placed item is set down on the
plate, not thrown, and is not warned of.
"""

from __future__ import annotations

from typing import Any

from cell.jobbins import places
from cell.jobschema import BIN_WALL_M

__all__ = ["low_rim_warnings", "resting_centre_m"]


def resting_centre_m(size: Any) -> float:
    """[m] The lowest height an item's centre of mass rests at on a flat floor: half its
    smallest extent (a box on its largest face, a sphere's or a lying cylinder's radius;
    a mesh's box is taken for it)."""
    return min(float(s) for s in size) / 2.0


def low_rim_warnings(job: Any) -> tuple[str, ...]:
    """A warning for each item line thrown (not placed: `cell.jobbins.places`) into a bin
    whose wall stands above its floor plate (`rim_height_m` less the plate's `BIN_WALL_M`)
    lower than the item's centre rests (`resting_centre_m`)."""
    out = []
    for it in job.items:
        b = job.bin(it.bin)
        if places(job.policy, job.place_reach_m, b, job.thrown_bins):
            continue
        wall = b.rim_height - BIN_WALL_M
        centre = resting_centre_m(it.obj.size)
        if wall >= centre - 1e-9:
            continue
        out.append(
            f"{job.path}, line {it.line}: the wall of bin {it.bin!r} stands {wall * 1000:.0f} "
            f"mm above its floor plate (rim_height_m {b.rim_height:g} less the plate's "
            f"{BIN_WALL_M:g} m), under the {centre * 1000:.0f} mm at which {it.obj.name}'s "
            "centre rests: thrown, it lands moving and may slide or roll over the wall "
            "(a sphere40 thrown 2.5 m rolled out of a 0.40 m bin with a 0.02 m rim, a cube50 "
            "thrown 4 m slid out of a 0.50 m one); a rim of at least "
            f"{centre + BIN_WALL_M:.3g} m keeps the item's centre under the wall's top"
        )
    return tuple(out)
