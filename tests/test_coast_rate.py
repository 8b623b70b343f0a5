"""`cell.robot.moving_coast.CoastTrajectory`'s joint rates by LAPACK's gelsd called
directly against `np.linalg.lstsq` (what it called before): the same coast, bit for bit,
on random lines of two arms, forwards and as a run-in; and the grip on it moving along
its straight line at its velocity (the coast's own law, checked from the arm's
kinematics)."""

from __future__ import annotations

import numpy as np
import pytest

from cell.errors import TrajectoryError
from cell.robot.model import load_robot
from cell.robot.moving_coast import CoastTrajectory


def _integrated_by_numpys_lstsq(
    rb: object, q0: np.ndarray, v: np.ndarray, duration: float, ending: bool
) -> tuple[np.ndarray, np.ndarray]:
    """The coast's (q, q̇) at its steps as it was integrated before: RK4 of
    q̇ = `np.linalg.lstsq`(J(q), [v; 0], rcond=1e-10) every 1 ms."""
    sign = -1.0 if ending else 1.0
    twist = np.concatenate([sign * np.asarray(v, float), np.zeros(3)])

    def rate(q: np.ndarray) -> np.ndarray:
        return np.linalg.lstsq(rb.tcp_jacobian(q), twist, rcond=1e-10)[0]  # type: ignore[attr-defined]

    n = max(1, int(np.ceil(duration / 1e-3)))
    h = duration / n
    qs, dqs = [np.asarray(q0, float)], [rate(np.asarray(q0, float))]
    for _ in range(n):
        q, k1 = qs[-1], dqs[-1]
        k2 = rate(q + h / 2 * k1)
        k3 = rate(q + h / 2 * k2)
        k4 = rate(q + h * k3)
        qs.append(q + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4))
        dqs.append(rate(qs[-1]))
    q_arr, dq_arr = np.array(qs), np.array(dqs)
    if ending:
        q_arr, dq_arr = q_arr[::-1].copy(), -dq_arr[::-1]
    return q_arr, dq_arr


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_the_coast_is_the_one_numpys_lstsq_integrates(name: str) -> None:
    rb = load_robot(name)
    rng = np.random.default_rng(66)
    made = 0
    for i in range(24):
        q0 = rb.home + 0.3 * (rb.random_configuration(rng, 1)[0] - rb.home)
        v = rng.normal(0.0, 0.3, 3)
        ending = i % 2 == 1
        try:
            got = CoastTrajectory(rb, q0, v, 0.03, ending=ending)
        except TrajectoryError:
            continue
        want_q, want_dq = _integrated_by_numpys_lstsq(rb, q0, v, 0.03, ending)
        assert got._qs.tobytes() == want_q.tobytes()
        assert got._dqs.tobytes() == want_dq.tobytes()
        # the grip moves along the line at v, its axis fixed
        ts = np.linspace(0.0, got.duration, 7)
        qs = got.sample_many(ts)[0]
        p = rb.tcp_positions(qs)
        np.testing.assert_allclose(p - p[0], np.outer(ts, v), atol=1e-6)
        made += 1
    assert made >= 12
