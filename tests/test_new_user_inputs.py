"""Issue 62, line by line: what a new user ran into. Each bad input gives a `cell: error:`
line naming the option or file, exit 2, no traceback, and no file created or changed (the
inputs' and the shipped robots/ and tasks/ files' checksums before and after)."""

from __future__ import annotations

import hashlib
import json
import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

import cell
from cell.cli import main
from cell.cli.common import human, plural
from tests.cli_exit import cell_exit

ROOT = Path(cell.__file__).resolve().parents[1]
SHIPPED_PARAMS = ROOT / "robots" / "cell_scene" / "ee_params.yaml"

TINY_JOB = """\
bins:
  - {id: near, position_m: [0.55, 0.35], size_m: [0.3, 0.3], rim_height_m: 0.12}
items:
  - {object: cube50, count: 1, bin: near}
"""


def _tree(*folders: Path) -> dict[str, str]:
    """sha256 of every file under the folders (name -> digest)."""
    out = {}
    for folder in folders:
        for p in sorted(folder.rglob("*")):
            if p.is_file():
                out[str(p)] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with a 40-throw log (t.csv), a 5-row one (few.csv), a store and a tiny job."""
    d = tmp_path_factory.mktemp("logs")
    assert main(["synth", "-o", str(d / "t.csv"), "--n", "40", "--db", str(d / "a.sqlite")]) == 0
    lines = (d / "t.csv").read_text().splitlines()
    (d / "few.csv").write_text("\n".join(lines[:6]) + "\n")
    (d / "job.yaml").write_text(TINY_JOB)
    (d / "job.json").write_text(TINY_JOB)  # YAML is a superset of JSON's syntax: a job too
    return d


@pytest.fixture
def work(logs: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A fresh folder (the current one) holding copies of the logs; on leaving, nothing in
    it or under robots/ and tasks/ may have been created or changed."""
    for p in logs.iterdir():
        (tmp_path / p.name).write_bytes(p.read_bytes())
    monkeypatch.chdir(tmp_path)
    before = _tree(tmp_path, ROOT / "robots", ROOT / "tasks")
    yield tmp_path
    assert _tree(tmp_path, ROOT / "robots", ROOT / "tasks") == before


def _refused(argv: list[str], named: str, capsys: pytest.CaptureFixture[str]) -> str:
    """Run `cell argv` (at most 20 s: a read that blocks fails the test) and check the refusal."""

    def hung(*_: object) -> None:
        raise TimeoutError(f"cell {' '.join(argv)[:80]} did not return within 20 s")

    old = signal.signal(signal.SIGALRM, hung)
    signal.alarm(20)
    try:
        code = cell_exit(argv)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    err = capsys.readouterr().err
    assert code == 2, err
    assert "cell: error: " in err and "Traceback" not in err, err
    assert named in err, err
    return err


# -- Tracebacks (exit 1) ------------------------------------------------------------


def test_learn_on_a_five_row_log(work: Path, capsys: pytest.CaptureFixture[str]) -> None:
    err = _refused(["learn", "few.csv", "-o", "l.skops", "--grid", "small"], "few.csv", capsys)
    assert "at least 20" in err


