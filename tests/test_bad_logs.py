"""Throw logs and tracks with values no cell can have are refused with the row and column
named and the valid range; logs too uniform to diagnose or identify are refused up front."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from cell.cli import main
from cell.log import write_throws_csv
from cell.synth import Campaign, default_world, draw_campaign


@pytest.fixture(scope="module")
def good_csv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("logs") / "good.csv"
    write_throws_csv(draw_campaign(default_world(), Campaign(n=30), seed=3), path)
    return path


def _edit(src: Path, dst: Path, row: int, column: str, value: str) -> Path:
    with open(src, newline="") as fh:
        rows = list(csv.DictReader(fh))
    rows[row][column] = value
    with open(dst, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return dst


BAD_VALUES = [
    ("elevation_rad", "10"),
    ("elevation_rad", "-2"),
    ("azimuth_rad", "100"),
    ("mass_kg", "1e308"),
    ("mass_kg", "25"),
    ("size_x_m", "5"),
    ("size_z_m", "1.5"),
    ("stroke_m", "0.9"),
    ("z_m", "5000"),
    ("landed_x_m", "-2e3"),
    ("vx_mps", "300"),
    ("rotor_rpm", "1e7"),
]


@pytest.mark.parametrize(("column", "value"), BAD_VALUES)
def test_a_value_no_cell_has_names_row_column_and_range(
    column: str, value: str, good_csv: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = _edit(good_csv, tmp_path / "bad.csv", 4, column, value)
    out = tmp_path / "out.csv"
    assert main(["predict", str(bad), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"row 5, column '{column}'" in err and "valid range" in err, err
    assert not out.exists()


def test_tracks_with_nan_are_refused(tmp_path: Path, good_csv: Path, capsys) -> None:
    tracks = tmp_path / "tracks.csv"
    tracks.write_text("throw_id,t_s,x_m,y_m,z_m\nsynth3-00000,0.0,0.1,0.0,nan\n")
    db = tmp_path / "s.sqlite"
    assert main(["log", "import", str(good_csv), "--tracks", str(tracks), "--db", str(db)]) == 2
    err = capsys.readouterr().err
    assert "column 'z_m'" in err and "finite" in err
    assert not db.exists()


def test_identical_rows_are_too_few_to_diagnose_or_identify(
    tmp_path: Path, good_csv: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with open(good_csv, newline="") as fh:
        rows = list(csv.DictReader(fh))
    same = [dict(rows[0], throw_id=f"t{k}") for k in range(len(rows))]
    path = tmp_path / "same.csv"
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(same)
    assert main(["gap", str(path)]) == 2
    assert "1 distinct" in capsys.readouterr().err
    assert main(["identify", str(path), "-o", str(tmp_path / "ee.yaml")]) == 2
    assert "identification needs at least 10 distinct throws" in capsys.readouterr().err
    assert not (tmp_path / "ee.yaml").exists()


def test_a_byte_order_mark_is_read_as_the_text_it_is(good_csv: Path, tmp_path: Path) -> None:
    from cell.log import read_throws_csv

    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbf" + good_csv.read_bytes())
    assert len(read_throws_csv(bom)) == len(read_throws_csv(good_csv)) == 30


@pytest.mark.parametrize("kind", ["folder", "binary", "missing"])
@pytest.mark.parametrize("what", ["throws", "tracks"])
def test_files_that_are_not_csv_text_are_named(
    kind: str, what: str, good_csv: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = {"folder": tmp_path / "d", "binary": tmp_path / "b.csv", "missing": tmp_path / "m.csv"}[
        kind
    ]
    if kind == "folder":
        bad.mkdir()
    elif kind == "binary":
        bad.write_bytes(bytes(range(256)) * 8)
    throws, extra = (bad, []) if what == "throws" else (good_csv, ["--tracks", str(bad)])
    db = tmp_path / "s.sqlite"
    assert main(["log", "import", str(throws), *extra, "--db", str(db)]) == 2
    err = capsys.readouterr().err
    expected = {"folder": "is a folder", "binary": "not a readable CSV", "missing": "no such file"}
    assert str(bad) in err and expected[kind] in err and "Traceback" not in err
    assert not db.exists()


def test_a_release_below_its_landing_plane_blames_z_m(
    good_csv: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = _edit(good_csv, tmp_path / "bad.csv", 2, "z_m", "-0.5")
    assert main(["predict", str(bad), "-o", str(tmp_path / "o.csv")]) == 2
    err = capsys.readouterr().err
    assert "row 3, column 'z_m'" in err and "below the floor" in err


def test_hold_out_zero_is_named_as_such(
    good_csv: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "r.skops"
    assert main(["learn", str(good_csv), "-o", str(out), "--hold-out", "0"]) == 2
    err = capsys.readouterr().err
    assert "--hold-out 0: hold out at least 1 object" in err
    assert not out.exists()
