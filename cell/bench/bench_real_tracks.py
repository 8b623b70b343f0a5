"""What the whole-track fit and `cell gap` find on the real tracked flights shipped under
tests/data/ (docs/gap-tracks.md quotes these figures).

Four public sets (each folder has its LICENSE and a README saying where it came from):
Jugglebot's Ball Butler (`jugglebot_mocap`, 300 Hz motion capture, two sessions),
table-tennis balls from a ball machine (`tabletennis_3cam`, three-camera triangulation,
time base 120 Hz), from MPI-IS's ball launcher (`tabletennis_tennicam`, 180 Hz with
the tracker's own time stamps, frames missing) and DAIR Lab's cube tossed onto a board
(`contactnets_cube`, AprilTags at 148 Hz, falls of about 0.1 s). Per set: cell's
whole-track fit (`cell.gap.tracks.fit_tracks`), a second fit written here without
`cell.gap` (scipy `solve_ivp` + `least_squares`: start state, gravity and a drag constant
k free; for the cube, whose drag 0.1 s falls do not tell, linear least squares with
gravity's vector free), and for Jugglebot, the launcher's flights and the cube `cell gap`
itself on the flights as a throw log of another launcher with their tracks.

    python -m cell.bench.bench_real_tracks [--json OUT.json]

(one step of `make figures`, `docs/figures/real_tracks.json`; about 95 CPU-s).
"""

from __future__ import annotations

import argparse
import csv
import gzip
import json
import math
import sys
import tempfile
from contextlib import redirect_stdout
from io import StringIO
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

from cell.outfile import write_whole

__all__ = ["cube", "jugglebot", "main", "tabletennis", "tennicam"]

DATA = Path(__file__).resolve().parents[2] / "tests" / "data"
G0 = 9.80665  # [m/s²] standard gravity
JB_HZ = 300.0  # the motion capture's rate (tests/data/jugglebot_mocap/README.md)
JB_MASS_KG = 0.07  # the Jugglebot project's own simulation constant for its balls
JB_DIAMETER_M = 0.065  # assumed (a juggling ball)
JB_SKIP = 30  # frames after the last rest frame: the ball has left the launcher (0.1 s)
JB_EVERY = 3  # the second fit takes every third flight of a session
TT_HZ = 120.0  # the time base used: the source gives no rate
TT_MASS_KG = 0.0027  # a regulation 40 mm table-tennis ball
TT_DIAMETER_M = 0.040
TT_CD = 0.47  # a sphere's drag coefficient, for the table-tennis ball's nominal drag
TT_RHO = 1.204  # [kg/m³] air at 20 °C, the same
TT_CLEAN = ("tt2", "tt5", "tt6", "tt7", "tt8", "tt9")  # flights whose first stretch is clean
TC_AFTER_BOUNCE = 15  # frames the shipped slice keeps after each flight's first bounce
TC_AXIS_FRAMES = 10  # the first frames whose chord gives a flight's logged throw axis
TC_SKIP = 18  # frames the second fit skips: 0.1 s, the ball is clear of the launcher
CB_HZ = 148.0  # the cube's tracker rate (tests/data/contactnets_cube/README.md)
CB_MASS_KG = 0.37  # the source's figure for its acrylic cube
CB_SIDE_M = 0.1048  # twice the source's half width
CB_AFTER_CONTACT = 10  # frames the shipped slice keeps after each toss's first contact
CB_AXIS_FRAMES = 6  # the first frames whose chord gives a toss's logged throw axis
CB_GAP_TOSSES = 40  # `cell gap` runs on this many of the tosses of 0.1 s or more


def _log_row(
    tid: str, obj: tuple[str, str, float, float], start: Any, chord: Any, landing: Any
) -> dict[str, Any]:
    """A throw-log row of another launcher (no stroke) for one tracked flight of the object
    `obj` (its id, shape, mass [kg] and side or diameter [m]): released at `start` [m], its
    throw axis along `chord` (two of its first samples' difference), landed at `landing`
    [m] on the plane at that height."""
    d, (name, shape, mass_kg, size_m) = chord, obj
    return {
        "throw_id": tid, "object_id": name, "shape": shape, "mass_kg": mass_kg,
        "size_x_m": size_m, "size_y_m": size_m, "size_z_m": size_m,
        "stroke_m": "", "x_m": start[0], "y_m": start[1], "z_m": start[2],
        "elevation_rad": math.atan2(d[2], math.hypot(d[0], d[1])),
        "azimuth_rad": math.atan2(d[1], d[0]), "roll_rad": 0.0, "vx_mps": 0.0,
        "vy_mps": 0.0, "vz_mps": 0.0, "platform": "arm", "rotor_rpm": 0.0,
        "land_z_m": landing[2], "landed_x_m": landing[0], "landed_y_m": landing[1],
    }  # fmt: skip


