"""Real tracked flights shipped under tests/data, as throw logs and tracks (test helper)."""

from __future__ import annotations

import csv
import gzip
import math
from pathlib import Path

import numpy as np

DATA = Path(__file__).parent / "data"
JUGGLEBOT_HZ = 300.0
BALL_MASS_KG = 0.07  # the Jugglebot project's own simulation constant for its balls
BALL_DIAMETER_M = 0.065  # assumed (a juggling ball); README says so


def jugglebot_flights() -> dict[str, np.ndarray]:
    """{"s4-b1": (k, 4) frame, x, y, z [m]} from the first rest frame to the floor contact."""
    out: dict[str, list[list[float]]] = {}
    with gzip.open(DATA / "jugglebot_mocap" / "flights.csv.gz", "rt") as fh:
        for r in csv.DictReader(fh):
            key = f"{r['session']}-{r['marker']}"
            out.setdefault(key, []).append(
                [float(r["frame"])] + [float(r[c]) / 1000.0 for c in ("x_mm", "y_mm", "z_mm")]
            )
    return {k: np.asarray(v) for k, v in out.items()}


def jugglebot_log(trim_contact: int = 3) -> tuple[list[dict], dict[str, np.ndarray]]:
    """The flights as a throw log of another launcher (no stroke) and its tracks.

    Time 0 is the last frame the ball rests in the launcher; the landing is the ball's
    centre at its first floor contact (the lowest sample), on the plane at that height;
    the track stops `trim_contact` frames before the contact.
    """
    rows, tracks = [], {}
    for tid, f in jugglebot_flights().items():
        t = (f[:, 0] - f[0, 0]) / JUGGLEBOT_HZ
        p = f[:, 1:4]
        free = slice(20, 30)  # frames of free flight: the axis of the throw
        d = p[free][-1] - p[free][0]
        rows.append(
            {
                "throw_id": tid,
                "object_id": "juggling_ball",
                "shape": "sphere",
                "mass_kg": BALL_MASS_KG,
                "size_x_m": BALL_DIAMETER_M,
                "size_y_m": BALL_DIAMETER_M,
                "size_z_m": BALL_DIAMETER_M,
                "stroke_m": "",
                "x_m": p[0, 0],
                "y_m": p[0, 1],
                "z_m": p[0, 2],
                "elevation_rad": math.atan2(d[2], math.hypot(d[0], d[1])),
                "azimuth_rad": math.atan2(d[1], d[0]),
                "roll_rad": 0.0,
                "vx_mps": 0.0,
                "vy_mps": 0.0,
                "vz_mps": 0.0,
                "platform": "arm",
                "rotor_rpm": 0.0,
                "land_z_m": p[-1, 2],
                "landed_x_m": p[-1, 0],
                "landed_y_m": p[-1, 1],
                "session": tid.split("-")[0],
            }
        )
        tracks[tid] = np.c_[t, p][: len(t) - trim_contact]
    return rows, tracks


