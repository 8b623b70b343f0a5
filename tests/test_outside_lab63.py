"""Inputs of a lab with its own launcher and tracker, a ninth round: a ping-pong ball, whose
flight the fast path integrated with steps too long for its drag (the diagnosis then named
`spin` for a world with no effect), and `--json` given a log's name."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cell.cli import main
from cell.gap.run import diagnose_log
from cell.log import read_throws_csv
from cell.model.params import DEFAULT_EE
from cell.model.throw import ThrowBatch, predict_landing

G = 9.81  # [m/s²], the model's
RHO = 1.225  # [kg/m³], the model's air
HEADER = (
    "throw_id,object_id,shape,mass_kg,size_x_m,size_y_m,size_z_m,stroke_m,x_m,y_m,z_m,"
    "elevation_rad,azimuth_rad,roll_rad,vx_mps,vy_mps,vz_mps,platform,rotor_rpm,land_z_m,"
    "landed_x_m,landed_y_m"
).split(",")
PP_MASS, PP_D = 0.0027, 0.040  # [kg], [m]: a ping-pong ball
PP_K = 0.5 * RHO * 0.47 * np.pi * PP_D**2 / 4 / PP_MASS  # [1/m], k = ½ρC_dA/m


def _pingpong(n: int, seed: int) -> ThrowBatch:
    rng = np.random.default_rng(seed)
    return ThrowBatch.build(
        stroke=rng.uniform(0.04, 0.11, n),
        position=np.c_[rng.uniform(-0.1, 0.1, (n, 2)), rng.uniform(0.7, 0.9, n)],
        elevation=rng.uniform(0.35, 0.95, n),
        azimuth=rng.uniform(-0.5, 0.5, n),
        shape=np.full(n, 3),
        mass=np.full(n, PP_MASS),
        size=np.full((n, 3), PP_D),
    )


def _landing_ivp(p: np.ndarray, v: np.ndarray, land_z: float = 0.0) -> np.ndarray:
    """The landing (x, y) of a flight from p, v under gravity and drag −k|v|v, by scipy's
    adaptive RK45 to 1e-11 with an event at the plane: a second solver, not cell's."""

    def rates(_t: float, s: np.ndarray) -> np.ndarray:
        vel = s[3:]
        return np.r_[vel, -PP_K * np.linalg.norm(vel) * vel - [0.0, 0.0, G]]

    def plane(_t: float, s: np.ndarray) -> float:
        return float(s[2] - land_z)

    plane.terminal, plane.direction = True, -1  # type: ignore[attr-defined]
    sol = solve_ivp(rates, (0.0, 30.0), np.r_[p, v], events=plane, rtol=1e-11, atol=1e-11)
    return sol.y_events[0][0][:2]


def test_a_ping_pong_balls_flight_is_integrated_to_a_millimetre() -> None:
    """A 2.7 g, 40 mm ball launched by the band at 40-93 m/s: drag dominates its flight
    (k|v| up to 12/s). The fast path's planar RK4 took steps of 0.5/(k|v|), and landed it
    up to 25 mm (8 mm RMS) off its own flight, where an ordinary object is within
    microns: a lab's ping-pong log with no effect was diagnosed `spin`, the flight
    effect's other integrator curing the fast path's error. Now within 1 mm of a second
    solver (scipy RK45 to 1e-11 from the fast path's own launch state)."""
    b = _pingpong(30, 1063)
    fast = predict_landing(b, DEFAULT_EE)
    ref = np.array(
        [
            _landing_ivp(p, v)
            for p, v in zip(fast.launch_position, fast.launch_velocity, strict=True)
        ]
    )
    miss = np.hypot(fast.x - ref[:, 0], fast.y - ref[:, 1])
    assert np.max(np.linalg.norm(fast.launch_velocity, axis=1)) > 40.0  # drag-dominated
    assert miss.max() < 1e-3, miss.max()


def test_a_ping_pong_log_with_no_effect_is_none(tmp_path: Path) -> None:
    """240 throws of a ping-pong ball landing where their flight takes them (the second
    solver above, from the model's launch), with 10 mm of scatter per axis: the verdict
    was `spin` (a spin of −0.008 rad/s, held-out 0.0164 → 0.0142 m against a 0.0146 m
    floor); it is `none`."""
    n = 240
    b = _pingpong(n // 2, 2063)
    fast = predict_landing(b, DEFAULT_EE)
    true = np.array(
        [
            _landing_ivp(p, v)
            for p, v in zip(fast.launch_position, fast.launch_velocity, strict=True)
        ]
    )
    rng = np.random.default_rng(3063)
    path = tmp_path / "pingpong.csv"
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(HEADER)
        for k in range(n):  # each configuration thrown twice: a floor from repeats
            i = k // 2
            xy = true[i] + rng.normal(0.0, 0.01, 2)
            p = b.position[i]
            w.writerow([f"t{k:03d}", "pingpong", "sphere", PP_MASS, PP_D, PP_D, PP_D,
                        f"{b.stroke[i]:.6f}", f"{p[0]:.6f}", f"{p[1]:.6f}", f"{p[2]:.6f}",
                        f"{b.elevation[i]:.6f}", f"{b.azimuth[i]:.6f}", 0, 0, 0, 0, "arm", 0,
                        0, f"{xy[0]:.6f}", f"{xy[1]:.6f}"])  # fmt: skip
    d, _ = diagnose_log(read_throws_csv(path), DEFAULT_EE)
    assert d.report["verdict"]["effects"] == ["none"], d.report["verdict"]


@pytest.mark.parametrize("name", ["throws.csv", "report.txt"])
def test_json_given_a_name_not_ending_in_json_says_how_it_was_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str
) -> None:
    """`cell gap throws.csv --json throws.csv` said only "unrecognized arguments:
    …/throws.csv": --json followed by a name not ending in .json is the bare flag (JSON on
    standard output), and the name an argument of its own. The message now says so, and
    what --json PATH takes; nothing is written."""
    log = tmp_path / "throws.csv"
    log.write_text(",".join(HEADER) + "\n")
    before = log.read_bytes()
    other = tmp_path / name
    with pytest.raises(SystemExit) as ex:
        main(["gap", str(log), "--json", str(other)])
    assert ex.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]  # after argparse's usage line
    assert f"unrecognized arguments: {other}" in err
    assert f"--json {other}: a path for --json must end in .json" in err, err
    assert "bare --json prints the JSON on standard output" in err, err
    assert log.read_bytes() == before
    assert not other.exists() or other == log


