"""Arms of example-robot-data the cell ships no mount for, each from a mount file written
from its URDF alone (docs/arms.md): what went wrong on them, fixed.

- TALOS' URDF writes its meshes `package:///example-robot-data/...`: the composite kept
  them, and PyBullet refused the whole file ("Cannot load URDF file", a traceback).
- A mesh that is not a file is refused at load naming its link.
- The Unitree Z1's grip points down only low (its joint 4 turns ±87°): the job check
  passed a tote it tested 5 cm over the rim, and every place into it failed (`ik`).
- Baxter's left arm hangs from the torso, not from the URDF's root: the scene puts the
  grip where the planner's model does.

Independent checks: PyBullet's own loader; the run's outcome in the scene; PyBullet's
kinematics against Pinocchio's.
"""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from cell.errors import InvalidParameter, JobError
from cell.jobcheck import OVER_RIM_M, STROKE_RANGE_M, _reaches, _tcp_z
from cell.jobs import load_job, parse_job
from cell.robot import paths
from cell.robot.composite import composite_urdf, composite_urdf_text
from cell.robot.model import load_robot
from cell.robot.paths import example_robot_data_dir

pybullet = pytest.importorskip("pybullet")

TALOS = """\
arm: talos_left
arm_joints: [torso_1_joint, torso_2_joint, arm_left_1_joint, arm_left_2_joint, arm_left_3_joint,
             arm_left_4_joint, arm_left_5_joint, arm_left_6_joint, arm_left_7_joint]
arm_urdf: talos_data/robots/talos_full_v2.urdf
flange: arm_left_7_link
end_effector: throwing_ee/throwing_ee.urdf
mount_xyz: [0.0, 0.0, -0.051]
mount_rpy: [3.141592653589793, 0.0, 0.0]
acceleration_limits: [2.0, 2.0, 3.0, 3.0, 3.0, 3.0, 5.0, 5.0, 5.0]
jerk_limits: [200.0, 200.0, 300.0, 300.0, 300.0, 300.0, 500.0, 500.0, 500.0]
home: [-0.2385, -0.2073, -0.5695, 1.7815, -0.4217, -1.4928, 0.2960, -1.37, -0.0462]
"""

Z1 = """\
arm: z1
arm_joints: [joint1, joint2, joint3, joint4, joint5, joint6]
arm_urdf: z1_description/urdf/z1.urdf
flange: link06
end_effector: throwing_ee/throwing_ee.urdf
mount_xyz: [0.051, 0.0, 0.0]
mount_rpy: [0.0, 1.5707963267948966, 0.0]
acceleration_limits: [10.0, 10.0, 10.0, 15.0, 15.0, 15.0]
jerk_limits: [1000.0, 1000.0, 1000.0, 1500.0, 1500.0, 1500.0]
home: [0.0, 1.863, -1.376, 1.113, 0.0, 0.0]
"""

# a tote whose near corner the Z1's grip reaches pointing down 5 cm over the rim (the
# pose the check tested), though not as high as a place carries the item over it
Z1_JOB = """\
cell: {mount: z1/mount.yaml, ee: pybullet}
pick_station: {position_m: [0.30, -0.15, 0.05]}
bins:
  - {id: tote_a, position_m: [0.28, 0.32], size_m: [0.20, 0.20], rim_height_m: 0.10}
items:
  - {object: cuboid_c, bin: tote_a}
policy: POLICY
seed: 0
limits: {place_reach_m: 0.45, item_time_limit_s: 20}
"""

BAXTER = """\
arm: baxter_left
arm_joints: [left_s0, left_s1, left_e0, left_e1, left_w0, left_w1, left_w2]
arm_urdf: baxter_description/urdf/baxter.urdf
flange: left_hand_link
end_effector: throwing_ee/throwing_ee.urdf
mount_xyz: [0.0, 0.0, 0.0]
mount_rpy: [0.0, 0.0, 0.0]
acceleration_limits: [3.0, 3.0, 3.0, 3.0, 6.0, 6.0, 6.0]
jerk_limits: [300.0, 300.0, 300.0, 300.0, 600.0, 600.0, 600.0]
home: [-0.4940, -1.3736, -0.2722, 1.8252, 0.0584, 1.1269, 0.0]
"""


def _mount(tmp_path: Path, text: str, folder: str) -> Path:
    p = tmp_path / folder / "mount.yaml"
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(text)
    return p


