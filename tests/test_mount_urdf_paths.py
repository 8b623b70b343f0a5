"""A mount file's URDFs of the user's own (`cell.robot.mount_paths.arm_urdf_file`,
`end_effector_file`): `arm_urdf` and `end_effector` relative to their library folders as
the shipped arms have them, else to the mount file's folder, or absolute; the arm built from
a URDF kept beside its mount file is the arm built from the library's copy; a name that is
no file is refused naming the field and every place looked in; a run never writes over
such a URDF."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from cell.cli import main
from cell.errors import InvalidParameter
from cell.robot.model import load_robot
from cell.robot.mount import load_mount
from cell.robot.mount_paths import arm_urdf_file, end_effector_file
from cell.robot.paths import example_robot_data_dir

ROOT = Path(__file__).resolve().parents[1]
UR3 = ROOT / "robots" / "ur3_throwing" / "mount.yaml"
LIB_ARM = "ur_description/urdf/ur3_robot.urdf"  # the UR3 mount's arm_urdf
LIB_EE = "throwing_ee/throwing_ee.urdf"


def _own_ur3(tmp_path: Path, arm: str, ee: str = LIB_EE) -> Path:
    """The UR3's mount file under another arm name, its URDF fields replaced."""
    text = UR3.read_text()
    assert LIB_ARM in text and LIB_EE in text
    text = text.replace("arm: ur3", "arm: own_ur3").replace(LIB_ARM, arm).replace(LIB_EE, ee)
    p = tmp_path / "own" / "mount.yaml"
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(text)
    return p


@pytest.fixture(scope="module")
def ur3_home_tcp() -> np.ndarray:
    rb = load_robot("ur3")
    return rb.tcp_pose(np.asarray(rb.home))[0]


def test_urdfs_beside_the_mount_file_build_the_arm_the_library_copies_build(
    tmp_path: Path, ur3_home_tcp: np.ndarray
) -> None:
    # the arm's URDF (its meshes named package://example-robot-data/..., found as before)
    # and the end-effector's copied beside the mount file, named relative to it
    shutil.copy(example_robot_data_dir() / LIB_ARM, tmp_path / "own_arm.urdf")
    shutil.copy(ROOT / "robots" / LIB_EE, tmp_path / "own_ee.urdf")
    mount = _own_ur3(tmp_path, "../own_arm.urdf", "../own_ee.urdf")
    spec = load_mount(str(mount))
    assert arm_urdf_file(spec) == mount.parent / "../own_arm.urdf"
    assert end_effector_file(spec) == mount.parent / "../own_ee.urdf"
    rb = load_robot(str(mount))
    np.testing.assert_allclose(rb.tcp_pose(np.asarray(rb.home))[0], ur3_home_tcp, atol=1e-12)
    # and absolute
    mount = _own_ur3(tmp_path, str(tmp_path / "own_arm.urdf"))
    assert arm_urdf_file(load_mount(str(mount))) == tmp_path / "own_arm.urdf"


def test_the_library_folders_come_first() -> None:
    spec = load_mount("ur3")
    assert arm_urdf_file(spec) == example_robot_data_dir() / LIB_ARM
    assert end_effector_file(spec) == ROOT / "robots" / LIB_EE


@pytest.mark.parametrize("field", ["arm_urdf", "end_effector"])
def test_a_urdf_that_is_no_file_is_refused_naming_the_field_and_the_places_looked_in(
    tmp_path: Path, field: str
) -> None:
    mount = (
        _own_ur3(tmp_path, "mine/arm.urdf")
        if field == "arm_urdf"
        else _own_ur3(tmp_path, LIB_ARM, "mine/ee.urdf")
    )
    missing = "mine/arm.urdf" if field == "arm_urdf" else "mine/ee.urdf"
    with pytest.raises(InvalidParameter) as exc:
        load_robot(str(mount))
    msg = str(exc.value)
    assert f"field '{field}': '{missing}' is not a file" in msg
    assert str(mount.parent / missing) in msg  # beside the mount file
    library = example_robot_data_dir() if field == "arm_urdf" else ROOT / "robots"
    assert str(library / missing) in msg


def test_a_run_is_refused_where_its_output_is_the_arms_own_urdf(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    urdf = tmp_path / "own_arm.urdf"
    shutil.copy(example_robot_data_dir() / LIB_ARM, urdf)
    before = urdf.read_bytes()
    mount = _own_ur3(tmp_path, "../own_arm.urdf")
    job = tmp_path / "job.yaml"
    text = (ROOT / "tasks" / "bins_ur3.yaml").read_text()
    assert "robot: ur3" in text
    job.write_text(text.replace("robot: ur3", f"mount: {mount}"))
    code = main(["run", str(job), "--no-log", f"--json={urdf}"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "the arm's URDF this run reads" in err and "Traceback" not in err
    assert urdf.read_bytes() == before