def test_object_ids_differing_only_by_case_are_said(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A lab's log wrote one cube as `cube50` and `Cube50 ` (a trailing space, stripped):
    read as two objects without a word, so per-object laws, `cell identify`'s objects and
    `cell learn`'s objects held out split one object in two. It is read so still, and
    said, naming both ids and a row of each; ids that differ otherwise say nothing."""
    row = "cube,0.09,0.05,0.05,0.05,0.06,0,0,0.8,0.5,0,0,0,0,0,arm,0,0,1.0,0.1"
    path = tmp_path / "throws.csv"
    path.write_text(
        ",".join(HEADER)
        + "\n"
        + "".join(
            f"t{i},{oid},{row}\n" for i, oid in enumerate(["cube50", "Cube50 ", "cube30", "cube50"])
        )  # fmt: skip
    )
    with caplog.at_level("WARNING"):
        table = read_throws_csv(path)
    assert table.text("object_id") == ["cube50", "Cube50", "cube30", "cube50"]
    said = [r.getMessage() for r in caplog.records]
    assert said == [
        f"{path}: object ids 'cube50' (row 1), 'Cube50' (row 2) differ only by letter case: "
        "they are read as different objects (rows with one object_id are one object); write "
        "one id if they are one object"
    ], said
    caplog.clear()
    path.write_text(",".join(HEADER) + "\n" + f"t0,cube50,{row}\nt1,cube30,{row}\n")
    with caplog.at_level("WARNING"):
        read_throws_csv(path)
    assert not caplog.records


def test_the_null_device_as_an_output_is_written_into_not_replaced(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """`/dev/null` is an output every command accepts; the writers wrote `/dev/null.tmp`
    and moved it over `/dev/null`, which, where the user may (root in a container), puts
    a regular file holding the CSV where the device was, for every program. A FIFO of the
    test's own stands in for the device (`os.devnull` pointed at it): the output is written
    into it, read whole at its other end, and the FIFO is still a FIFO."""
    import os
    import stat
    import threading

    log = tmp_path / "throws.csv"
    row = "cube,0.09,0.05,0.05,0.05,0.06,0,0,0.8,0.5,0,0,0,0,0,arm,0,0,1.0,0.1"
    log.write_text(",".join(HEADER) + "\n" + "".join(f"t{i},cube50,{row}\n" for i in range(3)))
    null = tmp_path / "null"
    os.mkfifo(null)
    monkeypatch.setattr(os, "devnull", str(null))
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(null.read_bytes()), daemon=True)
    reader.start()
    assert main(["predict", str(log), "-o", str(null)]) == 0
    reader.join(10.0)
    assert stat.S_ISFIFO(os.stat(null).st_mode), "the output was replaced by a regular file"
    assert got and got[0].decode().startswith(",".join(HEADER) + ",pred_x_m"), got
    assert {p.name for p in tmp_path.iterdir()} == {"throws.csv", "null"}


def test_two_writers_of_one_report_at_once_both_succeed(tmp_path: Path) -> None:
    """Two `cell gap` runs given one `--json` path at once: both wrote `PATH.tmp` and moved
    it, so one moved the other's away and that one failed after its diagnosis ("….tmp: No
    such file or directory"; 9 and 7 of 300 writes each in two processes). Each write now
    has a temporary file of its own: every write succeeds and the report is one whole."""
    import json
    import threading

    from cell.gap.report import write_json

    path = tmp_path / "report.json"
    errors: list[BaseException] = []

    def writer(who: str) -> None:
        rep = {"who": who, "x": list(range(5000))}
        for _ in range(200):
            try:
                write_json(rep, path)
            except OSError as exc:
                errors.append(exc)

    threads = [threading.Thread(target=writer, args=(w,)) for w in "AB"]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors[:2]
    assert json.loads(path.read_text())["who"] in ("A", "B")
    assert [p.name for p in tmp_path.iterdir()] == ["report.json"]
