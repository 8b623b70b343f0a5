"""`cell gap` on a log longer than its memory allows: refused in one line naming the file, the
count and the bound, before the diagnosis, with no report written and the log left as it was
(the diagnosis' memory grows about 20 kB a throw: 4.1 GB on a 200,000-row log, so a log at the
CSV size bound would want some 40 GB)."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

import cell.cli.cmd_gap as cmd_gap
from cell.cli import main

HEADER = (
    "throw_id,object_id,shape,mass_kg,size_x_m,size_y_m,size_z_m,stroke_m,x_m,y_m,z_m,"
    "elevation_rad,azimuth_rad,roll_rad,vx_mps,vy_mps,vz_mps,platform,rotor_rpm,land_z_m,"
    "landed_x_m,landed_y_m"
)
ROW = "t{i},cube50,cube,0.05,0.05,0.05,0.05,0.06,0,0,0.8,0.6,0,0,0,0,0,arm,0,0,1.{i:02d},0.0{i}"


def test_a_log_over_the_bound_is_refused_before_the_diagnosis(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    log = tmp_path / "log.csv"
    log.write_text(HEADER + "\n" + "\n".join(ROW.format(i=i) for i in range(25)) + "\n")
    before = hashlib.sha256(log.read_bytes()).hexdigest()
    monkeypatch.setattr(cmd_gap, "MAX_GAP_THROWS", 24)
    out = tmp_path / "report.json"
    assert main(["gap", str(log), "--json", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in err[0]
    assert str(log) in err[0] and "25 throws" in err[0] and "at most 24" in err[0]
    assert not out.exists()
    assert hashlib.sha256(log.read_bytes()).hexdigest() == before
