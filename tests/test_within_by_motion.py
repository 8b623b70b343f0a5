"""`cell.robot.motion._within_by_motion`: the bound that lets `_ruckig` skip sampling a
move's positions (`RuckigTrajectory.position_bounds`).

Independent check: random ruckig moves of the Panda and the UR5 (from rest and from a
moving start, to rest and to a moving end, at reduced scales too), their extrema found
by sampling and refining (`position_bounds`, every joint): where a joint's limit is put
just inside the extremum the move reaches, the bound must not say the move stays
within its limits. And it must be of use: it clears moves `_within_by_speed` does not.
"""

from __future__ import annotations

import numpy as np
import pytest

from cell.errors import TrajectoryError
from cell.robot.model import load_robot
from cell.robot.motion import _ruckig, _within_by_motion, _within_by_speed


def _moves(name: str, n: int, seed: int) -> list[tuple[np.ndarray, ...]]:
    rb = load_robot(name)
    lim = rb.limits
    rng = np.random.default_rng(seed)
    out = []
    mid, half = (lim.lower + lim.upper) / 2, (lim.upper - lim.lower) / 2
    while len(out) < n:
        scale = rng.choice([1.0, 0.6, 0.3])
        vmax, amax, jmax = lim.velocity * scale, lim.acceleration * scale, lim.jerk * scale
        p0 = mid + rng.uniform(-0.6, 0.6, rb.dof) * half
        p1 = mid + rng.uniform(-0.6, 0.6, rb.dof) * half
        # rest to rest, a moving start, a moving end, both (and a0), and a fast start
        # back to about where it began (it brakes, turns and comes back)
        kind = len(out) % 5
        v0 = rng.uniform(-0.8, 0.8, rb.dof) * vmax if kind in (1, 3) else np.zeros(rb.dof)
        if kind == 4:
            p1 = p0 + rng.uniform(-0.02, 0.02, rb.dof) * half
            v0 = rng.choice([-1.0, 1.0], rb.dof) * rng.uniform(0.7, 1.0, rb.dof) * vmax
        v1 = rng.uniform(-0.8, 0.8, rb.dof) * vmax if kind in (2, 3) else np.zeros(rb.dof)
        a0 = rng.uniform(-0.5, 0.5, rb.dof) * amax if kind == 3 else np.zeros(rb.dof)
        try:
            traj = _ruckig(rb, p0, v0, a0, p1, v1, vmax, amax, jmax, velocity_interface=False)
        except TrajectoryError:
            continue  # past the model's limits: not a move the cell would make
        lo, hi = traj.position_bounds(amax)  # every joint refined
        out.append((p0, v0, a0, p1, v1, vmax, amax, traj.duration, lo, hi))
    return out


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_no_move_the_bound_clears_passes_a_limit(name: str) -> None:
    moves = _moves(name, 150, 7)
    for p0, v0, a0, p1, v1, vmax, amax, dur, lo, hi in moves:
        wide_lo, wide_hi = lo - 1.0, hi + 1.0
        for j in range(len(p0)):
            # joint j's upper (then lower) limit 1 µrad inside what the move reaches
            upper = wide_hi.copy()
            upper[j] = hi[j] - 1e-6
            assert not _within_by_motion(p0, v0, a0, p1, v1, vmax, amax, dur, wide_lo, upper)
            lower = wide_lo.copy()
            lower[j] = lo[j] + 1e-6
            assert not _within_by_motion(p0, v0, a0, p1, v1, vmax, amax, dur, lower, wide_hi)
    # of use: against the arm's own limits, the moves from rest to rest it clears and
    # those the speed bound alone clears (Panda 12 and 7 of 30, UR5 20 and 12), and
    # the others (86 and 87 of 120)
    lim = load_robot(name).limits
    by_speed = by_motion = others = 0
    for p0, v0, a0, p1, v1, vmax, amax, dur, _, _ in moves:
        cleared = _within_by_motion(p0, v0, a0, p1, v1, vmax, amax, dur, lim.lower, lim.upper)
        if not (np.any(v0) or np.any(v1) or np.any(a0)):
            by_speed += _within_by_speed(p0, p1, vmax, dur, lim.lower, lim.upper)
            by_motion += cleared
        else:
            others += cleared
    assert by_motion > by_speed, (by_motion, by_speed)
    assert others > 0


def test_a_start_outside_the_limits_is_not_cleared() -> None:
    z, one = np.zeros(2), np.ones(2)
    wide = (-10 * one, 10 * one)
    assert _within_by_motion(z, z, z, 0.1 * one, z, one, one, 1.0, *wide)
    assert not _within_by_motion(z, 1.5 * one, z, 0.1 * one, z, one, one, 1.0, *wide)
    assert not _within_by_motion(z, z, z, 0.1 * one, -1.5 * one, one, one, 1.0, *wide)
    assert not _within_by_motion(z, z, 2 * one, 0.1 * one, z, one, one, 1.0, *wide)
    assert not _within_by_motion(z, z, z, 0.1 * one, z, one, one, float("inf"), *wide)
