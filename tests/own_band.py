"""The tests' own band launcher (numpy RK4; nothing of the cell's model or worlds): the
reference band's published law, both halves pulling along the throw axis with a constant
force over the push, with gravity and quadratic drag, then free flight under gravity and
drag until the centre crosses z = 0 going down. For the tests of `cell learn` and `cell
identify` on logs of no effect and of one the test puts in (tests/test_learn_heldout.py)."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

G = 9.81  # [m/s²]
RHO = 1.225  # [kg/m³]
CD = {"cube": 1.05, "cuboid": 1.05, "cylinder": 0.82, "sphere": 0.47}
# the reference band: roller radius, clamp length, wrap angle, hoop, base, free half-length [m]
R, L1, PHI, D, LT, L0 = 0.010, 0.030, math.pi / 2, 0.020, 0.160, 0.095
K3, K2, K1 = 400.0, 150.0, 114.6  # [N/m³], [N/m²], [N/m]
PUSH_S = 0.012  # [s]
PUSH_STEPS = 96
FLIGHT_STEP = 5e-4  # [s]

# id: (shape, mass [kg], size x, y, z [m]); a ping-pong ball and a medicine ball among them
OBJECTS = {
    "cube50": ("cube", 0.09, 0.05, 0.05, 0.05),
    "cube30": ("cube", 0.03, 0.03, 0.03, 0.03),
    "ball65": ("sphere", 0.058, 0.065, 0.065, 0.065),
    "ball43": ("sphere", 0.046, 0.043, 0.043, 0.043),
    "cyl40": ("cylinder", 0.07, 0.04, 0.04, 0.08),
    "box": ("cuboid", 0.12, 0.06, 0.04, 0.09),
    "pingpong": ("sphere", 0.0027, 0.040, 0.040, 0.040),
    "medball": ("sphere", 1.0, 0.12, 0.12, 0.12),
    "cube40": ("cube", 0.06, 0.04, 0.04, 0.04),
    "ball55": ("sphere", 0.05, 0.055, 0.055, 0.055),
    "cyl30": ("cylinder", 0.05, 0.03, 0.03, 0.07),
    "slab": ("cuboid", 0.08, 0.07, 0.03, 0.05),
}
HEADER = (
    "throw_id,object_id,shape,mass_kg,size_x_m,size_y_m,size_z_m,stroke_m,x_m,y_m,z_m,"
    "elevation_rad,azimuth_rad,roll_rad,vx_mps,vy_mps,vz_mps,platform,rotor_rpm,land_z_m,"
    "landed_x_m,landed_y_m"
).split(",")


def area(shape: str, x: float, y: float, z: float) -> float:
    """Mean projected area [m²]: a quarter of the surface."""
    if shape == "sphere":
        return math.pi * x * x / 4
    if shape == "cylinder":
        return (2 * math.pi * (x / 2) ** 2 + 2 * math.pi * (x / 2) * z) / 4
    return (x * y + y * z + z * x) / 2


def push_n(stroke: np.ndarray, width: np.ndarray, extra: np.ndarray) -> np.ndarray:
    """Both halves' pull along the axis [N] at this stroke and grip width [m]; `extra` [m]
    stretches the band beyond the law's geometry (0: the law)."""
    free = np.hypot((width - D) / 2, LT - stroke)
    s = L1 + R * PHI + D / 2 + free - L0 + extra
    f = np.where(s > 0, np.maximum(((K3 * s + K2) * s + K1) * s, 0.0), 0.0)
    return 2 * f * np.cos(np.arctan2(width - D, 2 * (LT - stroke)))


