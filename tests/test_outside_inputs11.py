"""Inputs a new user's shell, terminal and files give, a tenth round: a reader gone
(`| head -1`), a full disk, standard streams closed, an ASCII terminal, a misspelt
command or option, an arm's URDF written in millimetres."""

from __future__ import annotations

import json
import os
import re
import resource
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import cell
from cell.errors import InvalidParameter
from cell.robot.model import load_robot
from cell.robot.mount import check_against_urdf, load_mount
from cell.robot.paths import example_robot_data_dir, robots_dir
from tests.cli_exit import cell_exit

ROOT = Path(cell.__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": str(ROOT)}
AT = (0.5, 0.0, 0.3)  # [m, W]: the grip's TCP, pointing down, in the Panda's reach
REACH = ["reach", "--robot", "panda", "--at", *map(str, AT), "--elevation", "-1.5707"]


def _cell(args: list[str], **kw: object) -> subprocess.CompletedProcess[str]:
    return subprocess.run(  # type: ignore[call-overload, no-any-return]
        [sys.executable, "-m", "cell", *args], env=ENV, text=True, timeout=300, **kw
    )


def _solved_at(path: Path) -> np.ndarray:
    """The TCP position [m, W] the JSON of `cell reach` puts the Panda's grip at, by the
    arm's forward kinematics (not by the command)."""
    q = np.asarray(json.loads(path.read_text())["q"], float)
    tcp, _ = load_robot("panda").tcp_pose(q)
    return np.asarray(tcp, float)


def test_a_reader_gone_still_gets_the_json_file_written(tmp_path: Path) -> None:
    """`cell reach ... --json r.json | head -1` (a reader that stops): the first failed
    write to standard output (BrokenPipeError) ended the command with 141 before the JSON
    file, written after the text, was written. The command now goes on: r.json holds
    a solution whose forward kinematics is at the asked point; the exit status is still
    141, nothing said (the reader asked for no more)."""
    out = tmp_path / "r.json"
    proc = subprocess.Popen(
        [sys.executable, "-m", "cell", *REACH, "--json", str(out)],
        env=ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()  # the reader gone before the first line
    err = proc.stderr.read()
    assert proc.wait(timeout=300) == 141, err
    assert "Traceback" not in err, err
    assert np.allclose(_solved_at(out), AT, atol=1e-3)


def test_a_full_standard_output_is_said_and_the_json_file_written(tmp_path: Path) -> None:
    """`cell reach ... --json r.json > /dev/full`: was "cell: error: No space left on
    device" (no word of which file) and no r.json; now standard output is named, the
    command goes on and r.json is written."""
    out = tmp_path / "r.json"
    with open("/dev/full", "w") as full:
        proc = _cell([*REACH, "--json", str(out)], stdout=full, stderr=subprocess.PIPE)
    assert proc.returncode == 2, proc.stderr
    assert re.search(r"cell: error: standard output: No space left on device", proc.stderr)
    assert "Traceback" not in proc.stderr
    assert np.allclose(_solved_at(out), AT, atol=1e-3)


def _fsize_limit(limit: int) -> None:  # in the child, before exec
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))


def test_an_output_the_disk_cannot_take_is_named_and_left_as_it_was(tmp_path: Path) -> None:
    """A write the file system refuses (here the file-size limit, `ulimit -f`, as a full
    disk or a quota would: Python ignores SIGXFSZ, so the write fails with EFBIG) named no
    file: "cell: error: File too large". It now names the output, and the file that was
    there is left as it was."""
    out = tmp_path / "r.json"
    # the caches built, with no limit (in this process: the same files, no second start)
    assert cell_exit([*REACH]) == 0
    out.write_text('{"old": 1}\n')
    proc = _cell(
        [*REACH, "--json", str(out)],
        capture_output=True,
        preexec_fn=lambda: _fsize_limit(64),  # the reach JSON is ~500 bytes
    )
    assert proc.returncode == 2, proc.stderr
    said = f"cell: error: {out}: File too large; not written (a file there is left as it was)"
    assert said in proc.stderr, proc.stderr
    assert out.read_text() == '{"old": 1}\n'
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]  # no temporary file left


BIN = "ящик"
ONE_ITEM = f"""cell: {{robot: panda}}
bins:
  - {{id: {BIN}, position_m: [0.55, 0.35], size_m: [0.30, 0.30], rim_height_m: 0.12}}
items:
  - {{object: cyl50, bin: {BIN}}}
"""


@pytest.mark.parametrize("closed", ["1", "2"])
def test_a_closed_standard_stream_neither_tracebacks_nor_loses_the_json(
    tmp_path: Path, closed: str
) -> None:
    """`cell run job.yaml --json run.json >&-` (or `2>&-`): with standard output closed,
    Python's `sys.stdout` is None and the scene's first flush (`cell.sim.quiet`) was an
    AttributeError traceback (exit 1, no run.json); with standard error closed the same,
    unseen. (And a file opened then took descriptor 1, where PyBullet's C code writes.)
    A closed descriptor now gets /dev/null first: exit 0, the item placed in its bin."""
    job = tmp_path / "job.yaml"
    job.write_text(ONE_ITEM, encoding="utf-8")
    out = tmp_path / "run.json"
    proc = subprocess.run(
        ["sh", "-c", f'exec "$@" {closed}>&-', "sh", sys.executable, "-m", "cell"]
        + ["run", str(job), "--no-log", "--json", str(out)],
        env=ENV,
        text=True,
        timeout=600,
        capture_output=True,
    )
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr + proc.stdout
    (result,) = json.loads(out.read_text())["results"]
    assert result["bin_id"] == BIN and result["in_bin"], result


