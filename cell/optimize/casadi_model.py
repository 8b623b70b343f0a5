"""The throw model in CasADi: launch push and flight as symbolic expressions.

The band law is not re-derived here: the push force f_o and the stored energy
come from `cell.model.band` evaluated with the CasADi back-end
(`cell.model.ops.casadi_ops`), and the drag constant k = ½ ρ C_d A / m from
`cell.model.throw.drag_constant`. The push phase repeats the model's
`launch_state` step for step (4 RK4 steps over Δt, acceleration
f_o u / m + g - k |v| v) and its ride on the carriage to L_e when η_ee has one
(`cell.model.throw.ride`), so the two agree to rounding (a test checks 1e-9).

The flight after the push is a fixed-step RK4 integration in normalised time:
the flight time T after the push is an input (a decision variable of the NLP)
and the N steps have length T/N. The landing is the state at T; the NLP makes
it the crossing with the terminal constraints z(T) = land_z and ż(T) < 0.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.model.band import band_stretch, push_force, stored_energy
from cell.model.integrate import rk4_step
from cell.model.ops import casadi_ops
from cell.model.params import EndEffectorParams, G
from cell.model.throw import _PUSH_STEPS, _RIDE_MIN_SPEED2

__all__ = [
    "N_FLIGHT_STEPS",
    "SymbolicThrow",
    "casadi_landing",
    "symbolic_throw",
    "throw_function",
]

N_FLIGHT_STEPS = 20  # RK4 steps over the flight after the push
_EPS_SPEED = 1e-12  # [m/s] keeps d|v|/dv finite at v = 0 (|v| changes by < 1e-12 m/s)


@dataclass(frozen=True)
class SymbolicThrow:
    """CasADi expressions of one throw (all SX).

    Attributes:
        launch_position: centre of mass at the end of the push [m, W], (3, 1).
        launch_velocity: velocity at the end of the push [m/s, W], (3, 1).
        position: centre of mass at the end of the flight time [m, W], (3, 1).
        velocity: velocity there [m/s, W], (3, 1).
        energy: stored band energy, both halves [J].
    """

    launch_position: Any
    launch_velocity: Any
    position: Any
    velocity: Any
    energy: Any


def _rk4(p: Any, v: Any, acc: Any, h: Any, steps: int) -> tuple[Any, Any]:
    """RK4 on p' = v, v' = acc(v): the model's own step (`cell.model.integrate.rk4_step`)."""
    for _ in range(steps):
        (p,), (v,) = rk4_step(lambda _p, vs: [acc(vs[0])], [p], [v], h)
    return p, v


def symbolic_throw(
    sigma: Any,
    t_flight: Any,
    width: Any,
    mass: Any,
    k_drag: Any,
    ee: EndEffectorParams,
    n_steps: int = N_FLIGHT_STEPS,
) -> SymbolicThrow:
    """The throw of release state σ, flown for t_flight after the push.

    Args:
        sigma: release state, (10, 1) SX in SIGMA_COLUMNS order.
        t_flight: flight time after the push [s] (SX scalar).
        width: grip width a [m].
        mass: object mass [kg].
        k_drag: drag constant k [1/m] (drag acceleration -k |v| v).
        ee: end-effector parameters.
        n_steps: RK4 steps over the flight.

    Returns:
        The symbolic throw.
    """
    import casadi as ca

    ops = casadi_ops()
    p0 = sigma[0:3]
    v0 = sigma[3:6]
    elev, azim, stroke = sigma[7], sigma[8], sigma[9]
    f_o = push_force(stroke, width, ee, ops)
    u = ca.vertcat(ca.cos(elev) * ca.cos(azim), ca.cos(elev) * ca.sin(azim), ca.sin(elev))
    gravity = ca.vertcat(0, 0, -G)
    a_push = u * (f_o / mass) + gravity

    def speed(v: Any) -> Any:
        return ca.sqrt(ca.dot(v, v) + _EPS_SPEED**2)

    p1, v1 = _rk4(
        p0, v0, lambda v: a_push - k_drag * speed(v) * v, ee.dt / _PUSH_STEPS, _PUSH_STEPS
    )
    if ee.L_e > 0:  # the ride on the carriage to L_e (`cell.model.throw.ride`)
        d = ca.fmax(ee.L_e - stroke - ca.dot(p1 - p0, u), 0.0)
        w = ca.dot(v1, u)
        w2 = ca.sqrt(ca.fmax(w * w - 2 * G * u[2] * d, _RIDE_MIN_SPEED2))
        p1 = p1 + d * u
        v1 = v1 + (w2 - w) * u
    p2, v2 = _rk4(p1, v1, lambda v: gravity - k_drag * speed(v) * v, t_flight / n_steps, n_steps)
    energy = 2 * stored_energy(band_stretch(stroke, width, ee, ops), ee, ops)
    return SymbolicThrow(
        launch_position=p1, launch_velocity=v1, position=p2, velocity=v2, energy=energy
    )