def _jugglebot_log() -> tuple[list[dict[str, Any]], dict[str, np.ndarray]]:
    """The flights as a throw log of another launcher (no stroke) and their tracks: time 0
    at the last rest frame, the landing at the lowest sample, the track cut 3 frames
    before it."""
    frames: dict[str, list[list[float]]] = {}
    with gzip.open(DATA / "jugglebot_mocap" / "flights.csv.gz", "rt") as fh:
        for r in csv.DictReader(fh):
            frames.setdefault(f"{r['session']}-{r['marker']}", []).append(
                [float(r["frame"])] + [float(r[c]) / 1000.0 for c in ("x_mm", "y_mm", "z_mm")]
            )
    rows, tracks = [], {}
    for tid, v in frames.items():
        f = np.asarray(v)
        t, p = (f[:, 0] - f[0, 0]) / JB_HZ, f[:, 1:4]
        d = p[29] - p[20]  # frames of free flight: the axis of the throw
        rows.append(
            _log_row(tid, ("juggling_ball", "sphere", JB_MASS_KG, JB_DIAMETER_M), p[0], d, p[-1])
        )
        tracks[tid] = np.c_[t, p][: len(t) - 3]
    return rows, tracks


def _write_log(rows: list[dict[str, Any]], tracks: dict[str, np.ndarray], folder: Path) -> None:
    with open(folder / "throws.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    with open(folder / "tracks.csv", "w", newline="") as fh:
        w2 = csv.writer(fh)
        w2.writerow(["throw_id", "t_s", "x_m", "y_m", "z_m"])
        for tid, tr in tracks.items():
            for s in tr:
                w2.writerow([tid, f"{s[0]:.6f}", f"{s[1]:.5f}", f"{s[2]:.5f}", f"{s[3]:.5f}"])


def _fit(t: np.ndarray, p: np.ndarray, g_vector: bool) -> np.ndarray:
    """Start state (6), gravity (a vector [m/s²], or its size along -z) and k [1/m] of a
    free flight ṗ = v, v̇ = g - k|v|v, by least squares through solve_ivp."""

    def sim(th: np.ndarray) -> np.ndarray:
        g = th[6:9] if g_vector else np.array([0.0, 0.0, -th[6]])
        k = th[-1]

        def rhs(_: float, s: np.ndarray) -> np.ndarray:
            return np.r_[s[3:], g - k * np.linalg.norm(s[3:]) * s[3:]]

        sol = solve_ivp(rhs, (0.0, float(t[-1])), th[:6], t_eval=t, rtol=1e-9, atol=1e-11)
        return np.asarray(sol.y[:3].T)

    v = (p[3] - p[0]) / (t[3] - t[0])
    g0 = [0.0, 0.0, -G0] if g_vector else [G0]
    th0 = np.r_[p[0], v, g0, 0.013 if g_vector else 0.1]
    return np.asarray(least_squares(lambda th: (sim(th) - p).ravel(), th0).x)


def _span(a: np.ndarray) -> list[float]:
    return [float(np.min(a)), float(np.max(a))]


def jugglebot() -> dict[str, Any]:
    """cell's track fit and the second fit per session, and `cell gap` on all flights."""
    from cell.gap.run import _k_of
    from cell.gap.tracks import fit_tracks
    from cell.log.table import ThrowTable

    rows, tracks = _jugglebot_log()
    table = ThrowTable.from_records(rows)
    ids = table.text("throw_id")
    k = _k_of(table)
    fit = fit_tracks(ids, tracks, k)
    sessions: dict[str, Any] = {}
    for ses in sorted({t.split("-")[0] for t in ids}):
        sel = [i for i, t in enumerate(ids) if t.startswith(ses + "-")]
        ind = []
        for i in sel[::JB_EVERY]:
            tr = tracks[ids[i]]
            ind.append(_fit(tr[JB_SKIP:, 0] - tr[JB_SKIP, 0], tr[JB_SKIP:, 1:4], True))
        a = np.array(ind)
        gh = np.median(a[:, 6:8], axis=0)
        sessions[ses] = {
            "flights": len(sel),
            "second_fit_flights": len(ind),
            "second_g_ratio": float(np.median(np.linalg.norm(a[:, 6:9], axis=1)) / G0),
            "second_drag_ratio": float(np.median(a[:, 9]) / k[sel[0]]),
            "second_sideways_mps2": float(np.linalg.norm(gh)),
            "second_tilt_deg": math.degrees(math.atan2(float(np.linalg.norm(gh)), G0)),
            "cell_g_ratio": float(np.median(fit.g_ratio[sel])),
            "cell_drag_ratio": float(np.median(fit.drag_ratio[sel])),
            "cell_sideways_mps2": float(np.linalg.norm(np.median(fit.a0[sel, :2], axis=0))),
        }
    gap = _cell_gap(rows, tracks, "Jugglebot flights")
    return {
        "rate_hz": JB_HZ,
        "throws": len(ids),
        "mass_kg": JB_MASS_KG,
        "diameter_m": JB_DIAMETER_M,
        "sessions": sessions,
        **_cell_fit(fit),
        "gap": gap,
    }


def _tabletennis_flights() -> dict[str, np.ndarray]:
    """{"tt0": (k, 4) t [s] (frame / 120 Hz, from the first), x, y, z [m]}, each up to its
    first bounce on the table (a local minimum of the height under 0.15 m followed by a
    rise of over 1 cm)."""
    seqs: dict[str, list[list[float]]] = {}
    with open(DATA / "tabletennis_3cam" / "flights.csv") as fh:
        for r in csv.DictReader(fh):
            seqs.setdefault(f"tt{r['seq']}", []).append(
                [float(r["frame"]) / TT_HZ] + [float(r[c]) for c in ("x_m", "y_m", "z_m")]
            )
    flights = {}
    for key, v in seqs.items():
        f = np.asarray(v)
        f[:, 0] -= f[0, 0]
        z, end = f[:, 3], len(f)
        for j in range(2, len(z) - 3):  # the first bounce on the table
            if z[j] <= z[j - 1] and z[j] <= z[j + 1] and z[j + 3] - z[j] > 0.01 and z[j] < 0.15:
                end = j
                break
        flights[key] = f[:end]
    return flights


def tabletennis() -> dict[str, Any]:
    """cell's track fit and the second fit on the clean flights up to their first bounce;
    the rate each flight implies (the 120 Hz base scaled by the second fit's gravity)."""
    from cell.gap.tracks import fit_tracks

    flights = _tabletennis_flights()
    k_nom = 0.5 * TT_RHO * TT_CD * math.pi * (TT_DIAMETER_M / 2) ** 2 / TT_MASS_KG
    ids = list(TT_CLEAN)
    fit = fit_tracks(ids, {i: flights[i] for i in ids}, np.full(len(ids), k_nom))
    ind = np.array([_fit(flights[i][:, 0], flights[i][:, 1:4], False) for i in ids])
    g_ind, k_ind = ind[:, 6] / G0, ind[:, 7]
    v0 = np.linalg.norm(ind[:, 3:6], axis=1)
    return {
        "flights": len(flights),
        "clean_flights": len(ids),
        "time_base_hz": TT_HZ,
        "mass_kg": TT_MASS_KG,
        "diameter_m": TT_DIAMETER_M,
        "drag_coefficient": TT_CD,
        "air_density_kg_m3": TT_RHO,
        "k_nominal_per_m": k_nom,
        "second_k_per_m": _span(k_ind),
        "second_g_ratio": _span(g_ind),
        "implied_rate_hz": _span(TT_HZ / np.sqrt(g_ind)),
        "drag_over_gravity_at_launch": float(np.median(k_ind * v0**2 / (g_ind * G0))),
        "cell_g_ratio_max_dev": float(np.max(np.abs(fit.g_ratio - g_ind))),
        "cell_drag_ratio_median": float(np.median(fit.drag_ratio)),
        "second_drag_ratio_median": float(np.median(k_ind) / k_nom),
        "unusable": len(fit.unusable),
    }


def _tennicam_frames() -> dict[str, np.ndarray]:
    """{"e01": (k, 5) frame number, t [s] (time stamp from the first), x, y, z [m]}: each
    shipped episode, its bounce and the 15 frames after it included."""
    eps: dict[str, list[list[float]]] = {}
    with gzip.open(DATA / "tabletennis_tennicam" / "flights.csv.gz", "rt") as fh:
        for r in csv.DictReader(fh):
            eps.setdefault(f"e{int(r['episode']):02d}", []).append(
                [float(r["frame"]), int(r["t_ns"]) * 1e-9]
                + [float(r[c]) for c in ("x_m", "y_m", "z_m")]
            )
    return {key: np.asarray(v) for key, v in eps.items()}


def _tennicam_log() -> tuple[list[dict[str, Any]], dict[str, np.ndarray]]:
    """The launcher's flights as a throw log of another launcher (no stroke) and their
    tracks, up to the frame before the first bounce: time 0 at the first frame, the release
    there, the throw axis the chord of the first 10 frames, the landing the ball's centre at
    the bounce on the plane at that height."""
    rows, tracks = [], {}
    for tid, f in _tennicam_frames().items():
        tr = f[: len(f) - TC_AFTER_BOUNCE - 1, 1:5]
        p = tr[:, 1:4]
        d = p[TC_AXIS_FRAMES - 1] - p[0]
        bounce = f[len(tr), 2:5]
        rows.append(
            _log_row(tid, ("tt_ball", "sphere", TT_MASS_KG, TT_DIAMETER_M), p[0], d, bounce)
        )
        tracks[tid] = tr
    return rows, tracks


def tennicam() -> dict[str, Any]:
    """The tracker's timing (frame period, time-stamp jitter, missing frames), cell's track
    fit and the second fit on every flight up to its bounce, and `cell gap` on all of
    them."""
    from cell.gap.run import _k_of
    from cell.gap.tracks import fit_tracks
    from cell.log.table import ThrowTable

    frames = _tennicam_frames()
    periods, jitter, missing, samples = [], [], 0, 0
    for f in frames.values():
        c = np.polyfit(f[:, 0] - f[0, 0], f[:, 1], 1)
        periods.append(c[0])
        jitter.append(np.std(f[:, 1] - np.polyval(c, f[:, 0] - f[0, 0])))
        missing += int(np.sum(np.diff(f[:, 0]) > 1))
        samples += len(f)
    rows, tracks = _tennicam_log()
    table = ThrowTable.from_records(rows)
    ids = table.text("throw_id")
    k = _k_of(table)
    fit = fit_tracks(ids, tracks, k)
    ind = []
    for tid in ids:
        tr = tracks[tid]
        ind.append(_fit(tr[TC_SKIP:, 0] - tr[TC_SKIP, 0], tr[TC_SKIP:, 1:4], False))
    a = np.array(ind)
    g_ind, k_ind = a[:, 6] / G0, a[:, 7]
    speed = np.linalg.norm(a[:, 3:6], axis=1)
    gap = _cell_gap(rows, tracks, "launcher's flights")
    return {
        "episodes": len(frames),
        "samples": samples,
        "flights": len(ids),
        "flight_samples": sum(len(t) for t in tracks.values()),
        "frame_period_s": float(np.median(periods)),
        "stamp_jitter_s": float(np.median(jitter)),
        "missing_frame_gaps": missing,
        "mass_kg": TT_MASS_KG,
        "diameter_m": TT_DIAMETER_M,
        "k_nominal_per_m": float(k[0]),
        "second_skip_frames": TC_SKIP,
        "second_g_ratio_median": float(np.median(g_ind)),
        "second_g_ratio": _span(g_ind),
        "second_drag_ratio_median": float(np.median(k_ind) / k[0]),
        "second_speed_mps_median": float(np.median(speed)),
        "second_velocity_mps_median": [float(x) for x in np.median(a[:, 3:6], axis=0)],
        "drag_over_gravity": float(np.median(k_ind * speed**2 / (g_ind * G0))),
        **_cell_fit(fit),
        "gap": gap,
    }


def _cube_log() -> tuple[list[dict[str, Any]], dict[str, np.ndarray], int]:
    """The tosses of 0.1 s or more up to the frame before their first contact, as a throw
    log of another launcher (no stroke) and their tracks (time 0 at the first frame, the
    throw axis the chord of the first 6 frames, the landing the cube's centre at the
    contact on the plane at that height), and how many tosses the slice holds."""
    seqs: dict[str, list[list[float]]] = {}
    with gzip.open(DATA / "contactnets_cube" / "flights.csv.gz", "rt") as fh:
        for r in csv.DictReader(fh):
            seqs.setdefault(f"c{int(r['toss']):03d}", []).append(
                [int(r["frame"]) / CB_HZ] + [float(r[c]) for c in ("x_m", "y_m", "z_m")]
            )
    rows, tracks = [], {}
    for tid, v in seqs.items():
        f = np.asarray(v)
        tr = f[: len(f) - CB_AFTER_CONTACT - 1]
        if tr[-1, 0] < 0.1 - 1e-9:
            continue
        p, touch = tr[:, 1:4], f[len(tr), 1:4]
        d = p[CB_AXIS_FRAMES - 1] - p[0]
        rows.append(_log_row(tid, ("acrylic_cube", "cube", CB_MASS_KG, CB_SIDE_M), p[0], d, touch))
        tracks[tid] = tr
    return rows, tracks, len(seqs)


def cube() -> dict[str, Any]:
    """The cube's tosses of 0.1 s or more: the second fit (gravity vector free by linear
    least squares, the drag left out), cell's track fit, and `cell gap` on 40 of them."""
    from cell.gap.run import _k_of
    from cell.gap.tracks import fit_tracks
    from cell.log.table import ThrowTable

    rows, tracks, n_all = _cube_log()
    table = ThrowTable.from_records(rows)
    ids = table.text("throw_id")
    k = _k_of(table)
    fit = fit_tracks(ids, tracks, k)
    g, rms, speed = [], [], []
    for tid in ids:
        t, p = tracks[tid][:, 0], tracks[tid][:, 1:4]
        a = np.c_[np.ones_like(t), t, 0.5 * t**2]
        c = np.linalg.lstsq(a, p, rcond=None)[0]
        g.append(c[2])
        rms.append(np.sqrt(np.mean(np.sum((p - a @ c) ** 2, axis=1))))
        speed.append(np.linalg.norm(c[1]))
    gv = np.array(g)
    g_ind = np.linalg.norm(gv, axis=1) / G0
    told = np.isfinite(fit.g_ratio)
    sel = rows[:: len(rows) // CB_GAP_TOSSES][:CB_GAP_TOSSES]
    gap = _cell_gap(sel, {r["throw_id"]: tracks[r["throw_id"]] for r in sel}, "cube's tosses")
    return {
        "tosses": n_all,
        "tosses_usable": len(ids),
        "rate_hz": CB_HZ,
        "mass_kg": CB_MASS_KG,
        "side_m": CB_SIDE_M,
        "k_nominal_per_m": float(k[0]),
        "samples_median": float(np.median([len(t) for t in tracks.values()])),
        "speed_mps_median": float(np.median(speed)),
        "drag_over_gravity": float(k[0] * np.median(speed) ** 2 / G0),
        "second_g_ratio_median": float(np.median(g_ind)),
        "second_g_ratio_p10_p90": [float(x) for x in np.percentile(g_ind, [10, 90])],
        "second_horizontal_g_mps2": float(np.linalg.norm(np.median(gv[:, :2], axis=0))),
        "second_rms_m": float(np.median(rms)),
        "implied_rate_hz": float(CB_HZ / np.sqrt(np.median(g_ind))),
        "cell_g_ratio": float(np.median(fit.g_ratio[told])),
        "cell_gravity_told": int(told.sum()),
        "cell_drag_ratio": float(np.median(fit.drag_ratio)),
        "cell_fit_rms_m": float(np.median(fit.rms_m)),
        "cell_dropped_tracks": int(np.sum(fit.dropped > 0)),
        "cell_dropped_max": int(np.max(fit.dropped)),
        "unusable": len(fit.unusable),
        "gap": gap,
    }


def _cell_fit(fit: Any) -> dict[str, Any]:
    """The medians of cell's whole-track fit over a set's flights (`fit_tracks`' TrackFit)
    and how many tracks it could not use."""
    return {
        "cell_g_ratio": float(np.median(fit.g_ratio)),
        "cell_drag_ratio": float(np.median(fit.drag_ratio)),
        "cell_fit_rms_m": float(np.median(fit.rms_m)),
        "cell_dropped_median": float(np.median(fit.dropped)),
        "unusable": len(fit.unusable),
    }


def _cell_gap(rows: list[dict[str, Any]], tracks: dict[str, np.ndarray], what: str) -> Any:
    """`cell gap`'s JSON report on the flights as a throw log with their tracks, written
    to a temporary folder (RuntimeError naming `what` if it does not exit 0)."""
    from cell.cli import main as cell_main

    with tempfile.TemporaryDirectory() as tmp:
        _write_log(rows, tracks, Path(tmp))
        out = Path(tmp) / "gap.json"
        args = ["gap", f"{tmp}/throws.csv", "--tracks", f"{tmp}/tracks.csv", "--json", str(out)]
        with redirect_stdout(StringIO()):
            rc = cell_main(args)
        if rc != 0:
            raise RuntimeError(f"cell gap on the {what} exited {rc}")
        return json.loads(out.read_text())


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m cell.bench.bench_real_tracks")
    p.add_argument("--json", metavar="PATH", help="write the figures as JSON to PATH")
    a = p.parse_args(argv)
    doc = {
        "jugglebot": jugglebot(),
        "tabletennis": tabletennis(),
        "tennicam": tennicam(),
        "cube": cube(),
    }
    text = json.dumps(doc, indent=1)
    print(text)
    if a.json:
        write_whole(a.json, lambda p: p.write_text(text + "\n"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
