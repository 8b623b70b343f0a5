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


# -- the command line (issue 62): numbers at inf, nan, ±1e300; paths long, special, unwritable

CLI_FUZZ = settings(
    max_examples=120,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
BAD_NUMBERS_CLI = ["inf", "-inf", "nan", "NaN", "Infinity", "1e300", "-1e300", "1e999", "1e7"]
# (the rest of a command line that works, the numeric option, how many values it takes)
NUMERIC_OPTIONS = [
    (["throw", "--object", "cube50"], "--stroke", 1),
    (["throw", "--object", "cube50"], "--at", 3),
    (["throw", "--object", "cube50"], "--elevation", 1),
    (["throw", "--object", "cube50"], "--azimuth", 1),
    (["throw", "--object", "cube50"], "--base-velocity", 3),
    (["throw", "--object", "cube50"], "--land-z", 1),
    (["throw", "--shape", "cube", "--size", "0.05", "0.05", "0.05"], "--mass", 1),
    (["throw", "--shape", "cube", "--mass", "0.1"], "--size", 3),
    (["plan", "--object", "cube50"], "--target", 3),
    (["plan", "--target", "2", "0", "0", "--object", "cube50"], "--moving-base", 1),
    (["plan", "--target", "2", "0", "0", "--object", "cube50"], "--box", 6),
    (["plan", "--target", "2", "0", "0", "--object", "cube50"], "--elevation-range", 2),
    (["plan", "--target", "2", "0", "0", "--object", "cube50"], "--current", 3),
    (["reach", "--robot", "panda"], "--at", 3),
    (["reach", "--at", "0.4", "0", "0.8"], "--roll", 1),
    (["reach", "--at", "0.4", "0", "0.8"], "--from", 7),
    (["synth", "-o", "s.csv"], "--noise-along", 1),
    (["synth", "-o", "s.csv"], "--noise-floor", 1),
    (["identify", "t.csv", "-o", "e.yaml"], "--holdout", 1),
    (["identify", "t.csv", "-o", "e.yaml"], "--tol", 1),
    (["run", "job.yaml"], "--speed-scale", 1),
    (["study", "repeatability"], "--arm-height", 1),
    (["study", "repeatability"], "--elevation", 1),
]
P = "{path}"
PATH_SLOTS = [
    ["run", P],
    ["predict", P, "-o", "o.csv"],
    ["log", "import", P],
    ["learn", P, "-o", "o.skops"],
    ["identify", P, "-o", "o.yaml"],
    ["gap", P],
    ["throw", "--object", "cube50", "--params", P],
    ["log", "show", "--db", P],
    ["synth", "-o", P, "--n", "5"],
    ["predict", "t.csv", "-o", P],
    ["job", "random", "-o", P],
    ["run", "job.yaml", "--no-log", "--snapshot", P],
    ["run", "job.yaml", "--no-log", "--json", P],
    ["gap", "t.csv", "--report", P],
    ["identify", "t.csv", "-o", P],
    ["calibrate", "--n", "2", "--log", P],
]
CLI_JOB = """\
bins:
  - {id: near, position_m: [0.55, 0.35], size_m: [0.3, 0.3], rim_height_m: 0.12}
items:
  - {object: cube50, count: 1, bin: near}
"""


@pytest.fixture(scope="module")
def cli_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with a throw log, a job, a sub-folder and a FIFO."""
    import os

    from cell.cli import main

    d = tmp_path_factory.mktemp("cli")
    assert main(["synth", "-o", str(d / "t.csv"), "--n", "20"]) == 0
    (d / "job.yaml").write_text(CLI_JOB)
    (d / "sub").mkdir()
    os.mkfifo(d / "pipe")
    return d


def _digest(d: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in d.iterdir() if p.is_file()}


def _refused_cleanly(argv: list[str], d: Path, named: str) -> None:
    """`cell argv` in `d`: exit 2, a `cell: error:` naming `named`, no traceback, `d` as it was."""
    import contextlib
    import io
    import os
    import signal

    from tests.cli_exit import cell_exit

    before = _digest(d)
    err = io.StringIO()
    cwd = os.getcwd()

    def hung(*_: object) -> None:
        raise TimeoutError(f"cell {' '.join(argv)[:80]} blocked")

    old = signal.signal(signal.SIGALRM, hung)
    signal.alarm(20)
    os.chdir(d)
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            code = cell_exit(argv)
    finally:
        os.chdir(cwd)
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    text = err.getvalue()
    assert code == 2, (argv, text)
    assert "cell: error: " in text and "Traceback" not in text, text
    assert named in text, (named, text)
    assert _digest(d) == before and sorted(p.name for p in d.iterdir()) == sorted(
        ["t.csv", "job.yaml", "sub", "pipe"]
    )


@CLI_FUZZ
@given(
    case=st.sampled_from(NUMERIC_OPTIONS),
    bad=st.sampled_from(BAD_NUMBERS_CLI),
    where=st.integers(0, 6),
)
def test_fuzzed_numbers_on_the_command_line(
    case: tuple[list[str], str, int], bad: str, where: int, cli_dir: Path
) -> None:
    prefix, flag, arity = case
    values = ["0.1"] * arity
    values[where % arity] = bad
    # "-inf" and "-1e300" are values too (argparse alone reads them as options)
    _refused_cleanly([*prefix, flag, *values], cli_dir, flag)


def _bad_paths(d: Path) -> st.SearchStrategy[str]:
    return st.one_of(
        st.integers(256, 700).map(lambda n: "n" * n + ".csv"),
        st.integers(256, 300).map(lambda n: f"sub/{'x' * n}/t.csv"),
        st.integers(2100, 2500).map(lambda n: "a/" * n + "t.csv"),
        st.sampled_from(
            [
                "/dev/zero",
                "/dev/urandom",
                str(d / "pipe"),
                str(d / "sub"),
                "/proc/x.csv",
                "/nonexistent/x.csv",
                "t.csv/x.csv",
            ]
        ),
    )


@CLI_FUZZ
@given(data=st.data(), slot=st.sampled_from(PATH_SLOTS))
def test_fuzzed_paths_on_the_command_line(
    data: st.DataObject, slot: list[str], cli_dir: Path
) -> None:
    path = data.draw(_bad_paths(cli_dir))
    if not Path("/dev/urandom").exists() and path.startswith("/dev/"):
        return
    argv = [a.replace(P, path) for a in slot]
    raw = path.encode()
    if "--json" in slot:  # not a .json name: the bare flag, and the path an extra argument
        named = "unrecognized arguments"
    elif len(raw) > 4095:
        named = "4095"
    elif max(len(part) for part in raw.split(b"/")) > 255:
        named = "255"
    else:
        named = path
    _refused_cleanly(argv, cli_dir, named)
