"""Inputs of a lab with its own launcher and tracker, an eleventh round: a tracker whose
time is in microseconds, and a log with its units in a second header row, are refused
naming the file, the row, the column and what is meant, by the readers and by `cell gap`
and `cell log import` in one line, the input left as it was and the store as it was."""

from __future__ import annotations

import csv
import hashlib
import sqlite3
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cell.cli import main
from cell.errors import LogFormatError
from cell.gap.run import diagnose_log
from cell.log import read_throws_csv
from cell.log.csvio import read_tracks_csv
from cell.model.params import DEFAULT_EE
from cell.model.throw import ThrowBatch, predict_landing

HEADER = (
    "throw_id,object_id,shape,mass_kg,size_x_m,size_y_m,size_z_m,stroke_m,x_m,y_m,z_m,"
    "elevation_rad,azimuth_rad,roll_rad,vx_mps,vy_mps,vz_mps,platform,rotor_rpm,land_z_m,"
    "landed_x_m,landed_y_m"
)
ROW = "{p}{i},cube50,cube,0.05,0.05,0.05,0.05,0.06,0,0,0.8,0.6,0,0,0,0,0,arm,0,0,1.{i:02d},0.0{i}"
UNITS = ",,,kg,m,m,m,m,m,m,m,rad,rad,rad,m/s,m/s,m/s,,rpm,m,m,m"


def _log(path: Path, prefix: str = "t", units: str | None = None) -> Path:
    rows = [ROW.format(p=prefix, i=i) for i in range(25)]
    path.write_text("\n".join([HEADER] + ([units] if units else []) + rows) + "\n")
    return path


def _tracks(path: Path, scale: float, hz: float = 120.0) -> Path:
    """Track t0 of a free flight from 0.012 s after the release command (the band's push),
    sampled at `hz`, its time written times `scale` (1e6: microseconds)."""
    lines = ["throw_id,t_s,x_m,y_m,z_m"]
    for k in range(60):
        t = 0.012 + k / hz
        lines.append(f"t0,{t * scale:.6g},{0.3 + 2 * t:.5f},0,{0.8 + 2 * t - 4.905 * t * t:.5f}")
    path.write_text("\n".join(lines) + "\n")
    return path


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


# --- a tracker's time in microseconds (cell.log.track_time) ---


@pytest.mark.parametrize(
    ("scale", "said", "not_said"),
    [
        (1e6, "is it 0.012 s written in microseconds?", "milliseconds"),
        (1e3, "row 12, column 't_s': 103.667 s is outside", "microseconds"),
    ],
)
def test_a_track_in_microseconds_is_called_microseconds(
    tmp_path: Path, scale: float, said: str, not_said: str
) -> None:
    """A tracker stamping in microseconds writes 0.012 s as 12,000: within a flight's
    time in milliseconds (12 s), and it was asked whether it was 12 s in milliseconds. Its
    samples lie 8,333 apart (120 Hz), a 0.12 Hz tracker in milliseconds: microseconds.
    Milliseconds (the 12th sample, 0.1037 s, the first beyond 100, steps of 8.3) still are."""
    path = _tracks(tmp_path / "tracks.csv", scale)
    with pytest.raises(LogFormatError) as e:
        read_tracks_csv(path)
    msg = str(e.value).split("tracks.csv", 1)[1]  # the message past the file's path
    assert "column 't_s'" in msg and said in msg and not_said not in msg
    if scale == 1e3:
        assert "is it 0.103667 s written in milliseconds?" in msg
    else:
        assert "row 1, column 't_s'" in msg