def land(ids: list[str], stroke: np.ndarray, p0: np.ndarray, el: np.ndarray,
         az: np.ndarray, extra: np.ndarray) -> np.ndarray:  # fmt: skip
    """Landing points (n, 2) [m] on z = 0 of all throws at once."""
    n = len(ids)
    obj = [OBJECTS[i] for i in ids]
    m = np.array([o[1] for o in obj])
    k = np.array([0.5 * RHO * CD[o[0]] * area(o[0], *o[2:]) for o in obj]) / m
    width = np.array([o[2] for o in obj])
    u = np.c_[np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)]
    a_push = (push_n(stroke, width, extra) / m)[:, None] * u

    def acc(v: np.ndarray, pushing: bool) -> np.ndarray:
        a = -k[:, None] * np.linalg.norm(v, axis=1)[:, None] * v
        a[:, 2] -= G
        return a + a_push if pushing else a

    def step(p: np.ndarray, v: np.ndarray, h: float, pushing: bool
             ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        k1 = acc(v, pushing)
        k2 = acc(v + h / 2 * k1, pushing)
        k3 = acc(v + h / 2 * k2, pushing)
        k4 = acc(v + h * k3, pushing)
        p1 = p + h / 6 * (v + 2 * (v + h / 2 * k1) + 2 * (v + h / 2 * k2) + (v + h * k3))
        return p1, v + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    p, v = p0.astype(float).copy(), np.zeros((n, 3))
    for _ in range(PUSH_STEPS):
        p, v = step(p, v, PUSH_S / PUSH_STEPS, True)
    out = np.full((n, 2), np.nan)
    live = np.ones(n, bool)
    while live.any():
        p1, v1 = step(p, v, FLIGHT_STEP, False)
        down = live & (p1[:, 2] <= 0.0) & (p[:, 2] > 0.0)
        for i in np.flatnonzero(down):  # the crossing on the step's cubic Hermite
            h = FLIGHT_STEP
            lo, hi = 0.0, 1.0
            for _ in range(50):
                s = (lo + hi) / 2
                z = ((2 * s**3 - 3 * s**2 + 1) * p[i, 2] + (s**3 - 2 * s**2 + s) * h * v[i, 2]
                     + (-2 * s**3 + 3 * s**2) * p1[i, 2] + (s**3 - s**2) * h * v1[i, 2])  # fmt: skip
                lo, hi = (s, hi) if z > 0 else (lo, s)
            s = (lo + hi) / 2
            out[i] = ((2 * s**3 - 3 * s**2 + 1) * p[i, :2] + (s**3 - 2 * s**2 + s) * h * v[i, :2]
                      + (-2 * s**3 + 3 * s**2) * p1[i, :2] + (s**3 - s**2) * h * v1[i, :2])  # fmt: skip
        live &= ~down
        p, v = p1, v1
    return out


def write_log(path: Path, ids: list[str], seed: int, *, scatter_m: float = 0.010,
              curved_stretch: float = 0.0) -> tuple[Path, np.ndarray]:  # fmt: skip
    """A log (docs/throw_log.md) of one throw of each of `ids`, drawn with `seed`, landing
    with `scatter_m` [m] of Gaussian scatter per axis; a curved object (sphere, cylinder)
    stretches the band `curved_stretch` × its grip width further than the law (0: a log of
    no effect). Returns the path and the scatter added to each landing (n, 2) [m]."""
    rng = np.random.default_rng(seed)
    n = len(ids)
    stroke = np.round(rng.uniform(0.035, 0.105, n), 4)
    el = np.round(rng.uniform(0.35, 0.95, n), 4)
    az = np.round(rng.uniform(-0.5, 0.5, n), 4)
    p0 = np.round(np.c_[rng.uniform(-0.1, 0.1, (n, 2)), rng.uniform(0.7, 0.9, n)], 4)
    curved = np.array([OBJECTS[i][0] in ("sphere", "cylinder") for i in ids])
    extra = np.where(curved, curved_stretch * np.array([OBJECTS[i][2] for i in ids]), 0.0)
    noise = rng.normal(0.0, scatter_m, (n, 2))
    xy = land(ids, stroke, p0, el, az, extra) + noise
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(HEADER)
        for j, oid in enumerate(ids):
            shape, mass, sx, sy, sz = OBJECTS[oid]
            w.writerow([f"t{j:04d}", oid, shape, mass, sx, sy, sz, stroke[j], *p0[j], el[j],
                        az[j], 0, 0, 0, 0, "arm", 0, 0, f"{xy[j, 0]:.6f}", f"{xy[j, 1]:.6f}"])  # fmt: skip
    return path, noise
