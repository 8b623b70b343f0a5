"""The steep tier's plan is held to the ordinary plans' tests (`cell.arm.steep.steep_shortfall`,
`cell.arm.choice.grip_short`, `Planner._plan_to`): where it falls short, the ordinary bounds' plan.

Independent checks: the twist of a joint path measured with scipy's rotations from the
arm's forward kinematics (`tests.test_swing_twist.twist_deg`), and the decision the cell
makes with the steep rule off (the ordinary bounds alone), which a steep plan that falls
short must give bit for bit.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import pytest

from cell.arm.choice import ThrowChoice, grip_short
from cell.arm.steep import steep_shortfall
from cell.arm.tuning import TUNING
from tests.test_reach_kept import decide_presented
from tests.test_swing_twist import JOB, twist_deg  # random layout 4 (Panda): spheres


@pytest.fixture(scope="module")
def orchestrator(orchestrator_on: Any) -> Any:
    return orchestrator_on(JOB, "steep_checks", cycle_search=True)


def _choice(cost: Any = (False, 2.0), held: bool = True, route: Any = None) -> ThrowChoice:
    return ThrowChoice(
        cost, None, 0.0, np.zeros(7), None, np.zeros(3), None, held=held, route=route
    )  # type: ignore[arg-type]


def test_a_plan_short_of_the_grip_is_named() -> None:
    assert grip_short(_choice()) is None
    assert grip_short(_choice(cost=None)) is None  # no estimate: nothing to judge
    assert "asks more of the grip" in str(grip_short(_choice(cost=(True, 2.0))))
    assert "does not hold the item still" in str(grip_short(_choice(held=False)))
    # and so the steep tier's plan is not kept, whatever its route
    assert steep_shortfall(_choice(), "short", False, None, TUNING) == "short"


def test_the_twist_bound_is_for_items_held_at_points(orchestrator: Any) -> None:
    rb = orchestrator.robot
    q0 = np.asarray(rb.home, float)
    q1 = q0.copy()
    q1[-1] += 1.2  # the flange about its own axis: no twist
    about_one = (q0, q1)
    mid = (q0 + q1) / 2
    mid[-2] += 1.2  # out of that rotation and back
    off = (q0, mid, q1)
    assert twist_deg(rb, np.asarray(about_one)) < 1.0
    # the spline through `off`, sampled as the carry follows it, turns the grip far off
    from cell.robot.motion import spline_path

    qs = np.asarray(
        spline_path(list(off), rb.limits.lower, rb.limits.upper)(np.linspace(0, 1, 200))
    )
    assert twist_deg(rb, qs) > 45.0
    assert steep_shortfall(_choice(route=about_one), None, True, rb, TUNING) is None
    why = steep_shortfall(_choice(route=off), None, True, rb, TUNING)
    assert why is not None and "off one rotation" in why
    # a box's level swing is judged by its grip use held still, not by this
    assert steep_shortfall(_choice(route=off), None, False, rb, TUNING) is None
    assert steep_shortfall(_choice(route=None), None, True, rb, TUNING) is None
    loose = dataclasses.replace(TUNING, steep_twist_max_rad=math.pi)
    assert steep_shortfall(_choice(route=off), None, True, rb, loose) is None


def test_a_steep_plan_that_twists_falls_through_to_the_ordinary_one(orchestrator: Any) -> None:
    """The 43 mm sphere into a 0.051 m rim behind the arm: its steep release's carry turns
    the grip 112-121° (the level swing goes round); the decision is the one the ordinary
    bounds alone make. With the twist bound lifted, the steep plan is kept (60° up)."""
    o = orchestrator
    kept = o.tuning
    try:
        with_rule = decide_presented(o, 0)
        o.tuning = dataclasses.replace(kept, steep_rim_m=0.0)
        without = decide_presented(o, 0)
        o.tuning = dataclasses.replace(kept, steep_twist_max_rad=math.pi)
        lifted = decide_presented(o, 0)
    finally:
        o.tuning = kept
    assert with_rule.plan == without.plan
    np.testing.assert_array_equal(with_rule.state.q_release, without.state.q_release)
    assert without.plan.elevation_rad < TUNING.steep_elevation_rad
    assert lifted.plan.elevation_rad >= TUNING.steep_elevation_rad - 1e-9
