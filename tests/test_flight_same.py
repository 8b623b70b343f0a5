"""The flight integrators and the flight effects' callback, made faster, give the numbers
they gave before (tests/flight_before.py, frozen at f56b63f) on random batches: with every
flight effect, alone and together, with throws that never land, over flights that end at
different steps, and sampled along their paths."""

from __future__ import annotations

import numpy as np
import pytest

from cell.model.effects import Downwash, DownwashDecay, DragScale, Spin, Wind
from cell.model.effects_apply import flight_accel
from cell.model.flight3d import acceleration, fly, sample_path
from cell.model.params import EndEffectorParams
from cell.model.planar import flight_planar
from cell.model.throw import ThrowBatch, drag_constant, launch_state
from tests import flight_before as before

EE = EndEffectorParams()
# far below 1 mm: what the diagnosis reads; RK4's own error at its 10-20 ms step is ~1e-6 m
REL, ABS = 1e-12, 1e-12

EFFECT_SETS = {
    "nominal": [],
    "wind": [Wind(x_mps=1.5, y_mps=-0.8, z_mps=0.3)],
    "downwash": [Downwash(speed_mps=6.0, radius_m=0.4, exponent=1.5)],
    "downwash_decay": [DownwashDecay(speed_mps=9.0, radius_m=0.3, depth_m=0.6, exponent=1.2)],
    "spin": [Spin(spin_rad_s=-250.0, lift_max=0.3)],
    "drag_scale": [DragScale(factor=2.5)],
    "all": [
        Wind(x_mps=-0.7, y_mps=0.4, z_mps=-0.2),
        DownwashDecay(speed_mps=5.0, radius_m=0.6, depth_m=1.5, exponent=1.0),
        Spin(spin_rad_s=180.0, lift_max=0.5),
        DragScale(factor=0.6),
    ],
}


def _batch(seed: int, n: int) -> ThrowBatch:
    rng = np.random.default_rng(seed)
    return ThrowBatch.build(
        stroke=rng.uniform(0.03, 0.11, n),
        position=np.c_[
            rng.uniform(-0.3, 0.3, n), rng.uniform(-0.3, 0.3, n), rng.uniform(0.5, 1.5, n)
        ],
        elevation=rng.uniform(-0.3, 1.3, n),
        azimuth=rng.uniform(-np.pi, np.pi, n),
        shape=rng.integers(0, 5, n),
        mass=rng.uniform(0.02, 0.2, n),
        size=rng.uniform(0.03, 0.07, (n, 3)),
        base_velocity=rng.uniform(-0.5, 0.5, (n, 3)),
        # some planes above the release: those throws never land
        land_z=np.where(rng.random(n) < 0.1, 3.0, rng.uniform(-0.5, 0.4, n)),
        roll=0.0,
    )


def _close(got: np.ndarray, want: np.ndarray) -> None:
    assert np.array_equal(np.isnan(got), np.isnan(want))
    np.testing.assert_allclose(got, want, rtol=REL, atol=ABS)


@pytest.mark.parametrize("name", sorted(EFFECT_SETS))
def test_fly_gives_the_landings_it_gave_before(name: str) -> None:
    for seed, n in ((1, 157), (2, 31), (3, 1)):
        b = _batch(seed + 10 * len(name), n)
        rpm = np.random.default_rng(seed).uniform(0.0, 9000.0, n)
        p1, v1 = launch_state(b, EE)
        k = drag_constant(b.shape, b.mass, b.size)
        t0 = np.random.default_rng(seed + 1).uniform(0.0, 0.02, n)
        step = (0.01, 0.02, 0.004)[seed - 1]
        new = fly(p1, v1, k, b.land_z, accel=flight_accel(b, EFFECT_SETS[name], rpm), t0=t0,
                  step=step)  # fmt: skip
        acc = before.flight_accel(b, EFFECT_SETS[name], rpm)
        old_p, old_v, old_t, old_landed = before.fly(p1, v1, k, b.land_z, accel=acc, t0=t0,
                                                     step=step)  # fmt: skip
        assert np.array_equal(new.landed, old_landed)
        assert 0 < new.landed.sum() or n == 1
        assert not new.landed.all() or n == 1  # the planes above the release are never crossed
        for got, want in ((new.position, old_p), (new.velocity, old_v), (new.t, old_t)):
            _close(got, want)


def test_fly_gives_up_after_t_max_as_before() -> None:
    b = _batch(5, 40)
    p1, v1 = launch_state(b, EE)
    k = drag_constant(b.shape, b.mass, b.size)
    acc = EFFECT_SETS["all"]
    new = fly(p1, v1, k, b.land_z, accel=flight_accel(b, acc), t_max=0.35)
    old = before.fly(p1, v1, k, b.land_z, accel=before.flight_accel(b, acc, np.zeros(40)),
                     t_max=0.35)  # fmt: skip
    assert np.array_equal(new.landed, old[3]) and 0 < new.landed.sum() < 40
    _close(new.position, old[0])
    _close(new.t, old[2])


