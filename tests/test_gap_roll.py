"""Issue 57: the bounce's roll law (`cell.model.effects_bounce.BounceRoll`) against balls
rolling in the PyBullet scene on `s:bounce-roll-hard`'s floor, and its closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from cell.model.effects import FAMILIES, BounceDrop, BounceRoll
from cell.model.effects_apply import _after_landing, roll_move
from cell.model.objects import SHAPES
from tests.ball_drop import PLANE_Z, drop_ball

G = 9.81  # [m/s²]
_SIZE = {"sphere40": 0.04, "sphere55": 0.055, "sphere70": 0.07}  # [m] the balls' diameters


def _rolled(obj: str, vh: float, vz: float, floor: tuple[float, float, float]
            ) -> tuple[float, float, float]:  # fmt: skip
    """A ball set with its centre on the landing plane moving at (v_h, 0, −v_z) [m/s],
    no spin, onto the scene's floor (restitution, friction, rolling friction [m]): (rest −
    start along x [m], across [m], ω r / v [-] 0.1 s after the start, on the floor)."""
    x, y, t, vx, wr = drop_ball(obj, vh, vz, floor)
    late = np.flatnonzero(t >= 0.1)
    if not late.size:
        return x, y, float("nan")
    i = late[0]
    return x, y, float(wr[i] / max(vx[i], 1e-9))


def test_a_ball_on_a_hard_floor_rolls_to_rest_as_the_roll_law_says():
    """On `s:bounce-roll-hard`'s floor (friction 1.0, rolling friction 0.01 m) Bullet's
    rolling friction μ_r = 0.01 · 0.7 + 0.0005 · 1.0 = 0.0075 m (the two bodies' rolling
    frictions times the other's friction) is below the friction's torque arm μ r (μ = 1.0 ·
    0.7, r ≥ 20 mm): the ball turns, ω r = v. Its rest point is the roll law's with that
    μ_r and the floor 0.1 m below the plane, neither fitted; the drop law (a slide) at its
    best misses by far more, and `roll_fit` recovers μ_r and the depth."""
    from cell.sim.items import ITEM_FRICTION
    from cell.sim.slide_fit import drop_fit, roll_fit

    throws = [("sphere40", 3.0, 3.0), ("sphere55", 2.0, 2.0), ("sphere70", 1.5, 3.5),
              ("sphere55", 3.5, 4.0), ("sphere70", 2.5, 2.5), ("sphere40", 1.5, 4.5)]  # fmt: skip
    got = np.array([_rolled(o, vh, vz, (0.05, 1.0, 0.01)) for o, vh, vz in throws])
    v = np.array([[vh, 0.0, -vz] for _, vh, vz in throws])
    size = np.array([[_SIZE[o]] * 3 for o, _, _ in throws])
    mu_r = 0.01 * ITEM_FRICTION + 0.0005 * 1.0  # [m]
    want = roll_move(v, 1.0 / mu_r, PLANE_Z, size)
    assert np.allclose(got[:5, 2], 1.0, atol=0.02), got[:, 2]  # rolling: ω r = v
    assert np.abs(got[:, 1]).max() < 1e-3
    assert np.abs(got[:, 0] - want[:, 0]).max() < 0.012, (got[:, 0], want[:, 0])
    # the last, steep and slow, is stopped at its impact by the resistance's impulse
    assert np.isnan(got[5, 2]) and want[5, 0] == pytest.approx(
        roll_move(v, 1e-9, PLANE_Z, size)[5, 0]
    )
    d = got[:, :2]
    assert drop_fit(d, v, size)[2] > 0.05  # a slide law at its best misses the rolls
    inv_mu_r, depth, rms = roll_fit(d, v, size)  # the world's measurement recovers both
    assert inv_mu_r == pytest.approx(1.0 / mu_r, rel=0.05)
    assert depth == pytest.approx(PLANE_Z, rel=0.05)
    assert rms < 0.005


def test_the_roll_law_by_its_energy_and_momentum_and_neutral_does_nothing():
    """The roll after the impact, from the ball's angular momentum about the contact point
    (m r v_h less the rolling resistance's angular impulse μ_r m v_z' leaves (7/5) m r v')
    and its energy (7/10) m v'² spent by the torque μ_r m g over the turned angle s / r:
    s = 7 r v'² / (10 μ_r g); the fall alone where the resistance stops the ball at the
    impact; the neutral size does nothing; a block is not moved; the world's writing
    (`roll_along`) agrees."""
    from cell.sim.slide_fit import roll_along

    rng = np.random.default_rng(5)
    n = 12
    v = np.c_[rng.uniform(-4, 4, (n, 2)), -rng.uniform(0.5, 4, n)]
    xy = rng.uniform(-1, 1, (n, 2))
    d = rng.uniform(0.03, 0.07, n)
    size = np.c_[d, d, d]
    mu_r, depth = 0.004, 0.12  # [m]
    r = d / 2
    vz = np.abs(v[:, 2])
    vz1 = np.sqrt(vz**2 + 2 * G * (depth - r))  # the speed at the floor, by energy
    vh = np.linalg.norm(v[:, :2], axis=1)
    v_roll = np.maximum(r * vh - mu_r * vz1, 0.0) / (7 / 5 * r)
    s = 0.7 * v_roll**2 / (mu_r * G / r)  # (7/10) m v'² = μ_r m g · s / r
    t_fall = 2 * (depth - r) / (vz + vz1)  # the mean speed over the fall
    u = v[:, :2] / vh[:, None]
    want = xy + u * (vh * t_fall + s)[:, None]
    got = _after_landing(xy, v, [BounceRoll(1.0 / mu_r, depth)], size)
    assert np.allclose(got, want, atol=1e-9)
    assert np.allclose(roll_along(v, mu_r, depth, size), vh * t_fall + s, atol=1e-9)
    assert np.array_equal(_after_landing(xy, v, [BounceRoll()], size), xy)
    stopped = _after_landing(xy, v, [BounceRoll(1e-3, depth)], size)  # μ_r 1 km: no roll
    fall_only = _after_landing(xy, v, [BounceDrop(1e-9, depth)], size)
    assert np.allclose(stopped, fall_only, atol=1e-9)
    shape = np.array([SHAPES.index("sphere"), SHAPES.index("cube")] * (n // 2))
    mixed = _after_landing(xy, v, [BounceRoll(1.0 / mu_r, depth)], size, shape)
    ball = shape == SHAPES.index("sphere")  # a block does not roll: left where it landed
    assert np.allclose(mixed[ball], want[ball], atol=1e-9)
    assert np.array_equal(mixed[~ball], xy[~ball])
    assert BounceRoll in FAMILIES["bounce"]
