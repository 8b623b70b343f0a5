"""Inputs written by hand as a new user would, an eighth round: an arm of the user's own
whose tool only points down (a SCARA), a throw-log store in a read-only folder, two YAML
documents in one file, a YAML merge key, one item whose box is larger than its bin."""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import cell
from cell.errors import InvalidInput, JobError
from cell.jobs import parse_job
from tests.cli_exit import cell_exit

ROOT = Path(cell.__file__).resolve().parents[1]
BIN = "  - {id: far, position_m: [1.50, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}\n"
ITEM = "  - {object: cube50, bin: far}\n"
JOB = f"cell: {{robot: panda}}\nbins:\n{BIN}items:\n{ITEM}"

_INERTIA = '<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>'


def _link(name: str, mass: float) -> str:
    return f'<link name="{name}"><inertial><mass value="{mass}"/>{_INERTIA}</inertial></link>'


def _joint(
    name: str, kind: str, parent: str, child: str, xyz: str, lim: str, rpy: str = "0 0 0"
) -> str:
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="0 0 1"/><limit {lim} effort="100"/></joint>'
    )


def _scara(folder: Path) -> Path:
    """A SCARA of the user's own, in a folder of theirs: two joints turning about the
    vertical, a prismatic quill, a roll about the quill, its flange turned to face down;
    its mount file names the URDF by its absolute path."""
    parts = [
        _link("base_link", 10.0),
        _link("link1", 4.0),
        _link("link2", 3.0),
        _link("quill", 1.0),
        _link("flange", 0.2),
        _joint(
            "j1",
            "revolute",
            "base_link",
            "link1",
            "0 0 0.6",
            'lower="-2.6" upper="2.6" velocity="3"',
        ),
        _joint(
            "j2", "revolute", "link1", "link2", "0.5 0 0", 'lower="-2.6" upper="2.6" velocity="3"'
        ),
        _joint(
            "j3", "prismatic", "link2", "quill", "0.4 0 0", 'lower="-0.58" upper="0" velocity="1"'
        ),
        _joint(
            "j4",
            "revolute",
            "quill",
            "flange",
            "0 0 0",
            'lower="-3" upper="3" velocity="5"',
            rpy="3.14159265359 0 0",
        ),
    ]
    urdf = folder / "scara.urdf"
    urdf.write_text(
        '<?xml version="1.0"?>\n<robot name="my_scara">' + "".join(parts) + "</robot>\n"
    )
    mount = folder / "mount.yaml"
    mount.write_text(
        f"arm: my_scara\narm_urdf: {urdf}\narm_joints: [j1, j2, j3, j4]\nflange: flange\n"
        "end_effector: throwing_ee/throwing_ee.urdf\nmount_xyz: [0, 0, 0]\nmount_rpy: [0, 0, 0]\n"
        "acceleration_limits: [10, 10, 5, 20]\njerk_limits: [1000, 1000, 500, 2000]\n"
        "home: [0.5, -1.0, -0.1, 0.0]\n"
    )
    return urdf