def test_a_name_an_ascii_terminal_cannot_show_is_printed_escaped(tmp_path: Path) -> None:
    """`cell run` of a bin named `ящик` with `PYTHONIOENCODING=ascii` (a terminal that
    shows ASCII alone): the table's first row was a UnicodeEncodeError traceback (exit 1),
    no --json file. Each character it cannot show is now its escape, `\\u044f`; the run
    is the run: the JSON (ASCII, as JSON escapes it) has the item at rest in `ящик`."""
    job = tmp_path / "job.yaml"
    job.write_text(ONE_ITEM, encoding="utf-8")
    out = tmp_path / "run.json"
    env = {**ENV, "PYTHONIOENCODING": "ascii"}
    proc = subprocess.run(
        [sys.executable, "-m", "cell", "run", str(job), "--no-log", "-q", "--json", str(out)],
        env=env,
        text=True,
        encoding="ascii",
        timeout=600,
        capture_output=True,
    )
    assert proc.returncode == 0, proc.stderr
    shown = BIN.encode("ascii", "backslashreplace").decode("ascii")
    assert shown == "\\u044f\\u0449\\u0438\\u043a"
    assert re.search(rf"place +{re.escape(shown)} +{re.escape(shown)} ", proc.stdout), proc.stdout
    (result,) = json.loads(out.read_text(encoding="ascii"))["results"]
    assert result["bin_id"] == BIN and result["in_bin"], result


def test_a_misspelt_subcommand_or_option_is_told_the_nearest(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """`cell rn` listed the fifteen commands and no nearest; `cell reach --robt panda`
    said "unrecognized arguments: --robt panda (see `cell --help`)" under `cell`'s usage,
    not `cell reach`'s. Each now names the nearest valid spelling, and the option's refusal
    is `cell reach`'s, whose help lists it."""
    assert cell_exit(["rn", "job.yaml"]) == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'rn'" in err and "did you mean 'run'?" in err, err
    args = ["reach", "--robt", "panda", "--at", "0.5", "0", "0.3"]
    assert cell_exit(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: cell reach"), err
    assert "unrecognized arguments: --robt panda; did you mean --robot?" in err, err
    assert "(see `cell reach --help`)" in err
    assert cell_exit(["run", "job.yaml", "--ee", "pybulet"]) == 2
    assert "did you mean 'pybullet'?" in capsys.readouterr().err
    assert cell_exit(["xyzzy"]) == 2  # nothing near: no guess
    assert "did you mean" not in capsys.readouterr().err


def _mount_in(folder: Path, scale: float) -> Path:
    """A copy of the UR5's URDF with every `<origin xyz>` times `scale`, beside a copy of
    the shipped UR5 mount file that names it."""
    src = example_robot_data_dir() / "ur_description/urdf/ur5_robot.urdf"

    def times(m: re.Match[str]) -> str:
        return f'{m[1]}xyz="{" ".join(repr(float(v) * scale) for v in m[2].split())}"'

    urdf = re.sub(r'(<origin[^>]*?)xyz="([^"]*)"', times, src.read_text())
    (folder / "ur5_scaled.urdf").write_text(urdf)
    mount = (robots_dir() / "ur5_throwing/mount.yaml").read_text()
    mount = re.sub(r"(?m)^arm_urdf: .*$", "arm_urdf: ur5_scaled.urdf", mount)
    mount = re.sub(r"(?m)^arm: ur5$", "arm: ur5_scaled", mount)
    path = folder / "mount.yaml"
    path.write_text(mount)
    return path


def test_an_arm_urdf_in_millimetres_is_refused_naming_the_likely_unit(tmp_path: Path) -> None:
    """The UR5's URDF with its lengths written in millimetres loaded as metres: an arm
    about 1.3 km long, whose IK missed the pick station by 26,763 mm while the job check
    said the arm "reaches about 919.08 m out". The mount file is now refused when read,
    naming the field, the chain's length and millimetres. The same copy at scale 1 (the
    URDF in metres, rewritten the same way) loads. The length said is the UR5's, in mm:
    its datasheet's DH lengths (below) sum to 1.34 m."""
    (tmp_path / "mm").mkdir()
    (tmp_path / "m").mkdir()
    with pytest.raises(InvalidParameter) as err:
        check_against_urdf(load_mount(str(_mount_in(tmp_path / "mm", 1000.0))))
    said = str(err.value)
    assert "field 'arm_urdf'" in said and "is it written in millimetres?" in said, said
    length = float(re.search(r"add up to ([\d,.]+) m", said)[1].replace(",", ""))  # type: ignore[index]
    check_against_urdf(load_mount(str(_mount_in(tmp_path / "m", 1.0))))  # metres: accepted
    # Universal Robots' DH table of the UR5 [m]: d1 0.089159, shoulder offset 0.13585, a2
    # 0.425, elbow offset 0.1197, a3 0.39225, d5 0.09465, d6 0.0823: 1.34 m, times 1000
    # (the URDF places its offsets a little differently: a band, not the figure)
    assert 1000 * 1.2 < length < 1000 * 1.45, length


def test_a_store_with_no_log_is_refused_before_the_job_is_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`cell run job.yaml --no-log --db s.db` ran the whole job and wrote no store, without a
    word (`--no-log` won); the user asked for both. Refused now, before the job is read,
    saying why; `--db` with `--no-log` and `--learn` (the store the refit reads) is still
    taken (tests/test_learn_refit.py)."""
    job = tmp_path / "job.yaml"
    job.write_text(ONE_ITEM, encoding="utf-8")
    db = tmp_path / "s.db"
    assert cell_exit(["run", str(job), "--no-log", "--db", str(db), "-q"]) == 2
    err = capsys.readouterr().err
    assert f"--db {db} with --no-log: --no-log records no throw" in err, err
    assert "warning" not in err  # refused before the job's own check
    assert not db.exists()
