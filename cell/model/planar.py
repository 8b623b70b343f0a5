"""Planar flight after the push, and the landing-plane crossing inside a step.

After the push the only forces on the object are gravity and drag along its
velocity, so its motion stays in the vertical plane of the launch velocity:
(h, z, vh, vz), h the horizontal distance along that plane. RK4 steps are
sized to the drag's time scale; the crossing of z = land_z is found on the
cubic Hermite interpolant of each step (exact for a drag-free parabola).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from cell.model.flight3d import current_gather
from cell.model.integrate import hermite, hermite_root
from cell.model.params import G

__all__ = [
    "flight_planar",
    "flight_planar_one",
    "hermite",
    "hermite_root",
    "planar_full_steps",
    "rk4_planar",
]

# step ≤ this / (k |v|): keeps the drag change per step small. At 0.5 a ping-pong ball
# (2.7 g, 40 mm, launched by the band at 40-93 m/s, k|v| up to 12/s) landed up to 25 mm
# (8 mm RMS) off a fine-step integration of its own flight; at 0.1 within 0.2 mm. It bites
# only where k|v| > 0.1 / 0.07 s = 1.4/s (the step is otherwise `max_step`): the
# catalogue's objects never reach that, and their landings are unchanged bit for bit.
_DRAG_STEP_SCALE = 0.1


def rk4_planar(h: Any, z: Any, vh: Any, vz: Any, k: Any, step: float, sqrt: Any) -> tuple:
    """One RK4 step of the planar flight (h, z, vh, vz) under gravity and drag -k|v|v.

    This is `cell.model.integrate.rk4_step` written out for the planar flight, the
    planner's and the fast path's inner loop (the general step's list handling costs
    this loop a third of its time); tests/test_integrate.py checks that the two give
    the same numbers to the last bit, for arrays (sqrt = np.sqrt) and for Python
    floats (math.sqrt).
    """
    speed = sqrt(vh * vh + vz * vz)
    a1h = -k * speed * vh
    a1z = -k * speed * vz - G
    vh2 = vh + 0.5 * step * a1h
    vz2 = vz + 0.5 * step * a1z
    s2 = sqrt(vh2 * vh2 + vz2 * vz2)
    a2h = -k * s2 * vh2
    a2z = -k * s2 * vz2 - G
    vh3 = vh + 0.5 * step * a2h
    vz3 = vz + 0.5 * step * a2z
    s3 = sqrt(vh3 * vh3 + vz3 * vz3)
    a3h = -k * s3 * vh3
    a3z = -k * s3 * vz3 - G
    vh4 = vh + step * a3h
    vz4 = vz + step * a3z
    s4 = sqrt(vh4 * vh4 + vz4 * vz4)
    a4h = -k * s4 * vh4
    a4z = -k * s4 * vz4 - G
    return (
        h + step / 6 * (vh + 2 * vh2 + 2 * vh3 + vh4),
        z + step / 6 * (vz + 2 * vz2 + 2 * vz3 + vz4),
        vh + step / 6 * (a1h + 2 * a2h + 2 * a3h + a4h),
        vz + step / 6 * (a1z + 2 * a2z + 2 * a3z + a4z),
    )


def flight_planar_one(
    z: float, vh: float, vz: float, k: float, lz: float, max_step: float, t_max: float = 30.0
) -> tuple[float, float, bool, float, float]:
    """`flight_planar` for a single throw in Python floats: the same steps and arithmetic,
    without NumPy's per-call overhead (a planner verifies one throw at a time)."""
    h, t = 0.0, 0.0
    nan = math.nan
    while t < t_max:
        step = min(max_step, _DRAG_STEP_SCALE / max(k * math.sqrt(vh * vh + vz * vz), 1e-9))
        h1, z1, vh1, vz1 = rk4_planar(h, z, vh, vz, k, step, math.sqrt)
        if z > lz >= z1:
            s = float(hermite_root(*(np.array([v]) for v in (z, z1, step * vz, step * vz1, lz)))[0])
            s2, s3 = s * s, s * s * s
            dist = (
                (2 * s3 - 3 * s2 + 1) * h
                + (s3 - 2 * s2 + s) * (step * vh)
                + (-2 * s3 + 3 * s2) * h1
                + (s3 - s2) * (step * vh1)
            )
            return dist, t + s * step, True, vh + (vh1 - vh) * s, vz + (vz1 - vz) * s
        if z1 <= lz and vz1 < 0:
            break
        h, z, vh, vz = h1, z1, vh1, vz1
        t += step
    return nan, nan, False, nan, nan