def test_an_arm_whose_tool_only_points_down_is_refused_where_its_job_throws(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The SCARA's throw axis points straight down in every configuration (Pinocchio's
    model of its URDF, the judge), and a throw leaves with it level or up: a job throwing
    with it ran, every item failing `ik` one by one (exit 4); it is refused at load, naming
    the bins thrown into. A job that only places loads."""
    import pinocchio as pin

    urdf = _scara(tmp_path)
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    fid = model.getFrameId("flange")
    rng = np.random.default_rng(1000)
    for _ in range(50):
        q = rng.uniform(model.lowerPositionLimit, model.upperPositionLimit)
        pin.framesForwardKinematics(model, data, q)
        assert data.oMf[fid].rotation[2, 2] == pytest.approx(-1.0, abs=1e-9)

    tote = "  - {id: tote, position_m: [0.55, 0.30], size_m: [0.30, 0.30], rim_height_m: 0.12}\n"
    job = tmp_path / "job.yaml"
    job.write_text(
        f"cell: {{mount: mount.yaml}}\nbins:\n{tote}{BIN}items:\n"
        "  - {object: cube50, bin: tote}\n" + ITEM
    )
    code = cell_exit(["run", str(job), "--no-log", "-q"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err
    assert "the my_scara arm cannot throw" in err and "points at most -90°" in err
    assert "'far' (" in err and "line 4" in err and "'tote'" not in err  # the tote is placed

    placing = parse_job(
        f"cell: {{mount: mount.yaml}}\nbins:\n{tote}items:\n  - {{object: cube50, bin: tote}}\n",
        str(job),
    )
    assert placing.thrown_bins == frozenset()


def test_the_shipped_arms_tilt_their_tool_up() -> None:
    """Every arm under robots/ turns its throw axis well above level (the refusal above
    leaves their jobs alone)."""
    from cell.jobtilt import highest_axis_rad
    from cell.robot.model import load_robot
    from cell.robot.mount import robot_names

    for name in robot_names():
        assert highest_axis_rad(load_robot(name)) > math.radians(60), name


def _in_read_only_folder(folder: Path, argv: list[str]) -> subprocess.CompletedProcess[str]:
    """`python -m cell argv` with `folder` read-only: a read-only bind mount of it in a
    mount namespace of its own where the user is root (root writes through permissions),
    else the folder's permissions."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "cell", *argv]
    if os.geteuid() != 0:
        folder.chmod(0o555)
        try:
            return subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=300)
        finally:
            folder.chmod(0o755)
    if shutil.which("unshare") is None:
        pytest.skip("root without unshare: no read-only folder to write into")
    script = (
        f'mount --bind "{folder}" "{folder}" && mount -o remount,bind,ro "{folder}" && exec "$@"'
    )
    p = subprocess.run(
        ["unshare", "-m", "sh", "-c", script, "sh", *cmd],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    if "mount:" in p.stderr or "unshare:" in p.stderr:
        pytest.skip(f"no mount namespace here: {p.stderr.strip()}")
    return p


def test_a_store_in_a_read_only_folder_says_why(tmp_path: Path) -> None:
    """`--db` in a folder that cannot be written: the store (WAL mode) needs its folder for
    its -wal and -shm files, whether it exists or not. Refused before the run, saying so
    (it said "unable to open database file")."""
    job = tmp_path / "job.yaml"
    job.write_text(JOB)
    ro = tmp_path / "ro"
    ro.mkdir()
    p = _in_read_only_folder(ro, ["run", str(job), "-q", "--db", str(ro / "log.sqlite")])
    assert p.returncode == 2, p.stderr
    assert "Traceback" not in p.stderr
    assert f"{ro / 'log.sqlite'}: cannot write the throw-log store" in p.stderr
    assert "read-only file system" in p.stderr or "is not writable" in p.stderr
    assert "give --db a file in a writable folder" in p.stderr
    assert not (ro / "log.sqlite").exists()


def test_two_yaml_documents_are_refused_by_line(tmp_path: Path) -> None:
    """A job of two documents (`---` between two jobs) was refused with PyYAML's message
    over six lines, naming "<unicode string>"; a parameter file alike. Now one line: the
    file, the line the second starts on. One document between `---` and `...` loads."""
    with pytest.raises(JobError) as exc:
        parse_job(JOB + "---\n" + JOB, "two.yaml")
    msg = str(exc.value)
    assert msg.startswith("two.yaml, line 6: a second YAML document starts here")
    assert "\n" not in msg and "unicode string" not in msg
    with pytest.raises(JobError, match=r"line 6: a second YAML document"):
        parse_job(JOB + "---\n", "trailing.yaml")
    assert parse_job("---\n" + JOB + "...\n", "one.yaml").items[0].bin == "far"

    from cell.params import load_params

    params = (ROOT / "robots" / "cell_scene" / "ee_params.yaml").read_text()
    p = tmp_path / "p.yaml"
    p.write_text(params + "---\n" + params)
    with pytest.raises(InvalidInput, match=r"p.yaml, line \d+: a second YAML document"):
        load_params(p)


def test_a_merge_key_is_refused_as_such() -> None:
    """`<<: {size_m: …}` in a bin (no alias) was refused as "unknown key '<<'"; it is YAML's
    merge key, and said so; `description: <<` as "YAML tag tag:yaml.org,2002:merge is not
    allowed" (YAML reads a plain `<<` as the merge key wherever it stands). Quoted, it is
    text."""
    merged = JOB.replace(
        BIN,
        "  - <<: {size_m: [0.30, 0.30], rim_height_m: 0.15}\n    id: far\n"
        "    position_m: [1.50, 0.00]\n",
    )
    with pytest.raises(
        JobError, match=r"m.yaml, line 3: a YAML merge key \(<<, unquoted\) is not accepted"
    ):
        parse_job(merged, "m.yaml")
    with pytest.raises(JobError, match=r"line 3: a YAML merge key"):
        parse_job(merged.replace("<<:", "!!merge <<:"), "m.yaml")
    with pytest.raises(JobError, match=r"v.yaml, line 1: a YAML merge key .* quote it"):
        parse_job("description: <<\n" + JOB, "v.yaml")
    assert parse_job("description: '<<'\n" + JOB, "v.yaml").items[0].bin == "far"
    with pytest.raises(JobError, match=r"unknown key '<<'"):
        parse_job(merged.replace("<<:", '"<<":'), "q.yaml")


def test_one_item_larger_than_its_bin_is_warned_of_as_one() -> None:
    """A duck (a mesh, not refused by its box) sent alone to a 30 mm bin: the warning spoke
    of "the later ones" resting "on the others"; it now says the one item stands above the
    rim. Its box is 2.35 times the bin's inside (the catalogue's box against the bin's)."""
    job = parse_job(
        "cell: {robot: panda}\nbins:\n"
        "  - {id: cup, position_m: [1.40, 0.00], size_m: [0.03, 0.03], rim_height_m: 0.10}\n"
        "items:\n  - {object: duck, bin: cup}\n",
        "duck.yaml",
    )
    (w,) = [w for w in job.warnings if "bin 'cup' is sent" in w]
    assert "is sent 1 item whose box takes" in w and "it will stand above the rim" in w
    assert "the later ones" not in w and "split the items" not in w
    box = math.prod(job.items[0].obj.size)
    assert f"{box / (0.03 * 0.03 * 0.09):.3g} times" in w