def write_log(rows: list[dict], tracks: dict[str, np.ndarray], folder: Path) -> tuple[Path, Path]:
    """throws.csv and tracks.csv (THROW_LOG.md) in folder."""
    tp, kp = folder / "throws.csv", folder / "tracks.csv"
    with open(tp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    with open(kp, "w", newline="") as fh:
        w2 = csv.writer(fh)
        w2.writerow(["throw_id", "t_s", "x_m", "y_m", "z_m"])
        for tid, tr in tracks.items():
            for s in tr:
                w2.writerow([tid, f"{s[0]:.6f}", f"{s[1]:.5f}", f"{s[2]:.5f}", f"{s[3]:.5f}"])
    return tp, kp


TT_RATE_HZ = 120.0  # not given by the source; the rate the flights imply (README)
TT_BALL_MASS_KG = 0.0027  # a regulation 40 mm table-tennis ball
TT_BALL_DIAMETER_M = 0.040


def _first_bounce(z: np.ndarray) -> int:
    """Index of the first local minimum of the height followed by a rise of over 1 cm
    below 0.15 m (a bounce on the table), or len(z)."""
    for j in range(2, len(z) - 3):
        if z[j] <= z[j - 1] and z[j] <= z[j + 1] and z[j + 3] - z[j] > 0.01 and z[j] < 0.15:
            return j
    return len(z)


def tabletennis_flights(cut_bounce: bool = True) -> dict[str, np.ndarray]:
    """{"tt0": (k, 4) t [s] (frame / 120 Hz, from the first), x, y, z [m]}: the 3-camera
    reconstructions, each up to its first bounce on the table when `cut_bounce`."""
    out: dict[str, list[list[float]]] = {}
    with open(DATA / "tabletennis_3cam" / "flights.csv") as fh:
        for r in csv.DictReader(fh):
            out.setdefault(f"tt{r['seq']}", []).append(
                [float(r["frame"]) / TT_RATE_HZ] + [float(r[c]) for c in ("x_m", "y_m", "z_m")]
            )
    res = {}
    for key, v in out.items():
        a = np.asarray(v)
        a[:, 0] -= a[0, 0]
        res[key] = a[: _first_bounce(a[:, 3])] if cut_bounce else a
    return res


TC_BALL_MASS_KG = 0.0027  # a regulation 40 mm table-tennis ball (the source gives none)
TC_BALL_DIAMETER_M = 0.040
TC_AXIS_FRAMES = 10  # the first frames whose chord gives a flight's logged throw axis


def tennicam_flights(cut_bounce: bool = True) -> dict[str, np.ndarray]:
    """{"e01": (k, 4) t [s] (the tracker's time stamps, from the first frame), x, y, z [m]}:
    the launcher's ball in MPI-IS's table-tennis lab, each flight up to (not including) its
    first bounce on the table when `cut_bounce` (the frame the converter found it at: the
    lowest frame of the first dip below 0.9 m), else with the 15 frames after it."""
    out: dict[str, list[list[float]]] = {}
    with gzip.open(DATA / "tabletennis_tennicam" / "flights.csv.gz", "rt") as fh:
        for r in csv.DictReader(fh):
            out.setdefault(f"e{int(r['episode']):02d}", []).append(
                [int(r["t_ns"]) * 1e-9] + [float(r[c]) for c in ("x_m", "y_m", "z_m")]
            )
    res = {}
    for key, v in out.items():
        a = np.asarray(v)
        res[key] = a[: len(a) - 16] if cut_bounce else a
    return res


def tennicam_log() -> tuple[list[dict], dict[str, np.ndarray]]:
    """The launcher's flights as a throw log of another launcher (no stroke) and their
    tracks: time 0 at the first frame the ball is seen, the release there, the throw axis
    the chord of the first 10 frames, the landing the ball's centre at its first bounce on
    the plane at that height; the track stops the frame before the bounce."""
    rows, tracks = [], {}
    uncut = tennicam_flights(cut_bounce=False)
    for tid, tr in tennicam_flights().items():
        p = tr[:, 1:4]
        d = p[TC_AXIS_FRAMES - 1] - p[0]
        bounce = uncut[tid][len(tr), 1:4]
        rows.append({
            "throw_id": tid, "object_id": "tt_ball", "shape": "sphere",
            "mass_kg": TC_BALL_MASS_KG, "size_x_m": TC_BALL_DIAMETER_M,
            "size_y_m": TC_BALL_DIAMETER_M, "size_z_m": TC_BALL_DIAMETER_M, "stroke_m": "",
            "x_m": p[0, 0], "y_m": p[0, 1], "z_m": p[0, 2],
            "elevation_rad": math.atan2(d[2], math.hypot(d[0], d[1])),
            "azimuth_rad": math.atan2(d[1], d[0]), "roll_rad": 0.0, "vx_mps": 0.0,
            "vy_mps": 0.0, "vz_mps": 0.0, "platform": "arm", "rotor_rpm": 0.0,
            "land_z_m": bounce[2], "landed_x_m": bounce[0], "landed_y_m": bounce[1],
        })  # fmt: skip
        tracks[tid] = tr
    return rows, tracks


CUBE_RATE_HZ = 148.0  # the tracker's rate (the source's files carry no time stamps)
CUBE_MASS_KG = 0.37  # the source's own figure for its acrylic cube
CUBE_SIDE_M = 0.1048  # twice the source's half width, 0.0524 m
CUBE_AFTER_CONTACT = 10  # frames the shipped slice keeps after each toss's first contact
CUBE_AXIS_FRAMES = 6  # the first frames whose chord gives a toss's logged throw axis


def cube_flights(cut_contact: bool = True) -> dict[str, np.ndarray]:
    """{"c000": (k, 4) t [s] (frame / 148 Hz), x, y, z [m]}: DAIR Lab's cube tossed onto a
    board, each up to (not including) its first contact with the board when `cut_contact`
    (the frame the converter found it at), else with the contact and the 10 frames after."""
    out: dict[str, list[list[float]]] = {}
    with gzip.open(DATA / "contactnets_cube" / "flights.csv.gz", "rt") as fh:
        for r in csv.DictReader(fh):
            out.setdefault(f"c{int(r['toss']):03d}", []).append(
                [int(r["frame"]) / CUBE_RATE_HZ] + [float(r[c]) for c in ("x_m", "y_m", "z_m")]
            )
    res = {}
    for key, v in out.items():
        a = np.asarray(v)
        res[key] = a[: len(a) - CUBE_AFTER_CONTACT - 1] if cut_contact else a
    return res


def cube_log(ids: list[str] | None = None) -> tuple[list[dict], dict[str, np.ndarray]]:
    """The tosses as a throw log of another launcher (no stroke) and their tracks: time 0
    at the first frame (after the release), the throw axis the chord of the first 6
    frames, the landing the cube's centre at its first contact, on the plane at that
    height; the track stops the frame before the contact."""
    rows, tracks = [], {}
    uncut = cube_flights(cut_contact=False)
    for tid, tr in cube_flights().items():
        if ids is not None and tid not in ids:
            continue
        p = tr[:, 1:4]
        d = p[CUBE_AXIS_FRAMES - 1] - p[0]
        touch = uncut[tid][len(tr), 1:4]
        rows.append({
            "throw_id": tid, "object_id": "acrylic_cube", "shape": "cube",
            "mass_kg": CUBE_MASS_KG, "size_x_m": CUBE_SIDE_M, "size_y_m": CUBE_SIDE_M,
            "size_z_m": CUBE_SIDE_M, "stroke_m": "", "x_m": p[0, 0], "y_m": p[0, 1],
            "z_m": p[0, 2], "elevation_rad": math.atan2(d[2], math.hypot(d[0], d[1])),
            "azimuth_rad": math.atan2(d[1], d[0]), "roll_rad": 0.0, "vx_mps": 0.0,
            "vy_mps": 0.0, "vz_mps": 0.0, "platform": "arm", "rotor_rpm": 0.0,
            "land_z_m": touch[2], "landed_x_m": touch[0], "landed_y_m": touch[1],
        })  # fmt: skip
        tracks[tid] = tr
    return rows, tracks
