"""`cell.robot.ruckig_move._ruckig_kept` (a move planned once for the same arguments) and
`plan_approach`, which uses it: the moves remembered are the moves ruckig plans afresh,
sample for sample, bit for bit; the failures are the same failures; and approaches from
many starts to the same pick, planned one after the other, are each the approach planned
with nothing remembered."""

from __future__ import annotations

import numpy as np
import pytest

from cell.errors import TrajectoryError
from cell.robot import ruckig_move
from cell.robot.model import load_robot
from cell.robot.motion import _ON_SEGMENT, plan_approach
from cell.robot.ruckig_move import _ruckig, _ruckig_kept


def _samples(tr: object) -> bytes:
    t = np.linspace(0.0, tr.duration, 97)  # type: ignore[attr-defined]
    return b"".join(a.tobytes() for a in tr.sample_many(t))  # type: ignore[attr-defined]


def test_a_kept_move_is_the_move_ruckig_plans() -> None:
    rb = load_robot("panda")
    lim = rb.limits
    rng = np.random.default_rng(63)
    zero = np.zeros(rb.dof)
    ruckig_move._KEPT.clear()
    kept = failed = 0
    for i in range(60):
        p0, p1 = rb.home + 0.7 * (rb.random_configuration(rng, 2) - rb.home)
        v0 = zero.copy()
        vmax, amax = lim.velocity * rng.uniform(0.4, 1.0), lim.acceleration
        if i % 6 == 5:  # moving fast at a limit: the move passes it braking (an error)
            p0[3], v0[3] = lim.upper[3] - 0.01, 0.9 * vmax[3]
        v1 = zero if i % 2 else 0.3 * rng.uniform(-1, 1, rb.dof) * vmax
        args = (rb, p0, v0, zero, p1, v1, vmax, amax, lim.jerk)
        phase = i % 3 == 0
        try:
            fresh = _ruckig(*args, velocity_interface=False, phase=phase)
        except TrajectoryError as exc:
            for _ in range(2):
                with pytest.raises(TrajectoryError) as got:
                    _ruckig_kept(*args, velocity_interface=False, phase=phase)
                assert str(got.value) == str(exc)
            failed += 1
            continue
        first = _ruckig_kept(*args, velocity_interface=False, phase=phase)
        assert _ruckig_kept(*args, velocity_interface=False, phase=phase) is first
        assert first.duration == fresh.duration
        assert _samples(first) == _samples(fresh)
        # another target velocity or synchronisation is another move
        other = _ruckig_kept(*args[:5], v1 + 0.01, *args[6:], velocity_interface=False)
        assert other is not first
        assert _samples(other) == _samples(
            _ruckig(*args[:5], v1 + 0.01, *args[6:], velocity_interface=False)
        )
        turned = _ruckig_kept(*args, velocity_interface=False, phase=not phase)
        assert _samples(turned) == _samples(
            _ruckig(*args, velocity_interface=False, phase=not phase)
        )
        kept += 1
    assert kept > 30 and failed > 0, (kept, failed)


def test_approaches_to_one_pick_are_each_planned_as_afresh() -> None:
    """Approaches from many starts to one pick share their descents (the same objects);
    each is the approach planned with nothing remembered, and each part sampled is
    ruckig's own."""
    rb = load_robot("panda")
    rng = np.random.default_rng(64)
    q_to = rb.home.copy()
    q_over = q_to + np.array([0.0, -0.15, 0.0, 0.2, 0.0, -0.05, 0.0])
    starts = rb.home + 0.5 * (rb.random_configuration(rng, 12) - rb.home)
    ruckig_move._KEPT.clear()
    _ON_SEGMENT.clear()
    planned = [plan_approach(q0, q_over, q_to, rb) for q0 in starts]
    assert len({id(tr.parts[1]) for tr in planned}) < len(planned)  # descents shared
    for q0, tr in zip(starts, planned, strict=True):
        ruckig_move._KEPT.clear()
        _ON_SEGMENT.clear()
        afresh = plan_approach(q0, q_over, q_to, rb)
        assert tr.duration == afresh.duration
        assert _samples(tr) == _samples(afresh)
