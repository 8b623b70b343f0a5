"""The steep tiers of the release bounds: into a low-rimmed bin a throw is planned first
with the throw axis steeply up (`ArmTuning.steep_rim_m`, `steep_elevation_rad`;
`cell.arm.planner.Planner._plan_facing` tries these tiers before the ordinary ones)."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from cell.arm.tuning import ArmTuning

__all__ = ["steep_tiers"]


def steep_tiers(
    tuning: ArmTuning, rim_height_m: float, ordinary: list[Any], shrunk: list[Any]
) -> tuple[tuple[list[Any], bool], ...]:
    """For a bin whose rim (`rim_height_m`) is lower than `ArmTuning.steep_rim_m`, the release bounds
    `ordinary` and `shrunk` (`Planner._release_bounds`) with the throw axis at least
    `ArmTuning.steep_elevation_rad` up, those left with an elevation range, tried
    before the others (`_plan_facing`): a throw that comes down steeply stays in a
    low-rimmed bin, where one that comes down at 50-58° skips off its floor (its
    landing within 3 cm of the aim, still 2.2 of its 2.9 m/s across, rising to
    0.09-0.13 m) and over the far rim. Where the band does not reach the bin so
    steeply, the ordinary bounds (a 141 g cube 2.0 m out reaches 1.46 m at 60°).
    Measured on tune layouts 8, 14 and 16 (docs/HISTORY.md, branch grip8): their
    cubes and cylinders thrown into 0.050-0.061 m rims 1.4-2.4 m out, 0 of 8 in
    the bin, 8 of 8 thrown at 60° and more (landing at 69-74°). None for another
    bin. Each tier with whether its first plan reached is kept (the shrunk boxes')."""
    e_min = tuning.steep_elevation_rad
    if rim_height_m >= tuning.steep_rim_m:
        return ()

    def raised(tier: list[Any]) -> list[Any]:
        return [
            replace(b, elevation_min=max(b.elevation_min, e_min))
            for b in tier
            if b.elevation_max >= e_min
        ]

    tiers = ((raised(ordinary), False), (raised(shrunk), True))
    return tuple((t, first) for t, first in tiers if t)
