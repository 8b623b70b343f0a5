"""The 3-D integrator keeps its states column-major (`cell.model.flight3d._column_major`)
and the flight effects' callback keeps what is the same at every stage of a set of rows
(`cell.model.effects_apply._flight_accel`): both pure speed-ups. Checked against the
row-major arithmetic written out here (bitwise), against a closed form (no drag, no
effect: a parabola), and for a stale value when the rows or the states change."""

from __future__ import annotations

import numpy as np
import pytest

from cell.model import flight3d
from cell.model.effects import DownwashJet, DragScale, Spin, Wind
from cell.model.effects_apply import flight_accel
from cell.model.flight3d import fly, sample_path
from cell.model.integrate import rk4_step
from cell.model.params import EndEffectorParams, G
from cell.model.throw import ThrowBatch, drag_constant, launch_state

EE = EndEffectorParams()


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
        land_z=rng.uniform(-0.5, 0.4, n),
        roll=0.0,
    )


def _row_major_step(p, v, neg_k, accel, h):  # type: ignore[no-untyped-def]
    """One RK4 step of C-ordered (m, 3) states through `rk4_step`, the rates written out
    with rows of three (|rel|² summed in the integrator's order)."""
    idx = np.arange(p.shape[0])

    def rates(ps, vs):  # type: ignore[no-untyped-def]
        w, extra = accel(np.ascontiguousarray(ps[0]), np.ascontiguousarray(vs[0]), idx)
        rel = vs[0] - (np.zeros(3) if w is None else w)  # still air: v − 0, as before
        sq = (rel[:, 0] * rel[:, 0] + rel[:, 2] * rel[:, 2]) + rel[:, 1] * rel[:, 1]
        a = np.empty_like(rel)
        for j in range(3):
            a[:, j] = neg_k * np.sqrt(sq) * rel[:, j]
        a[:, 2] -= G
        return [a if extra is None else a + extra]

    pn, vn = rk4_step(rates, [p], [v], h, reads_position=True)
    return pn[0], vn[0]


def test_column_major_steps_are_bitwise_the_row_major_ones() -> None:
    """Every flight effect together (the downwash's jet, a wind, spin, a drag factor):
    ten steps of the integrator equal, bit for bit, the same steps on row-major arrays."""
    b = _batch(3, 57)
    rpm = np.random.default_rng(4).uniform(3000.0, 8000.0, 57)
    effs = [
        DownwashJet(speed_mps=9.0, radius_m=0.5, exponent=1.2),
        Wind(x_mps=0.8, y_mps=-0.4, z_mps=0.1),
        Spin(spin_rad_s=150.0, lift_max=0.4),
        DragScale(factor=1.6),
    ]
    p, v = launch_state(b, EE)
    neg_k = -drag_constant(b.shape, b.mass, b.size)
    acc = flight_accel(b, effs, rpm)
    pc, vc = np.ascontiguousarray(p), np.ascontiguousarray(v)
    pf, vf = flight3d._column_major(p), flight3d._column_major(v)
    assert pf.flags.f_contiguous and not pf.flags.c_contiguous
    idx = np.arange(57)
    for _ in range(10):
        pc, vc = _row_major_step(pc, vc, neg_k, acc, 0.01)
        pf, vf = flight3d._rk4(pf, vf, neg_k, idx, acc, 0.01)
        assert pf.flags.f_contiguous  # the elementwise results keep the layout
        assert np.array_equal(pf, pc) and np.array_equal(vf, vc)


@pytest.mark.parametrize(
    "effs",
    [
        [DragScale(factor=1.6)],
        [Spin(spin_rad_s=150.0, lift_max=0.4), DragScale(factor=0.7)],
        [Wind(x_mps=0.8, y_mps=-0.4, z_mps=0.1), DragScale(factor=1.6)],
    ],  # fmt: skip
    ids=["drag", "spin+drag", "wind+drag"],
)
def test_steps_in_still_air_or_off_the_position_are_bitwise_the_row_major_ones(effs) -> None:  # type: ignore[no-untyped-def]
    """Effects that read no position (no downwash: `reads_position` false, the stages'
    positions not formed) and, without a wind, no air velocity (still air: v itself, not
    v − 0): ten steps equal, bit for bit, the row-major steps that form every stage's
    position and subtract the zero air."""
    b = _batch(13, 41)
    p, v = launch_state(b, EE)
    neg_k = -drag_constant(b.shape, b.mass, b.size)
    acc = flight_accel(b, effs)
    assert acc.reads_position is False
    pc, vc = np.ascontiguousarray(p), np.ascontiguousarray(v)
    pf, vf = flight3d._column_major(p), flight3d._column_major(v)
    idx = np.arange(41)
    for _ in range(10):
        pc, vc = _row_major_step(pc, vc, neg_k, acc, 0.01)
        pf, vf = flight3d._rk4(pf, vf, neg_k, idx, acc, 0.01)
        assert pf.tobytes() == np.asfortranarray(pc).tobytes()
        assert vf.tobytes() == np.asfortranarray(vc).tobytes()


