"""The steep tiers of the release bounds: into a low-rimmed bin a throw is planned first
with the throw axis steeply up (`ArmTuning.steep_rim_m`, `steep_elevation_rad`;
`cell.arm.planner.Planner._plan_to` tries these tiers, at each facing, before the
ordinary ones), and the tests a plan in them must pass to be kept (`steep_shortfall`)."""

from __future__ import annotations

import logging
import math
from dataclasses import replace
from typing import Any

from cell.arm.choice import grip_short
from cell.arm.grip_limits import carry_hold
from cell.arm.joints import twist
from cell.arm.tuning import ArmTuning
from cell.model.objects import ObjectParams

__all__ = ["steep_kept", "steep_shortfall", "steep_tiers"]

log = logging.getLogger(__name__)


def steep_tiers(
    tuning: ArmTuning, rim_height_m: float, ordinary: list[Any], shrunk: list[Any]
) -> tuple[tuple[list[Any], bool], ...]:
    """For a bin whose rim (`rim_height_m`) is lower than `ArmTuning.steep_rim_m`, the release bounds
    `ordinary` and `shrunk` (`Planner._release_bounds`) with the throw axis at least
    `ArmTuning.steep_elevation_rad` up, those left with an elevation range, tried
    before the others (`Planner._plan_to`): a throw that comes down steeply stays in a
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


def steep_shortfall(
    choice: Any, short: str | None, at_points: bool, robot: Any, tuning: ArmTuning
) -> str | None:
    """Why the plan `choice` (a `ThrowChoice`) found in a steep tier is not kept, the
    ordinary bounds planned instead unless another facing's is kept (`Planner._plan_to`);
    None where it is. The steep tier is a preference, not the cell's last resort: its
    plan must pass what an ordinary plan is searched past for (`short`, what
    `cell.arm.choice.grip_short` says of it: its route asks more of the grip than it holds, or its
    release does not hold the item still).

    For an item held at points (`at_points`: a sphere, a mesh) carried level, that route
    test asks nothing (`GripUse._swing_static`: any roll turns it, the twist-free swing is
    all a route can do for it): its carry must instead turn the grip no more than
    `ArmTuning.steep_twist_max_rad` off the one rotation between its ends
    (`cell.arm.joints.twist`, `_direct_is_better`'s measure), along the route the release
    search judged (`ThrowChoice.route`). A steep release the level swing cannot reach
    without going round is carried along the spline between the ends: a 43 mm sphere's
    into a bin behind the arm turned the grip 52° and 132° in the scene (tests/
    test_swing_twist.py; its routes 112-121° so measured, the ordinary releases' 21-31°).
    A box's or a cylinder's level swing is not about one axis (the grip turns in azimuth
    on the way up): 58-67° so measured on ordinary routes the pads hold, the grip use
    held still its test."""
    if short is not None:
        return short
    if not at_points or choice.route is None:
        return None
    turned = twist(robot, list(choice.route), tuning.swing_check_samples)
    if turned > tuning.steep_twist_max_rad:
        return (
            f"its carry turns the grip {math.degrees(turned):.0f}° off one rotation "
            f"(at most {math.degrees(tuning.steep_twist_max_rad):.0f}° for an item held at "
            "points)"
        )
    return None


def steep_kept(choice: Any, obj: ObjectParams, params: Any, robot: Any, tuning: ArmTuning) -> bool:
    """Is the steep tiers' plan `choice` for `obj` kept (`steep_shortfall`; `params` the
    model's, for whether the pads hold `obj` at points at its stroke)? Where not, why is
    logged, and `Planner._plan_to` plans the ordinary bounds unless another facing's
    steep plan is kept."""
    at_points = carry_hold(params, obj, choice.plan.stroke_m + choice.delta).torque_nm <= 0.0
    why = steep_shortfall(choice, grip_short(choice), at_points, robot, tuning)
    if why is not None:
        log.info(
            "%s: the steep release (%.0f° up) is not kept: %s",
            obj.name or obj.shape,
            math.degrees(choice.plan.elevation_rad),
            why,
        )
    return why is None
