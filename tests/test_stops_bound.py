"""`cell.arm.mover.stops_bound_s` never exceeds the time of the stops it bounds: each
stretch planned as `Mover._stops` plans it (toppra's path empty, the grip's carry held),
over many random stretches of both arms. A bound over the true time would leave out stops
that were sooner, and change the move."""

from __future__ import annotations

import numpy as np
import pytest

from cell.arm.joints import plan_time
from cell.arm.mover import stops_bound_s
from cell.errors import TrajectoryError
from cell.robot.carry_plan import plan_carry
from cell.robot.grip_hold import GripHold
from cell.robot.model import load_robot
from cell.robot.path_plan import plan_path

HOLD = GripHold(
    force_n=6.0,
    torque_nm=0.05,
    mass_kg=0.15,
    inertia_xx=2e-4,
    offset_tcp_m=(0.0, 0.0, 0.06),
    lever_m=0.03,
)


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_bound_below_the_stops(name: str) -> None:
    rb = load_robot(name)
    lo, hi = rb.limits.lower, rb.limits.upper
    lo, hi = np.maximum(lo, -3.0), np.minimum(hi, 3.0)
    rng = np.random.default_rng(7)
    checked = 0
    for i in range(16):
        q0 = lo + (hi - lo) * rng.uniform(0.1, 0.9, rb.dof)
        way = [
            np.clip(q0 + rng.normal(0.0, 0.6, rb.dof), lo, hi)
            for _ in range(int(rng.integers(1, 4)))
        ]
        settle = float(rng.choice([0.0, 0.1]))
        stops, q = [], q0
        try:
            for w in way:
                if i % 2:
                    stops.append(plan_carry([q, w], rb, HOLD)[0])
                else:
                    stops.append(plan_path([q, w], rb, velocity_scale=float(rng.uniform(0.5, 1.0))))
                q = w
        except TrajectoryError:
            continue
        checked += 1
        assert stops_bound_s(rb, q0, way, settle) <= plan_time(stops, settle) + 1e-9
    assert checked >= 10


def test_bound_of_one_stretch_by_hand() -> None:
    """A single joint moved d from rest to rest: 2√(d/a) below v²/a, d/v + v/a above."""
    rb = load_robot("panda")
    v, a = rb.limits.velocity[0] * (1 + 1e-3), rb.limits.acceleration[0] * (1 + 1e-3)
    q0 = (rb.limits.lower + rb.limits.upper) / 2
    for d in (0.5 * v * v / a, 3.0 * v * v / a):
        q1 = q0.copy()
        q1[0] += d
        want = 2.0 * np.sqrt(d / a) if d <= v * v / a else d / v + v / a
        assert stops_bound_s(rb, q0, [q1], 0.2) == pytest.approx(want)
        assert stops_bound_s(rb, q0, [q1, q0], 0.2) == pytest.approx(2 * want + 0.2)
