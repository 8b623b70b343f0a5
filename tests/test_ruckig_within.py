"""`cell.robot.ruckig_move._within_by_speed`: a jerk-limited move it clears without sampling
stays within the joint limits however densely it is sampled (the bound is sound), and
`_ruckig` then finds what sampling would (the planner's speed-up changes no plan)."""

from __future__ import annotations

import numpy as np
import pytest

from cell.errors import TrajectoryError
from cell.robot.model import load_robot
from cell.robot.ruckig_move import _ruckig, _within_by_speed
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


def _moves(rb, rng, count):  # type: ignore[no-untyped-def]
    """Random ruckig moves of `_ruckig`: from rest, moving, accelerating, on the velocity
    interface (a stop), some from a joint at its limit, some passing the target moving."""
    lim = rb.limits
    zero = np.zeros(rb.dof)
    for i in range(count):
        p0 = rb.random_configuration(rng, 1)[0]
        if i % 4 == 1:  # one joint waiting at a limit, as an IK answer clamped to it
            j = int(rng.integers(rb.dof))
            p0[j] = lim.upper[j] if i % 8 == 1 else lim.lower[j]
        p1 = np.clip(p0 + rng.normal(0.0, 0.4 if i % 2 else 1.5, rb.dof), lim.lower, lim.upper)
        vmax = lim.velocity * rng.uniform(0.3, 1.0)
        amax = lim.acceleration * rng.uniform(0.3, 1.0)
        v0 = a0 = v1 = zero
        if i % 3 == 0:
            d = p1 - p0
            v1 = np.clip(d / np.max(np.abs(d) / vmax) * rng.uniform(0.0, 0.5), -vmax, vmax)
        if i % 5 == 2:
            v0 = rng.uniform(-0.5, 0.5, rb.dof) * vmax
            a0 = rng.uniform(-0.5, 0.5, rb.dof) * amax if i % 10 == 2 else zero
        stop = i % 7 == 3
        if stop:
            v0, p1 = rng.uniform(-0.8, 0.8, rb.dof) * vmax, p0
        try:
            tr = _ruckig(
                rb,
                p0,
                v0,
                a0,
                p1,
                zero if stop else v1,
                vmax,
                amax,
                lim.jerk,
                velocity_interface=stop,
            )
        except TrajectoryError:
            continue
        yield tr, amax


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_moves_stays_within_clears_keep_within_the_limits(name: str) -> None:
    """`RuckigTrajectory.stays_within` is sound: a move it clears has every sample of a
    dense sampling (5,000) and `position_bounds`'s extrema within the limits; and it
    clears most moves, those from a joint waiting at its limit included."""
    rb = load_robot(name)
    lim = rb.limits
    lower, upper = lim.lower - POSITION_TOL_RAD, lim.upper + POSITION_TOL_RAD
    rng = np.random.default_rng(1)
    cleared = moves = 0
    for tr, amax in _moves(rb, rng, 160):
        moves += 1
        if not tr.stays_within(amax, lower, upper):
            continue
        cleared += 1
        q = tr.sample_many(np.linspace(0.0, tr.duration, 5000))[0]
        assert np.all(q >= lower) and np.all(q <= upper)
        lo, hi = tr.position_bounds(amax, within=(lower, upper))
        assert np.all(lo >= lower) and np.all(hi <= upper)
    assert moves > 100 and cleared > 0.8 * moves


def test_stays_within_does_not_clear_a_peak_between_its_samples() -> None:
    """Moves that start moving away from their targets turn back between samples: a bound
    set just under a joint's true extremum there (found densely), which its first 16
    samples stay under, is not cleared; set just over it, it is."""
    rb = load_robot("panda")
    lim = rb.limits
    rng = np.random.default_rng(2)
    zero = np.zeros(rb.dof)
    checked = 0
    for _ in range(12):
        p0 = (lim.lower + lim.upper) / 2 + rng.uniform(-0.3, 0.3, rb.dof)
        p1 = p0 + rng.uniform(-0.5, 0.5, rb.dof)
        v0 = -np.sign(p1 - p0) * rng.uniform(0.2, 0.6, rb.dof) * lim.velocity
        a0 = rng.uniform(-0.3, 0.3, rb.dof) * lim.acceleration
        tr = _ruckig(
            rb,
            p0,
            v0,
            a0,
            p1,
            zero,
            lim.velocity,
            lim.acceleration,
            lim.jerk,
            velocity_interface=False,
        )
        q = tr.sample_many(np.linspace(0.0, tr.duration, 50001))[0]
        coarse = tr._positions(np.linspace(0.0, tr.duration, 16))
        for j in range(rb.dof):
            for sign in (1.0, -1.0):
                top = float(np.max(sign * q[:, j]))
                if top - float(np.max(sign * coarse[:, j])) < 1e-6:
                    continue  # the extremum is (nearly) a sample's
                checked += 1
                hi, lo = lim.upper + 10.0, lim.lower - 10.0
                (hi if sign > 0 else lo)[j] = sign * (top - 1e-9)
                assert not tr.stays_within(lim.acceleration, lo, hi)
                (hi if sign > 0 else lo)[j] = sign * (top + 1e-6)
                assert tr.stays_within(lim.acceleration, lo, hi, most=4000)
    assert checked > 10
