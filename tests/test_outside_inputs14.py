"""Inputs a new user's cell gives, a thirteenth round: a store the disk refuses mid-run,
an arm slowed past what any arm is."""

from __future__ import annotations

import json
import resource
import sqlite3
from pathlib import Path

import pytest

from cell.log.store import ThrowStore
from cell.robot.mount import MIN_ACCELERATION, load_mount
from tests.cli_exit import cell_exit

FAR = "{id: far, position_m: [1.60, 0.00], size_m: [0.40, 0.40], rim_height_m: 0.15}"


def _job(tmp_path: Path, items: str, cell: str = "{robot: panda}") -> Path:
    job = tmp_path / "job.yaml"
    job.write_text(f"cell: {cell}\nbins:\n  - {FAR}\nitems:\n{items}")
    return job


class _FileSizeLimit:
    """RLIMIT_FSIZE of one byte while in the block: every file write past its first byte
    fails with EFBIG (Python ignores SIGXFSZ), as on a full disk."""

    def __enter__(self) -> None:
        self.before = resource.getrlimit(resource.RLIMIT_FSIZE)
        resource.setrlimit(resource.RLIMIT_FSIZE, (1, self.before[1]))

    def __exit__(self, *exc: object) -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, self.before)


def test_a_store_the_disk_refuses_mid_run_stops_the_run_keeping_what_was_recorded(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A full disk (here a file-size limit, `ulimit -f`) when `cell run` records its second
    throw: on main, sqlite3's "disk I/O error" came out of the run as a traceback (exit 1)
    and the --json summary was not written. Now the run stops there: `cell: error:` names
    the store and what refused it (exit 2), the first throw is in the store, read back
    whole, and the JSON holds the item finished, marked interrupted."""
    db, out = tmp_path / "s.db", tmp_path / "out.json"
    real = ThrowStore.append
    calls: list[int] = []

    def append(self: ThrowStore, *a: object, **k: object) -> None:
        calls.append(1)
        if len(calls) < 2:
            return real(self, *a, **k)
        with _FileSizeLimit():  # the disk fills at the second throw
            return real(self, *a, **k)

    monkeypatch.setattr(ThrowStore, "append", append)
    job = _job(tmp_path, "  - {object: cube50, count: 3, bin: far}\n")
    argv = ["run", str(job), "--db", str(db), "--json", str(out), "-q", "--plan-workers", "1"]
    assert cell_exit(argv + ["--no-cycle-search", "--no-turn-release"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    assert f"cell: error: {db}: cannot write the throw-log store (disk I/O error" in err, err
    assert "stopped after 1 of 3 items; 1 throw kept in" in err, err
    assert len(calls) == 2  # the run stopped at the refused write, the third item not taken
    doc = json.loads(out.read_text())
    assert doc["interrupted"] and doc["items"] == 1 and doc["items_planned"] == 3, doc
    (r,) = doc["results"]
    with sqlite3.connect(db) as conn:  # the store as SQLite reads it, not as `cell` does
        assert conn.execute("PRAGMA integrity_check").fetchone() == ("ok",)
        rows = conn.execute("SELECT throw_id, object_id FROM throws").fetchall()
    assert rows == [(r["throw_id"], "cube50")], (rows, r)


def test_an_import_the_disk_refuses_is_said_and_leaves_the_store_as_it_was(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """`cell log import` of a log larger than the room left on the disk (the store opened,
    its import refused): on main, sqlite3's OperationalError came out as a traceback; now
    `cell: error:` names the store (exit 2), the throws committed before stay, and the same
    import goes in once there is room."""
    a, b, db = tmp_path / "a.csv", tmp_path / "b.csv", tmp_path / "s.db"
    for path, seed in ((a, "1"), (b, "2")):
        assert cell_exit(["synth", "-o", str(path), "--n", "6", "--seed", seed]) == 0
    assert cell_exit(["log", "--db", str(db), "import", str(a)]) == 0
    capsys.readouterr()
    real = ThrowStore.import_table

    def full(self: ThrowStore, *a: object, **k: object) -> int:
        with _FileSizeLimit():
            return real(self, *a, **k)

    with monkeypatch.context() as m:
        m.setattr(ThrowStore, "import_table", full)
        code = cell_exit(["log", "--db", str(db), "import", str(b)])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err, err
    assert f"cell: error: {db}: cannot write the throw-log store (disk I/O error" in err, err
    with sqlite3.connect(db) as conn:  # the store as SQLite reads it, not as `cell` does
        assert conn.execute("PRAGMA integrity_check").fetchone() == ("ok",)
        assert conn.execute("SELECT COUNT(*) FROM throws").fetchone() == (6,)
    assert cell_exit(["log", "--db", str(db), "import", str(b)]) == 0
    with ThrowStore(db, read_only=True) as store:
        assert len(store) == 12


def test_a_speed_scale_slower_than_any_arm_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`cell run --speed-scale 1e-9` came out of its first move as a traceback (NumPy asked
    for a 5.8 TiB array), `--speed-scale 0.001` ran for minutes growing past 2 GB. Refused
    now where the arm's slowest joint would accelerate under MIN_ACCELERATION, what a
    mount file may give (the mount's own limits, not a constant of this test); the least
    scale the message gives is taken."""
    job = _job(tmp_path, "  - {object: cube50, bin: far}\n")
    slowest = min(load_mount("panda").acceleration_limits)
    least = MIN_ACCELERATION / slowest
    for scale in ("1e-9", "0.001", f"{least * 0.99:.6f}"):
        assert cell_exit(["run", str(job), "--no-log", "--speed-scale", scale]) == 2
        err = capsys.readouterr().err
        assert "Traceback" not in err, err
        assert f"--speed-scale {float(scale):g}: the panda arm's slowest joint" in err, err
        assert f"an acceleration limit of {slowest:g} rad/s²" in err, err
    given = float(err.split("; give ")[1].split(" to 1")[0])
    assert least <= given < least + 1e-4
    for argv in (
        ["bench", "sort", "--layouts", "1", "--robots", "ur10", "--speed-scale", "0.02"],
        ["bench", "tradeoff", "--layouts", "1", "--robots", "ur10", "--scales", "0.02,1"],
    ):
        assert cell_exit(argv) == 2
        assert "the ur10 arm's slowest joint" in capsys.readouterr().err


def test_bench_sort_records_a_layout_its_arm_cannot_sort_and_goes_on(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`cell bench sort --robots panda,ur3`: a random layout keeps the default pick station,
    0.60 m out, beyond what the UR3's grip pointing down reaches (docs/arms.md). On main
    the job check's refusal ended the whole benchmark (exit 2) after the Panda's layout had
    run, its results lost; now the UR3's layout is recorded refused, its reason said, and
    the Panda's is reported. Every layout refused exits 4, as a run that sorts nothing."""
    out = tmp_path / "b.json"
    argv = ["bench", "sort", "--set", "tune", "--max-items", "1", "--workers", "1"]
    argv += ["--no-cycle-search", "--no-turn-release"]
    assert cell_exit(argv + ["--layouts", "2", "--robots", "panda,ur3", "--json", str(out)]) == 0
    err = capsys.readouterr().err
    assert "layout 1 (ur3) refused: <random layout 1>, line " in err, err
    assert "the ur3 arm does not reach the pick station" in err, err
    doc = json.loads(out.read_text())
    assert doc["layouts_refused"] == 1 and doc["items"] == 1, doc
    rows = {r["robot"]: r for r in doc["per_layout"]}
    assert rows["ur3"]["refused"] and not rows["panda"]["refused"], rows
    assert cell_exit(argv + ["--layouts", "1", "--robots", "ur3", "--json", str(out)]) == 4
    assert "every layout was refused" in capsys.readouterr().err


def test_a_release_under_the_floor_is_refused_and_a_moved_current_said(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`cell plan --box` wholly under the floor planned a release at z = -0.2 m; `cell throw
    --at 0 0 -0.5` told the user to lower the landing plane (under the floor, which it
    refuses); `cell plan --current` below the release box released elsewhere, silently.
    Refused now, by flag; a --current outside the box is said with the point the plan
    released from, which the JSON's release point is."""
    plan = ["plan", "--object", "cube50", "--target", "1.0", "0", "0.1"]
    for argv, flag in (
        (plan + ["--box", "0.2", "-0.4", "-0.5", "0.6", "0.4", "-0.2"], "--box"),
        (plan + ["--current", "0.4", "0", "-0.3"], "--current"),
        (["throw", "--object", "cube50", "--at", "0", "0", "-0.5"], "--at"),
    ):
        assert cell_exit(argv) == 2, argv
        err = capsys.readouterr().err
        assert f"cell: error: {flag}: a release point z = -" in err, err
        assert "is under the floor" in err, err
    out = tmp_path / "p.json"
    argv = plan + ["--current", "0.4", "0", "0.3", "--method", "fast", "--json", str(out)]
    assert cell_exit(argv) == 0
    err = capsys.readouterr().err
    doc = json.loads(out.read_text())
    at = (doc["x_m"], doc["y_m"], doc["z_m"])
    assert at != (0.4, 0.0, 0.3), doc  # not released where --current is
    said = ", ".join(f"{v:.2f}" for v in at)
    assert "--current (0.40, 0.00, 0.30) m lies outside the release box" in err, err
    assert f"releases from its nearest point, ({said}) m, instead" in err, err
    assert cell_exit(plan + ["--current", "0.4", "0", "0.6", "--method", "fast"]) == 0
    assert "outside the release box" not in capsys.readouterr().err  # inside: not said


def _ceiling_ur5(tmp_path: Path) -> Path:
    """A mount file of the UR5 hung from a ceiling 1.3 m up, upside down: a copy of its
    URDF whose `world_joint` has that origin (docs/arms.md: a stand or a turn is written
    so), the meshes by absolute path."""
    from cell.robot.paths import example_robot_data_dir

    erd = Path(example_robot_data_dir())
    text = (erd / "ur_description/urdf/ur5_robot.urdf").read_text()
    old = '<child link="base_link"/>\n    <origin rpy="0.0 0.0 0.0" xyz="0.0 0.0 0.0"/>'
    assert old in text
    text = text.replace(
        old,
        old.replace('rpy="0.0', 'rpy="3.141592653589793').replace(
            'xyz="0.0 0.0 0.0"', 'xyz="0.0 0.0 1.3"'
        ),
    )
    text = text.replace("package://example-robot-data/robots/", f"{erd}/")
    (tmp_path / "ur5_ceil.urdf").write_text(text)
    mount = Path(__file__).parents[1] / "robots/ur5_throwing/mount.yaml"
    spec = mount.read_text().replace("arm: ur5", "arm: ur5_ceil")
    spec = spec.replace("arm_urdf: ur_description/urdf/ur5_robot.urdf", "arm_urdf: ur5_ceil.urdf")
    (tmp_path / "mount.yaml").write_text(spec)
    return tmp_path / "mount.yaml"


def test_an_arm_hung_from_the_ceiling_is_not_told_to_place_nearer_than_a_bin_may_stand(
    tmp_path: Path,
) -> None:
    """The UR5 hung 1.3 m up reaches down to a bin's place pose only 0.21 m out, nearer the
    base than a bin may stand (ROBOT_BASE_CLEARANCE_M): on main the warning ended "to have
    them placed, move the bin closer", which no job can do, and a station below its reach
    was told "move the station within that" of a reach it had none of. Now the warning says
    the reach lies nearer than a bin may stand, and the station's error where to look."""
    from cell.errors import JobError
    from cell.jobbins import ROBOT_BASE_CLEARANCE_M
    from cell.jobs import load_job

    _ceiling_ur5(tmp_path)
    near = "{id: near, position_m: [0.55, 0.35], size_m: [0.30, 0.30], rim_height_m: 0.12}"
    items = "  - {object: cube50, bin: far}\n  - {object: cyl50, bin: near}\n"
    job = tmp_path / "job.yaml"
    job.write_text(
        "cell: {mount: mount.yaml}\npick_station: {position_m: [0.40, -0.30, 0.75]}\n"
        f"bins:\n  - {near}\n  - {FAR}\nitems:\n{items}"
    )
    (warning,) = [w for w in load_job(job).warnings if "cannot place into bin 'near'" in w]
    reach = float(warning.split("reaches about ")[1].split(" m out")[0])
    assert 0.0 < reach < ROBOT_BASE_CLEARANCE_M, warning
    assert "move the bin closer" not in warning, warning
    assert f"nearer the base than a bin may stand ({ROBOT_BASE_CLEARANCE_M} m)" in warning
    job.write_text(job.read_text().replace("[0.40, -0.30, 0.75]", "[0.45, -0.40, 0.20]"))
    with pytest.raises(JobError) as exc:
        load_job(job)
    said = str(exc.value)
    assert "does not get there at that height: move the station to a height the grip" in said
    assert "within that" not in said, said


def test_a_plan_onto_the_arms_own_base_is_warned(capsys: pytest.CaptureFixture[str]) -> None:
    """`cell plan --target 0 0 0.1` planned a throw onto the arm's base without a word (the
    model has no arm in it; a job refuses a bin within ROBOT_BASE_CLEARANCE_M of the base).
    Warned now, with the target's distance from the base; a target beyond it is not."""
    from cell.jobbins import ROBOT_BASE_CLEARANCE_M

    plan = ["plan", "--object", "cube50", "--target"]
    assert cell_exit(plan + ["0.1", "-0.1", "0.1"]) == 0
    err = capsys.readouterr().err
    assert "warning: the target is 0.14 m from the arm's base" in err, err
    assert f"within the {ROBOT_BASE_CLEARANCE_M} m a job keeps its bins from it" in err, err
    assert cell_exit(plan + [str(ROBOT_BASE_CLEARANCE_M + 0.01), "0", "0.1"]) == 0
    assert "arm's base" not in capsys.readouterr().err
