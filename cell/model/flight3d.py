"""A general 3-D flight integrator for model augmentations (effects).

The nominal fast path (`cell.model.throw`) uses that, after the push, drag
acts along the velocity so the flight stays in one vertical plane. Effects
such as wind, rotor downwash or spin lift break that: they need the full 3-D
equations of motion

    dv/dt = g + a_extra(p, v) - k |v - w(p)| (v - w(p))     [m/s², world W]

with w the air velocity [m/s] and k = ½ ρ C_d A / m [1/m]. This module
integrates them with fixed RK4 steps over a batch, locates the crossing of
each throw's landing plane inside the step on the cubic Hermite interpolant
(as the fast path does), and can sample the path at given times (to compare
with observed tracks).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.model.integrate import hermite as _hermite
from cell.model.integrate import plane_crossing
from cell.model.params import G

__all__ = [
    "Accel",
    "FlightResult",
    "Rows",
    "acceleration",
    "column_fraction",
    "current_gather",
    "fly",
    "route_flights",
    "sample_path",
]

# acc(p, v, idx) -> (air velocity (m, 3) or None, extra acceleration (m, 3) or None);
# idx are the indices (into the batch) of the rows in p and v. An accel whose attribute
# `reads_position` is False is handed the step's starting positions at every stage.
Accel = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray | None, np.ndarray | None]]


def column_fraction(rho: np.ndarray, radius: np.ndarray | float, edge: float) -> np.ndarray:
    """How much of a vertical air column's speed reaches a point, by its horizontal distance.

    A smooth top hat, 0.5 (1 + tanh((radius − ρ) / edge)): 1 well inside, 0 well outside,
    0.5 on the edge. Every downwash law of the cell shapes its column with it (the
    drone's, `cell.platforms.downwash`, and the gap diagnosis's `Downwash` effect).

    Args:
        rho: horizontal distance from the column's axis [m].
        radius: the column's radius [m].
        edge: width of its smooth edge [m].
    """
    return 0.5 * (1.0 + np.tanh((radius - rho) / edge))


class Rows:
    """Per-throw arrays taken at the rows of the last `idx` an `Accel` was handed.

    `fly` and `sample_path` pass the same `idx` object (never changed in place) while
    the rows they integrate stay the same, so a callback that reads its per-throw
    arrays through this takes them once per set of rows, not at every stage of every step.
    """

    def __init__(self, per_throw: dict[str, np.ndarray]) -> None:
        self._all = per_throw
        self._idx: np.ndarray | None = None
        self._rows: dict[str, np.ndarray] = {}

    def __call__(self, idx: np.ndarray) -> dict[str, np.ndarray]:
        """{name: array[idx]} of the arrays given."""
        if idx is not self._idx:
            self._rows = {name: a[idx] for name, a in self._all.items()}
            self._idx = idx
        return self._rows


@dataclass(frozen=True)
class FlightResult:
    """Where and when each throw crosses its landing plane.

    Attributes:
        position: crossing point [m, W], shape (n, 3) (NaN where it never lands).
        velocity: velocity at the crossing [m/s, W], shape (n, 3).
        t: time of the crossing [s] (same clock as the start time), shape (n,).
        landed: True where the plane is crossed while descending, shape (n,).
    """

    position: np.ndarray
    velocity: np.ndarray
    t: np.ndarray
    landed: np.ndarray


def _speed_sq(rel: np.ndarray) -> np.ndarray:
    """|rel|² of each row of rel (m, 3), from its columns: the sum `np.einsum("ij,ij->i")`
    made before the states were kept column-major, in its order ((x² + z²) + y², its two-lane
    accumulator), so the rates are bitwise the ones it gave (tests/test_flight_layout.py).
    The squares in one call (rel²'s columns are x², y², z²), their sums column by column."""
    sq = rel * rel
    return (sq[:, 0] + sq[:, 2]) + sq[:, 1]


def _rates(
    p: np.ndarray, v: np.ndarray, neg_k: np.ndarray, idx: np.ndarray, accel: Accel | None
) -> np.ndarray:
    """dv/dt for rows idx; neg_k is -k of those rows [1/m]."""
    if accel is None:
        w, extra = None, None
    else:
        w, extra = accel(p, v, idx)
    rel = v if w is None else v - w
    a = (neg_k * np.sqrt(_speed_sq(rel)))[:, None] * rel
    a[:, 2] -= G
    if extra is not None:
        a += extra
    return a


def acceleration(
    position: np.ndarray, velocity: np.ndarray, k: np.ndarray, accel: Accel | None = None
) -> np.ndarray:
    """dv/dt [m/s², W] at these states (gravity, drag in the air flow, extra effects)."""
    idx = np.arange(position.shape[0])
    neg_k = -np.asarray(k, float)
    return _rates(_column_major(position), _column_major(velocity), neg_k, idx, accel)


def _rk4(
    p: np.ndarray, v: np.ndarray, neg_k: np.ndarray, idx: np.ndarray, accel: Accel | None, h: float
) -> tuple[np.ndarray, np.ndarray]:
    """One RK4 step of rows idx: `cell.model.integrate.rk4_step` written out for whole
    (m, 3) vectors, the same arithmetic operation for operation (tests/test_flight_layout.py).
    The stages' positions are formed only for an accel that reads them (`reads_position`,
    true unless the accel says otherwise): gravity and drag alone, a wind, a spin or a drag
    factor do not (`rk4_step`'s `reads_position`)."""
    half = 0.5 * h
    reads = accel is not None and getattr(accel, "reads_position", True)
    a1 = _rates(p, v, neg_k, idx, accel)
    v2 = v + half * a1
    a2 = _rates(p + half * v if reads else p, v2, neg_k, idx, accel)
    v3 = v + half * a2
    a3 = _rates(p + half * v2 if reads else p, v3, neg_k, idx, accel)
    v4 = v + h * a3
    a4 = _rates(p + h * v3 if reads else p, v4, neg_k, idx, accel)
    sixth = h / 6
    p_new = p + sixth * (v + 2 * v2 + 2 * v3 + v4)
    v_new = v + sixth * (a1 + 2 * a2 + 2 * a3 + a4)
    return p_new, v_new


# Rows whose flight is over stay in the batch (their steps cost little beside NumPy's
# per-call overhead) until fewer than this share of the rows integrated still fly.
KEEP_SHARE = 0.5


def _column_major(a: np.ndarray) -> np.ndarray:
    """A copy of the (m, 3) states a, laid out column by column (Fortran order): each
    component contiguous, so the rates' column reads and per-row scalings run over
    contiguous memory (NumPy's elementwise results keep their operands' layout)."""
    return np.array(a, float, order="F")


def _keep(a: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The rows of column-major states a (m, 3) where rows is True, column-major still."""
    return np.asarray(a.T[:, rows].T)


# the thread's gatherer of flights (`cell.model.flight_batch.together`), if any
_ROUTE = threading.local()


def route_flights(gather: Any) -> None:
    """Hand this thread's `fly` calls to `gather` (its `submit`), not integrate them."""
    _ROUTE.gather = gather


def current_gather() -> Any:
    """This thread's gatherer of flights, or None."""
    return getattr(_ROUTE, "gather", None)


def fly(
    position: np.ndarray,
    velocity: np.ndarray,
    k: np.ndarray,
    land_z: np.ndarray,
    *,
    accel: Accel | None = None,
    t0: np.ndarray | float = 0.0,
    step: float = 0.01,
    t_max: float = 30.0,
) -> FlightResult:
    """Integrate flights until each crosses its plane z = land_z going down.

    In a thread of `cell.model.flight_batch.together` the flights are integrated in one
    batch with the other threads' (the same crossings, bit for bit).

    Args:
        position: start positions [m, W], shape (n, 3).
        velocity: start velocities [m/s, W], shape (n, 3).
        k: drag constant ½ ρ C_d A / m [1/m], shape (n,).
        land_z: landing-plane heights [m], shape (n,).
        accel: the effects' air velocity and extra acceleration (None: nominal).
        t0: start time(s) [s]; the returned crossing times count on this clock.
        step: RK4 step [s].
        t_max: give up after this flight time [s] (the throw is marked not landed).

    Returns:
        The crossings.
    """
    gather = getattr(_ROUTE, "gather", None)
    if gather is not None:
        from cell.model.flight_batch import FlightRequest

        n = position.shape[0]
        return gather.submit(  # type: ignore[no-any-return]
            FlightRequest(
                position=np.asarray(position, float),
                velocity=np.asarray(velocity, float),
                k=np.broadcast_to(np.asarray(k, float), (n,)),
                land_z=np.broadcast_to(np.asarray(land_z, float), (n,)),
                accel=accel,
                t0=np.broadcast_to(np.asarray(t0, float), (n,)),
                step=step,
                t_max=t_max,
            )
        )
    return _fly(position, velocity, k, land_z, accel=accel, t0=t0, step=step, t_max=t_max)


def _fly(
    position: np.ndarray,
    velocity: np.ndarray,
    k: np.ndarray,
    land_z: np.ndarray,
    *,
    accel: Accel | None = None,
    t0: np.ndarray | float = 0.0,
    step: float = 0.01,
    t_max: float = 30.0,
) -> FlightResult:
    """`fly` integrated here and now."""
    n = position.shape[0]
    t_start = np.broadcast_to(np.asarray(t0, float), (n,))
    idx = np.arange(n)
    p = _column_major(position)
    v = _column_major(velocity)
    neg_k = -np.broadcast_to(np.asarray(k, float), (n,))
    lz = np.broadcast_to(np.asarray(land_z, float), (n,))
    flying = np.ones(n, bool)
    n_flying = n
    crossed: list[tuple[np.ndarray, ...]] = []  # rows, the step's end states, plane, t
    t = 0.0
    while n_flying and t < t_max:
        p1, v1 = _rk4(p, v, neg_k, idx, accel, step)
        below = p1[:, 2] <= lz
        cross = below & (p[:, 2] > lz) & flying
        if cross.any():
            rows = idx[cross]
            states = (p[cross], p1[cross], v[cross], v1[cross])
            crossed.append((rows, *states, lz[cross], np.full(rows.size, t)))
        # over: crossed, or below the plane still falling (never lands)
        flying &= ~(cross | (below & (v1[:, 2] < 0)))
        n_flying = int(np.count_nonzero(flying))
        t += step
        if n_flying < KEEP_SHARE * idx.size:
            idx, p, v = idx[flying], _keep(p1, flying), _keep(v1, flying)
            neg_k, lz, flying = neg_k[flying], lz[flying], flying[flying]
        else:
            p, v = p1, v1
    return _crossings(n, crossed, t_start, step)


def _crossings(
    n: int, crossed: list[tuple[np.ndarray, ...]], t_start: np.ndarray, step: float
) -> FlightResult:
    """The crossings of the steps `fly` found crossing, located all at once."""
    out_p = np.full((n, 3), np.nan)
    out_v = np.full((n, 3), np.nan)
    out_t = np.full(n, np.nan)
    if crossed:
        rows, p0, p1, v0, v1, lz, t = (np.concatenate(a) for a in zip(*crossed, strict=True))
        s, out_p[rows], out_v[rows] = plane_crossing(p0, p1, v0, v1, step, lz)
        out_t[rows] = t_start[rows] + t + s * step
    return FlightResult(position=out_p, velocity=out_v, t=out_t, landed=np.isfinite(out_t))


def sample_path(
    position: np.ndarray,
    velocity: np.ndarray,
    k: np.ndarray,
    t_rel: np.ndarray,
    *,
    accel: Accel | None = None,
    step: float = 0.01,
) -> np.ndarray:
    """Positions along each flight at given times after the start.

    Args:
        position: start positions [m, W], shape (n, 3).
        velocity: start velocities [m/s, W], shape (n, 3).
        k: drag constant [1/m], shape (n,).
        t_rel: sample times after the start [s], shape (n, m) (NaN = no sample).
        accel: the effects' air velocity and extra acceleration (None: nominal).
        step: RK4 step [s].

    Returns:
        Positions [m, W], shape (n, m, 3) (NaN where t_rel is NaN or negative).
    """
    n, m = t_rel.shape
    out = np.full((n, m, 3), np.nan)
    t_end = np.nanmax(np.where(np.isfinite(t_rel), t_rel, -1.0), axis=1)
    idx = np.arange(n)[t_end >= 0]
    p = _column_major(np.asarray(position, float)[idx])
    v = _column_major(np.asarray(velocity, float)[idx])
    neg_k = -np.broadcast_to(np.asarray(k, float), (n,))[idx]
    tr, te = t_rel[idx], t_end[idx]
    t = 0.0
    while idx.size:
        p1, v1 = _rk4(p, v, neg_k, idx, accel, step)
        inside = (tr >= t) & (tr < t + step)
        if inside.any():
            rows, cols = np.nonzero(inside)
            s = (tr[rows, cols] - t) / step
            for j in range(3):
                out[idx[rows], cols, j] = _hermite(
                    p[rows, j], p1[rows, j], step * v[rows, j], step * v1[rows, j], s
                )
        t += step
        # rows past their last sample stay until fewer than the share go on
        going = te >= t
        if np.count_nonzero(going) < KEEP_SHARE * idx.size:
            idx, neg_k, tr, te = (a[going] for a in (idx, neg_k, tr, te))
            p, v = _keep(p1, going), _keep(v1, going)
        else:
            p, v = p1, v1
    return out
