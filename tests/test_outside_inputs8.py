"""Inputs written by hand as a new user would, a seventh round: files a job or an arm's mount
file names are inputs too (never overwritten by an output), a bin given a height, a job
saved in another encoding, ids wider than one column in the results table."""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import numpy as np
import pytest

import cell
from tests.cli_exit import cell_exit

ROOT = Path(cell.__file__).resolve().parents[1]
BIN = "  - {id: far, position_m: [1.50, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}\n"
ITEM = "  - {object: cube50, bin: far}\n"


def _digest(p: Path) -> str:
    return hashlib.sha256(p.read_bytes()).hexdigest()


def _refused(argv: list[str], capsys: pytest.CaptureFixture[str], *named: str) -> str:
    code = cell_exit(argv)
    err = capsys.readouterr().err
    assert code == 2, err
    assert "cell: error: " in err and "Traceback" not in err, err
    for word in named:
        assert word in err, err
    return err


def _mount_json(folder: Path) -> Path:
    """The UR5's mount file written as JSON (YAML reads it), in a folder of the user's."""
    import yaml

    raw = yaml.safe_load((ROOT / "robots" / "ur5_throwing" / "mount.yaml").read_text())
    p = folder / "mount.json"
    p.write_text(json.dumps(raw))
    return p


def test_the_jobs_parameter_file_is_never_an_output(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`cell.params: params.json` and `--json params.json`: the run reads the file, so the
    summary may not be written over it (it was: the run went on and replaced the model's
    parameters with the run's summary)."""
    import yaml

    params = tmp_path / "params.json"
    raw = yaml.safe_load((ROOT / "robots" / "cell_scene" / "ee_params.yaml").read_text())
    params.write_text(json.dumps(raw))
    job = tmp_path / "job.yaml"
    job.write_text(f"cell: {{robot: panda, params: params.json}}\nbins:\n{BIN}items:\n{ITEM}")
    before = _digest(params)
    _refused(
        ["run", str(job), "--no-log", "-q", "--json", str(params)],
        capsys,
        "cell.params",
        "never overwritten",
    )
    assert _digest(params) == before


def test_the_jobs_mount_file_is_never_an_output(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`cell.mount: mount.json` and `--json mount.json`, or the same file by a symbolic link."""
    mount = _mount_json(tmp_path)
    (tmp_path / "link.json").symlink_to(mount)
    job = tmp_path / "job.yaml"
    job.write_text(f"cell: {{mount: mount.json}}\nbins:\n{BIN}items:\n{ITEM}")
    before = _digest(mount)
    for out in (mount, tmp_path / "link.json"):
        _refused(
            ["run", str(job), "--no-log", "-q", "--json", str(out)],
            capsys,
            "cell.mount",
            "never overwritten",
        )
    assert _digest(mount) == before


def test_a_mount_file_given_to_reach_or_job_random_is_never_an_output(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`cell reach --robot M --json M` wrote the IK result over the mount file; `cell job
    random --robot M -o M` would write the job over it."""
    mount = _mount_json(tmp_path)
    before = _digest(mount)
    pose = ["--at", "0.45", "0", "0.3", "--elevation", "-1.5707", "--azimuth", "0"]
    _refused(["reach", "--robot", str(mount), *pose, "--json", str(mount)], capsys, "--robot")
    _refused(["job", "random", "--robot", str(mount), "-o", str(mount)], capsys, "--robot")
    assert _digest(mount) == before
    # an arm's name is no file: an output of that name in the current folder is written
    assert cell_exit(["job", "random", "--robot", "ur5", "-o", str(tmp_path / "ur5")]) == 0
    assert (tmp_path / "ur5").stat().st_size > 0


@pytest.mark.parametrize(
    "argv,flag",
    [
        (["throw", "--object", "cube50", "--land-z", "-1"], "--land-z"),
        (["plan", "--target", "1.5", "0", "-0.3", "--object", "cube50"], "--target"),
    ],
)
def test_a_landing_plane_under_the_floor_is_refused(
    argv: list[str], flag: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """The world's floor is z = 0: `cell throw --land-z -1` said the cube landed 1.90 m out
    "on z = -1.000 m", through the floor; `cell plan` aimed at a target 0.3 m under it."""
    _refused(argv, capsys, flag, "under the floor")
    # the floor itself is a landing plane (the throw's default)
    assert cell_exit(["throw", "--object", "cube50", "--land-z", "0"]) == 0


def test_an_item_the_pads_cannot_hold_is_said_so_by_throw_and_plan(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """`cell throw` of a 2 kg cube printed its landing as if the cell could throw it
    (`cell run` refuses it: the pads hold under 0.5 kg at 0.1 m across); both commands now
    say so on standard error, with why, and a catalogue cube is told nothing."""
    from cell.arm.grip_limits import grip_refusal
    from cell.model import ObjectParams
    from cell.params import load_params

    heavy = ["--shape", "cube", "--mass", "2", "--size", "0.1", "0.1", "0.1"]
    why = grip_refusal(load_params(None), ObjectParams(shape="cube", mass=2.0, size=(0.1,) * 3))
    assert why  # the independent judge: the same rule the job check refuses it by
    assert cell_exit(["throw", *heavy]) == 0
    err = capsys.readouterr().err
    assert "cell: warning: " in err and "cannot be held" in err and why in err, err
    assert cell_exit(["plan", "--target", "0.5", "0", "0.15", *heavy]) in (0, 2)
    err = capsys.readouterr().err
    assert "cannot be held" in err and why in err, err
    assert cell_exit(["throw", "--object", "cube50"]) == 0
    assert "cannot be held" not in capsys.readouterr().err


@pytest.mark.parametrize(
    "encoding,said",
    [
        ("latin-1", "not UTF-8 (byte 0xe9 on line 1, column 10: Latin-1 or Windows-1252?)"),
        ("cp1252", "not UTF-8 (byte 0xe9 on line 1, column 10: Latin-1 or Windows-1252?)"),
        ("utf-16", "UTF-16"),
        ("utf-32", "UTF-32"),
    ],
)
def test_a_job_saved_in_another_encoding_is_named(
    encoding: str, said: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A job whose `name: café` was saved in Latin-1 (or as Notepad's "Unicode") was
    refused as "not a text file"; the encoding is said, and how to save it."""
    job = tmp_path / "job.yaml"
    job.write_bytes(f"name: café\nbins:\n{BIN}items:\n{ITEM}".encode(encoding))
    err = _refused(["run", str(job), "--no-log"], capsys, str(job), said, "save it as UTF-8")
    assert "not a text file" not in err
    (tmp_path / "bin.yaml").write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\xff\xfe")
    _refused(["run", str(tmp_path / "bin.yaml"), "--no-log"], capsys, "not a text file")


def test_a_bin_given_a_height_is_told_that_bins_stand_on_the_floor(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`position_m: [1.5, 0.0, 0.8]`, a bin on a shelf as a user would write it, was told
    only "must be a list of 2 numbers"."""
    job = tmp_path / "job.yaml"
    shelf = BIN.replace("[1.50, 0.00]", "[1.50, 0.00, 0.80]")
    job.write_text(f"bins:\n{shelf}items:\n{ITEM}")
    _refused(
        ["run", str(job), "--no-log"],
        capsys,
        "line 2, bins[0].position_m: must be a list of 2 numbers",
        "on the floor",
        "rim_height_m",
    )


def test_the_results_table_keeps_its_columns_with_wide_or_long_names(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Bins named `箱📦` (four columns on a terminal in two characters) and
    `outbound_chute_north` (20 characters, over the column's 9) shifted every column after
    them in `cell run`'s table. Each row's `error` figure now ends in the header's column,
    as wcwidth (a separate implementation of the terminal's widths) counts them."""
    from wcwidth import wcswidth

    job = tmp_path / "job.yaml"
    job.write_text(
        "bins:\n"
        '  - {id: "箱📦", position_m: [0.55, 0.35], size_m: [0.30, 0.30], rim_height_m: 0.12}\n'
        "  - {id: outbound_chute_north, position_m: [1.50, 0.00], size_m: [0.30, 0.30],"
        " rim_height_m: 0.15}\n"
        "items:\n"
        '  - {object: cube50, bin: "箱📦"}\n'
        "  - {object: cube50, bin: outbound_chute_north}\n",
        encoding="utf-8",
    )
    assert cell_exit(["run", str(job), "--no-log", "-q"]) == 0
    out = capsys.readouterr().out.splitlines()
    head = next(i for i, line in enumerate(out) if line.startswith("item "))
    rows = out[head + 1 : head + 3]
    assert "箱📦" in rows[0] and "outbound_chute_north" in rows[1], out

    def end_of(line: str, word: str) -> int:
        """The terminal column just after the first `word` of `line`."""
        k = line.index(word) + len(word)
        return wcswidth(line[:k])

    error_end = end_of(out[head], "error")
    for row in rows:
        figures = [w for w in row.split() if w.replace(".", "").isdigit()]
        error = f"{figures[1]} m"  # the item's index, then its landing error
        assert end_of(row, error) == error_end, out


def _vacuum_range_m(speed_mps: float, drop_m: float) -> float:
    """The farthest a point thrown at `speed_mps` lands `drop_m` below its release, without
    drag (closed form, the best elevation searched on a 0.1° grid): drag only shortens it."""
    g = 9.81
    best = 0.0
    for k in range(-900, 901):
        th = math.radians(k / 10)
        vx, vz = speed_mps * math.cos(th), speed_mps * math.sin(th)
        best = max(best, vx * (vz + math.sqrt(vz * vz + 2 * g * drop_m)) / g)
    return best


@pytest.mark.parametrize(
    "platform,release_z_m",
    [("platform: drone, drone: {hover_height_m: 2.0}", 1.75), ("platform: mobile", 0.9)],
)
def test_a_bin_beyond_the_drones_or_the_bases_throws_is_refused_with_the_job(
    platform: str, release_z_m: float, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A bin 6 m out for the drone or the moving base ran, and its items failed
    `unreachable` one by one in the run; the arm's jobs are refused for that before
    anything moves, now the drone's and the moving base's too, by the plan the run makes
    (the line, the bin, the reach said). Independently: the cube's fastest launch (the
    longest stroke, the model's launch speed) thrown without drag from the highest release
    lands short of 5 m. A job of the reachable bin alone runs."""
    from cell.catalogue import get_object
    from cell.model import ThrowBatch, predict_landing
    from cell.params import load_params, scene_params_path

    away = "  - {id: away, position_m: [6.00, 0.00], size_m: [0.40, 0.40], rim_height_m: 0.15}\n"
    head = f"cell: {{robot: panda, {platform}}}\nbins:\n"
    job = tmp_path / "job.yaml"
    job.write_text(head + BIN + away + "items:\n  - {object: cube50, bin: away}\n" + ITEM)
    ee = load_params(scene_params_path()).ee
    batch = ThrowBatch.single(
        get_object("cube50"),
        stroke=ee.stroke_max,
        position=(0.0, 0.0, release_z_m),
        elevation=0.0,
        azimuth=0.0,
        base_velocity=(0.0, 0.0, 0.0),
        land_z=0.15,
    )
    speed = float(np.linalg.norm(predict_landing(batch, ee).launch_velocity[0]))
    base = 1.5 if "mobile" in platform else 0.0  # the base's speed bound (docs/jobs.md)
    assert _vacuum_range_m(speed + base, release_z_m - 0.15) < 5.0
    err = _refused(["run", str(job), "--no-log", "-q"], capsys, "line 6", "bin 'away'")
    assert "out of reach" in err and "line 7" not in err, err
    job.write_text(head + BIN + "items:\n" + ITEM)
    assert cell_exit(["run", str(job), "--no-log", "-q"]) == 0


XARM7_MOUNT = """\
arm: xarm7
arm_joints: [joint1, joint2, joint3, joint4, joint5, joint6, joint7]
arm_urdf: xarm_description/urdf/xarm7.urdf
flange: link7
end_effector: throwing_ee/throwing_ee.urdf
mount_xyz: [0.0, 0.0, 0.0]
mount_rpy: [0.0, 0.0, 0.0]
acceleration_limits: [8.0, 8.0, 8.0, 10.0, 10.0, 12.0, 12.0]
jerk_limits: [800.0, 800.0, 800.0, 1000.0, 1000.0, 1200.0, 1200.0]
home: {home}
"""


def test_a_home_with_the_grip_under_the_floor_is_refused_by_field(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An xArm7 (example-robot-data; no shipped mount) whose home, within every joint's
    limits, folds the arm under the floor: the job ran from there (the arm is kinematic).
    Independently of cell's kinematics, Pinocchio's model of the unmodified URDF puts the
    flange 0.14 m under the floor with the tool axis (the flange's +z, along which the
    end-effector's TCP lies) pointing down, so the TCP is lower still. The home the
    docs' `cell reach` solves (grip down 0.3 m high in front) runs."""
    import pinocchio as pin

    from cell.robot.paths import example_robot_data_dir

    bad = [0.0, 1.2, 0.0, 1.2, 0.0, 0.8, 0.0]
    model = pin.buildModelFromUrdf(
        str(example_robot_data_dir() / "xarm_description/urdf/xarm7.urdf")
    )
    data = model.createData()
    pin.forwardKinematics(model, data, np.array(bad))
    pin.updateFramePlacements(model, data)
    flange = data.oMf[model.getFrameId("link7")]
    assert flange.translation[2] < -0.1 and flange.rotation[2, 2] < -0.5

    mount = tmp_path / "arm" / "mount.yaml"
    mount.parent.mkdir()
    mount.write_text(XARM7_MOUNT.format(home=bad))
    job = tmp_path / "job.yaml"
    job.write_text(f"cell: {{mount: arm/mount.yaml}}\nbins:\n{BIN}items:\n{ITEM}")
    _refused(
        ["run", str(job), "--no-log", "-q"],
        capsys,
        "line 1, cell.mount",
        "field 'home'",
        "under the floor",
    )
    mount.write_text(XARM7_MOUNT.format(home=[0.0, -0.0983, 0.0, 1.188, 0.0, 1.2862, 0.0]))
    assert cell_exit(["run", str(job), "--no-log", "-q"]) == 0


@pytest.mark.parametrize(
    "command,obj,flag,said",
    [
        (["throw"], ["cube", "0.0001", "0.05", "0.05", "0.05"], "--mass", "lighter than the air"),
        (["throw"], ["cube", "50", "0.01", "0.01", "0.01"], "--mass", "denser than any solid"),
        (["throw"], ["sphere", "0.05", "0.05", "0.06", "0.07"], "--size", "a sphere's three"),
        (
            ["plan", "--target", "1", "0", "0.1"],
            ["cylinder", "0.05", "0.03", "0.05", "0.1"],
            "--size",
            "a cylinder's x and y",
        ),
    ],
)
def test_an_ad_hoc_object_no_job_would_take_is_refused_by_throw_and_plan(
    command: list[str],
    obj: list[str],
    flag: str,
    said: str,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """`cell throw --shape cube --mass 0.0001 --size 0.05 0.05 0.05` (0.8 kg/m³, lighter than
    air) printed a launch at 79.7 m/s landing 1.02 m out; a sphere 50 by 60 by 70 mm was
    thrown as one. A job (and a throw log) refuses each: the two commands now do too.
    Independently: the density by hand, against air's 1.2 kg/m³ and osmium's 22,590."""
    shape, mass, *size = obj
    density = float(mass) / math.prod(float(s) for s in size)
    if "air" in said:
        assert density < 1.2
    if "solid" in said:
        assert density > 22_590
    argv = [*command, "--shape", shape, "--mass", mass, "--size", *size]
    _refused(argv, capsys, flag, said)
    # a 30 g sphere of 40 mm (the catalogue's sphere40 is 40 mm) is thrown as before
    assert cell_exit(["throw", "--shape", "sphere", "--mass", "0.03", "--size", *["0.04"] * 3]) == 0


def test_bins_whose_ids_look_alike_are_warned_of_and_an_items_bin_told_apart(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`near` and `ｎear` (a full-width n, as an input method types it) were two bins without
    a word; an item sent to `ｎear` in a job whose one bin is `near` was told "choose one of
    near", the same text to the eye. Independently: NFC (the id check's) keeps them apart,
    NFKC makes them one."""
    import unicodedata

    fw = "\uff4eear"
    assert unicodedata.normalize("NFC", fw) != "near" == unicodedata.normalize("NFKC", fw)
    job = tmp_path / "job.yaml"
    near = "  - {id: near, position_m: [0.55, 0.35], size_m: [0.30, 0.30], rim_height_m: 0.12}\n"
    job.write_text(
        f"bins:\n{near}{BIN.replace('far', fw)}items:\n  - {{object: cube50, bin: {fw}}}\n",
        encoding="utf-8",
    )
    from cell.jobs import load_job

    (warning,) = [w for w in load_job(job).warnings if "look alike" in w]
    assert "'near'" in warning and f"'{fw}'" in warning and "U+FF4E" in warning
    job.write_text(f"bins:\n{near}items:\n  - {{object: cube50, bin: {fw}}}\n", encoding="utf-8")
    _refused(["run", str(job), "--no-log"], capsys, "line 4, items[0].bin", "U+FF4E")


@pytest.mark.parametrize("platform", ["drone", "mobile"])
def test_the_drone_or_the_base_refuses_a_place_policy_and_an_item_the_pads_cannot_hold(
    platform: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """On the drone, `policy: place` was ignored (every item thrown, the summary "placed 0")
    and a 2 kg 100 mm cube, which the arm's job refuses (the pads hold under 0.5 kg at that
    width), was thrown into its bin. Both refused now, the cube by its line with why (the
    same rule as the arm's, `grip_refusal`, the judge here)."""
    from cell.arm.grip_limits import grip_refusal
    from cell.model import ObjectParams
    from cell.params import load_params, scene_params_path

    heavy = "  - {shape: cube, mass_kg: 2.0, size_m: [0.1, 0.1, 0.1], bin: far}\n"
    why = grip_refusal(load_params(scene_params_path()), ObjectParams("cube", 2.0, (0.1,) * 3))
    assert why
    job = tmp_path / "job.yaml"
    head = f"cell: {{robot: panda, platform: {platform}}}\nbins:\n{BIN}items:\n{ITEM}"
    job.write_text(head + "policy: place\n")
    _refused(["run", str(job), "--no-log", "-q"], capsys, "policy", "place")
    job.write_text(head + heavy)
    err = _refused(["run", str(job), "--no-log", "-q"], capsys, "line 6", why)
    assert "line 5" not in err, err  # the catalogue cube50 is held