def test_a_flight_without_drag_lands_on_its_parabola() -> None:
    """k = 0, no effect: RK4 integrates the parabola exactly and the cubic crossing finds
    its root, so each landing is the closed form's within rounding."""
    rng = np.random.default_rng(8)
    n = 40
    p0 = np.c_[rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), rng.uniform(0.5, 2.0, n)]
    v0 = np.c_[rng.uniform(-3, 3, n), rng.uniform(-3, 3, n), rng.uniform(-1, 4, n)]
    lz = rng.uniform(-0.5, 0.3, n)
    res = fly(p0, v0, np.zeros(n), lz, step=0.01)
    # z0 + vz t - g t² / 2 = lz, the later root
    t = (v0[:, 2] + np.sqrt(v0[:, 2] ** 2 + 2 * G * (p0[:, 2] - lz))) / G
    assert res.landed.all()
    np.testing.assert_allclose(res.t, t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.position[:, :2], p0[:, :2] + v0[:, :2] * t[:, None], atol=1e-9)
    np.testing.assert_allclose(res.velocity[:, 2], v0[:, 2] - G * t, atol=1e-9)
    # sampled along the path: the parabola too
    ts = np.sort(rng.uniform(0.0, 0.5, (n, 4)), axis=1)
    got = sample_path(p0, v0, np.zeros(n), ts, step=0.01)
    want = p0[:, None, :] + v0[:, None, :] * ts[..., None]
    want[..., 2] -= 0.5 * G * ts**2
    np.testing.assert_allclose(got, want, atol=1e-9)


def _stacked_wind(winds: np.ndarray) -> Wind:
    """A wind with one value per throw (as a fit's stacked Jacobian builds it)."""
    e = object.__new__(Wind)
    for j, name in enumerate(("x_mps", "y_mps", "z_mps")):
        object.__setattr__(e, name, winds[:, j].copy())
    return e


def test_the_callback_reads_the_rows_it_is_handed_not_the_last_ones() -> None:
    """One wind per throw: after a call for some rows, a call for other rows (a new idx
    object, as the integrator hands after dropping rows) gets those rows' air, not the
    air kept from the first call; the values equal a fresh callback's."""
    n = 30
    b = _batch(5, n)
    winds = np.random.default_rng(6).normal(0.0, 2.0, (n, 3))
    acc = flight_accel(b, [_stacked_wind(winds), DragScale(factor=1.3)])
    rng = np.random.default_rng(7)
    p, v = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    first = np.arange(n)
    w1, e1 = acc(p, v, first)
    assert np.array_equal(w1, winds)
    later = np.flatnonzero(np.arange(n) % 3 != 0)  # fewer rows, a new object
    w2, e2 = acc(p[later], v[later], later)
    assert np.array_equal(w2, winds[later])
    fresh = flight_accel(b, [_stacked_wind(winds), DragScale(factor=1.3)])
    w3, e3 = fresh(p[later], v[later], later)
    assert np.array_equal(w2, w3) and np.array_equal(e2, e3)
    # the same rows at new states: the drag follows the velocity
    w4, e4 = acc(p[later], 2.0 * v[later], later)
    assert np.array_equal(w4, winds[later]) and not np.allclose(e4, e2)


def test_the_downwash_air_follows_the_position_at_every_stage() -> None:
    """With a downwash the air depends on where the item is: two calls for the same rows at
    different positions give each position's air (the air is not kept between stages)."""
    n = 12
    b = _batch(9, n)
    rpm = np.full(n, 6000.0)
    acc = flight_accel(b, [DownwashJet(speed_mps=10.0, radius_m=0.4, exponent=1.0)], rpm)
    idx = np.arange(n)
    below = b.position - np.array([0.0, 0.0, 0.3])
    further = b.position - np.array([0.0, 0.0, 0.9])
    w_near, _ = acc(below, np.zeros((n, 3)), idx)
    w_far, _ = acc(further, np.zeros((n, 3)), idx)
    assert np.all(w_near[:, 2] < w_far[:, 2])  # stronger (more negative) near the rotor
    fresh = flight_accel(b, [DownwashJet(speed_mps=10.0, radius_m=0.4, exponent=1.0)], rpm)
    assert np.array_equal(fresh(further, np.zeros((n, 3)), idx)[0], w_far)


def test_the_speeds_are_the_sums_written_out_column_by_column() -> None:
    """|rel|² of the rates ((x² + z²) + y²) and |x| of the callback ((x² + y²) + z²), their
    squares taken in one call: the sums of the columns' squares in that order, to the bit."""
    from cell.model.effects_air import _norm

    rel = flight3d._column_major(np.random.default_rng(14).normal(0.0, 3.0, (300, 3)))
    x, y, z = rel[:, 0], rel[:, 1], rel[:, 2]
    assert flight3d._speed_sq(rel).tobytes() == ((x * x + z * z) + y * y).tobytes()
    assert _norm(rel).tobytes() == np.sqrt((x * x + y * y) + z * z).tobytes()
