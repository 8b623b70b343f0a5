"""The outside labs' common parts (tests/test_outside_lab66.py, test_outside_lab67.py,
test_gap_propvs.py): each lab flies its own worlds, written from MODEL.md and
docs/throw_log.md with nothing of `cell`'s model; what they share is here once. SI units,
the world frame W (z up).

- the reference band of MODEL.md: its cubic pull `push` [N] of the stroke [m] and the
  object's width [m] (no damping), pushing for `PUSH_S` from rest at the grip centre;
- the air: quadratic drag ½ρC_dA|v − w|(v − w), C_d by shape (`CD`), A the box's surface
  over four (`area`), the RK4 step `H` [s];
- a log's rows as docs/throw_log.md's columns (`write_log`), `NOISE` [m] of landing
  scatter per axis.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

G, RHO, H, PUSH_S, NOISE = 9.81, 1.225, 5e-4, 0.012, 0.010  # [m/s²], [kg/m³], [s], [s], [m]
R_R, L1, PHI, HOOP, L_T, L0 = 0.010, 0.030, math.pi / 2, 0.020, 0.160, 0.095  # [m], [rad]
KE3, KE2, KE1 = 400.0, 150.0, 114.6  # [N/m³], [N/m²], [N/m]
CD = {"cube": 1.05, "cuboid": 1.05, "cylinder": 0.82, "sphere": 0.47}
COLUMNS = ["throw_id", "object_id", "shape", "mass_kg", "size_x_m", "size_y_m", "size_z_m",
           "stroke_m", "x_m", "y_m", "z_m", "elevation_rad", "azimuth_rad", "roll_rad",
           "vx_mps", "vy_mps", "vz_mps", "platform", "rotor_rpm", "land_z_m", "landed_x_m",
           "landed_y_m"]  # fmt: skip


def area(shape: str, s: tuple[float, float, float]) -> float:
    """The drag's reference area [m²] of an object of extents s [m]."""
    x, y, z = s
    if shape == "sphere":
        return math.pi * x * x / 4
    if shape == "cylinder":
        return (2 * math.pi * (x / 2) ** 2 + 2 * math.pi * (x / 2) * z) / 4
    return (x * y + y * z + z * x) / 2


def push(stroke: np.ndarray, width: np.ndarray) -> np.ndarray:
    """The band's push [N] (MODEL.md's band law, no damping)."""
    l2 = np.hypot((width - HOOP) / 2, L_T - stroke)
    dl = np.maximum(L1 + R_R * PHI + HOOP / 2 + l2 - L0, 0.0)
    fe = KE3 * dl**3 + KE2 * dl**2 + KE1 * dl
    return 2 * fe * np.cos(np.arctan2(width - HOOP, 2 * (L_T - stroke)))


def paired_throws(rng: np.random.Generator, objects: list[tuple]) -> list[dict]:
    """60 configurations of the objects, each thrown twice, in shuffled order."""
    cfgs = [{"obj": objects[int(rng.integers(len(objects)))],
             "stroke": float(rng.choice(np.linspace(0.07, 0.11, 5))),
             "el": math.radians(float(rng.choice((15.0, 30.0, 45.0, 55.0)))),
             "az": float(rng.uniform(-0.6, 0.6)),
             "p0": (float(rng.uniform(-0.1, 0.2)), float(rng.uniform(-0.2, 0.2)),
                    float(rng.uniform(0.5, 1.0)))} for _ in range(60)]  # fmt: skip
    rows = cfgs + cfgs
    return [dict(rows[i]) for i in rng.permutation(len(rows))]


def write_log(path: Path, throws: list[dict], landed: np.ndarray,
              times: np.ndarray | None = None, *, prefix: str) -> Path:  # fmt: skip
    """The throws as a log (docs/throw_log.md), ids `prefix` and the row's number, landed
    at `landed` [m] on the level floor; with `times` [s] a `time_s` column."""
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS + ([] if times is None else ["time_s"]))
        for i, t in enumerate(throws):
            oid, shape, mass, size = t["obj"]
            row = [f"{prefix}{i:03d}", oid, shape, mass, *size, t["stroke"], *t["p0"], t["el"],
                   t["az"], 0, 0, 0, 0, "arm", 0, 0, *landed[i]]  # fmt: skip
            w.writerow(row + ([] if times is None else [f"{times[i]:.1f}"]))
    return path


def rk4(acc: Callable[[np.ndarray, bool], np.ndarray], p: np.ndarray, v: np.ndarray,
        push: bool) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """One RK4 step of `H` [s] of positions p and velocities v (n, 3) [m, m/s] under the
    lab's acceleration `acc(v, push)` [m/s²] (drag, gravity, the band while `push`)."""
    k1 = acc(v, push)
    k2 = acc(v + 0.5 * H * k1, push)
    k3 = acc(v + 0.5 * H * k2, push)
    k4 = acc(v + H * k3, push)
    dp = H / 6 * (v + 2 * (v + 0.5 * H * k1) + 2 * (v + 0.5 * H * k2) + (v + H * k3))
    return p + dp, v + H / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def land_step(p: np.ndarray, v: np.ndarray, p1: np.ndarray, v1: np.ndarray, live: np.ndarray,
              land: np.ndarray, tilt: float = 0.0) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """One step from (p, v) to (p1, v1) (n, 3) [m, m/s] of the flights still `live` (n,)
    bool, across the
    landing plane z = tilt · x: the crossings' (x, y) [m], interpolated, written into
    `land` (n, 2) and their rows cleared from `live` (both in place); the positions and
    velocities each flight has after the step (a landed one keeps its last)."""
    above0, above1 = p[:, 2] - tilt * p[:, 0], p1[:, 2] - tilt * p1[:, 0]
    hit = live & (above1 <= 0) & (v1[:, 2] < 0)
    s = (above0[hit] / (above0[hit] - above1[hit]))[:, None]
    land[hit] = p[hit, :2] + s * (p1[hit, :2] - p[hit, :2])
    live &= ~hit
    return np.where(live[:, None], p1, p), np.where(live[:, None], v1, v)