def test_import_refuses_microsecond_tracks_in_one_line_and_keeps_the_store(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "store.sqlite"
    assert main(["log", "import", str(_log(tmp_path / "a.csv", "a")), "--db", str(db)]) == 0
    log, tracks = _log(tmp_path / "log.csv"), _tracks(tmp_path / "us.csv", 1e6)
    before = (_sha(log), _sha(tracks))
    capsys.readouterr()
    assert main(["log", "import", str(log), "--tracks", str(tracks), "--db", str(db)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "us.csv, row 1, column 't_s'" in err[0], err
    assert "microseconds" in err[0] and "Traceback" not in err[0]
    assert (_sha(log), _sha(tracks)) == before
    with sqlite3.connect(db) as con:
        (n,) = con.execute("SELECT COUNT(*) FROM throws").fetchone()
    assert n == 25  # the store holds what it held


# --- a row of units under the header (cell.log.units_row) ---


def test_a_row_of_units_under_the_header_is_said_to_be_one(tmp_path: Path) -> None:
    """`,,,kg,m,m,...` under the header was "row 1, column 'mass_kg': 'kg' is not a
    number"; it is a row of units, and the log's units are in its column names."""
    with pytest.raises(LogFormatError) as e:
        read_throws_csv(_log(tmp_path / "log.csv", units=UNITS))
    msg = str(e.value)
    assert "row 1:" in msg and "row of units ('kg', 'm', 'm', 'm', …)" in msg
    assert "column names" in msg and "delete the row" in msg and "another unit" not in msg


def test_a_row_of_other_units_names_them(tmp_path: Path) -> None:
    """Millimetres and grams in the units row: the values under them are not SI, and the
    message names those columns."""
    units = UNITS.replace(",kg,m,m,m,", ",g,mm,mm,mm,", 1)
    with pytest.raises(LogFormatError) as e:
        read_throws_csv(_log(tmp_path / "log.csv", units=units))
    msg = str(e.value)
    assert "row of units" in msg and "'g' under 'mass_kg'" in msg
    assert "'mm' under 'size_x_m'" in msg and "another unit" in msg


def test_a_word_in_a_number_column_is_still_not_a_number(tmp_path: Path) -> None:
    """The control: one cell of text in a throw's row is no row of units."""
    path = tmp_path / "log.csv"
    text = _log(path).read_text().replace("t3,cube50,cube,0.05,", "t3,cube50,cube,heavy,", 1)
    path.write_text(text)
    with pytest.raises(LogFormatError) as e:
        read_throws_csv(path)
    assert "row 4, column 'mass_kg': 'heavy' is not a number" in str(e.value)


@pytest.mark.parametrize("command", ["gap", "import"])
def test_the_commands_refuse_a_units_row_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str
) -> None:
    path = _log(tmp_path / "log.csv", units=UNITS)
    before = _sha(path)
    db = tmp_path / "store.sqlite"
    argv = ["gap", str(path)] if command == "gap" else ["log", "import", str(path), "--db", str(db)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "log.csv, row 1: is a row of units" in err[0], err
    assert _sha(path) == before


# --- tracks begun mid-flight: the release not seen (cell.gap.tracks_unseen) ---

G = 9.81  # [m/s²], the model's
RHO = 1.225  # [kg/m³], the model's air
BALL = (3, 0.47, 0.065, 0.070)  # shape code, C_d, kg, diameter [m]


def _band_tracks(tmp_path: Path, start_share: float) -> tuple[Path, Path, float]:
    """24 throws of the band (the model's launch states, `predict_landing`), flown from its
    release time dt by scipy's RK45 (a second solver) with drag, tracked at 120 Hz with
    1 mm of scatter from `start_share` of each flight on; landings with 10 mm. Returns the
    log, the tracks and the median time [s] from the release to the first sample."""
    rng = np.random.default_rng(3065)
    code, cd, kg, a = BALL
    k = 0.5 * RHO * cd * np.pi * a * a / 4.0 / kg  # [1/m] ½ρC_dA/m
    n = 24
    b = ThrowBatch.build(
        stroke=rng.uniform(0.04, 0.10, n),
        position=np.c_[rng.uniform(-0.1, 0.1, (n, 2)), rng.uniform(0.7, 0.9, n)],
        elevation=rng.uniform(0.4, 0.9, n),
        azimuth=rng.uniform(-0.3, 0.3, n),
        shape=np.full(n, code),
        mass=np.full(n, kg),
        size=np.full((n, 3), a),
    )
    fast = predict_landing(b, DEFAULT_EE)
    dt = DEFAULT_EE.dt
    log, tracks = tmp_path / "band.csv", tmp_path / "tracks.csv"
    firsts = []
    with log.open("w", newline="") as fh, tracks.open("w", newline="") as ft:
        w, wt = csv.writer(fh), csv.writer(ft)
        w.writerow(HEADER.split(","))
        wt.writerow(["throw_id", "t_s", "x_m", "y_m", "z_m"])
        for i in range(n):

            def rates(_t: float, s: np.ndarray) -> np.ndarray:
                return np.r_[s[3:], -k * np.linalg.norm(s[3:]) * s[3:] - [0.0, 0.0, G]]

            def floor(_t: float, s: np.ndarray) -> float:
                return float(s[2])

            floor.terminal, floor.direction = True, -1  # type: ignore[attr-defined]
            s0 = np.r_[fast.launch_position[i], fast.launch_velocity[i]]
            sol = solve_ivp(rates, (dt, dt + 10.0), s0, events=floor, dense_output=True,
                            rtol=1e-10, atol=1e-10)  # fmt: skip
            t_land = float(sol.t_events[0][0])
            xy = sol.y_events[0][0][:2] + rng.normal(0.0, 0.01, 2)
            p = b.position[i]
            w.writerow([f"b{i:02d}", "ball", "sphere", kg, a, a, a, f"{b.stroke[i]:.6f}",
                        f"{p[0]:.6f}", f"{p[1]:.6f}", f"{p[2]:.6f}", f"{b.elevation[i]:.6f}",
                        f"{b.azimuth[i]:.6f}", 0, 0, 0, 0, "arm", 0, 0, xy[0], xy[1]])  # fmt: skip
            times = np.arange(dt, t_land, 1.0 / 120.0)
            times = times[times >= dt + start_share * (t_land - dt)]
            firsts.append(times[0] - dt)
            for t in times:
                q = sol.sol(t)[:3] + rng.normal(0.0, 0.001, 3)
                wt.writerow([f"b{i:02d}", f"{t:.5f}", f"{q[0]:.5f}", f"{q[1]:.5f}", f"{q[2]:.5f}"])
    return log, tracks, float(np.median(firsts))


def test_tracks_begun_mid_flight_say_the_release_is_not_seen(tmp_path: Path) -> None:
    """Tracks picked up 40 % into each flight of a log with no effect: the evidence gave a
    launch speed from tracks 1.1 % off and a launch share of centimetres as if seen (the
    halves carried back over a third of a second by a Taylor series). It now says when
    the tracks begin and that the release is not seen; tracks from the release do not."""
    log, tracks, first = _band_tracks(tmp_path, 0.4)
    d, _ = diagnose_log(read_throws_csv(log), DEFAULT_EE, tracks=read_tracks_csv(tracks))
    unseen = d.report["tracks"]["unseen"]
    # the first kept sample: the first written, or a few after it (a leading run off the fit)
    assert first - 1e-9 <= unseen["release_to_first_s"] <= first + 4.5 / 120.0, (unseen, first)
    assert unseen["unseen_share"] >= 0.25
    said = f"the tracks begin {unseen['release_to_first_s']:.3f} s (median) after the release"
    assert said in d.report["where"]["evidence"] and "not seen" in d.report["where"]["evidence"]
    log0, tracks0, first0 = _band_tracks(tmp_path, 0.0)
    d0, _ = diagnose_log(read_throws_csv(log0), DEFAULT_EE, tracks=read_tracks_csv(tracks0))
    assert first0 == 0.0 and d0.report["tracks"]["unseen"]["unseen_share"] < 0.25
    assert "not seen" not in d0.report["where"]["evidence"]


# --- sessions appended with their headers (cell.log.table) ---


def test_three_sessions_appended_name_every_header_row(tmp_path: Path) -> None:
    """Three sessions of 10 throws appended, each with its header: the refusal named the
    first repeated header (row 11) alone, so the file was mended one header at a time. It
    now names both (rows 11 and 22: the 11th and 22nd data rows) and the files they make."""
    rows = [ROW.format(p="s", i=i) for i in range(30)]
    path = tmp_path / "sessions.csv"
    path.write_text("\n".join([HEADER, *rows[:10], HEADER, *rows[10:20], HEADER, *rows[20:]]))
    with pytest.raises(LogFormatError) as e:
        read_throws_csv(path)
    msg = str(e.value)
    assert "row 11: is a header row again" in msg and "row 22 too (3 files in all?)" in msg
    two = tmp_path / "two.csv"  # the control: one header repeated, said as before
    two.write_text("\n".join([HEADER, *rows[:10], HEADER, *rows[10:20]]))
    with pytest.raises(LogFormatError) as e:
        read_throws_csv(two)
    assert str(e.value).endswith("check the throw ids of the two are distinct")