def test_talos_meshes_written_with_three_slashes_load_in_pybullet(tmp_path: Path) -> None:
    mount = _mount(tmp_path, TALOS, "talos")
    text = composite_urdf_text(str(mount))
    assert "package://" not in text
    cl = pybullet.connect(pybullet.DIRECT)
    try:  # PyBullet's own loader: every mesh found, the file accepted
        body = pybullet.loadURDF(
            str(composite_urdf(str(mount))), useFixedBase=True, physicsClientId=cl
        )
        assert pybullet.getNumJoints(body, physicsClientId=cl) > 9
    finally:
        pybullet.disconnect(cl)


def test_a_mesh_that_is_not_a_file_is_refused_naming_its_link(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The Z1's URDF in an example-robot-data folder without its meshes."""
    erd = tmp_path / "share" / "example-robot-data" / "robots"
    (erd / "panda_description").mkdir(parents=True)
    (erd / "z1_description" / "urdf").mkdir(parents=True)
    shutil.copy(
        example_robot_data_dir() / "z1_description/urdf/z1.urdf", erd / "z1_description/urdf"
    )
    monkeypatch.setenv(paths.ERD_ENV, str(erd))
    mount = _mount(tmp_path, Z1, "z1")
    paths.example_robot_data_dir.cache_clear()
    try:
        with pytest.raises(InvalidParameter) as err:
            composite_urdf_text(str(mount))
    finally:
        monkeypatch.delenv(paths.ERD_ENV)
        paths.example_robot_data_dir.cache_clear()
    msg = str(err.value)
    assert "field 'arm_urdf': link 'link00'" in msg
    assert "package://example-robot-data/robots/z1_description/meshes/" in msg
    assert "not a file at " + str(erd / "z1_description") in msg


def test_a_place_the_z1_cannot_make_is_found_before_the_run(tmp_path: Path) -> None:
    mount = _mount(tmp_path, Z1, "z1")
    robot = load_robot(str(mount))
    # the pose the check tested before: the near corner, 5 cm over the rim, is reached
    tall = 0.07  # cuboid_c's height [m]
    old = _tcp_z(0.10 + OVER_RIM_M + tall / 2, STROKE_RANGE_M[0], tall)
    assert _reaches(robot, np.array([0.21, 0.25, old])) == 0.0
    job = tmp_path / "job.yaml"
    job.write_text(Z1_JOB.replace("POLICY", "auto"))
    (warning,) = load_job(job).warnings
    assert "cannot place into bin 'tote_a'" in warning
    # the grip points down at that height nearer the base, not as far out as the spot: the
    # reach the message gives is reached and the spot lies beyond it
    said = re.search(
        r"spot nearest the base, \((\S+), (\S+)\) m .* TCP at \(\S+, \S+, (\S+)\) m, is out of "
        r"reach \(missed by \d+ mm; the arm's grip pointing down reaches about ([\d.]+) m out at "
        r"that height\): under policy auto its items are thrown",
        warning,
    )
    assert said, warning
    x, y, z, reach = (float(v) for v in said.groups())
    assert 0.15 < reach < math.hypot(x, y) and "move the bin closer" in warning
    u = np.array([x, y]) / math.hypot(x, y)
    assert _reaches(robot, np.array([*(u * (reach - 0.01)), z])) == 0.0
    assert load_job(job).thrown_bins == frozenset({"tote_a"})
    job.write_text(Z1_JOB.replace("POLICY", "place"))
    with pytest.raises(JobError, match="cannot place into bin 'tote_a'"):
        load_job(job)


def test_the_place_the_check_warns_of_fails_in_the_scene(tmp_path: Path) -> None:
    """The run's own outcome, the check's independent witness: placed (the job loaded
    without the check, which has `auto` throw into the bin), the item fails (`ik`), and
    the failure is recorded."""
    from cell.orchestrator import Orchestrator

    _mount(tmp_path, Z1, "z1")
    job = tmp_path / "job.yaml"
    job.write_text(Z1_JOB.replace("POLICY", "auto"))
    unchecked = parse_job(job.read_text(), str(job), check_reach=False)
    assert unchecked.thrown_bins == frozenset()
    orch = Orchestrator(unchecked)
    try:
        s = orch.run()
    finally:
        orch.close()
    assert [(r.bin_id, r.failure) for r in s.results] == [("", "ik")]


def test_baxters_left_arm_off_the_root_is_where_the_planner_puts_it(tmp_path: Path) -> None:
    from cell.sim import EE_TO_TCP_M, CellScene

    mount = str(_mount(tmp_path, BAXTER, "baxter"))
    rb = load_robot(mount)
    with CellScene(mount) as sc:
        for q in rb.random_configuration(np.random.default_rng(7), 10):
            sc.set_arm(q, teleport=True)
            p, r = sc.ee_pose()
            assert np.linalg.norm(p + r[:, 2] * EE_TO_TCP_M - rb.tcp_pose(q)[0]) < 1e-4
    # the first joint off the root, as the URDF's fixed joints put it: the arm mount
    # (0.024645, 0.219645, 0.118588) m turned 45°, then left_s0's (0.055695, 0, 0.011038) m
    c = np.sqrt(0.5)
    s1 = np.array([0.024645 + 0.055695 * c, 0.219645 + 0.055695 * c, 0.118588 + 0.011038])
    np.testing.assert_allclose(rb.model.jointPlacements[1].translation, s1, atol=1e-4)


def test_an_elevation_just_past_vertical_is_told_apart_from_the_bound(capsys) -> None:
    """docs/arms.md's check gave `--elevation -1.5708`: refused as "outside the valid
    range -1.5708 … 1.5708", the value and the bound printed alike (-π/2 = -1.5707963)."""
    from cell.cli import main

    assert (
        main(["reach", "--robot", "ur5", "--at", "0.4", "0", "0.3", "--elevation", "-1.5708"]) == 2
    )
    err = capsys.readouterr().err
    assert "-1.5708: outside the valid range -1.570796 … 1.570796 rad" in err
    assert main(["reach", "--robot", "ur5", "--at", "0.4", "0", "0.3", "--elevation", "1.6"]) == 2
    assert "1.6: outside the valid range -1.5708 … 1.5708 rad" in capsys.readouterr().err
    arms_md = (Path(__file__).resolve().parents[1] / "docs" / "arms.md").read_text()
    assert "--elevation -1.5708 " not in arms_md


def test_cell_job_random_takes_a_mount_files_path(tmp_path: Path, capsys) -> None:
    """docs/arms.md: `cell job random --robot` takes an arm; a mount file's path was
    refused as "not an arm under robots/ ... or give cell.mount", a field of a job the
    command writes itself."""
    from cell.cli import main

    mount = _mount(tmp_path, BAXTER, "baxter")
    out = tmp_path / "out" / "random3.yaml"
    out.parent.mkdir()
    assert main(["job", "random", "--seed", "3", "--robot", str(mount), "-o", str(out)]) == 0
    job = load_job(out)  # written in another folder: the mount named by its absolute path
    assert f"mount: {mount.resolve()}" in out.read_text()
    assert job.robot == str(mount.resolve())
    # an arm that does not reach the random layouts' one station: said so
    z1 = _mount(tmp_path, Z1, "z1")
    capsys.readouterr()
    assert main(["job", "random", "--seed", "3", "--robot", str(z1)]) == 2
    err = capsys.readouterr().err
    assert "the z1 arm does not reach the pick station" in err
    assert "every random layout has its pick station at (0.45, -0.4) m" in err


SO100 = """\
arm: so100
arm_joints: [shoulder_pan, shoulder_lift, elbow_flex, wrist_flex, wrist_roll]
arm_urdf: so_arm_description/urdf/so100.urdf
flange: gripper
end_effector: throwing_ee/throwing_ee.urdf
mount_xyz: [0.0, 0.0, 0.0]
mount_rpy: [1.5707963267948966, 0.0, 0.0]
acceleration_limits: [5.0, 5.0, 5.0, 5.0, 5.0]
jerk_limits: [500.0, 500.0, 500.0, 500.0, 500.0]
home: [1.863, 1.492, -1.376, 1.113, 0.0]
"""

SO100_JOB = """\
cell: {mount: so100/mount.yaml, ee: pybullet}
pick_station: {position_m: [0.17, -0.05, 0.0]}
bins:
  - {id: chute_1, position_m: [0.70, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}
items:
  - {object: cube30, bin: chute_1}
policy: throw
seed: 0
"""


def test_a_five_joint_arm_loads_and_its_missed_throw_names_the_release_box(
    tmp_path: Path,
) -> None:
    """The SO-ARM100: five joints suffice for a pose of position and axis, roll free
    (accepted, its grip pointing down solved); no release of the cell's box is within its
    reach, and the failure says so rather than naming one pose as if it were the release."""
    from cell.orchestrator import Orchestrator
    from cell.robot import ik

    mount = _mount(tmp_path, SO100, "so100")
    rb = load_robot(str(mount))
    assert rb.dof == 5
    down = np.array([0.15, 0.0, 0.05])
    q = ik.solve_ik(rb, ik.ReleasePose(down, np.array([0.0, 0.0, -1.0]))).q
    p, r = rb.tcp_pose(q)  # the forward kinematics: the pose is reached
    assert np.linalg.norm(p - down) < 1e-3 and r[2, 2] < -0.999
    job = tmp_path / "job.yaml"
    job.write_text(SO100_JOB)
    orch = Orchestrator(load_job(job))
    try:
        (res,) = orch.run().results
    finally:
        orch.close()
    assert res.failure == "ik"
    assert "no release with the grip in the cell's release box, x 0.2 to 0.6, y -0.4 to 0.4" in (
        res.reason
    )


TIAGO_HELD = """\
arm: tiago_held
arm_joints: [arm_1_joint, arm_2_joint, arm_3_joint, arm_4_joint, arm_5_joint, arm_6_joint,
             arm_7_joint]
arm_urdf: tiago_description/robots/tiago.urdf
flange: arm_tool_link
end_effector: throwing_ee/throwing_ee.urdf
mount_xyz: [0.0, 0.0, 0.0]
mount_rpy: [0.0, 1.5707963267948966, 0.0]
acceleration_limits: [3.0, 3.0, 5.0, 5.0, 5.0, 5.0, 5.0]
jerk_limits: [300.0, 300.0, 500.0, 500.0, 500.0, 500.0, 500.0]
home: [1.0460, 0.1875, -0.0866, 1.6026, -2.0717, 0.1778, 0.0]
held_joints: {torso_lift_joint: 0.1}
"""


def test_a_torso_lift_held_still_is_where_the_urdf_puts_it(tmp_path: Path) -> None:
    """TIAGo's arm with `held_joints: {torso_lift_joint: 0.1}`: the planner's flange is
    where Pinocchio's model of the whole URDF puts it with the lift at 0.1 m (every other
    joint at zero), and the scene's grip where the planner's is."""
    import pinocchio as pin

    from cell.sim import EE_TO_TCP_M, CellScene

    mount = str(_mount(tmp_path, TIAGO_HELD, "tiago"))
    rb = load_robot(mount)
    assert rb.dof == 7
    full = pin.buildModelFromUrdf(
        str(example_robot_data_dir() / "tiago_description/robots/tiago.urdf")
    )
    data = full.createData()
    fid = rb.model.getFrameId("arm_tool_link")
    for q in rb.random_configuration(np.random.default_rng(3), 5):
        x = pin.neutral(full)
        x[full.joints[full.getJointId("torso_lift_joint")].idx_q] = 0.1
        for k, name in enumerate(rb.spec.arm_joints):
            x[full.joints[full.getJointId(name)].idx_q] = q[k]
        pin.framesForwardKinematics(full, data, x)
        pin.framesForwardKinematics(rb.model, rb.data, q)
        np.testing.assert_allclose(
            rb.data.oMf[fid].homogeneous,
            data.oMf[full.getFrameId("arm_tool_link")].homogeneous,
            atol=1e-9,
        )
    with CellScene(mount) as sc:
        for q in rb.random_configuration(np.random.default_rng(7), 5):
            sc.set_arm(q, teleport=True)
            p, r = sc.ee_pose()
            assert np.linalg.norm(p + r[:, 2] * EE_TO_TCP_M - rb.tcp_pose(q)[0]) < 1e-4


@pytest.mark.parametrize(
    ("held", "says"),
    [
        ("{arm_1_joint: 0.1}", "field 'held_joints': ['arm_1_joint'] are arm joints too"),
        ("{torso_lift: 0.1}", "field 'held_joints': ['torso_lift'] are not movable joints"),
        ("{torso_lift_joint: 0.5}", "field 'held_joints': 0.5 for torso_lift_joint is outside"),
        ("[torso_lift_joint]", "field 'held_joints' must map joint names to positions"),
        ("{torso_lift_joint: .nan}", "field 'held_joints' must map joint names to positions"),
    ],
)
def test_a_wrong_held_joint_is_refused_by_name(tmp_path: Path, held: str, says: str) -> None:
    text = TIAGO_HELD.replace("{torso_lift_joint: 0.1}", held)
    mount = _mount(tmp_path, text, "tiago")
    with pytest.raises(InvalidParameter, match=re.escape(says)):
        composite_urdf_text(str(mount))


def test_without_held_joints_the_torso_lift_is_named(tmp_path: Path) -> None:
    text = TIAGO_HELD.replace("held_joints: {torso_lift_joint: 0.1}\n", "")
    mount = _mount(tmp_path, text, "tiago")
    with pytest.raises(InvalidParameter, match=r"are \['torso_lift_joint', 'arm_1_joint'"):
        composite_urdf_text(str(mount))
