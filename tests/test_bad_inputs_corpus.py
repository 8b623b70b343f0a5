"""A corpus of bad inputs: every value a user can get wrong in a sort job, a parameter file
and on the command line gives a named error (file, line, field and what is valid), exit 2,
no traceback and no output file."""

from __future__ import annotations

from pathlib import Path

import pytest

from cell.cli import main
from cell.errors import CellError, JobError
from cell.jobs import parse_job
from cell.params import load_params
from tests.cli_exit import cell_exit

# one field per line, so a field's line is known: (line, yaml key path, text)
JOB_LINES = [
    ("bins", "bins:"),
    ("bins[0]", "  - id: near"),
    ("bins[0].position_m", "    position_m: [0.55, 0.35]"),
    ("bins[0].size_m", "    size_m: [0.3, 0.3]"),
    ("bins[0].rim_height_m", "    rim_height_m: 0.12"),
    ("bins[1]", "  - id: far"),
    ("bins[1].position_m", "    position_m: [2.0, 0.0]"),
    ("bins[1].size_m", "    size_m: [0.3, 0.3]"),
    ("bins[1].rim_height_m", "    rim_height_m: 0.15"),
    ("items", "items:"),
    ("items[0]", "  - object: cube50"),
    ("items[0].count", "    count: 2"),
    ("items[0].bin", "    bin: far"),
    ("items[1]", "  - shape: sphere"),
    ("items[1].mass_kg", "    mass_kg: 0.03"),
    ("items[1].size_m", "    size_m: [0.04, 0.04, 0.04]"),
    ("items[1].bin", "    bin: near"),
    ("limits", "limits:"),
    ("limits.place_reach_m", "  place_reach_m: 0.75"),
    ("limits.max_items", "  max_items: 10"),
    ("seed", "seed: 3"),
    ("policy", "policy: auto"),
]
GOOD_JOB = "\n".join(text for _, text in JOB_LINES) + "\n"

NUMBER_FIELDS = [
    "bins[0].rim_height_m",
    "bins[1].rim_height_m",
    "items[1].mass_kg",
    "limits.place_reach_m",
]
VECTOR_FIELDS = [
    "bins[0].position_m",
    "bins[0].size_m",
    "bins[1].position_m",
    "bins[1].size_m",
    "items[1].size_m",
]
INTEGER_FIELDS = ["items[0].count", "limits.max_items", "seed"]
CHOICE_FIELDS = ["items[0].bin", "items[1].bin", "policy"]
BAD_NUMBERS = ["-1", "0", "abc", "1e999", ".nan", "[1, 2]", "{a: 1}", "null", "true", "1000"]
BAD_VECTORS = ["[1]", "[a, b]", "1.0", "[.nan, 1]", "[1, 2, 3, 4]", "[-1, -1]", "{x: 1}", "[]"]
BAD_INTEGERS = ["-5", "1.5", "two", "99999999999", "true", "[1]", "null"]
BAD_CHOICES = ["nowhere", "123", "[far]", "''"]


def _mutate(field: str, value: str) -> tuple[str, int]:
    lines = []
    line_no = 0
    for k, (path, text) in enumerate(JOB_LINES, start=1):
        if path == field:
            key = text.split(":")[0]
            text = f"{key}: {value}"
            line_no = k
        lines.append(text)
    return "\n".join(lines) + "\n", line_no


CASES = (
    [(f, v) for f in NUMBER_FIELDS for v in BAD_NUMBERS]
    + [
        (f, v)
        for f in VECTOR_FIELDS
        for v in BAD_VECTORS
        if not (f.endswith("position_m") and v == "[-1, -1]")  # a bin behind the robot is valid
    ]
    + [(f, v) for f in INTEGER_FIELDS for v in BAD_INTEGERS]
    + [(f, v) for f in CHOICE_FIELDS for v in BAD_CHOICES]
)


def test_the_good_job_is_good() -> None:
    assert len(parse_job(GOOD_JOB, "job.yaml").expanded_items()) == 3


@pytest.mark.parametrize(("field", "value"), CASES)
def test_a_bad_job_field_is_named_with_its_line(field: str, value: str) -> None:
    text, line = _mutate(field, value)
    with pytest.raises(JobError) as exc:
        parse_job(text, "job.yaml")
    msg = str(exc.value)
    assert msg.startswith("job.yaml, line "), msg
    assert f"line {line}, {field}" in msg or field.split(".")[0] in msg, msg


BAD_PARAMS = [
    ("end_effector: 5", "end_effector"),
    ("- a\n- b", "must be a mapping"),
    ("end_effector: {Ke1: -3}", "Ke1"),
    ("end_effector: {Ke3: -1}", "Ke3"),
    ("end_effector: {dt: 0}", "dt"),
    ("end_effector: {dt: abc}", "dt"),
    ("end_effector: {phi: 9}", "phi"),
    ("end_effector: {stroke_min: 0.2}", "stroke"),
    ("end_effector: {warp: 1}", "warp"),
    ("end_effector: {L_t: .nan}", "L_t"),
    ("objects: 3", "objects"),
    ("objects: {cube: 3}", "cube"),
    ("objects: {cube: {shape: pyramid, mass_kg: 0.1, size_m: [0.05, 0.05, 0.05]}}", "pyramid"),
    ("objects: {cube: {shape: cube, mass_kg: -1, size_m: [0.05, 0.05, 0.05]}}", "mass"),
    ("objects: {cube: {shape: cube, mass_kg: 0.1, size_m: [0.05]}}", "size"),
    ("objects: {cube: {shape: cube, size_m: [0.05, 0.05, 0.05]}}", "mass_kg"),
    ("effects: 5", "effects"),
    ("effects: {no_such_effect: 1}", "no_such_effect"),
    ("colour: red", "colour"),
    ("a: &x 1\nb: *x", "aliases"),
    ("{{{{", "YAML"),
    ("!!python/object/apply:os.system ['true']", "YAML"),
    # issue 62: absurd magnitudes in a parameter file are named with the valid range
    ("end_effector: {L0: 1e300}", "L0"),
    ("end_effector: {Ke3: 1e300}", "Ke3"),
    ("end_effector: {C: -1e300}", "C"),
    ("end_effector: {dt: 1e30}", "dt"),
    ("objects: {cube: {shape: cube, mass_kg: 1e300, size_m: [0.05, 0.05, 0.05]}}", "1000 kg"),
    ("objects: {cube: {shape: cube, mass_kg: 0.1, size_m: [1e300, 0.05, 0.05]}}", "10 m"),
]


