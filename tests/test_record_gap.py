"""Rerun recordings of `cell calibrate`, read back with Rerun's reader (`cell gap`'s are
read in test_gap.py, beside the diagnoses they record); the predicted flight against the
fast landing path; a missing rerun-sdk."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from cell.cli import main
from cell.log import read_throws_csv
from cell.model.objects import ObjectParams
from cell.model.params import DEFAULT_EE
from cell.model.throw import ThrowBatch, predict_landing
from cell.record.flight import predicted_flight
from cell.record.read import read_rows

F32 = 1e-6  # [m] Rerun stores positions as float32


def _values(rows: list[dict], column: str) -> list:
    return [r[column] for r in rows]


def test_predicted_flight_starts_at_release_and_ends_on_the_fast_path_landing() -> None:
    obj = ObjectParams(shape="cube", mass=0.05, size=(0.05, 0.05, 0.05))
    batch = ThrowBatch.single(
        obj, stroke=0.05, position=(0.4, 0.1, 0.6), elevation=0.6, azimuth=0.3, land_z=0.15
    )
    land = predict_landing(batch, DEFAULT_EE)
    f = predicted_flight(batch, DEFAULT_EE)
    assert np.allclose(f[0, 1:], (0.4, 0.1, 0.6)) and f[0, 0] == 0.0
    assert np.all(np.diff(f[:, 0]) > 0)
    # the 3-D integrator's path ends where the planar fast path lands (a second solver)
    assert f[-1, 0] == pytest.approx(float(land.t_flight[0]), abs=1e-9)
    assert f[-1, 3] == pytest.approx(0.15, abs=1e-3)
    assert np.hypot(f[-1, 1] - land.x[0], f[-1, 2] - land.y[0]) < 2e-3


def test_cli_calibrate_record_nominal_and_fitted_against_the_scene(tmp_path) -> None:
    from cell.identify.report import predicted_landing
    from cell.params import ModelParams, load_params

    rrd, log, out = tmp_path / "cal.rrd", tmp_path / "cal.csv", tmp_path / "ee.yaml"
    # no ad-hoc campaign: the recording holds the campaign's throws (the mass rule fitted
    # to ad-hoc throws is neither recorded nor read here)
    argv = ["calibrate", "--n", "20", "--adhoc", "0", "-o", str(out), "--log", str(log)]
    argv += ["--record", str(rrd)]
    assert main([*argv, "--json"]) == 0
    table = read_throws_csv(log)
    rows = read_rows(rrd)
    nominal = np.array(_values(rows["/calibrate/nominal_m"], "Scalars:scalars"))[:, 0]
    fitted = np.array(_values(rows["/calibrate/fitted_m"], "Scalars:scalars"))[:, 0]
    # recomputed here from the logged CSV and the written parameter file
    for params, got in ((ModelParams(), nominal), (load_params(out), fitted)):
        want = np.hypot(*(table.landed - predicted_landing(table, params)).T)
        assert np.allclose(got, want, atol=1e-9)
    assert np.sqrt(np.mean(fitted**2)) < 0.5 * np.sqrt(np.mean(nominal**2))
    assert len(rows["/world/throw/release"]) == len(table) == 20


def test_a_missing_rerun_sdk_is_a_cell_error_naming_the_extra(
    tmp_path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """In this process (a child paid the start and the imports, about 1.4 CPU-s, for the
    same check): `import rerun`, made at the call (`cell.record.stream.import_rerun`),
    fails as it does where rerun-sdk is not installed, whether or not a test before had
    imported it."""
    monkeypatch.setitem(sys.modules, "rerun", None)  # makes `import rerun` fail
    code = main(["gap", "throws.csv", "--record", str(tmp_path / "x.rrd")])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "cell: error: --record needs rerun-sdk" in err
    assert "cell[record]" in err and "Traceback" not in err


def test_reading_a_file_that_is_not_a_recording_names_it(tmp_path) -> None:
    from cell.errors import InvalidInput

    bad = tmp_path / "bad.rrd"
    bad.write_text("not a recording\n")
    with pytest.raises(InvalidInput, match="bad.rrd: not a Rerun recording"):
        read_rows(bad)
    with pytest.raises(InvalidInput, match="no such recording"):
        read_rows(tmp_path / "missing.rrd")
