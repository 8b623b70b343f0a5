"""Inputs written by hand, what the sixth round left: YAML 1.1's base-60 numbers, a log
cell Python's `float` reads as no writer means it, a rim of 0. Each test was seen failing
with its fix undone."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cell.errors import JobError, LogFormatError
from cell.jobs import parse_job
from cell.log import read_throws_csv, read_tracks_csv, write_throws_csv
from cell.synth import Campaign, default_world, draw_campaign
from cell.yamlsafe import safe_load
from tests.test_outside_inputs6 import _job


@pytest.mark.parametrize("text", ["1:30", "1:30.5", "-2:05"])
def test_a_base_60_number_is_text_not_its_sum(text: str) -> None:
    """PyYAML reads `count: 1:30` as 90 items (YAML 1.1's base 60; 1:30.5 as 90.5): the
    job took 90. It is text now, refused by the field's name as a number it is not;
    the plain forms read as before."""
    assert safe_load(f"a: {text}\nb: 12\nc: 1_000\nd: 0.5\ne: .inf\n", "x.yaml") == {
        "a": text, "b": 12, "c": 1000, "d": 0.5, "e": float("inf")}  # fmt: skip
    item = f"{{object: cube50, bin: far, count: {text}}}"
    with pytest.raises(JobError, match=rf"items\[0\]\.count: '{text}' must be a whole number"):
        parse_job(_job(item=item), "j.yaml", check_reach=False)


def _log(tmp_path: Path, cell: str) -> Path:
    log = tmp_path / "ok.csv"
    write_throws_csv(draw_campaign(default_world(), Campaign(n=6), seed=3), log)
    head, *rows = log.read_text().splitlines()
    col = head.split(",").index("mass_kg")
    cells = rows[1].split(",")
    cells[col] = cell
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join([head, rows[0], ",".join(cells)]) + "\n")
    return bad


@pytest.mark.parametrize(
    ("cell", "said"),
    [("0.0_6", r"digit groups\? write the digits alone: 0.06"), ("０.06", "is not a number")],
)
def test_a_log_cell_python_reads_and_no_writer_writes_is_refused(
    tmp_path: Path, cell: str, said: str
) -> None:
    """`float` reads '0.0_6' as 0.06 and full-width digits as ASCII ones: the log took
    them. Both are refused by row and column; the same cell 0.06 is read."""
    with pytest.raises(LogFormatError, match=f"row 2, column 'mass_kg': .*{said}"):
        read_throws_csv(_log(tmp_path, cell))
    assert read_throws_csv(_log(tmp_path, "0.06")).data["mass_kg"][1] == 0.06


def test_a_track_cell_with_digit_groups_is_refused(tmp_path: Path) -> None:
    """The tracks reader took `1_0` as 10 m; it is refused by row and column now."""
    t = np.linspace(0.0, 0.5, 20)
    rows = [f"t1,{x:.3f},{x:.3f},0.0,{1.0 + 2.0 * x - 4.9 * x * x:.4f}" for x in t]
    f = tmp_path / "tracks.csv"
    f.write_text("throw_id,t_s,x_m,y_m,z_m\n" + "\n".join(rows) + "\n")
    assert list(read_tracks_csv(f)) == ["t1"]
    rows[3] = rows[3].replace(",0.0,", ",1_0,")
    f.write_text("throw_id,t_s,x_m,y_m,z_m\n" + "\n".join(rows) + "\n")
    with pytest.raises(LogFormatError, match=r"row 4, column 'y_m': '1_0' is not a number"):
        read_tracks_csv(f)


@pytest.mark.parametrize("rim", ["0", "-0.1", "0.005"])
def test_a_rim_at_or_below_the_floor_plate_names_the_plate(rim: str) -> None:
    """`rim_height_m: 0` said "must be > 0.0" where 0.005 was told of the 0.01 m floor
    plate: every rim at or below the plate now names it."""
    far = f"{{id: far, position_m: [1.50, 0.00], size_m: [0.30, 0.30], rim_height_m: {rim}}}"
    with pytest.raises(JobError, match="not above the bin's floor plate, 0.01 m thick"):
        parse_job(_job(far), "j.yaml", check_reach=False)
