"""examples/convert_tennicam.py: the converter of the shipped slice
tests/data/tabletennis_tennicam, on a small logged episode written here in the source's
form (a ball falling onto a table and bouncing, frames repeated and missing)."""

from __future__ import annotations

import csv
import gzip
import importlib.util
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location(
    "convert_tennicam", ROOT / "examples/convert_tennicam.py"
)
conv = importlib.util.module_from_spec(_spec)  # type: ignore[arg-type]
_spec.loader.exec_module(conv)  # type: ignore[union-attr]


def _episode(bounce_at: int | None) -> str:
    """Logged lines: no ball for 3 cycles, then frames 100.. every 5.5 ms (each logged
    twice, frame 104 never), the height falling 1 cm per frame to 0.78 m at `bounce_at`
    and rising 1 cm per frame after it (None: rising from 0.9 m, no bounce)."""
    lines = [repr(((-1, 0, [0.7, 0.2, 1.3], [0, 0, 0]), (0, [0.0] * 4)))] * 3
    for i in range(40):
        if i == 4:
            continue
        b = bounce_at if bounce_at is not None else 0
        z = 0.9 - 0.01 * min(i, b) + 0.01 * max(i - b, 0)
        ball = (100 + i, 10**18 + i * 5_555_556, [0.01 * i, 3.0 - 0.02 * i, z], [0, 0, 0])
        lines += [repr((ball, (i, [0.0] * 4)))] * 2
    return "\n".join(lines) + "\n"


def test_the_converter_keeps_each_frame_once_up_to_15_after_the_bounce(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    src = tmp_path / "o80_robot_ball.zip"
    with zipfile.ZipFile(src, "w") as zf:
        zf.writestr("o80_robot_ball_001", _episode(bounce_at=12))
        zf.writestr("o80_robot_ball_002", _episode(bounce_at=None))  # rises: no bounce
    out = tmp_path / "flights.csv.gz"
    assert conv.main([str(src), str(out)]) == 0
    assert "o80_robot_ball_002: no bounce on the table found, left out" in capsys.readouterr().err
    with gzip.open(out, "rt") as fh:
        rows = list(csv.DictReader(fh))
    assert {r["episode"] for r in rows} == {"1"}
    frames = [int(r["frame"]) for r in rows]
    assert frames == sorted(set(frames)) and 104 not in frames and frames[0] == 100
    z = [float(r["z_m"]) for r in rows]
    j = z.index(min(z))
    assert frames[j] == 112 and len(rows) == j + 1 + conv.AFTER_BOUNCE
    assert rows[0]["t_ns"] == "0" and int(rows[1]["t_ns"]) == 5_555_556


def test_a_line_that_is_no_logged_tuple_is_named(tmp_path) -> None:  # type: ignore[no-untyped-def]
    src = tmp_path / "o80_robot_ball.zip"
    text = _episode(bounce_at=12) + "not a tuple\n"
    with zipfile.ZipFile(src, "w") as zf:
        zf.writestr("o80_robot_ball_001", text)
    n = len(text.splitlines())
    with pytest.raises(SystemExit, match=rf"o80_robot_ball_001: line {n}: not a logged"):
        conv.main([str(src), str(tmp_path / "f.csv.gz")])
