"""With `cycle_search`, the lower release bounds (`ArmTuning.release_fallbacks`) are searched
after a plan in the cell's bounds only where that plan leaves room for a lower release to
be sooner (`ArmTuning.release_lower_room_s`, `Planner._lower_bounds_wanted`).

Independent checks: the room a plan reports is its timed cycle estimate less a lower bound
on it, so never negative (the bound is the arm's bang-bang limit, checked against
ruckig in tests/test_release_search_cost.py); with the rule off, or a threshold no plan is
under, every bounds is searched and the decision is the one without the rule, bit for bit;
with a threshold every plan is under, only the cell's bounds are, and the release chosen
is the full search's plan in the cell's bounds.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import pytest

from cell.arm.planner import Planner, ThrowChoice
from cell.arm.tuning import TUNING
from cell.orchestrator import Orchestrator
from tests.test_release_choice import JOB  # random layout 2's geometry (Panda)


@pytest.fixture(scope="module")
def orchestrator(orchestrator_on: Any) -> Any:
    return orchestrator_on(JOB, "low", cycle_search=True)


def _decide(o: Orchestrator, k: int, room: float | None) -> tuple[Any, list[ThrowChoice], int]:
    """Item k's decision with `release_lower_room_s = room`, the arm at rest where it is;
    the plans `_plan_in` made and how many release bounds it was asked to search."""
    spec = o.job.expanded_items()[k]
    o.present(k, spec.obj)
    made: list[ThrowChoice] = []
    asked = [0]
    plan_in = o._plan_in

    def watched(*a: Any, **kw: Any) -> ThrowChoice:
        asked[0] += 1
        made.append(plan_in(*a, **kw))
        return made[-1]

    kept = o.tuning
    o._plan_in = watched  # type: ignore[method-assign]
    o.tuning = dataclasses.replace(kept, release_lower_room_s=room)
    try:
        d = o.decide(k, spec.obj, o.job.bin(spec.bin))
    finally:
        o.__dict__.pop("_plan_in", None)
        o.tuning = kept
        o.scene.remove_item(o._presented)
    return d, made, asked[0]


@pytest.mark.parametrize("k", [0, 1])
def test_the_rule_skips_only_the_lower_bounds(orchestrator: Any, k: int) -> None:
    o = orchestrator
    full, made_full, asked_full = _decide(o, k, None)
    n_bounds = len(o._release_bounds(o.job.bin(o.job.expanded_items()[k].bin))[0])
    assert n_bounds == 1 + len(TUNING.release_fallbacks)
    assert asked_full >= n_bounds  # every ordinary bounds searched, each facing
    timed = [c for c in made_full if c.room_s is not None]
    assert timed
    for c in timed:  # an estimate is never under its own lower bound
        assert c.room_s >= -1e-9
        assert c.cost is not None and math.isfinite(c.cost[1])
    # a threshold no plan's room is under: the same searches, the same decision
    same, _, asked_same = _decide(o, k, -1.0)
    assert asked_same == asked_full
    np.testing.assert_array_equal(same.state.q_release, full.state.q_release)
    assert same.plan == full.plan
    # a threshold every plan is under: each facing searches the cell's bounds only, and
    # keeps the plan the full search made there
    cell, made_cell, asked_cell = _decide(o, k, 1e9)
    assert asked_cell < asked_full
    assert all(c.bounds.release_height == o.bounds.release_height for c in made_cell)
    firsts = [c for c in made_full if c.bounds.release_height == o.bounds.release_height]
    assert any(
        np.array_equal(cell.state.q_release, c.q_release) and cell.plan == c.plan for c in firsts
    )


def test_when_the_lower_bounds_are_wanted(orchestrator: Any) -> None:
    o = orchestrator
    first = ThrowChoice((False, 2.0), None, 0.0, np.zeros(7), None, np.zeros(3), None)
    kept = o.tuning
    try:
        o.tuning = dataclasses.replace(kept, release_lower_room_s=0.5)
        want = lambda c: Planner._lower_bounds_wanted(o, c)  # noqa: E731
        assert want(dataclasses.replace(first, room_s=0.6))  # the carry held back: search
        assert want(dataclasses.replace(first, room_s=0.5))
        assert not want(dataclasses.replace(first, room_s=0.1))  # near the arm's limits
        assert want(first)  # nothing timed: no room known
        assert want(dataclasses.replace(first, room_s=0.1, cost=(True, 2.0)))  # it slips
        assert want(dataclasses.replace(first, room_s=0.1, held=False))
        assert want(dataclasses.replace(first, room_s=0.1, cost=(False, math.inf)))
        assert want(dataclasses.replace(first, room_s=0.1, cost=None))
        o.tuning = dataclasses.replace(kept, release_lower_room_s=None)
        assert want(dataclasses.replace(first, room_s=0.1))  # the rule off: as before
        o.cycle_search = False
        assert not want(dataclasses.replace(first, room_s=9.0))  # the first reached is kept
    finally:
        o.tuning = kept
        o.cycle_search = True
