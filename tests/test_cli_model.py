"""`cell predict` and `cell throw` from the command line, against an independent implementation."""

import csv
import json
import math
import subprocess
import sys

import numpy as np
import pytest

from cell.catalogue import catalogue
from cell.cli import main
from cell.log import REQUIRED_COLUMNS, read_throws_csv
from tests import mdl_reference as ref


def write_log(path, rows):
    cols = list(REQUIRED_COLUMNS) + ["session"]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        for r in rows:
            w.writerow(r)


def varied_rows(n, seed=5, landed=False):
    rng = np.random.default_rng(seed)
    objs = [e.params for e in catalogue().values()]
    rows = []
    for i in range(n):
        o = objs[rng.integers(len(objs))]
        rows.append(
            dict(
                throw_id=f"t{i:03d}",
                object_id=o.name,
                shape=o.shape,
                mass_kg=o.mass,
                size_x_m=o.size[0],
                size_y_m=o.size[1],
                size_z_m=o.size[2],
                stroke_m=rng.uniform(0.03, 0.11),
                x_m=rng.uniform(-0.3, 0.3),
                y_m=rng.uniform(-0.3, 0.3),
                z_m=rng.uniform(0.4, 1.3),
                elevation_rad=rng.uniform(-0.1, 1.1),
                azimuth_rad=rng.uniform(-3, 3),
                roll_rad=0.0,
                vx_mps=rng.uniform(-0.3, 0.3),
                vy_mps=rng.uniform(-0.3, 0.3),
                vz_mps=0.0,
                platform="arm",
                rotor_rpm=0,
                land_z_m=rng.uniform(0, 0.2),
                landed_x_m="1.0" if landed else "",
                landed_y_m="0.5" if landed else "",
                session="s1",
            )
        )
    return rows


def test_predict_matches_independent_implementation(tmp_path):
    rows = varied_rows(40)
    src, out = tmp_path / "throws.csv", tmp_path / "out.csv"
    write_log(src, rows)
    assert main(["predict", str(src), "-o", str(out)]) == 0
    table = read_throws_csv(out)
    assert table.text("session") == ["s1"] * 40  # extra columns are kept
    for i, r in enumerate(rows):
        x, y, t = ref.land(
            r["shape"],
            r["mass_kg"],
            (r["size_x_m"], r["size_y_m"], r["size_z_m"]),
            r["stroke_m"],
            (r["x_m"], r["y_m"], r["z_m"]),
            r["elevation_rad"],
            r["azimuth_rad"],
            (r["vx_mps"], r["vy_mps"], r["vz_mps"]),
            r["land_z_m"],
        )
        assert math.hypot(table.num("pred_x_m")[i] - x, table.num("pred_y_m")[i] - y) < 1e-3
        assert table.num("pred_t_flight_s")[i] == pytest.approx(t, abs=1e-3)


def test_predict_names_the_row_that_never_lands(tmp_path, capsys):
    rows = varied_rows(5)
    rows[3]["land_z_m"] = 9.0
    src = tmp_path / "throws.csv"
    write_log(src, rows)
    assert main(["predict", str(src), "-o", str(tmp_path / "o.csv")]) == 2
    err = capsys.readouterr().err
    assert "row 4" in err and "land_z_m" in err and "never crosses" in err
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.parametrize(
    "column, value, message",
    [
        ("mass_kg", "-0.1", "negative"),
        ("shape", "pyramid", "unknown shape"),
        ("stroke_m", "abc", "not a number"),
        ("stroke_m", "0.5", "outside"),
    ],
)
def test_predict_rejects_bad_cells_naming_file_row_column(tmp_path, capsys, column, value, message):
    rows = varied_rows(4)
    rows[2][column] = value
    src = tmp_path / "bad.csv"
    write_log(src, rows)
    assert main(["predict", str(src), "-o", str(tmp_path / "o.csv")]) == 2
    err = capsys.readouterr().err
    assert "bad.csv" in err and "row 3" in err and column in err and message in err


def test_throw_json_from_a_subprocess():
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "cell",
            "throw",
            "--object",
            "cube50",
            "--stroke",
            "0.0625",
            "--at",
            "0",
            "0",
            "0.6",
            "--elevation",
            str(math.radians(30)),
            "--json",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    d = json.loads(out.stdout)
    assert d["landed_x_m"] == pytest.approx(1.2902, abs=1e-3)
    assert d["t_flight_s"] == pytest.approx(0.5290, abs=1e-3)
    assert d["push_force_n"] == pytest.approx(14.6559, abs=1e-3)
    # launch speed = |impulse of push and gravity| / m, less a little drag
    e = math.radians(30)
    v = np.array([math.cos(e), 0, math.sin(e)]) * d["push_force_n"] * 0.012 / 0.06
    v[2] -= 9.81 * 0.012
    assert d["launch_speed_mps"] == pytest.approx(np.linalg.norm(v), rel=2e-3)
    assert d["launch_speed_mps"] < np.linalg.norm(v)


def test_throw_adhoc_object_and_errors(capsys):
    assert (
        main(
            [
                "throw",
                "--shape",
                "sphere",
                "--mass",
                "0.03",
                "--size",
                "0.04",
                "0.04",
                "0.04",
                "--json",
            ]
        )
        == 0
    )
    assert (
        main(["throw", "--shape", "sphere", "--mass", "-1", "--size", "0.04", "0.04", "0.04"]) == 2
    )
    assert "mass" in capsys.readouterr().err
    assert main(["throw", "--object", "nope"]) == 2
    assert "cube50" in capsys.readouterr().err  # lists the valid ids
    assert main(["throw", "--object", "cube50", "--stroke", "0.5"]) == 2
    assert "0.030 … 0.110" in capsys.readouterr().err


def test_predict_honours_effects_switched_on_in_the_parameter_file(tmp_path, capsys):
    rows = varied_rows(10)
    src = tmp_path / "throws.csv"
    write_log(src, rows)
    (tmp_path / "nominal.yaml").write_text("end_effector: {}\n")
    (tmp_path / "wind.yaml").write_text("effects: {wind: {x_mps: 3.0, y_mps: 0.0, z_mps: 0.0}}\n")
    assert (
        main(
            [
                "predict",
                str(src),
                "-o",
                str(tmp_path / "a.csv"),
                "--params",
                str(tmp_path / "nominal.yaml"),
            ]
        )
        == 0
    )
    assert (
        main(
            [
                "predict",
                str(src),
                "-o",
                str(tmp_path / "b.csv"),
                "--params",
                str(tmp_path / "wind.yaml"),
            ]
        )
        == 0
    )
    a, b = read_throws_csv(tmp_path / "a.csv"), read_throws_csv(tmp_path / "b.csv")
    # a tail wind along +x carries every throw farther along +x
    assert np.all(b.num("pred_x_m") > a.num("pred_x_m"))
    (tmp_path / "bad.yaml").write_text("effects: {gremlins: {}}\n")
    assert (
        main(
            [
                "predict",
                str(src),
                "-o",
                str(tmp_path / "c.csv"),
                "--params",
                str(tmp_path / "bad.yaml"),
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert "bad.yaml" in err and "gremlins" in err and "band_mass" in err
