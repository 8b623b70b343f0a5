"""The numerics every flight integrator shares: one RK4 step, one landing-plane crossing.

* `rk4_step`: one classical Runge–Kutta step of p' = v, v' = a(p, v), the position and
  velocity as sequences of parts (floats, NumPy arrays or CasADi expressions). The push,
  the planar and 3-D flights, the reference, the rigid body (its spin an extra part of
  v) and the CasADi model all step with it, so they take the same arithmetic, operation
  for operation.
* `plane_crossing`: where a step crosses a landing plane z = level going down, on the
  cubic Hermite interpolant of the step's end states (positions and velocities), found
  by `hermite_root`; the velocity at the crossing is interpolated linearly in the step.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

__all__ = ["PUSH_STEPS", "hermite", "hermite_root", "plane_crossing", "push_steps", "rk4_step"]


def rk4_step(
    accel: Callable[..., Sequence[Any]],
    p: Sequence[Any],
    v: Sequence[Any],
    h: Any,
    *,
    reads_position: bool = False,
) -> tuple[list[Any], list[Any]]:
    """One classical RK4 step of p' = v, v' = accel(p, v).

    p and v are sequences of parts (floats, NumPy arrays or CasADi expressions): the
    components of a position and its velocity, or whole vectors. v may hold more parts
    than p: those are first-order states with no position (the rigid body's spin).

    Args:
        accel: the rates of v's parts from the stage's (p, v).
        p: positions.
        v: velocities (and any first-order states after them).
        h: the step [s] (a number or a CasADi expression).
        reads_position: accel uses p; otherwise the stages' positions are not formed
            (accel gets the step's start p) and the step costs less.

    Returns:
        (p, v) after the step: with a_k = accel at the stages, v_2 = v + h/2 a_1,
        v_3 = v + h/2 a_2, v_4 = v + h a_3, the new v = v + h/6 (a_1 + 2 a_2 + 2 a_3 + a_4)
        and the new p = p + h/6 (v + 2 v_2 + 2 v_3 + v_4).
    """
    half = 0.5 * h
    a1 = accel(p, v)
    v2 = [x + half * a for x, a in zip(v, a1, strict=True)]
    a2 = accel([x + half * w for x, w in zip(p, v, strict=False)] if reads_position else p, v2)
    v3 = [x + half * a for x, a in zip(v, a2, strict=True)]
    a3 = accel([x + half * w for x, w in zip(p, v2, strict=False)] if reads_position else p, v3)
    v4 = [x + h * a for x, a in zip(v, a3, strict=True)]
    a4 = accel([x + h * w for x, w in zip(p, v3, strict=False)] if reads_position else p, v4)
    sixth = h / 6
    p_new = [
        x + sixth * (w1 + 2 * w2 + 2 * w3 + w4)
        for x, w1, w2, w3, w4 in zip(p, v, v2, v3, v4, strict=False)
    ]
    v_new = [
        x + sixth * (b1 + 2 * b2 + 2 * b3 + b4)
        for x, b1, b2, b3, b4 in zip(v, a1, a2, a3, a4, strict=True)
    ]
    return p_new, v_new


def hermite_root(
    z0: np.ndarray, z1: np.ndarray, w0: np.ndarray, w1: np.ndarray, level: np.ndarray
) -> np.ndarray:
    """Parameter s ∈ [0, 1] where the cubic Hermite z(s) (w = h·dz/dt) first reaches `level`
    going down, with z0 > level ≥ z1. Safeguarded Newton from the secant guess, 8 steps
    (3a, 2b and the test f > 0 taken once, one error state around them: the same numbers)."""
    a = 2 * z0 - 2 * z1 + w0 + w1
    b = -3 * z0 + 3 * z1 - 2 * w0 - w1
    c = w0
    d = z0 - level
    a3, b2 = 3 * a, 2 * b
    lo = np.zeros_like(z0)
    hi = np.ones_like(z0)
    s = np.clip(d / np.maximum(z0 - z1, 1e-300), 0.0, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        for _ in range(8):
            f = ((a * s + b) * s + c) * s + d
            up = f > 0
            lo = np.where(up, s, lo)
            hi = np.where(up, hi, s)
            df = (a3 * s + b2) * s + c
            s_new = s - f / df
            bad = ~np.isfinite(s_new) | (s_new < lo) | (s_new > hi)
            s = np.where(bad, 0.5 * (lo + hi), s_new)
    return s


def hermite(y0: Any, y1: Any, w0: Any, w1: Any, s: Any) -> Any:
    """The cubic Hermite interpolant at s ∈ [0, 1] between y0 and y1 with end slopes
    w0, w1 (per unit s, i.e. step × derivative). Floats or arrays."""
    s2 = s * s
    s3 = s2 * s
    return (
        (2 * s3 - 3 * s2 + 1) * y0
        + (s3 - 2 * s2 + s) * w0
        + (-2 * s3 + 3 * s2) * y1
        + (s3 - s2) * w1
    )


def plane_crossing(
    p0: np.ndarray, p1: np.ndarray, v0: np.ndarray, v1: np.ndarray, step: float, level: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where steps from (p0, v0) to (p1, v1) cross the plane z = level going down.

    Args:
        p0, p1: positions at the step's start and end, shape (m, d); the last column is
            the height z [m].
        v0, v1: velocities there [m/s], shape (m, d).
        step: the step [s].
        level: plane height(s) [m], scalar or shape (m,); z0 > level ≥ z1 in every row.

    Returns:
        (s, position, velocity): the fraction of the step at the crossing, shape (m,);
        the position on the Hermite interpolant there, shape (m, d); the velocity
        interpolated linearly in s, shape (m, d). The time of the crossing is t0 + s·step.
    """
    z = p0.shape[1] - 1
    s = hermite_root(p0[:, z], p1[:, z], step * v0[:, z], step * v1[:, z], level)
    pos = np.empty(p0.shape)
    vel = np.empty(p0.shape)
    for j in range(p0.shape[1]):
        pos[:, j] = hermite(p0[:, j], p1[:, j], step * v0[:, j], step * v1[:, j], s)
        vel[:, j] = v0[:, j] + (v1[:, j] - v0[:, j]) * s
    return s, pos, vel


PUSH_STEPS = 2  # RK4 steps across the ~12 ms push (drag changes little in it)
# The push's drag stiffness: with the force f_o on mass m and drag k |v| v (k = ½ρC_dA/m),
# the speed's rate changes by λ = 2 k |v| per m/s, |v| up to the terminal speed
# √(f_o / (m k)); 2 RK4 steps across the reference push launch within 0.2 % of the
# converged push (4,000 steps) for λh ≤ 1 (25 and 50 mm cubes, 10 mm and 30 mm spheres of
# 0.05-20 g, both stroke ends), 1-30 % off at 1.4-2.9, and diverge past: 0.1-0.3 g in a
# 25 mm cube (λh 5-14 at the shortest stroke) were launched at 1e8-1e143 m/s. The push
# takes as many steps as keep λh ≤ PUSH_LAMBDA_H, at most PUSH_MAX_STEPS.
PUSH_LAMBDA_H = 1.0
PUSH_MAX_STEPS = 4096


def push_steps(kk: np.ndarray, accel: np.ndarray, v0: np.ndarray, dt: float) -> int:
    """RK4 steps across a push of `dt` [s] that keep λh ≤ PUSH_LAMBDA_H for every throw:
    drag per metre `kk` [1/m], a bound on the push's acceleration `accel` [m/s²], the
    velocity at its start `v0` [m/s] (n, 3); at least PUSH_STEPS, at most PUSH_MAX_STEPS.
    λ = 2 k max(|v0|, √(a/k)) is bounded by 2 max(k |v0|₁, √(a k)) (one pass each)."""
    kk = np.asarray(kk, dtype=float)
    with np.errstate(invalid="ignore", over="ignore"):
        lam = 2.0 * max(
            float(np.max(np.sqrt(np.abs(accel) * kk), initial=0.0)),
            float(np.max(kk * np.sum(np.abs(v0), axis=-1), initial=0.0)),
        )
    if not lam * dt / PUSH_STEPS > PUSH_LAMBDA_H:  # the common case, and NaN
        return PUSH_STEPS
    return min(PUSH_MAX_STEPS, math.ceil(lam * dt / PUSH_LAMBDA_H))