def test_learn_below_the_minimum_of_usable_throws(
    work: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = (work / "t.csv").read_text().splitlines()
    (work / "t19.csv").write_text("\n".join(lines[:20]) + "\n")  # 19 throws
    err = _refused(["learn", "t19.csv", "-o", "l.skops", "--grid", "small"], "t19.csv", capsys)
    assert "20" in err
    (work / "t19.csv").unlink()


@pytest.mark.parametrize("flag", ["--elevation", "--azimuth"])
@pytest.mark.parametrize("value", ["inf", "-inf", "nan"])
def test_reach_at_a_non_finite_angle(
    flag: str, value: str, work: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["reach", "--robot", "panda", "--at", "0.4", "0", "0.8", "--elevation", "0.3"]
    _refused([*argv, flag, value], flag, capsys)


LONG = "a" * 300


@pytest.mark.parametrize(
    ("argv", "named"),
    [
        (["run", LONG + ".yaml"], "255"),
        (["synth", "-o", LONG + ".csv", "--n", "5"], "-o"),
        (["predict", "t.csv", "-o", LONG + ".csv"], "-o"),
        (["predict", LONG + ".csv", "-o", "p.csv"], "255"),
        (["identify", "t.csv", "-o", LONG + ".yaml"], "-o"),
        (["learn", "t.csv", "-o", LONG + ".skops"], "-o"),
        (["gap", LONG + ".csv"], "255"),
        (["log", "show", "--db", LONG + ".sqlite"], "--db"),
        (["log", "export", "-o", LONG + ".csv", "--db", "a.sqlite"], "-o"),
        (["throw", "--object", "cube50", "--params", LONG + ".yaml"], "--params"),
        (["run", "job.yaml", "--json", LONG + ".json"], "--json"),
        (["run", "job.yaml", "--snapshot", LONG + ".png"], "--snapshot"),
        (["job", "random", "-o", "d/" + LONG + "/j.yaml"], "-o"),
        (["synth", "-o", "x/" * 2100 + "t.csv"], "4095"),
    ],
    ids=lambda v: " ".join(v)[:30] if isinstance(v, list) else v,
)
def test_a_path_over_255_bytes(
    argv: list[str], named: str, work: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _refused(argv, named, capsys)


def test_an_unwritable_snapshot_is_refused_before_the_run(
    work: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    err = _refused(
        ["run", "job.yaml", "--no-log", "--snapshot", "/proc/out.png"], "--snapshot", capsys
    )
    assert "/proc/out.png" in err


@pytest.mark.parametrize("command", [["run", "job.yaml", "--no-log"], ["calibrate", "--n", "2"]])
def test_gui_without_a_display(
    command: list[str], work: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    if not sys.platform.startswith("linux"):
        pytest.skip("the display check is for X servers (Linux)")
    _refused([*command, "--gui"], "--gui", capsys)


# -- Unbounded reads -----------------------------------------------------------------


@pytest.fixture
def fifo(work: Path) -> Iterator[Path]:
    p = work.parent / f"{work.name}.fifo"  # outside `work`, whose files are checksummed
    os.mkfifo(p)
    yield p
    p.unlink()


SPECIAL_READS = [
    ["run", "{f}"],
    ["predict", "{f}", "-o", "x.csv"],
    ["log", "import", "{f}"],
    ["learn", "{f}", "-o", "x.skops"],
    ["identify", "{f}", "-o", "x.yaml"],
    ["gap", "{f}"],
    ["throw", "--object", "cube50", "--params", "{f}"],
    ["synth", "-o", "s.csv", "--n", "5", "--world", "{f}"],
    ["log", "show", "--db", "{f}"],
    ["log", "import", "t.csv", "--tracks", "{f}"],
]


@pytest.mark.parametrize("argv", SPECIAL_READS, ids=lambda a: " ".join(a)[:30])
@pytest.mark.parametrize("special", ["/dev/zero", "/dev/urandom", "fifo", "folder"])
def test_a_special_file_is_refused_unread(
    argv: list[str], special: str, work: Path, fifo: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = {"fifo": str(fifo), "folder": str(work.parent)}.get(special, special)
    if not Path(path).exists():
        pytest.skip(f"{path} is not on this system")
    err = _refused([a.replace("{f}", path) for a in argv], path, capsys)
    assert any(w in err for w in ("device", "FIFO", "folder")), err
    assert not Path(work / "cell_log.sqlite").exists()


def test_the_size_bounds_are_checked_before_reading(
    work: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    big = work.parent / f"{work.name}.yaml"
    with open(big, "wb") as fh:  # a sparse file: 2 MB on paper, nothing on disk
        fh.truncate(2_000_001)
    try:
        _refused(["run", str(big)], "at most 1000000", capsys)
    finally:
        big.unlink()


# -- Files overwritten without asking -------------------------------------------------


@pytest.mark.parametrize(
    ("argv", "named"),
    [
        (["run", "job.json", "--json", "job.json"], "JOB job.json"),
        (["run", "job.yaml", "--json=job.yaml"], "JOB job.yaml"),
        (["identify", "t.csv", "-o", "t.csv"], "THROWS t.csv"),
        (["predict", "t.csv", "-o", "t.csv"], "THROWS t.csv"),
        (["learn", "t.csv", "-o", "t.csv"], "THROWS t.csv"),
        (["gap", "t.csv", "--json", "x.json", "--report", "x.json"], "--json x.json"),
        (["synth", "-o", "s.csv", "--save-world", "s.csv"], "-o s.csv"),
        (["synth", "-o", "a.sqlite", "--db", "a.sqlite"], "--db a.sqlite"),
        (["log", "export", "--db", "a.sqlite", "-o", "a.sqlite"], "--db a.sqlite"),
        (["log", "export", "--db", "a.sqlite", "-o", "e.csv", "--tracks", "e.csv"], "-o e.csv"),
        (["identify", "t.csv", "-o", str(SHIPPED_PARAMS)], "--replace"),
        (["job", "random", "-o", str(ROOT / "tasks" / "bins.yaml")], "--replace"),
        (["synth", "-o", str(ROOT / "tasks" / "drone.yaml"), "--n", "5"], "--replace"),
        (["synth", "-o", str(ROOT / "tasks" / "new.csv"), "--n", "5"], "--replace"),
        (["run", "job.yaml", "--json", str(ROOT / "tasks" / "out.json")], "--replace"),
    ],
    ids=lambda v: " ".join(v)[:40] if isinstance(v, list) else v,
)
def test_an_input_or_a_shipped_file_is_never_written(
    argv: list[str], named: str, work: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _refused(argv, named, capsys)


def test_replace_allows_writing_a_shipped_file(work: Path, capsys) -> None:
    out = ROOT / "tasks" / "i62_replace_probe.txt"  # not a .yaml: no test globs it
    try:
        assert main(["job", "random", "-o", str(out)]) == 2 and not out.exists()
        assert "--replace" in capsys.readouterr().err
        assert main(["job", "random", "-o", str(out), "--replace"]) == 0
        text = out.read_text()
        assert "\nbins:\n" in text and "\nitems:\n" in text
    finally:
        out.unlink(missing_ok=True)


def test_an_existing_output_is_probed_without_being_changed(work: Path, capsys) -> None:
    # identify fails on the log's length after the outputs were checked: ee.yaml untouched
    (work / "ee.yaml").write_text("keep: me\n")
    _refused(["identify", "few.csv", "-o", "ee.yaml"], "few.csv", capsys)
    assert (work / "ee.yaml").read_text() == "keep: me\n"
    (work / "ee.yaml").unlink()


# -- Reads that write ---------------------------------------------------------------


@pytest.mark.parametrize(
    "argv",
    [
        ["log", "show", "--db", "a.sqlite"],
        ["log", "show", "--db", "a.sqlite", "--json"],
        ["log", "export", "--db", "a.sqlite", "-o", "e.csv"],
        ["identify", "--db", "a.sqlite", "-o", "ee.yaml", "--max-iter", "1"],
    ],
    ids=lambda a: " ".join(a[:2]),
)
def test_a_store_read_leaves_no_file_behind(argv: list[str], logs: Path, tmp_path: Path) -> None:
    (tmp_path / "a.sqlite").write_bytes((logs / "a.sqlite").read_bytes())
    before = hashlib.sha256((tmp_path / "a.sqlite").read_bytes()).hexdigest()
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        assert main(argv) == 0
    finally:
        os.chdir(cwd)
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == sorted(
        {"a.sqlite", *(["e.csv"] if "export" in argv else [])}
        | ({"ee.yaml"} if "identify" in argv else set())
    ), left
    assert hashlib.sha256((tmp_path / "a.sqlite").read_bytes()).hexdigest() == before


# -- Accepted nonsense --------------------------------------------------------------

OBJ = ["--shape", "cube", "--size", "0.05", "0.05", "0.05"]


@pytest.mark.parametrize(
    ("argv", "named"),
    [
        (["throw", *OBJ, "--mass", "1e300"], "--mass"),
        (["throw", "--object", "cube50", "--at", "1e300", "0", "0"], "--at"),
        (["throw", "--object", "cube50", "--elevation", "100"], "--elevation"),
        (["throw", "--object", "cube50", "--base-velocity", "1e9", "0", "0"], "--base-velocity"),
        (["throw", "--object", "cube50", "--land-z", "-1e300"], "--land-z"),
        (["throw", "--object", "cube50", "--stroke", "1e300"], "--stroke"),
        (["plan", "--target", "1e300", "0", "0", "--object", "cube50"], "--target"),
        (
            ["plan", "--target", "2", "0", "0", "--object", "cube50", "--moving-base", "1e9"],
            "--moving-base",
        ),
        (["reach", "--at", "0.4", "0", "0.8", "--roll", "1e300"], "--roll"),
        (["synth", "-o", "s.csv", "--n", "10000000000"], "--n"),
        (["identify", "t.csv", "-o", "ee.yaml", "--tol", "nan"], "--tol"),
    ],
    ids=lambda v: " ".join(v)[:40] if isinstance(v, list) else v,
)
def test_absurd_numbers_name_the_valid_range(
    argv: list[str], named: str, work: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a NumPy warning would fail the test
        err = _refused(argv, named, capsys)
    assert "Warning" not in err


def test_elevation_range_is_said_in_degrees_too(work: Path, capsys) -> None:
    err = _refused(["throw", "--object", "cube50", "--elevation", "100"], "--elevation", capsys)
    assert "90°" in err and "1.5708" in err


# -- Conventions --------------------------------------------------------------------


def test_cell_alone_prints_help_and_exits_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main([]) == 2
    assert "COMMAND" in capsys.readouterr().err


def test_cell_version(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"cell {cell.__version__}"


@pytest.mark.parametrize("spelling", [["--json"], ["--json", "-"]])
def test_json_to_stdout_everywhere(
    spelling: list[str], work: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["throw", "--object", "cube50", *spelling]) == 0
    assert json.loads(capsys.readouterr().out)["object"] == "cube50"
    assert main(["log", "show", "--db", "a.sqlite", *spelling]) == 0
    assert json.loads(capsys.readouterr().out)["throws"] == 40
    assert not (work / "-").exists()


def test_json_path_writes_a_file_after_the_text(work: Path, capsys) -> None:
    assert main(["throw", "--object", "cube50", "--json", "t.json"]) == 0
    assert "lands at" in capsys.readouterr().out
    assert json.loads((work / "t.json").read_text())["object"] == "cube50"
    (work / "t.json").unlink()


def test_the_old_bare_flag_before_a_positional_still_works(work: Path, capsys) -> None:
    # `--json` then a name that is not a .json file: the flag, the name the log to read
    assert main(["predict", "t.csv", "-o", "p.csv"]) == 0
    capsys.readouterr()
    assert main(["log", "--db", "a.sqlite", "show", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["throws"] == 40
    (work / "p.csv").unlink()


def test_counts_and_dicts_as_a_person_writes_them() -> None:
    assert plural(1, "object") == "1 object" and plural(3, "object") == "3 objects"
    assert plural(0, "throw") == "0 throws"
    assert human({}) == "none" and human({"a": 2, "b": 3}) == "a 2, b 3"
    assert human([]) == "none" and human(float("nan")) == "n/a"


def test_synth_of_one_object_says_1_object(work: Path, capsys) -> None:
    assert main(["synth", "-o", "s.csv", "--n", "3", "--objects", "cube50"]) == 0
    out = capsys.readouterr().out
    assert "of 1 object " in out and "objects" not in out
    (work / "s.csv").unlink()


def test_run_off_a_terminal_a_line_per_item_no_banner(
    work: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    """In a child process (stderr a pipe, not a terminal): the banners PyBullet writes at the
    file-descriptor level are gone, each item has its line, --json - is stdout and no file
    named '-' is made; -q silences the lines (run in this process, its file descriptors
    captured: the scene's connect writes at that level too, PyBullet's import banner was
    the child's)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "cell", "run", "job.yaml", "--no-log"]
    res = subprocess.run(
        [*cmd, "--json", "-"], capture_output=True, text=True, env=env, timeout=300
    )
    assert res.returncode == 0, res.stderr
    assert "argv[0]=" not in res.stderr + res.stdout and "build time" not in res.stderr
    assert "[1/1] item 0 cube50: place to near" in res.stderr, res.stderr
    assert json.loads(res.stdout)["items"] == 1
    assert not (work / "-").exists()
    capfd.readouterr()
    code = main(["run", "job.yaml", "--no-log", "-q"])
    out, err = capfd.readouterr()
    assert code == 0 and err == "", err
    assert "not in their bin     none" in out and "{}" not in out
