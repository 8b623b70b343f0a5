"""`cell.robot.motion._within_by_speed`: a jerk-limited move it clears without sampling
stays within the joint limits however densely it is sampled (the bound is sound), and
`_ruckig` then finds what sampling would (the planner's speed-up changes no plan)."""

from __future__ import annotations

import numpy as np
import pytest

from cell.errors import TrajectoryError
from cell.robot.model import load_robot
from cell.robot.motion import _ruckig, _within_by_speed
from cell.robot.trajectory import POSITION_TOL_RAD


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_cleared_moves_stay_within_the_limits(name: str) -> None:
    rb = load_robot(name)
    lim = rb.limits
    lower, upper = lim.lower - POSITION_TOL_RAD, lim.upper + POSITION_TOL_RAD
    rng = np.random.default_rng(0)
    zero = np.zeros(rb.dof)
    cleared = sampled = 0
    for i in range(300):
        p0 = rb.random_configuration(rng, 1)[0]
        p1 = np.clip(p0 + rng.normal(0.0, 0.4 if i % 2 else 1.5, rb.dof), lim.lower, lim.upper)
        vmax = lim.velocity * rng.uniform(0.3, 1.0)
        amax = lim.acceleration * rng.uniform(0.3, 1.0)
        v1 = zero
        if i % 3 == 0:  # passing the target on the move, as an approach passes over the pick
            d = p1 - p0
            v1 = np.clip(d / np.max(np.abs(d) / vmax) * rng.uniform(0.0, 0.5), -vmax, vmax)
        try:
            tr = _ruckig(rb, p0, zero, zero, p1, v1, vmax, amax, lim.jerk, velocity_interface=False)
        except TrajectoryError:
            continue
        if not _within_by_speed(p0, p1, vmax, tr.duration, lower, upper):
            sampled += 1
            continue
        cleared += 1
        q = tr.sample_many(np.linspace(0.0, tr.duration, 2000))[0]
        assert np.all(q >= lower) and np.all(q <= upper)
        lo, hi = tr.position_bounds(amax)
        assert np.all(lo >= lower) and np.all(hi <= upper)
    assert cleared > 20 and sampled > 20  # both ways taken


def test_a_move_near_a_limit_is_not_cleared() -> None:
    rb = load_robot("panda")
    lim = rb.limits
    p0 = (lim.lower + lim.upper) / 2
    p1 = p0.copy()
    p1[0] = lim.upper[0] - 1e-3
    assert not _within_by_speed(p0, p1, lim.velocity, 2.0, lim.lower, lim.upper)
    assert not _within_by_speed(p0, p0, lim.velocity, float("inf"), lim.lower, lim.upper)
