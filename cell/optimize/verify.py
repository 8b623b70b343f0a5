"""Judging and polishing a release state σ with the NumPy model.

Every plan is flown by `cell.model.predict_landing`, whatever produced it.
`polish` removes what is left of the miss with a few Newton steps on that
model itself (finite differences, one vectorised call per step).
"""

from __future__ import annotations

import numpy as np

from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams
from cell.model.throw import ThrowBatch, predict_landing

__all__ = ["POLISH_TOL", "sigma_batch", "fly", "polish"]

POLISH_TOL = 1e-4  # [m] the polish stops below this miss
_POLISH_ITERS = 4


def sigma_batch(obj: ObjectParams, sigma: np.ndarray, land_z: float) -> ThrowBatch:
    """σ rows as a batch. σ comes from the planner (finite, in bounds), so the
    batch is assembled directly rather than through `ThrowBatch.build`'s checks."""
    s = np.atleast_2d(np.asarray(sigma, float))
    n = s.shape[0]
    return ThrowBatch(
        stroke=s[:, 9].copy(),
        position=s[:, 0:3].copy(),
        elevation=s[:, 7].copy(),
        azimuth=s[:, 8].copy(),
        base_velocity=s[:, 3:6].copy(),
        land_z=np.full(n, float(land_z)),
        shape=np.full(n, obj.code),
        mass=np.full(n, float(obj.mass)),
        size=np.tile(np.asarray(obj.size, float), (n, 1)),
        roll=s[:, 6].copy(),
    )


def fly(
    obj: ObjectParams, sigma: np.ndarray, target: np.ndarray, ee: EndEffectorParams
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Landing (n, 2), miss (n,) [m] and flight time (n,) [s] of σ rows; NaN/inf if no landing."""
    land = predict_landing(sigma_batch(obj, sigma, float(target[2])), ee, strict=False)
    xy = land.xy
    miss = np.where(land.landed, np.hypot(xy[:, 0] - target[0], xy[:, 1] - target[1]), np.inf)
    return xy, miss, land.t_flight


def polish(
    obj: ObjectParams,
    sigma: np.ndarray,
    target: np.ndarray,
    ee: EndEffectorParams,
    lower: np.ndarray,
    upper: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Newton on the NumPy model until the miss is below POLISH_TOL.

    The along-track variable is the stroke (else the elevation when the stroke
    sits on a bound), the cross-track one the azimuth; the 2×2 Jacobian comes
    from forward differences, all throws of an iteration in one vectorised
    call. A step that does not reduce the miss ends the polish.

    Args:
        obj: the object.
        sigma: starting σ, shape (10,).
        target: goal (x, y, land_z) [m, W].
        ee: end-effector parameters.
        lower: σ_L, shape (10,); upper: σ_U, shape (10,). σ stays inside.

    Returns:
        (σ, landing (x, y) [m], miss [m], flight time from the push's start [s]).
    """
    sigma = np.clip(sigma, lower, upper)
    xy, miss, tf = fly(obj, sigma, target, ee)
    for _ in range(_POLISH_ITERS):
        if miss[0] <= POLISH_TOL or not np.isfinite(miss[0]):
            break
        along = 9 if lower[9] + 1e-7 < sigma[9] < upper[9] - 1e-7 else 7
        cols = [along, 8]
        steps = np.array([1e-6 if along == 9 else 1e-5, 1e-6])
        trial = np.tile(sigma, (3, 1))
        for i, c in enumerate(cols):
            trial[i + 1, c] += steps[i]
        txy, tmiss, _ = fly(obj, trial, target, ee)
        if not np.all(np.isfinite(tmiss)):
            break
        jac = (txy[1:] - txy[0]).T / steps  # (2, 2): d landing / d (along, azimuth)
        try:
            delta = np.linalg.solve(jac, target[:2] - txy[0])
        except np.linalg.LinAlgError:
            break
        new = sigma.copy()
        new[cols] += delta
        new = np.clip(new, lower, upper)
        nxy, nmiss, ntf = fly(obj, new, target, ee)
        if not nmiss[0] < miss[0]:
            break
        sigma, xy, miss, tf = new, nxy, nmiss, ntf
    return sigma, xy[0], float(miss[0]), float(tf[0])
