"""Flights of independent computations integrated as one batch
(`cell.model.flight_batch.together`): each computation gets, bit for bit, the crossings
its own `fly` call gives (checked against the calls made one at a time, outside any batch),
whatever else shares the batch; the batch is really one integration (the integrator's
calls counted); errors and nesting."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from cell.model import flight3d, flight_batch, planar
from cell.model.effects import (
    Downwash,
    DownwashDecay,
    DownwashJet,
    DragScale,
    Effect,
    Spin,
    Wind,
)
from cell.model.effects_air import stack_accels
from cell.model.effects_apply import flight_accel, predict_with_effects
from cell.model.flight_batch import together
from cell.model.params import EndEffectorParams
from cell.model.throw import ThrowBatch, drag_constant, launch_state, predict_landing

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


def _drag_rows(n: int) -> DragScale:
    """A drag factor of one value per throw (as a fit's stacked Jacobian gives)."""
    e = DragScale(factor=1.0)
    object.__setattr__(e, "factor", np.linspace(0.6, 2.2, n))
    return e


# (seed, throws, effects): every kind of callback, two of some kinds (stacked into one)
SETS: list[tuple[int, int, list[Effect]]] = [
    (1, 23, []),
    (2, 31, [Wind(x_mps=1.2, y_mps=-0.5, z_mps=0.2)]),
    (3, 17, [Wind(x_mps=-0.4, y_mps=0.9, z_mps=0.0)]),
    (4, 29, [DragScale(factor=1.7)]),
    (5, 40, [_drag_rows(40)]),
    (6, 21, [Spin(spin_rad_s=120.0, lift_max=0.35)]),
    (7, 26, [Downwash(speed_mps=8.0, radius_m=0.4, exponent=1.1)]),
    (8, 19, [DownwashDecay(speed_mps=7.0, radius_m=0.5, exponent=1.0, depth_m=1.2)]),
    (9, 33, [DownwashJet(speed_mps=9.0, radius_m=0.5, exponent=1.2)]),
    (10, 27, [Wind(x_mps=0.7, y_mps=0.2, z_mps=0.0), DragScale(factor=1.4)]),
    (11, 25, [Spin(spin_rad_s=-80.0, lift_max=0.5), DragScale(factor=0.8)]),
]


def _predict(seed: int, n: int, effs: list[Effect]) -> Callable[[], Any]:
    b = _batch(seed, n)
    rpm = np.random.default_rng(seed + 100).uniform(3000.0, 8000.0, n)
    return lambda: predict_with_effects(b, EE, effs, rotor_rpm=rpm, launch=_launch(b), step=0.02)


def _launch(b: ThrowBatch) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Launch states given (as tracks give them), so that even the nominal set flies
    through `fly`."""
    p, v = launch_state(b, EE)
    return p, v, np.full(len(b), EE.dt)


def _own_accel(b: ThrowBatch) -> Any:
    """A callback of no kind the batch knows (its rows cannot be stacked with others')."""
    wind = np.array([0.3, -0.2, 0.1])

    def acc(p: np.ndarray, v: np.ndarray, idx: np.ndarray) -> tuple[Any, Any]:
        return np.broadcast_to(wind, p.shape), -0.01 * v * (1.0 + idx[:, None] % 3)

    return acc


def _fly_own(seed: int, n: int, step: float) -> Callable[[], Any]:
    b = _batch(seed, n)
    p, v = launch_state(b, EE)
    k = drag_constant(b.shape, b.mass, b.size)
    return lambda: flight3d.fly(p, v, k, b.land_z, accel=_own_accel(b), t0=0.1, step=step)


def _thunks() -> list[Callable[[], Any]]:
    return [_predict(*s) for s in SETS] + [_fly_own(12, 15, 0.02), _fly_own(13, 18, 0.01)]


def _fields(r: Any) -> list[np.ndarray]:
    names = ("x", "y", "t_flight", "impact_velocity", "landed", "launch_velocity")
    if hasattr(r, "x"):
        return [np.asarray(getattr(r, f)) for f in names]
    return [r.position, r.velocity, r.t, r.landed]


def test_each_flight_of_the_batch_is_its_own_call(monkeypatch: pytest.MonkeyPatch) -> None:
    """Eleven effect sets (none; two winds; a drag factor, also one per throw; spin; the
    three downwash laws; wind with drag; spin with drag) and a callback of its own at two
    steps: together, each gets its own call's crossings bit for bit, from one integration
    per step."""
    ref = [t() for t in _thunks()]
    calls: list[int] = []
    inner = flight3d._fly

    def counted(*a: Any, **kw: Any) -> Any:
        calls.append(a[0].shape[0])
        return inner(*a, **kw)

    monkeypatch.setattr(flight3d, "_fly", counted)
    got = together(_thunks())
    assert len(calls) == 2  # one batch per step (0.02 s and 0.01 s)
    assert sum(calls) == sum(n for _, n, _ in SETS) + 15 + 18
    for a, b in zip(ref, got, strict=True):
        for u, w in zip(_fields(a), _fields(b), strict=True):
            assert np.array_equal(u, w, equal_nan=True)
    assert all(np.any(r.landed) for r in ref)  # flights that land, not NaNs compared


def test_stacked_callbacks_give_each_row_its_own_values() -> None:
    """Callbacks of one kind (a wind with a drag factor, or a downwash) put end to end:
    each row's air velocity and extra acceleration are its own callback's, to the bit."""
    kinds = [
        [[Wind(x_mps=0.5, y_mps=0.1, z_mps=0.0), DragScale(factor=1.3)],
         [Wind(x_mps=-1.0, y_mps=0.4, z_mps=0.3), _drag_rows(9)]],
        [[Downwash(speed_mps=8.0, radius_m=0.4, exponent=1.1)],
         [Downwash(speed_mps=5.0, radius_m=0.7, exponent=0.9)]],
    ]  # fmt: skip
    for sets in kinds:
        bs = [_batch(20 + j, 9) for j in range(len(sets))]
        accs = [flight_accel(b, effs, np.full(9, 5000.0)) for b, effs in zip(bs, sets, strict=True)]
        p = np.concatenate([launch_state(b, EE)[0] for b in bs])
        v = np.concatenate([launch_state(b, EE)[1] for b in bs])
        w, extra = stack_accels(accs)(p, v, np.arange(18))
        for j, a in enumerate(accs):
            rows = slice(9 * j, 9 * j + 9)
            w_j, x_j = a(p[rows], v[rows], np.arange(9))
            assert np.array_equal(w[rows], w_j)
            assert (x_j is None and extra is None) or np.array_equal(extra[rows], x_j)


def test_an_error_is_raised_once_every_thunk_has_finished() -> None:
    done: list[int] = []

    def fails() -> None:
        _predict(2, 10, [Wind(x_mps=1.0, y_mps=0.0, z_mps=0.0)])()
        raise ValueError("a thunk failed")

    def flies() -> None:
        for _ in range(3):
            _predict(3, 12, [DragScale(factor=1.5)])()
        done.append(1)

    with pytest.raises(ValueError, match="a thunk failed"):
        together([fails, flies])
    assert done == [1]


def test_nested_together_joins_the_outer_batch() -> None:
    """`together` inside a thunk runs its thunks in turn; their flights still join the
    outer batch, and every result is its own call's."""
    ts = _thunks()
    ref = [t() for t in ts]
    got = together([lambda: together(ts[:4]), lambda: together(ts[4:])])
    for a, b in zip(ref, got[0] + got[1], strict=True):
        for u, w in zip(_fields(a), _fields(b), strict=True):
            assert np.array_equal(u, w, equal_nan=True)


def test_the_thunks_keep_the_callers_numpy_error_state() -> None:
    """`cell.cli` runs a command under `np.errstate(all="ignore")`; NumPy keeps that state
    per context, and a thread starts without it: each thunk runs in a copy of the
    caller's context."""
    with np.errstate(all="ignore"):
        got = together([np.geterr, np.geterr])
    assert got == [np.geterr() | {k: "ignore" for k in np.geterr()}] * 2


def _planar(seed: int, n: int, light: bool = False) -> Callable[[], Any]:
    """The fast path's landings (no effect: the planar flight); `light`: 2.7 g spheres of
    40 mm (a ping-pong ball), whose fast drag shortens the planar steps."""
    b = _batch(seed, n)
    if light:
        b = ThrowBatch.build(
            stroke=b.stroke, position=b.position, elevation=b.elevation, azimuth=b.azimuth,
            shape=np.full(n, 3), mass=np.full(n, 0.0027), size=np.full((n, 3), 0.04),
            base_velocity=b.base_velocity, land_z=b.land_z, roll=0.0,
        )  # fmt: skip
    return lambda: predict_landing(b, EE, strict=False, check_stroke=False)


def _planar_calls(monkeypatch: pytest.MonkeyPatch) -> list[tuple[int, bool]]:
    """The planar integrations made (rows, all steps full), counted where the batch calls
    them."""
    calls: list[tuple[int, bool]] = []
    inner = planar.planar_full_steps

    def counted(*a: Any, **kw: Any) -> Any:
        res, full = inner(*a, **kw)
        calls.append((a[0].shape[0], full))
        return res, full

    monkeypatch.setattr(flight_batch, "planar_full_steps", counted)
    return calls


def test_planar_flights_of_the_batch_are_each_their_own_call(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Five sets of throws on the fast path (no effect), together: each gets its own call's
    landings bit for bit, from one planar integration with every step full."""
    sets = [(31, 23), (32, 40), (33, 17), (34, 2), (35, 29)]
    ref = [_planar(*s)() for s in sets]
    calls = _planar_calls(monkeypatch)
    got = together([_planar(*s) for s in sets])
    assert calls == [(sum(n for _, n in sets), True)]
    for a, b in zip(ref, got, strict=True):
        for u, w in zip(_fields(a), _fields(b), strict=True):
            assert np.array_equal(u, w, equal_nan=True)
    assert all(np.all(r.landed) for r in ref)


def test_a_shortened_planar_step_flies_each_request_on_its_own(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Ping-pong balls shorten the batch's planar steps: the batch is flown again request by
    request, so the other throws keep the full steps of their own call, bit for bit."""
    thunks = [_planar(41, 20), _planar(42, 12, light=True), _planar(43, 25)]
    ref = [t() for t in thunks]
    calls = _planar_calls(monkeypatch)
    got = together(thunks)
    assert calls == [(57, False), (20, True), (12, False), (25, True)]
    for a, b in zip(ref, got, strict=True):
        for u, w in zip(_fields(a), _fields(b), strict=True):
            assert np.array_equal(u, w, equal_nan=True)