@pytest.mark.parametrize("name", ["nominal", "all", "downwash_decay"])
def test_sample_path_gives_the_positions_it_gave_before(name: str) -> None:
    n, m = 83, 40
    b = _batch(7, n)
    rng = np.random.default_rng(8)
    rpm = rng.uniform(0.0, 9000.0, n)
    p1, v1 = launch_state(b, EE)
    k = drag_constant(b.shape, b.mass, b.size)
    # tracks of different lengths, gaps (NaN), some throws with no sample at all
    t_rel = np.sort(rng.uniform(0.0, 1.0, (n, m)), axis=1) * rng.uniform(0.1, 1.0, (n, 1))
    t_rel[rng.random((n, m)) < 0.2] = np.nan
    t_rel[rng.random(n) < 0.1] = np.nan
    new = sample_path(p1, v1, k, t_rel, accel=flight_accel(b, EFFECT_SETS[name], rpm))
    old = before.sample_path(p1, v1, k, t_rel, accel=before.flight_accel(b, EFFECT_SETS[name], rpm))
    assert np.isfinite(new).sum() > n * m  # most samples are drawn
    _close(new, old)


def test_the_acceleration_at_a_state_is_the_one_before() -> None:
    b = _batch(9, 64)
    rng = np.random.default_rng(10)
    p, v = b.position + rng.normal(0, 0.2, (64, 3)), rng.normal(0, 4.0, (64, 3))
    k = drag_constant(b.shape, b.mass, b.size)
    rpm = rng.uniform(0, 9000, 64)
    for effects in EFFECT_SETS.values():
        got = acceleration(p, v, k, flight_accel(b, effects, rpm))
        acc = before.flight_accel(b, effects, rpm)
        _close(got, before._rates(p, v, k, np.arange(64), acc))


def test_the_planar_flight_gives_the_landings_it_gave_before() -> None:
    rng = np.random.default_rng(11)
    for n in (1, 9, 240):
        z = rng.uniform(0.2, 1.6, n)
        vh, vz = rng.uniform(0.0, 6.0, n), rng.uniform(-2.0, 5.0, n)
        k = rng.uniform(0.0, 0.2, n)
        land_z = np.where(rng.random(n) < 0.1, 9.0, rng.uniform(-0.5, 0.3, n))
        for max_step in (0.07, 0.013):
            got = flight_planar(z, vh, vz, k, land_z, max_step)
            want = before.flight_planar(z, vh, vz, k, land_z, max_step)
            assert np.array_equal(got[2], want[2]) and (n < 9 or 0 < got[2].sum() < n)
            for a, b in zip(got, want, strict=True):
                _close(np.asarray(a, float), np.asarray(b, float))


def test_the_track_fits_flights_are_the_ones_before() -> None:
    from cell.gap.track_ode import _simulate

    rng = np.random.default_rng(12)
    n, n_p, m = 23, 4, 30
    th = np.concatenate(
        [
            rng.uniform(-1.0, 1.0, (n, n_p, 3)),  # p0 [m]
            rng.uniform(-4.0, 4.0, (n, n_p, 3)),  # v0 [m/s]
            rng.normal(0.0, 0.5, (n, n_p, 3)),  # a [m/s²]
            rng.normal(0.0, 0.3, (n, n_p, 1)),  # λ
            rng.normal(0.0, 2.0, (n, n_p, 2)),  # w [m/s]
        ],
        axis=-1,
    )
    k = rng.uniform(0.0, 0.2, n)
    # flights that end at different steps: the tracks past their last sample are left out
    # as the rest go on (`_simulate`'s rows kept)
    tau = np.sort(rng.uniform(0.0, rng.uniform(0.05, 0.9, (n, 1)), (n, m)), axis=1)
    tau[rng.random((n, m)) < 0.2] = np.nan
    got = _simulate(th, k, tau)
    assert np.isfinite(got).sum() > 0.7 * got.size
    _close(got, before.track_simulate(th, k, tau))


def test_the_other_implementations_air_flow_flies_as_before() -> None:
    from cell.gap.world_laws import _accel

    n = 120
    b = _batch(13, n)
    rpm = np.random.default_rng(14).uniform(0.0, 9000.0, n)
    p1, v1 = launch_state(b, EE)
    k = drag_constant(b.shape, b.mass, b.size)
    jet = {"law": "jet", "w_mps": 6.0, "p": 1.3, "radius_m": 0.5, "depth_m": 1.5}
    breeze = {"law": "breeze", "x_mps": 1.0, "y_mps": -0.6}
    for laws in ([jet], [breeze], [jet, breeze]):
        new = fly(p1, v1, k, b.land_z, accel=_accel(b, laws, rpm), step=0.004)
        old = before.fly(p1, v1, k, b.land_z, accel=before.world_accel(b, laws, rpm), step=0.004)
        assert np.array_equal(new.landed, old[3]) and new.landed.sum() > n // 2
        _close(new.position, old[0])
        _close(new.t, old[2])
