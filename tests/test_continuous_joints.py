"""An arm whose URDF has continuous joints (example-robot-data's Kinova Jaco j2s6s200: its
joints 1, 4 and 6) from a mount file: planned as revolute joints over ±2π
(`cell.robot.composite.CONTINUOUS_RANGE_RAD`), one angle per joint.

Independent check: Pinocchio's own model of the arm's unmodified URDF, where a continuous
joint's position is (cos θ, sin θ), puts the flange where the cell's model puts it for the
same angles; and a pose the cell's IK solves is reached in that model too.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from cell.errors import InvalidParameter
from cell.robot import ik
from cell.robot.composite import composite_urdf_text
from cell.robot.model import Robot
from cell.robot.mount import load_mount
from cell.robot.paths import example_robot_data_dir

pin = pytest.importorskip("pinocchio")

JACO = """\
arm: jaco
arm_joints: [j2s6s200_joint_1, j2s6s200_joint_2, j2s6s200_joint_3, j2s6s200_joint_4,
             j2s6s200_joint_5, j2s6s200_joint_6]
arm_urdf: kinova_description/robots/kinova.urdf
flange: j2s6s200_link_6
end_effector: throwing_ee/throwing_ee.urdf
mount_xyz: [0.0, 0.0, 0.0]
mount_rpy: [0.0, 0.0, 0.0]
acceleration_limits: [3.0, 3.0, 3.0, 5.0, 5.0, 5.0]
jerk_limits: [300.0, 300.0, 300.0, 500.0, 500.0, 500.0]
home: [1.5707, 2.618, 1.5707, 3.1415, 2.618, 0.0]
"""


@pytest.fixture(scope="module")
def jaco(tmp_path_factory: pytest.TempPathFactory) -> Path:
    p = tmp_path_factory.mktemp("jaco") / "mount.yaml"
    p.write_text(JACO)
    return p


def _flange_of_original(q: np.ndarray) -> np.ndarray:
    """The flange's pose (4 x 4, arm base frame) in Pinocchio's model of the Jaco's own
    URDF: a continuous joint as (cos θ, sin θ)."""
    m = pin.buildModelFromUrdf(
        str(example_robot_data_dir() / "kinova_description/robots/kinova.urdf")
    )
    d = m.createData()
    x = pin.neutral(m)
    for k in range(6):
        jm = m.joints[m.getJointId(f"j2s6s200_joint_{k + 1}")]
        if jm.nq == 2:
            x[jm.idx_q : jm.idx_q + 2] = (math.cos(q[k]), math.sin(q[k]))
        else:
            x[jm.idx_q] = q[k]
    pin.framesForwardKinematics(m, d, x)
    return np.asarray(d.oMf[m.getFrameId("j2s6s200_link_6")].homogeneous)


def test_continuous_joints_planned_as_revolute_over_two_turns(jaco: Path) -> None:
    text = composite_urdf_text(str(jaco))
    assert 'type="continuous"' not in text
    robot = Robot(load_mount(str(jaco)))
    assert robot.model.nq == robot.model.nv == 6
    for k in (0, 3, 5):  # the continuous ones
        assert robot.limits.lower[k] == -2 * math.pi and robot.limits.upper[k] == 2 * math.pi
    assert robot.limits.lower[1] == pytest.approx(0.820304748437)  # a revolute one kept
    assert np.all(np.isfinite(robot.limits.velocity))


def test_the_same_kinematics_as_the_arms_own_urdf(jaco: Path) -> None:
    robot = Robot(load_mount(str(jaco)))
    fid = robot.model.getFrameId("j2s6s200_link_6")
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = rng.uniform(robot.limits.lower, robot.limits.upper)
        pin.framesForwardKinematics(robot.model, robot.data, q)
        ours = np.asarray(robot.data.oMf[fid].homogeneous)
        np.testing.assert_allclose(ours, _flange_of_original(q), atol=1e-9)


def test_a_pose_solved_is_reached_in_the_original_model(jaco: Path) -> None:
    robot = Robot(load_mount(str(jaco)))
    target = np.array([0.5, -0.3, 0.25])
    sol = ik.solve_release_ik(robot, target, -math.pi / 2, 0.0, np.asarray(robot.home, float))
    tcp, rot = robot.tcp_pose(sol.q)
    assert np.linalg.norm(tcp - target) < 1e-3
    # the TCP hangs off the flange by a fixed transform: the same in both models
    fid = robot.model.getFrameId("j2s6s200_link_6")
    pin.framesForwardKinematics(robot.model, robot.data, sol.q)
    np.testing.assert_allclose(
        np.asarray(robot.data.oMf[fid].homogeneous), _flange_of_original(sol.q), atol=1e-9
    )


def test_a_continuous_joint_without_a_velocity_limit_is_refused(
    jaco: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import shutil

    from cell.robot import paths

    erd = tmp_path / "erd"
    src = example_robot_data_dir() / "kinova_description"
    shutil.copytree(src, erd / "kinova_description")
    urdf = erd / "kinova_description/robots/kinova.urdf"
    text = urdf.read_text()
    i = text.index('<joint name="j2s6s200_joint_4" type="continuous">')
    j = text.index("<limit", i)
    k = text.index("/>", j)
    urdf.write_text(text[:j] + text[k + 2 :])
    monkeypatch.setattr(paths, "example_robot_data_dir", lambda: erd)
    import cell.robot.mount_paths as mount_paths

    monkeypatch.setattr(mount_paths, "example_robot_data_dir", lambda: erd)
    with pytest.raises(InvalidParameter, match="j2s6s200_joint_4.*velocity"):
        composite_urdf_text(str(jaco))


def test_a_station_inside_the_arms_inner_gap_is_told_to_move_out(tmp_path: Path) -> None:
    """The Jaco's grip points down 0.5 m out at the station's height (above) but not
    0.40 m out 0.30 m aside (its joints 2, 3 and 5 have limits): the job is refused up
    front, the message saying farther out, not "within" a reach the station is inside."""
    from cell.errors import JobError
    from cell.jobs import load_job

    (tmp_path / "jaco").mkdir()
    (tmp_path / "jaco" / "mount.yaml").write_text(JACO)
    job = tmp_path / "job.yaml"
    job.write_text(
        "cell: {mount: jaco/mount.yaml}\n"
        "bins:\n"
        "  - {id: far, position_m: [1.40, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}\n"
        "pick_station: {position_m: [0.40, -0.30, 0.20]}\n"
        "items:\n"
        "  - {object: cube50, count: 1, bin: far}\n"
    )
    with pytest.raises(JobError) as err:
        load_job(job)
    msg = str(err.value)
    assert "pick_station.position_m" in msg and "farther out" in msg, msg
    assert "within that" not in msg
    ok = job.read_text().replace("[0.40, -0.30, 0.20]", "[0.50, -0.30, 0.20]")
    job.write_text(ok)
    assert len(load_job(job).bins) == 1  # 0.50 m out: accepted