@pytest.mark.parametrize(("text", "named"), BAD_PARAMS)
def test_a_bad_parameter_file_is_named(
    text: str, named: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = tmp_path / "ee.yaml"
    f.write_text(text + "\n")
    with pytest.raises(CellError) as exc:
        load_params(f)
    assert str(f) in str(exc.value) and named in str(exc.value), str(exc.value)
    assert main(["throw", "--object", "cube50", "--params", str(f)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("cell: error: ") and "Traceback" not in err


BAD_ARGS = [
    ["throw", "--object", "nope"],
    ["throw", "--object", "cube50", "--stroke", "5"],
    ["throw", "--object", "cube50", "--stroke", "nan"],
    ["throw", "--shape", "cube", "--mass", "-1", "--size", "0.05", "0.05", "0.05"],
    ["throw", "--shape", "blob", "--mass", "0.1", "--size", "0.05", "0.05", "0.05"],
    ["plan", "--target", "2", "0", "0", "--object", "nope"],
    ["plan", "--target", "90", "0", "0", "--object", "cube50"],
    ["reach", "--robot", "kuka", "--at", "0.5", "0", "0.6", "--elevation", "0.5", "--azimuth", "0"],
    ["predict", "missing.csv", "-o", "out.csv"],
    ["identify", "missing.csv", "-o", "ee.yaml"],
    ["gap", "missing.csv"],
    ["learn", "missing.csv", "-o", "r.skops"],
    ["run", "missing.yaml"],
    ["log", "show", "--db", "missing.sqlite"],
    ["synth", "-o", "t.csv", "--n", "0"],
    ["synth", "-o", "t.csv", "--world", "missing.yaml"],
    ["calibrate", "--n", "-3"],
    ["calibrate", "--n", "2", "--gui", "--workers", "2"],
    ["calibrate", "--n", "2", "--workers", "0"],
    ["learn", "missing.csv", "-o", "r.skops", "--workers", "-1"],
    # issue 62: what a new user ran into
    ["reach", "--robot", "panda", "--at", "0.4", "0", "0.8", "--elevation", "inf"],
    ["reach", "--robot", "panda", "--at", "0.4", "0", "0.8", "--azimuth", "inf"],
    ["reach", "--robot", "panda", "--at", "0.4", "0", "0.8", "--azimuth", "-inf"],
    ["run", "a" * 300 + ".yaml"],
    ["synth", "-o", "a" * 300 + ".csv"],
    ["predict", "t.csv", "-o", "b" * 256 + ".csv"],
    ["run", "/dev/zero"],
    ["run", "/dev/urandom"],
    ["predict", "/dev/zero", "-o", "x.csv"],
    ["log", "import", "/dev/zero"],
    ["log", "show", "--db", "/dev/zero"],
    ["identify", "--db", "/dev/urandom", "-o", "e.yaml"],
    ["learn", "/dev/zero", "-o", "r.skops"],
    ["gap", "/dev/urandom"],
    ["throw", "--object", "cube50", "--params", "/dev/zero"],
    ["synth", "-o", "/dev/zero"],
    ["synth", "-o", "/proc/t.csv"],
    ["job", "random", "-o", "/proc/j.yaml"],
    ["throw", "--shape", "cube", "--mass", "1e300", "--size", "0.05", "0.05", "0.05"],
    ["throw", "--object", "cube50", "--at", "1e300", "0", "0"],
    ["throw", "--object", "cube50", "--elevation", "100"],
    ["throw", "--object", "cube50", "--base-velocity", "1e9", "0", "0"],
    ["throw", "--object", "cube50", "--land-z", "-1e300"],
    ["plan", "--target", "inf", "0", "0", "--object", "cube50"],
    [
        "plan",
        "--target",
        "2",
        "0",
        "0",
        "--object",
        "cube50",
        "--box",
        "-inf",
        "0",
        "0",
        "1",
        "1",
        "1",
    ],
    ["study", "repeatability", "--arm-height", "-1e300"],
    ["synth", "-o", "t.csv", "--noise-along", "nan"],
    ["synth", "-o", "t.csv", "--n", "99999999999"],
    ["identify", "t.csv", "-o", "t.csv"],
]


@pytest.mark.parametrize("argv", BAD_ARGS, ids=lambda a: " ".join(a)[:40])
def test_bad_command_lines_are_named(
    argv: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    monkeypatch.chdir(tmp_path)
    code = cell_exit(argv)  # argparse's own refusals (a choice list) exit 2 too
    err = capsys.readouterr().err
    assert code == 2, err
    assert "error:" in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_the_corpus_is_large() -> None:
    assert len(CASES) + len(BAD_PARAMS) + len(BAD_ARGS) >= 150
