"""Property-based fuzzing of the two files users hand over most: sort-job YAML and throw-log
CSV. Whatever the bytes, reading them either succeeds or raises the project's named error
(CellError) — never another exception, never a hang."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cell.errors import CellError
from cell.jobs import parse_job
from cell.log import read_throws_csv
from cell.log.csvio import REQUIRED_COLUMNS

FUZZ = settings(
    max_examples=150,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)

GOOD_JOB = """\
bins:
  - {id: near, position_m: [0.55, 0.35], size_m: [0.3, 0.3], rim_height_m: 0.12}
  - {id: far, position_m: [2.0, 0.0], size_m: [0.3, 0.3], rim_height_m: 0.15}
items:
  - {object: cube50, count: 2, bin: far}
  - {shape: sphere, mass_kg: 0.03, size_m: [0.04, 0.04, 0.04], bin: near}
limits: {max_items: 10}
"""

yaml_scalars = st.one_of(
    st.integers(-(10**30), 10**30).map(str),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.sampled_from(
        [
            "",
            "~",
            "null",
            "true",
            "[]",
            "{}",
            "&a x",
            "*a",
            "!!python/object:os.system",
            "5e-2",
            "-0",
            "0x1F",
            ".inf",
            "'''",
            '"',
            "- -",
            ": :",
            "\t",
            "\x00",
        ]
    ),
    st.text(max_size=12),
)


@FUZZ
@given(data=st.data())
def test_mutated_jobs_load_or_fail_with_a_named_error(data: st.DataObject) -> None:
    tokens = GOOD_JOB.replace("[", " [ ").replace("]", " ] ").replace(",", " , ").split(" ")
    for _ in range(data.draw(st.integers(1, 4))):
        k = data.draw(st.integers(0, len(tokens) - 1))
        tokens[k] = data.draw(yaml_scalars)
    text = " ".join(tokens)
    try:
        job = parse_job(text, "fuzz.yaml")
    except CellError as exc:
        assert str(exc).startswith("fuzz.yaml"), exc
        return
    assert 1 <= len(job.expanded_items()) <= job.max_items


@FUZZ
@given(st.binary(max_size=400))
def test_arbitrary_bytes_as_a_job(raw: bytes) -> None:
    try:
        parse_job(raw.decode("utf-8", errors="replace"), "fuzz.yaml")
    except CellError:
        pass


def _row() -> dict[str, str]:
    return {
        "throw_id": "t0", "object_id": "cube50", "shape": "cube", "mass_kg": "0.06",
        "size_x_m": "0.05", "size_y_m": "0.05", "size_z_m": "0.05", "stroke_m": "0.06",
        "x_m": "0.5", "y_m": "0.0", "z_m": "0.6", "elevation_rad": "0.6", "azimuth_rad": "0.0",
        "roll_rad": "0.0", "vx_mps": "0.0", "vy_mps": "0.0", "vz_mps": "0.0", "platform": "arm",
        "rotor_rpm": "0", "land_z_m": "0.0", "landed_x_m": "1.5", "landed_y_m": "0.0",
    }  # fmt: skip


@FUZZ
@given(
    edits=st.lists(
        st.tuples(st.sampled_from(list(REQUIRED_COLUMNS)), yaml_scalars), min_size=1, max_size=4
    ),
    drop=st.lists(st.sampled_from(list(REQUIRED_COLUMNS)), max_size=2),
    bom=st.booleans(),
)
def test_mutated_throw_logs_load_or_name_row_and_column(
    edits: list[tuple[str, str]], drop: list[str], bom: bool, tmp_path_factory
) -> None:
    row = _row()
    for col, value in edits:
        row[col] = value
    cols = [c for c in row if c not in drop]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=cols, extrasaction="ignore")
    w.writeheader()
    w.writerow(row)
    path = Path(tmp_path_factory.mktemp("fuzz")) / "t.csv"
    path.write_bytes((b"\xef\xbb\xbf" if bom else b"") + buf.getvalue().encode("utf-8", "replace"))
    try:
        table = read_throws_csv(path)
    except CellError as exc:
        assert str(exc).startswith(str(path)), exc
        return
    assert len(table) == 1 and not drop


@pytest.mark.parametrize("n", [0, 1])
def test_the_fuzzers_do_find_both_outcomes(n: int, tmp_path: Path) -> None:
    """The properties are not vacuous: the good inputs load, a broken one is a CellError."""
    if n == 0:
        assert len(parse_job(GOOD_JOB, "good.yaml").expanded_items()) == 3
        with pytest.raises(CellError):
            parse_job(GOOD_JOB.replace("0.03", "-1"), "bad.yaml")
    else:
        path = tmp_path / "t.csv"
        with open(path, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(_row()))
            w.writeheader()
            w.writerow(_row())
        assert len(read_throws_csv(path)) == 1
