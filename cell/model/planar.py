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

from cell.model.integrate import hermite, hermite_root, plane_crossing, rk4_step
from cell.model.params import G

__all__ = ["flight_planar", "flight_planar_one", "hermite", "hermite_root", "rk4_planar"]

_DRAG_STEP_SCALE = 0.5  # step ≤ this / (k |v|): keeps the drag change per step small


def rk4_planar(h: Any, z: Any, vh: Any, vz: Any, k: Any, step: float, sqrt: Any) -> tuple:
    """One RK4 step (`cell.model.integrate.rk4_step`) of the planar flight (h, z, vh, vz)
    under gravity and drag -k|v|v; for arrays (sqrt = np.sqrt) and Python floats
    (math.sqrt) alike."""

    def deriv(y: tuple) -> tuple:
        wh, wz = y[2], y[3]
        speed = sqrt(wh * wh + wz * wz)
        return (wh, wz, -k * speed * wh, -k * speed * wz - G)

    return rk4_step(deriv, (h, z, vh, vz), step)


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
            sa, pos, vel = plane_crossing(
                np.array([[h, z]]),
                np.array([[h1, z1]]),
                np.array([[vh, vz]]),
                np.array([[vh1, vz1]]),
                step,
                lz,
            )
            s = float(sa[0])
            return float(pos[0, 0]), t + s * step, True, float(vel[0, 0]), float(vel[0, 1])
        if z1 <= lz and vz1 < 0:
            break
        h, z, vh, vz = h1, z1, vh1, vz1
        t += step
    return nan, nan, False, nan, nan


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

    Returns (distance, time, landed, vh_at_impact, vz_at_impact), each shape (n,).
    """
    n = z.shape[0]
    out_h = np.full(n, np.nan)
    out_t = np.full(n, np.nan)
    out_vh = np.full(n, np.nan)
    out_vz = np.full(n, np.nan)
    idx = np.arange(n)
    h_pos = np.zeros(n)
    t = 0.0
    z = z.copy()
    vh = vh.copy()
    vz = vz.copy()
    k = k.copy()
    lz = land_z.copy()
    while idx.size and t < t_max:
        step = min(
            max_step, float(_DRAG_STEP_SCALE / max(np.max(k * np.sqrt(vh * vh + vz * vz)), 1e-9))
        )
        h1, z1, vh1, vz1 = rk4_planar(h_pos, z, vh, vz, k, step, np.sqrt)
        cross = (z > lz) & (z1 <= lz)
        if np.any(cross):
            c = cross
            s, pos, vel = plane_crossing(
                np.stack([h_pos[c], z[c]], axis=-1),
                np.stack([h1[c], z1[c]], axis=-1),
                np.stack([vh[c], vz[c]], axis=-1),
                np.stack([vh1[c], vz1[c]], axis=-1),
                step,
                lz[c],
            )
            ids = idx[c]
            out_h[ids] = pos[:, 0]
            out_t[ids] = t + s * step
            out_vh[ids] = vel[:, 0]
            out_vz[ids] = vel[:, 1]
        # drop crossed throws, and those below their plane still falling (never land)
        keep = ~cross & ~((z1 <= lz) & (vz1 < 0))
        t += step
        if not np.all(keep):
            idx = idx[keep]
            h_pos, z, vh, vz, k, lz = h1[keep], z1[keep], vh1[keep], vz1[keep], k[keep], lz[keep]
        else:
            h_pos, z, vh, vz = h1, z1, vh1, vz1
    landed = np.isfinite(out_t)
    return out_h, out_t, landed, out_vh, out_vz
