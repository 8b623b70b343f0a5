"""A throw as the planner chose it (`ThrowChoice`), and how such plans compare: the
soonest of several release bounds' (`soonest_of`), and how one falls short of the grip
(`grip_short`). `cell.arm.planner.Planner` makes them."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.model.objects import ObjectParams

__all__ = ["ThrowChoice", "grip_short", "sooner_beat", "soonest_of"]


@dataclass(frozen=True)
class ThrowChoice:
    """A throw as the planner chose it: the plan in one release bounds and its release.
    `Planner._plan` returns one; the release bounds compare them (`_plan_facing`).

    Attributes:
        cost: (asks more of the grip than it holds, cycle estimate [s]), or None where no
            estimate was made.
        plan: the static throw plan (`cell.optimize.ThrowPlan`).
        delta: [m] the learned ΔL_s (the residual's), added to the plan's stroke.
        q_release: [rad] the release configuration chosen.
        bounds: the release bounds it was planned in (the grip's cap not applied).
        aim: [m, W] where the plan aims to cross the rim plane (the goal, or the learned aim).
        model_obj: the object as the plan's model assumed it.
        goal: [m, W] the point of the rim plane the throw is for (`throw_spot`); None until
            `_plan` has set it.
        held: the pads hold the item still at the release, at the throw's stroke
            (`Planner._held_at_release`).
        room_s: [s] the release's cycle estimate less its lower bound (the carry's
            bang-bang bound, the settle, the push, the way back and the approach's share:
            `ReleaseChoice._way_bound_s`), how much slower than the arm's limits the carry
            is; None where no release was timed (`Planner._lower_bounds_wanted`).
        route: [rad] the release's carry route from the lift where the item is carried
            level (`ReleaseChoice._release_route`: the route `cost`'s grip use is judged
            on); None elsewhere, or where no release was timed.
    """

    cost: tuple[bool, float] | None
    plan: Any
    delta: float
    q_release: np.ndarray
    bounds: Any
    aim: np.ndarray
    model_obj: ObjectParams
    goal: np.ndarray | None = None
    held: bool = True
    room_s: float | None = None
    route: tuple[np.ndarray, ...] | None = None


def sooner_beat(a: float | None, b: float | None) -> float | None:
    """The sooner of two cycle estimates to beat [s] (None: none)."""
    if a is None:
        return b
    return a if b is None else min(a, b)


def soonest_of(found: list[ThrowChoice]) -> ThrowChoice:
    """Of the plans `found` in the release bounds in `Planner._release_bounds`' order, the
    first, unless a later one's cycle estimate is sooner and its route asks no more of
    the grip than the first's (and, where the first's release holds the item still,
    its release does too: `ThrowChoice.held`); the first where an estimate is missing."""
    first = best = found[0]
    for r in found[1:]:
        if first.cost is None or r.cost is None or best.cost is None:
            continue
        if r.held < first.held:
            continue
        if r.cost[0] <= first.cost[0] and r.cost < best.cost:
            best = r
    return best


def grip_short(r: ThrowChoice) -> str | None:
    """How the plan `r` falls short of the grip, or None: its route asks more of the
    grip than it holds (`ThrowChoice.cost`'s first), or its release does not hold the
    item still (`ThrowChoice.held`). A plan in the cell's bounds so short has the
    lower bounds searched after it (`Planner._lower_bounds_wanted`) and is not kept over one
    that is not (`soonest_of`); a steep tier's is not kept (`cell.arm.steep.steep_shortfall`)."""
    if r.cost is not None and r.cost[0]:
        return "its route asks more of the grip than it holds"
    if not r.held:
        return "its release does not hold the item still"
    return None
