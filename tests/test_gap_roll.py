"""Issue 57: the bounce's roll law (`cell.model.effects_bounce.BounceRoll`) against balls
rolling in the PyBullet scene on `s:bounce-roll-hard`'s floor, and its closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from cell.model.effects import FAMILIES, BounceRoll
from cell.model.effects_apply import _after_landing, drop_slide, roll_move
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
    best misses by far more, and `roll_fit` recovers μ_r and the depth, or μ_r alone with
    the depth the plane's (as the scene's check measures it, the model taking the depth
    from the log)."""
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
    inv_mu_r, depth, rms = roll_fit(d, v, size, depth_m=PLANE_Z)
    assert inv_mu_r == pytest.approx(1.0 / mu_r, rel=0.05) and depth == PLANE_Z
    assert rms < 0.008


def test_the_roll_law_by_its_energy_and_momentum_and_neutral_does_nothing():
    """The roll after the impact, from the ball's angular momentum about the contact point
    (m r v_h less the rolling resistance's angular impulse μ_r m v_z' leaves (7/5) m r v')
    and its energy (7/10) m v'² spent by the torque μ_r m g over the turned angle s / r:
    s = 7 r v'² / (10 μ_r g); the fall alone where the resistance stops the ball at the
    impact; the neutral size does nothing; a block is not moved; the world's writing
    (`roll_along`) agrees. The depth is each throw's plane height above the floor (the
    log's `land_z_m`): planes at 0.12 and 0.25 m, and one at the floor (no fall)."""
    from cell.sim.slide_fit import roll_along

    rng = np.random.default_rng(5)
    n = 12
    v = np.c_[rng.uniform(-4, 4, (n, 2)), -rng.uniform(0.5, 4, n)]
    xy = rng.uniform(-1, 1, (n, 2))
    d = rng.uniform(0.03, 0.07, n)
    size = np.c_[d, d, d]
    mu_r = 0.004  # [m]
    depth = np.resize([0.12, 0.25, 0.0], n)  # [m] each throw's plane above the floor
    r = d / 2
    vz = np.abs(v[:, 2])
    vz1 = np.sqrt(vz**2 + 2 * G * np.maximum(depth - r, 0.0))  # at the floor, by energy
    vh = np.linalg.norm(v[:, :2], axis=1)
    v_roll = np.maximum(r * vh - mu_r * vz1, 0.0) / (7 / 5 * r)
    s = 0.7 * v_roll**2 / (mu_r * G / r)  # (7/10) m v'² = μ_r m g · s / r
    t_fall = 2 * np.maximum(depth - r, 0.0) / (vz + vz1)  # the mean speed over the fall
    u = v[:, :2] / vh[:, None]
    want = xy + u * (vh * t_fall + s)[:, None]
    got = _after_landing(xy, v, [BounceRoll(1.0 / mu_r)], size, None, depth)
    assert np.allclose(got, want, atol=1e-9)
    assert np.all(t_fall[depth == 0.0] == 0.0) and np.any(t_fall > 0.0)
    assert np.allclose(roll_along(v, mu_r, depth, size), vh * t_fall + s, atol=1e-9)
    assert np.array_equal(_after_landing(xy, v, [BounceRoll()], size, None, depth), xy)
    stopped = _after_landing(xy, v, [BounceRoll(1e-3)], size, None, depth)  # μ_r 1 km
    fall_only = xy + drop_slide(v, 1e-9, depth, size)  # the drop law's fall alone
    assert np.allclose(stopped, fall_only, atol=1e-9)
    shape = np.array([SHAPES.index("sphere"), SHAPES.index("cube")] * (n // 2))
    mixed = _after_landing(xy, v, [BounceRoll(1.0 / mu_r)], size, shape, depth)
    ball = shape == SHAPES.index("sphere")  # a block does not roll: left where it landed
    assert np.allclose(mixed[ball], want[ball], atol=1e-9)
    assert np.array_equal(mixed[~ball], xy[~ball])
    assert BounceRoll in FAMILIES["bounce"]


def test_the_model_takes_the_roll_laws_depth_from_each_throws_plane():
    """The configured scene model's balls thrown onto planes 0.1 and 0.3 m above the floor
    (the log's `land_z_m`): the roll law moves each crossing by the world's own writing of
    the law (`roll_along`) at that throw's plane height, and the roll law alone is fitted
    to rests so made back to its 1/μ_r (a depth fitted as one value would have to be
    wrong on one plane or the other)."""
    from cell.gap.fit import score_set
    from cell.gap.problem import build_problem
    from cell.gap.world_scene import _records, draw_plan
    from cell.log.table import ThrowTable
    from cell.params import load_params, scene_params_path
    from cell.sim.slide_fit import roll_along

    mp = load_params(scene_params_path())
    n = 40
    plan = draw_plan(n, np.random.default_rng(3), objects=tuple(_SIZE))
    recs = _records(plan, np.zeros((n, 2)), np.ones(n), np.ones(n, bool))
    recs = [{**r, "land_z_m": (0.1, 0.3)[i % 2]} for i, r in enumerate(recs)]
    prob = build_problem(ThrowTable.from_records(recs), mp.ee, objects=mp.objects, seed=0)
    idx = np.arange(len(prob))
    cross = prob.landing(idx)
    xy0 = np.c_[cross.x, cross.y]
    v = cross.impact_velocity
    mu_r = 0.0075  # [m]
    along = roll_along(v, mu_r, prob.batch.land_z, prob.batch.size)
    u = v[:, :2] / np.linalg.norm(v[:, :2], axis=1)[:, None]
    rolled = prob.landing(idx, [BounceRoll(1.0 / mu_r)])
    assert np.allclose(np.c_[rolled.x, rolled.y], xy0 + u * along[:, None], atol=1e-6)
    high = prob.batch.land_z > 0.2
    assert high.sum() == n // 2 and np.all(along[high] > 0.0)
    recs = [{**r, "landed_x_m": float(p[0]), "landed_y_m": float(p[1])}
            for r, p in zip(recs, xy0 + u * along[:, None], strict=True)]  # fmt: skip
    fitted = score_set(build_problem(ThrowTable.from_records(recs), mp.ee, objects=mp.objects,
                                     seed=0), [BounceRoll])  # fmt: skip
    assert fitted.full.effects[-1].inv_mu_r_per_m == pytest.approx(1.0 / mu_r, rel=0.01)
    assert fitted.full.train_rmse_m < 1e-3
