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

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from cell.model.params import G
from cell.model.planar import hermite as _hermite
from cell.model.planar import hermite_root as _hermite_root

__all__ = ["Accel", "FlightResult", "acceleration", "fly", "sample_path"]

# acc(p, v, idx) -> (air velocity (m, 3) or None, extra acceleration (m, 3) or None);
# idx are the indices (into the batch) of the rows in p and v.
Accel = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray | None, np.ndarray | None]]


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


def _rates(
    p: np.ndarray, v: np.ndarray, k: np.ndarray, idx: np.ndarray, accel: Accel | None
) -> np.ndarray:
    """dv/dt for rows idx."""
    if accel is None:
        w, extra = None, None
    else:
        w, extra = accel(p, v, idx)
    rel = v if w is None else v - w
    a = -k[:, None] * np.sqrt(np.einsum("ij,ij->i", rel, rel))[:, None] * rel
    a[:, 2] -= G
    if extra is not None:
        a += extra
    return a


def acceleration(
    position: np.ndarray, velocity: np.ndarray, k: np.ndarray, accel: Accel | None = None
) -> np.ndarray:
    """dv/dt [m/s², W] at these states (gravity, drag in the air flow, extra effects)."""
    idx = np.arange(position.shape[0])
    return _rates(np.asarray(position, float), np.asarray(velocity, float), k, idx, accel)


def _rk4(
    p: np.ndarray, v: np.ndarray, k: np.ndarray, idx: np.ndarray, accel: Accel | None, h: float
) -> tuple[np.ndarray, np.ndarray]:
    a1 = _rates(p, v, k, idx, accel)
    p2, v2 = p + 0.5 * h * v, v + 0.5 * h * a1
    a2 = _rates(p2, v2, k, idx, accel)
    p3, v3 = p + 0.5 * h * v2, v + 0.5 * h * a2
    a3 = _rates(p3, v3, k, idx, accel)
    p4, v4 = p + h * v3, v + h * a3
    a4 = _rates(p4, v4, k, idx, accel)
    return (
        p + h / 6 * (v + 2 * v2 + 2 * v3 + v4),
        v + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4),
    )


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
    n = position.shape[0]
    out_p = np.full((n, 3), np.nan)
    out_v = np.full((n, 3), np.nan)
    out_t = np.full(n, np.nan)
    t_start = np.broadcast_to(np.asarray(t0, float), (n,))
    idx = np.arange(n)
    p = np.asarray(position, float).copy()
    v = np.asarray(velocity, float).copy()
    kk = np.asarray(k, float)
    lz = np.asarray(land_z, float)
    t = 0.0
    # the steps that cross, located inside the step all at once after the loop
    hits: list[tuple[np.ndarray, ...]] = []
    while idx.size and t < t_max:
        p1, v1 = _rk4(p, v, kk[idx], idx, accel, step)
        cross = (p[:, 2] > lz[idx]) & (p1[:, 2] <= lz[idx])
        if np.any(cross):
            c = cross
            hits.append((idx[c], p[c], p1[c], v[c], v1[c], np.full(int(c.sum()), t)))
        keep = ~cross & ~((p1[:, 2] <= lz[idx]) & (v1[:, 2] < 0))
        idx, p, v = idx[keep], p1[keep], v1[keep]
        t += step
    if hits:
        ids, pa, pb, va, vb, tt = (np.concatenate(x) for x in zip(*hits, strict=True))
        s = _hermite_root(pa[:, 2], pb[:, 2], step * va[:, 2], step * vb[:, 2], lz[ids])
        for j in range(3):
            out_p[ids, j] = _hermite(pa[:, j], pb[:, j], step * va[:, j], step * vb[:, j], s)
            out_v[ids, j] = va[:, j] + (vb[:, j] - va[:, j]) * s
        out_t[ids] = t_start[ids] + tt + s * step
    landed = np.isfinite(out_t)
    return FlightResult(position=out_p, velocity=out_v, t=out_t, landed=landed)


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
    p = np.asarray(position, float)[idx].copy()
    v = np.asarray(velocity, float)[idx].copy()
    kk = np.asarray(k, float)
    t = 0.0
    while idx.size:
        p1, v1 = _rk4(p, v, kk[idx], idx, accel, step)
        tr = t_rel[idx]
        inside = (tr >= t) & (tr < t + step)
        if np.any(inside):
            rows, cols = np.nonzero(inside)
            s = (tr[rows, cols] - t) / step
            for j in range(3):
                out[idx[rows], cols, j] = _hermite(
                    p[rows, j], p1[rows, j], step * v[rows, j], step * v1[rows, j], s
                )
        t += step
        keep = t_end[idx] >= t
        idx, p, v = idx[keep], p1[keep], v1[keep]
    return out