def _stage(
    vh: np.ndarray, vz: np.ndarray, dt: float, ah: np.ndarray, az: np.ndarray, neg_k: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One of RK4's later stages: the velocity dt [s] on at the previous stage's
    acceleration (ah, az) [m/s²] and the drag and gravity there."""
    vh_s = vh + dt * ah
    vz_s = vz + dt * az
    s = np.sqrt(vh_s * vh_s + vz_s * vz_s)
    return vh_s, vz_s, neg_k * s * vh_s, neg_k * s * vz_s - G


def _rk4_arrays(
    h: np.ndarray,
    z: np.ndarray,
    vh: np.ndarray,
    vz: np.ndarray,
    neg_k: np.ndarray,
    step: float,
    speed: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """`rk4_planar` for arrays with −k (neg_k) and the starting |v| (speed) given, as
    `flight_planar` holds them: the same arithmetic, operation for operation, without
    negating k at every stage nor taking the speed the step size was taken from again
    (tests/test_flight_same.py: equal to the bit)."""
    half = 0.5 * step
    a1h = neg_k * speed * vh
    a1z = neg_k * speed * vz - G
    vh2, vz2, a2h, a2z = _stage(vh, vz, half, a1h, a1z, neg_k)
    vh3, vz3, a3h, a3z = _stage(vh, vz, half, a2h, a2z, neg_k)
    vh4, vz4, a4h, a4z = _stage(vh, vz, step, a3h, a3z, neg_k)
    sixth = step / 6
    return (
        h + sixth * (vh + 2 * vh2 + 2 * vh3 + vh4),
        z + sixth * (vz + 2 * vz2 + 2 * vz3 + vz4),
        vh + sixth * (a1h + 2 * a2h + 2 * a3h + a4h),
        vz + sixth * (a1z + 2 * a2z + 2 * a3z + a4z),
    )


def flight_planar(
    z: np.ndarray,
    vh: np.ndarray,
    vz: np.ndarray,
    k: np.ndarray,
    land_z: np.ndarray,
    max_step: float,
    t_max: float = 30.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Planar flight under gravity and drag from horizontal distance 0.

    In a thread of `cell.model.flight_batch.together` the flights are integrated in one
    batch with the other threads' where that gives each the same numbers, bit for bit
    (`planar_full_steps`).

    Returns (distance, time, landed, vh_at_impact, vz_at_impact), each shape (n,).
    """
    gather = current_gather()
    if gather is not None:
        from cell.model.flight_batch import PlanarRequest

        return gather.submit(  # type: ignore[no-any-return]
            PlanarRequest(z, vh, vz, k, land_z, max_step, t_max)
        )
    return planar_full_steps(z, vh, vz, k, land_z, max_step, t_max)[0]


def planar_full_steps(
    z: np.ndarray,
    vh: np.ndarray,
    vz: np.ndarray,
    k: np.ndarray,
    land_z: np.ndarray,
    max_step: float,
    t_max: float = 30.0,
) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray], bool]:
    """`flight_planar` integrated here and now, and whether every step was `max_step`.

    A step is shortened where the drag is fast (the batch's largest k|v|), so the rows of
    one batch share their steps. Where no step was shortened, each row's numbers are those
    of its own batch: its steps would have been `max_step` too (its k|v| are among the
    batch's), and a row's arithmetic reads only its own row. So flights of several callers
    integrated as one batch are each the caller's own call's where this is True."""
    n = z.shape[0]
    idx = np.arange(n)
    h_pos = np.zeros(n)
    t = 0.0
    z = z.copy()
    vh = vh.copy()
    vz = vz.copy()
    k = k.copy()
    lz = land_z.copy()
    neg_k = -k
    crossed: list[tuple[np.ndarray, ...]] = []  # the crossing steps, located at the end
    full = True
    while idx.size and t < t_max:
        speed = np.sqrt(vh * vh + vz * vz)
        drag_step = float(_DRAG_STEP_SCALE / max((k * speed).max(), 1e-9))
        step = min(max_step, drag_step)
        full = full and drag_step >= max_step  # False for NaN too
        h1, z1, vh1, vz1 = _rk4_arrays(h_pos, z, vh, vz, neg_k, step, speed)
        below = z1 <= lz
        cross = (z > lz) & below
        if cross.any():
            c = cross
            ends = (h_pos[c], h1[c], z[c], z1[c], vh[c], vh1[c], vz[c], vz1[c], lz[c])
            crossed.append((idx[c], *ends, np.full(ends[0].size, t), np.full(ends[0].size, step)))
        # drop crossed throws, and those below their plane still falling (never land)
        keep = ~cross & ~(below & (vz1 < 0))
        t += step
        if not keep.all():
            idx, neg_k = idx[keep], neg_k[keep]
            h_pos, z, vh, vz, k, lz = h1[keep], z1[keep], vh1[keep], vz1[keep], k[keep], lz[keep]
        else:
            h_pos, z, vh, vz = h1, z1, vh1, vz1
    out_h, out_t, out_vh, out_vz = _crossings(n, crossed)
    landed = np.isfinite(out_t)
    return (out_h, out_t, landed, out_vh, out_vz), full


def _crossings(
    n: int, crossed: list[tuple[np.ndarray, ...]]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(distance, time, vh, vz) at the crossings of the steps `flight_planar` found
    crossing, located all at once (each row on its own step's interpolant)."""
    out_h, out_t, out_vh, out_vz = (np.full(n, np.nan) for _ in range(4))
    if crossed:
        ids, h0, h1, z0, z1, vh0, vh1, vz0, vz1, lz, t, step = (
            np.concatenate(a) for a in zip(*crossed, strict=True)
        )
        s = hermite_root(z0, z1, step * vz0, step * vz1, lz)
        out_h[ids] = hermite(h0, h1, step * vh0, step * vh1, s)
        out_t[ids] = t + s * step
        out_vh[ids] = vh0 + (vh1 - vh0) * s
        out_vz[ids] = vz0 + (vz1 - vz0) * s
    return out_h, out_t, out_vh, out_vz
