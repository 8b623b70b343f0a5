"""Carrying without slip (cell.robot.carry), the paths alone: the item's acceleration from
Pinocchio against a closed form and finite differences, the planned path against its bound,
a tall item's grip use against its closed form, the lift on the pick's IK branch. The scene's
side is tests/test_carry.py."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cell.arm.tuning import TUNING
from cell.errors import TrajectoryError
from cell.jobs import parse_job
from cell.model.params import G
from cell.orchestrator import Orchestrator
from cell.robot.carry import (
    CARRY_MARGIN,
    GripHold,
    grip_use,
    item_accelerations,
    peak_specific_force,
    plan_carry,
)
from cell.robot.model import load_robot
from cell.robot.motion import plan_path


def test_item_acceleration_matches_the_closed_form_of_a_turning_base():
    """Joint 1 turning at a constant rate ω (the Panda's first axis is the world's z
    through the origin): a point at horizontal radius r has a = ω² r toward the axis."""
    rb = load_robot("panda")
    q = rb.home.copy()
    w = 1.3  # [rad/s]
    dq = np.zeros(rb.dof)
    dq[0] = w
    offset = (0.0, 0.0, 0.04)
    a = item_accelerations(rb, q[None], dq[None], np.zeros((1, rb.dof)), offset)[0]
    p_tcp, r_tcp = rb.tcp_pose(q)
    p = p_tcp + r_tcp @ np.array(offset)
    radial = np.array([p[0], p[1], 0.0])
    np.testing.assert_allclose(a, -(w**2) * radial, atol=1e-9)


def test_item_acceleration_matches_finite_differences_along_a_path():
    rb = load_robot("panda")
    q0 = rb.home
    q1 = q0 + np.array([0.6, -0.3, 0.2, 0.4, -0.5, 0.3, 0.8])
    tr = plan_path([q0, q1], rb)
    offset = (0.01, -0.02, 0.05)
    ts = np.linspace(0.2 * tr.duration, 0.8 * tr.duration, 7)
    h = 1e-4
    qs, dqs, ddqs = tr.sample_many(ts)
    a = item_accelerations(rb, qs, dqs, ddqs, offset)

    def point(t: float) -> np.ndarray:
        p, r = rb.tcp_pose(tr.sample(t)[0])
        return p + r @ np.array(offset)

    fd = np.array([(point(t + h) - 2 * point(t) + point(t - h)) / h**2 for t in ts])
    # toppra's piecewise-constant path acceleration makes q̈ jump at grid points: compare
    # where the second difference does not straddle one (most samples)
    close = np.linalg.norm(a - fd, axis=1) < 1e-2 * (1 + np.linalg.norm(a, axis=1))
    assert close.sum() >= 5


def _hold(force_n: float, mass_kg: float = 0.05) -> GripHold:
    """A grip that only slips (no turning: a huge couple)."""
    return GripHold(force_n, 1e9, mass_kg, 1e-5, (0.0, 0.0, 0.0), 0.0)


def test_the_carry_path_keeps_under_its_bound_and_slows_for_a_tighter_one():
    rb = load_robot("panda")
    q0 = rb.home
    q1 = q0 + np.array([0.8, -0.4, 0.3, 0.5, -0.9, 0.4, 0.6])
    free = plan_path([q0, q1], rb)
    peak_free = peak_specific_force(free, rb)
    m = 0.05
    for frac in (0.8, 0.5):
        f_max = G + frac * (peak_free - G)  # the specific force the carry may ask [m/s²]
        hold = _hold(m * f_max * CARRY_MARGIN, m)
        tr, use = plan_carry([q0, q1], rb, hold)
        assert use <= 1 / CARRY_MARGIN + 1e-12
        assert peak_specific_force(tr, rb, n=801) <= f_max * 1.02  # finer sampling
        assert tr.duration > free.duration
    with pytest.raises(TrajectoryError, match="cannot be carried"):
        plan_carry([q0, q1], rb, _hold(m * G, m))


def _rolled_path_hold(over: float) -> tuple[list[np.ndarray], GripHold, float]:
    """A path that rolls the pads' y axis up from level to vertical, with a tall item
    whose grip use at rest peaks `over` above the carry's bound on it (the couple T
    chosen so: at rest, use = m g/F + m L |f_y|/T, the closed form below); the path,
    the hold and that peak."""
    from cell.robot.carry import static_grip_use
    from cell.robot.ik import ReleasePose, solve_ik

    rb = load_robot("panda")
    centre = np.array([0.45, 0.0, 0.5])
    q0 = solve_ik(rb, ReleasePose.from_angles(centre, 0.0, 0.0, 0.0), rb.home).q
    q1 = solve_ik(rb, ReleasePose.from_angles(centre, 0.0, 0.0, math.pi / 3), q0).q
    m, lever = 0.07, 0.025
    force_n = m * G / 0.3  # the weight asks 0.3 of the pads' force
    qs = np.linspace(q0, q1, 101)
    f_y = np.abs(static_grip_use(rb, GripHold(1e9, 1.0, m, 0.0, (0, 0, 0), lever), qs))
    f_y_max = float(np.max(f_y)) / (m * lever)  # |f_y| [m/s²] at its most
    peak = 1 / CARRY_MARGIN + over
    torque = m * lever * f_y_max / (peak - 0.3)
    hold = GripHold(force_n, torque, m, 0.0, (0.0, 0.0, 0.0), lever)
    assert float(np.max(static_grip_use(rb, hold, qs))) == pytest.approx(peak, abs=1e-3)
    return [q0, q1], hold, peak


def test_a_carry_whose_path_asks_a_little_more_than_its_bound_at_rest_goes_within_the_tie():
    """No time scaling keeps a path within 1/margin that asks more at rest. Up to `tie`
    more, the carry is the fastest within 1/margin + tie, where a gentle carry
    (GENTLE_SCALE) would ask more; beyond it, gentle, as without a tie."""
    from cell.robot.carry import GENTLE_SCALE

    rb = load_robot("panda")
    bound, tie = 1 / CARRY_MARGIN, 0.02
    path, hold, peak = _rolled_path_hold(0.01)
    gentle = plan_path(
        path, rb, velocity_scale=math.sqrt(GENTLE_SCALE), acceleration_scale=GENTLE_SCALE
    )
    tr0, use0 = plan_carry(path, rb, hold, shape=False)  # no tie: gentle
    assert use0 > bound + tie  # gentle is not within the tie here
    assert tr0.duration == pytest.approx(gentle.duration, rel=1e-6)
    tr, use = plan_carry(path, rb, hold, shape=False, tie=tie)
    assert peak - 1e-3 <= use <= bound + tie  # never under what the path asks at rest
    assert grip_use(tr, rb, hold, n=801) <= bound + tie + 2e-3  # finer sampling
    path, hold, _ = _rolled_path_hold(0.03)  # beyond the tie: gentle again
    tr, use = plan_carry(path, rb, hold, shape=False, tie=tie)
    assert use > bound + tie
    assert tr.duration == pytest.approx(gentle.duration, rel=1e-6)


def test_a_carry_with_the_gentle_floor_is_never_slower_than_the_gentle_one():
    """A path whose rest asks just under the bound: the fastest uniform carry within it
    crawls (the bisection's time scale near its floor), slower than the same path at
    GENTLE_SCALE; with `gentle_floor` the gentle one is taken, and nothing changes where
    the carry within the bound is the sooner."""
    from cell.robot.carry import GENTLE_SCALE

    rb = load_robot("panda")
    path, hold, _ = _rolled_path_hold(-0.002)  # 2e-3 under the bound at rest
    gentle = plan_path(
        path, rb, velocity_scale=math.sqrt(GENTLE_SCALE), acceleration_scale=GENTLE_SCALE
    )
    crawl, _ = plan_carry(path, rb, hold, shape=False)
    assert crawl.duration > gentle.duration
    floored, _ = plan_carry(path, rb, hold, shape=False, gentle_floor=True)
    assert floored.duration == pytest.approx(gentle.duration, rel=1e-6)
    path, hold, _ = _rolled_path_hold(-0.3)  # room to spare: the carry within is sooner
    within, _ = plan_carry(path, rb, hold, shape=False)
    assert within.duration < gentle.duration
    floored, _ = plan_carry(path, rb, hold, shape=False, gentle_floor=True)
    assert floored.duration == pytest.approx(within.duration, rel=1e-6)


def test_grip_use_of_a_tall_item_hanging_sideways_is_the_closed_form():
    """At rest with the pads' y axis up, gravity pulls the item along y: the pads carry
    m g and the couple m g × lever (a closed form), so use = m g/F + m g L/T."""
    import pinocchio as pin  # noqa: F401  (the robot model)

    from cell.robot.ik import ReleasePose, solve_ik

    rb = load_robot("panda")
    pose = ReleasePose.from_angles(np.array([0.45, 0.0, 0.5]), 0.0, 0.0, math.pi / 2)
    q = solve_ik(rb, pose, rb.home).q
    y_axis = rb.tcp_pose(q)[1][:, 1]
    assert abs(y_axis[2]) > 0.999  # the pads' y axis is vertical
    rest = plan_path([q, q + 1e-3], rb, velocity_scale=1e-3, acceleration_scale=1e-6)  # slow
    hold = GripHold(1.2, 0.012, 0.07, 4e-5, (0.0, 0.0, 0.0), 0.025)
    expect = 0.07 * G / 1.2 + 0.07 * G * 0.025 / 0.012
    assert grip_use(rest, rb, hold) == pytest.approx(expect, rel=0.02)


def test_the_lift_over_a_pick_stays_on_the_picks_ik_branch():
    """A UR5 grip folded back over the station (the pick's configuration after a throw
    behind the arm) reaches 0.15 m up only on another IK branch, 4.2 rad away in a
    joint: the lift comes lower, on the pick's own branch, instead of swinging round."""
    job = parse_job(
        "cell: {robot: ur5}\n"
        "bins:\n  - {id: far, position_m: [1.6, 0.0], size_m: [0.3, 0.3], rim_height_m: 0.1}\n"
        "items:\n  - {object: cube50, bin: far}\n",
        "lift.yaml",
    )
    orc = Orchestrator(job)
    try:
        obj = job.items[0].obj
        q_pick = np.array([2.597, -3.043, 0.734, -5.545, -1.571, -5.257])
        p_tcp, _ = orc.robot.tcp_pose(q_pick)
        stroke = 0.05
        down = (-math.pi / 2, 0.0)
        # the item's centre under this grip: the TCP's offset undone
        p_item = p_tcp - (orc._tcp_for_item_centre(np.zeros(3), *down, stroke, obj))
        q_lift = orc._lift_q(p_item, stroke, obj, q_pick)
        rise = orc.robot.tcp_pose(q_lift)[0] - p_tcp
        assert rise[2] >= TUNING.lift_m / 4 - 1e-3 and np.hypot(*rise[:2]) < 2e-3
        # the move between them (a straight line in joint space) stays near the vertical
        # over the item and never lower than the pick: the arm does not swing round
        for f in np.linspace(0.0, 1.0, 21):
            p = orc.robot.tcp_pose(q_pick + f * (q_lift - q_pick))[0]
            assert np.hypot(*(p - p_tcp)[:2]) < 0.03 and p[2] > p_tcp[2] - 1e-3
    finally:
        orc.close()
