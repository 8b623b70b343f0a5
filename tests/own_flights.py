"""The tests' own flights of a ball in moving air (numpy RK4, gravity and quadratic drag;
nothing of `cell.gap`'s worlds or the cell's flight model), for the tests of what tracks show
(tests/test_gap_track_gust.py, tests/test_gap_track_bend.py)."""

from __future__ import annotations

import csv
from collections.abc import Callable
from pathlib import Path

import numpy as np

G = 9.81  # [m/s²]
DT = 1e-3  # [s] integration step

# the air's velocity [m/s] (n, 3) at a time [s]
Air = Callable[[float], np.ndarray]


def fly(p0: np.ndarray, v0: np.ndarray, k: float, air: Air
        ) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:  # fmt: skip
    """Every flight from p0 [m], v0 [m/s] (n, 3) to z = 0 by RK4, drag k [1/m] on the
    velocity relative to `air`: landing xy [m], flight time [s], path (m, 4) t, x, y, z."""
    n = len(p0)
    p, v = p0.copy(), v0.copy()
    t = 0.0
    land, t_land = np.full((n, 2), np.nan), np.full(n, np.nan)
    # each step's time and positions, and how many steps each flight lived: the paths are
    # cut from them once the last flight lands (they were grown sample by sample)
    times, points = [0.0], [p0.copy()]
    steps = np.zeros(n, int)
    live = np.ones(n, bool)

    def acc(air_v: np.ndarray, vv: np.ndarray) -> np.ndarray:
        rel = vv - air_v
        # |rel|: np.linalg.norm's arithmetic without its per-call checks
        a = -k * np.sqrt(np.add.reduce(rel * rel, axis=1))[:, None] * rel
        a[:, 2] -= G
        return a

    while live.any():
        # the air at the step's middle taken once for its two stages
        air_0, air_h, air_1 = air(t), air(t + 0.5 * DT), air(t + DT)
        k1p, k1v = v, acc(air_0, v)
        k2p, k2v = v + 0.5 * DT * k1v, acc(air_h, v + 0.5 * DT * k1v)
        k3p, k3v = v + 0.5 * DT * k2v, acc(air_h, v + 0.5 * DT * k2v)
        k4p, k4v = v + DT * k3v, acc(air_1, v + DT * k3v)
        p1 = p + DT / 6 * (k1p + 2 * k2p + 2 * k3p + k4p)
        v1 = v + DT / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        down = live & (p1[:, 2] < 0.0)
        s = (p[down, 2] / (p[down, 2] - p1[down, 2]))[:, None]  # the crossing, linearly
        land[down] = (p[down] + s * (p1[down] - p[down]))[:, :2]
        t_land[down] = t + s[:, 0] * DT
        live &= ~down
        p, v, t = p1, v1, t + DT
        steps += live
        times.append(t)
        points.append(p)
    tt, pp = np.array(times), np.array(points)
    return land, t_land, [np.c_[tt[: m + 1], pp[: m + 1, i]] for i, m in enumerate(steps)]


def tracks_of(paths: list[np.ndarray], t_end: np.ndarray, rate_hz: float,
              rng: np.random.Generator) -> dict[str, np.ndarray]:  # fmt: skip
    """Each path sampled at rate_hz [Hz] from its start to t_end [s] with 1 mm of scatter per
    axis, as a tracker gives it: {throw_id b000…: (m, 4) t_s, x_m, y_m, z_m}."""
    tracks = {}
    for i, path in enumerate(paths):
        t = np.arange(0.0, t_end[i], 1.0 / rate_hz)
        pos = np.stack([np.interp(t, path[:, 0], path[:, j]) for j in (1, 2, 3)], axis=1)
        tracks[f"b{i:03d}"] = np.c_[t, pos + rng.normal(0.0, 0.001, pos.shape)]
    return tracks


def write_log(path: Path, mass: float, diam: float, p0: np.ndarray, el: list[float],
              az: list[float], land: np.ndarray) -> Path:  # fmt: skip
    """A throw log (docs/throw_log.md) of another launcher's throws of one ball `ball65`
    (mass [kg], diameter [m]; no stroke): releases p0 [m] at elevations el and azimuths az
    [rad], landings land [m] on z = 0."""
    cols = ["throw_id", "object_id", "shape", "mass_kg", "size_x_m", "size_y_m", "size_z_m",
            "stroke_m", "x_m", "y_m", "z_m", "elevation_rad", "azimuth_rad", "roll_rad",
            "vx_mps", "vy_mps", "vz_mps", "platform", "rotor_rpm", "land_z_m", "landed_x_m",
            "landed_y_m"]  # fmt: skip
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for i in range(len(p0)):
            w.writerow([f"b{i:03d}", "ball65", "sphere", mass, diam, diam, diam, "",
                        *(f"{x:.6f}" for x in p0[i]), f"{el[i]:.6f}", f"{az[i]:.6f}",
                        0.0, 0.0, 0.0, 0.0, "arm", 0.0, 0.0, f"{land[i, 0]:.6f}",
                        f"{land[i, 1]:.6f}"])  # fmt: skip
    return path
