"""An independent implementation of the nominal model, straight from the model
conventions (MODEL.md), for tests only: it imports nothing from `cell` and
integrates with SciPy's DOP853 and event location, not with the project's
fixed-step integrators."""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

G = 9.81
RHO = 1.225
CD = {"cube": 1.05, "cuboid": 1.05, "cylinder": 0.82, "sphere": 0.47, "mesh": 1.0}
EE = dict(
    r_r=0.010,
    l1=0.030,
    phi=math.pi / 2,
    d=0.020,
    L_t=0.160,
    L0=0.095,
    Ke3=400.0,
    Ke2=150.0,
    Ke1=114.6,
    C=0.0,
    dt=0.012,
)


def area(shape: str, size: tuple[float, float, float]) -> float:
    x, y, z = size
    if shape == "sphere":
        return math.pi * x * x / 4
    if shape == "cylinder":
        r = x / 2
        return (2 * math.pi * r * r + 2 * math.pi * r * z) / 4
    return (x * y + y * z + z * x) / 2


def push(stroke: float, a: float, ee: dict = EE) -> tuple[float, float]:
    """(ΔL, f_o) at this stroke and grip width."""
    l2 = math.sqrt(((a - ee["d"]) / 2) ** 2 + (ee["L_t"] - stroke) ** 2)
    dl = ee["l1"] + ee["r_r"] * ee["phi"] + ee["d"] / 2 + l2 - ee["L0"]
    fe = ee["Ke3"] * dl**3 + ee["Ke2"] * dl**2 + ee["Ke1"] * dl + ee["C"] if dl > 0 else 0.0
    fe = max(fe, 0.0)
    alpha = math.atan2(a - ee["d"], 2 * (ee["L_t"] - stroke))
    return dl, 2 * fe * math.cos(alpha)


def land(shape, mass, size, stroke, p0, elevation, azimuth, vb=(0, 0, 0), land_z=0.0, ee=EE):
    """(x, y, t_flight) of the landing, or None if it never lands."""
    _, fo = push(stroke, size[0], ee)
    u = np.array(
        [
            math.cos(elevation) * math.cos(azimuth),
            math.cos(elevation) * math.sin(azimuth),
            math.sin(elevation),
        ]
    )
    k = 0.5 * RHO * CD[shape] * area(shape, size) / mass

    def rhs(pushing):
        def f(t, y):
            v = y[3:]
            a = -k * np.linalg.norm(v) * v + np.array([0, 0, -G])
            if pushing:
                a = a + fo / mass * u
            return np.concatenate([v, a])

        return f

    s1 = solve_ivp(rhs(True), (0, ee["dt"]), np.r_[p0, vb], method="DOP853", rtol=1e-11, atol=1e-12)

    def ev(t, y):
        return y[2] - land_z

    ev.terminal = True
    ev.direction = -1
    s2 = solve_ivp(
        rhs(False), (ee["dt"], 30), s1.y[:, -1], method="DOP853", rtol=1e-11, atol=1e-12, events=ev
    )
    if not len(s2.t_events[0]):
        return None
    y = s2.y_events[0][0]
    return float(y[0]), float(y[1]), float(s2.t_events[0][0])
