"""The shared RK4 step and landing-plane crossing, against closed forms."""

import math

import numpy as np
import pytest

from cell.model.integrate import plane_crossing, rk4_step

G = np.array([0.0, 0.0, -9.81])


def test_one_step_of_y_equals_lambda_y_is_the_rk4_amplification_factor():
    for lam, h in ((-1.3, 0.2), (0.7, 0.05), (-20.0, 0.01)):
        # a first-order state: a part of v with no position
        _, (y1,) = rk4_step(lambda _p, v, lam=lam: (lam * v[0],), (), (2.0,), h)
        z = h * lam
        assert y1 == pytest.approx(2.0 * (1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24), rel=1e-14)


def test_a_flight_without_drag_is_integrated_exactly():
    p0, v0 = np.array([0.1, -0.2, 0.8]), np.array([2.0, 1.0, 3.0])
    p, v = p0, v0
    for _ in range(40):
        (p,), (v,) = rk4_step(lambda _p, vs: [G + 0 * vs[0]], [p], [v], 0.01)
    t = 0.4
    assert np.allclose(p, p0 + v0 * t + 0.5 * G * t * t, atol=1e-13)
    assert np.allclose(v, v0 + G * t, atol=1e-13)


def test_the_crossing_of_a_ballistic_step_is_the_parabolas_root():
    rng = np.random.default_rng(4)
    p0 = np.column_stack(
        [rng.uniform(-1, 1, 20), rng.uniform(-1, 1, 20), rng.uniform(0.3, 0.4, 20)]
    )
    v0 = np.column_stack([rng.uniform(-3, 3, 20), rng.uniform(-3, 3, 20), rng.uniform(-2, 1, 20)])
    h = 0.5
    p1 = p0 + v0 * h + 0.5 * G * h * h
    v1 = v0 + G * h
    level = 0.1
    s, pos, vel = plane_crossing(p0, p1, v0, v1, h, level)
    for i in range(20):
        # z0 + vz t - g t²/2 = level, the later root
        a, b, c = 0.5 * 9.81, -v0[i, 2], level - p0[i, 2]
        t = (-b + math.sqrt(b * b - 4 * a * c)) / (2 * a)
        assert s[i] * h == pytest.approx(t, abs=1e-12)
        assert np.allclose(pos[i], p0[i] + v0[i] * t + 0.5 * G * t * t, atol=1e-12)
        assert np.allclose(vel[i], v0[i] + G * t, atol=1e-12)


def test_the_planar_inner_loop_is_the_shared_step_to_the_last_bit():
    """rk4_planar is rk4_step written out (for speed): same numbers, floats and arrays."""
    from cell.model.params import G as g
    from cell.model.planar import _rk4_arrays, rk4_planar

    def accel_with(k, sqrt):
        def accel(_p, v):
            speed = sqrt(v[0] * v[0] + v[1] * v[1])
            return (-k * speed * v[0], -k * speed * v[1] - g)

        return accel

    rng = np.random.default_rng(8)
    h, z, vh, vz, k = (rng.uniform(-5, 5, 200) for _ in range(5))
    k, step = np.abs(k) * 0.01, 0.013
    (h1, z1), (vh1, vz1) = rk4_step(accel_with(k, np.sqrt), (h, z), (vh, vz), step)
    for got, want in zip(
        rk4_planar(h, z, vh, vz, k, step, np.sqrt), (h1, z1, vh1, vz1), strict=True
    ):
        assert np.array_equal(got, want)
    # `flight_planar`'s own step (−k held, the step's starting speed handed in): the same
    speed = np.sqrt(vh * vh + vz * vz)
    for got, want in zip(
        _rk4_arrays(h, z, vh, vz, -k, step, speed), (h1, z1, vh1, vz1), strict=True
    ):
        assert np.array_equal(got, want)
    for i in range(20):
        one = (float(h[i]), float(z[i]))
        vel = (float(vh[i]), float(vz[i]))
        (a, b), (c, d) = rk4_step(accel_with(float(k[i]), math.sqrt), one, vel, step)
        assert rk4_planar(*one, *vel, float(k[i]), step, math.sqrt) == (a, b, c, d)


def test_the_crossings_root_is_the_safeguarded_newton_written_out() -> None:
    """`hermite_root` (3a, 2b and f > 0 taken once per call or step) against its eight
    safeguarded Newton steps written out plainly, to the bit, on crossings of every kind:
    steep and shallow, slopes of either sign, a level at either end of the step."""
    from cell.model.integrate import hermite_root

    rng = np.random.default_rng(9)
    n = 2000
    z0 = rng.uniform(0.0, 1.0, n)
    z1 = z0 - rng.uniform(1e-6, 0.5, n)
    level = z0 - (z0 - z1) * rng.uniform(0.0, 1.0, n) ** rng.choice([0.1, 1.0, 10.0], n)
    level[:20] = z1[:20]  # the level at the step's end
    w0 = rng.normal(0.0, 0.3, n) * rng.choice([0.01, 1.0, 10.0], n)
    w1 = rng.normal(-0.3, 0.3, n) * rng.choice([0.01, 1.0, 10.0], n)
    a = 2 * z0 - 2 * z1 + w0 + w1
    b = -3 * z0 + 3 * z1 - 2 * w0 - w1
    lo, hi = np.zeros(n), np.ones(n)
    s = np.clip((z0 - level) / np.maximum(z0 - z1, 1e-300), 0.0, 1.0)
    for _ in range(8):
        f = ((a * s + b) * s + w0) * s + (z0 - level)
        lo, hi = np.where(f > 0, s, lo), np.where(f > 0, hi, s)
        with np.errstate(divide="ignore", invalid="ignore"):
            s_new = s - f / ((3 * a * s + 2 * b) * s + w0)
        bad = ~np.isfinite(s_new) | (s_new < lo) | (s_new > hi)
        s = np.where(bad, 0.5 * (lo + hi), s_new)
    got = hermite_root(z0, z1, w0, w1, level)
    assert got.tobytes() == s.tobytes()
    assert np.all((got >= 0) & (got <= 1))