@functools.lru_cache(maxsize=16)
def throw_function(ee: EndEffectorParams, n_steps: int = N_FLIGHT_STEPS) -> Any:
    """A CasADi Function (σ[10], T, q[3]) -> (p1, v1, p, v, energy).

    q = (width [m], mass [kg], k_drag [1/m]) carries the object, so one Function
    serves every object. Built once per end-effector and step count.
    """
    import casadi as ca

    sigma = ca.SX.sym("sigma", 10)
    t = ca.SX.sym("t_flight")
    q = ca.SX.sym("q", 3)
    th = symbolic_throw(sigma, t, q[0], q[1], q[2], ee, n_steps)
    return ca.Function(
        "throw",
        [sigma, t, q],
        [th.launch_position, th.launch_velocity, th.position, th.velocity, th.energy],
        ["sigma", "t_flight", "q"],
        ["p1", "v1", "p", "v", "energy"],
    )


@functools.lru_cache(maxsize=16)
def _landing_function(ee: EndEffectorParams, n_steps: int) -> Any:
    import casadi as ca

    sigma = ca.SX.sym("sigma", 10)
    t = ca.SX.sym("t_flight")
    q = ca.SX.sym("q", 3)
    th = symbolic_throw(sigma, t, q[0], q[1], q[2], ee, n_steps)
    p = th.position
    return ca.Function(
        "landing", [sigma, t, q], [p, th.velocity, ca.jacobian(p, sigma), ca.jacobian(p, t)]
    )


def casadi_landing(
    sigma: np.ndarray,
    land_z: float,
    width: float,
    mass: float,
    k_drag: float,
    ee: EndEffectorParams,
    t_guess: float,
    n_steps: int = N_FLIGHT_STEPS,
) -> tuple[np.ndarray, float, np.ndarray]:
    """The CasADi model's landing point and its Jacobian with respect to σ.

    The flight time T after the push is found by Newton on z(T) = land_z from
    t_guess; the landing's sensitivity then follows from the implicit function
    theorem: dT/dσ = -(∂z/∂σ) / (∂z/∂T), d(x, y)/dσ = ∂(x, y)/∂σ + ∂(x, y)/∂T dT/dσ.

    Args:
        sigma: release state, shape (10,).
        land_z: landing-plane height [m].
        width: grip width [m]; mass: [kg]; k_drag: [1/m].
        ee: end-effector parameters.
        t_guess: initial flight time after the push [s] (near the descending crossing).
        n_steps: RK4 steps over the flight.

    Returns:
        (landing (x, y) [m], flight time after the push [s], Jacobian (2, 10)).
    """
    f = _landing_function(ee, n_steps)
    q = [width, mass, k_drag]
    t = float(t_guess)
    for _ in range(20):
        p, v, _, _ = f(sigma, t, q)
        dz = float(p[2]) - land_z
        t -= dz / float(v[2])
        if abs(dz) < 1e-13:
            break
    p, v, js, jt = f(sigma, t, q)
    js = np.asarray(js, float)
    jt = np.asarray(jt, float).ravel()
    dt_ds = -js[2] / jt[2]
    jac = js[:2] + np.outer(jt[:2], dt_ds)
    return np.asarray(p, float).ravel()[:2], t, jac
