"""Every description in robots/ loads in Pinocchio and PyBullet, steps without a warning,
and both agree on where the grip centre is."""

import json
import math
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from cell.errors import InvalidInput, InvalidParameter, MissingDependency
from cell.robot import paths
from cell.robot.composite import composite_urdf, end_effector_urdf, load_mount
from cell.robot.model import EE_JOINTS, TCP_FRAME, load_robot
from cell.robot.mount import robot_names

ROBOTS_DIR = Path(__file__).resolve().parents[1] / "robots"
EE_LINKS = ("ee_base", "ee_finger_left", "ee_finger_right", "ee_band", "ee_tcp")


def all_descriptions() -> list[Path]:
    """Every URDF under robots/ and the composite of every mount."""
    return sorted(ROBOTS_DIR.rglob("*.urdf")) + [composite_urdf(r) for r in robot_names()]


def test_every_description_folder_has_a_readme():
    folders = {p.parent for p in ROBOTS_DIR.rglob("*.urdf")}
    folders |= {p.parent for p in ROBOTS_DIR.rglob("mount.yaml")}
    assert {p.name for p in folders} >= {"throwing_ee", "panda_throwing", "ur5_throwing"}
    for p in folders:
        assert (p / "README.md").is_file(), p
    assert end_effector_urdf() in all_descriptions()


def test_end_effector_names_and_geometry_are_the_interface():
    root = ET.parse(end_effector_urdf()).getroot()
    links = {lk.get("name") for lk in root.findall("link")}
    joints = {j.get("name"): j for j in root.findall("joint")}
    assert set(EE_LINKS) <= links
    assert set(EE_JOINTS) | {"ee_tcp_joint"} <= set(joints)

    def xyz(el, tag):
        return [float(v) for v in el.find(tag).get("xyz").split()]

    band = joints["ee_band_joint"]
    assert band.get("type") == "prismatic"
    assert band.find("parent").get("link") == "ee_base"
    assert xyz(band, "axis") == [0, 0, 1]
    # the stroke's zero, the plate face E, 15 mm in front of the flange
    assert xyz(band, "origin") == pytest.approx([0.0, 0.0, 0.015])
    lim = band.find("limit")
    # MODEL.md's stroke range (0.03 ... 0.11) inside the carriage's travel, whose end stop
    # (0.138) lies past the point where the band goes slack for every catalogue width.
    assert float(lim.get("lower")) == pytest.approx(0.02)
    assert float(lim.get("upper")) == pytest.approx(0.138)
    for name, axis in (("ee_finger_left_joint", [-1, 0, 0]), ("ee_finger_right_joint", [1, 0, 0])):
        pad = joints[name]
        assert pad.get("type") == "prismatic" and pad.find("parent").get("link") == "ee_band"
        assert xyz(pad, "axis") == axis
        assert [float(pad.find("limit").get(k)) for k in ("lower", "upper")] == [0.0, 0.06]
    tcp = joints["ee_tcp_joint"]
    assert tcp.get("type") == "fixed" and tcp.find("parent").get("link") == "ee_base"
    assert xyz(tcp, "origin") == pytest.approx([0.0, 0.0, 0.145])


def _box(m, s):
    x, y, z = s
    return m / 12 * np.diag([y * y + z * z, x * x + z * z, x * x + y * y])


# The README's parts: mass [kg], box [m] and its centre in the link frame [m], and where the
# link's mass sits (its inertial origin) [m].
EE_PARTS = {
    "ee_base": (0.6, (0.08, 0.06, 0.03), (0, 0, 0), (0, 0, 0.015)),
    "ee_band": (0.008, (0.04, 0.04, 0.004), (0, 0, -0.002), (0, 0, 0)),
    "ee_finger_left": (0.002, (0.004, 0.024, 0.03), (-0.002, 0, 0.015), (0, 0, 0)),
    "ee_finger_right": (0.002, (0.004, 0.024, 0.03), (0.002, 0, 0.015), (0, 0, 0)),
}


def test_end_effector_inertias_are_those_of_its_drawn_shapes():
    """Recompute every link's inertia from the shapes and masses the README lists."""
    root = ET.parse(end_effector_urdf()).getroot()
    total = 0.0
    for link in root.findall("link"):
        name = link.get("name")
        inertial = link.find("inertial")
        assert inertial is not None, name
        m_urdf = float(inertial.find("mass").get("value"))
        total += m_urdf
        if name not in EE_PARTS:
            assert m_urdf == 0.0
            continue
        m, size, centre, mass_at = EE_PARTS[name]
        assert m_urdf == pytest.approx(m, abs=1e-12), name
        # one box, drawn where it collides
        for tag in ("collision", "visual"):
            (el,) = link.findall(tag)
            assert [float(v) for v in el.find("geometry/box").get("size").split()] == list(size)
            xyz = [float(v) for v in el.find("origin").get("xyz").split()]
            np.testing.assert_allclose(xyz, centre, atol=1e-12, err_msg=name)
        xyz = [float(v) for v in inertial.find("origin").get("xyz").split()]
        np.testing.assert_allclose(xyz, mass_at, atol=1e-12, err_msg=name)
        el = inertial.find("inertia")
        got = np.array(
            [
                [float(el.get("ixx")), float(el.get("ixy")), float(el.get("ixz"))],
                [float(el.get("ixy")), float(el.get("iyy")), float(el.get("iyz"))],
                [float(el.get("ixz")), float(el.get("iyz")), float(el.get("izz"))],
            ]
        )
        np.testing.assert_allclose(got, _box(m, size), rtol=1e-4, atol=1e-12, err_msg=name)
    # housing 0.6 kg, carriage 8 g, two pads of 2 g
    assert total == pytest.approx(0.612, abs=1e-12)


@pytest.mark.parametrize("robot", robot_names())
def test_composite_has_the_arm_the_end_effector_and_no_franka_hand(robot):
    path = composite_urdf(robot)
    root = ET.parse(path).getroot()
    links = {lk.get("name") for lk in root.findall("link")}
    assert set(EE_LINKS) <= links
    assert not any(
        name.startswith("panda_hand") or "finger" in name and "ee_" not in name for name in links
    )
    mount = [j for j in root.findall("joint") if j.get("name") == "ee_mount_joint"]
    assert len(mount) == 1
    assert mount[0].find("parent").get("link") == load_mount(robot).flange
    for mesh in root.iter("mesh"):
        fn = mesh.get("filename")
        assert os.path.isabs(fn) and Path(fn).is_file(), fn
    # Generating again rewrites nothing.
    mtime = path.stat().st_mtime_ns
    assert composite_urdf(robot) == path and path.stat().st_mtime_ns == mtime


@pytest.mark.parametrize("robot,dof", [("panda", 7), ("ur5", 6)])
def test_pinocchio_model_is_reduced_to_the_arm(robot, dof):
    rb = load_robot(robot)
    assert rb.dof == dof == len(rb.home)
    assert rb.model.existFrame(TCP_FRAME)
    assert not any(j in list(rb.model.names) for j in EE_JOINTS)
    assert np.all(rb.limits.velocity > 0) and np.all(rb.limits.acceleration > 0)
    assert np.all(rb.limits.jerk > rb.limits.acceleration)


def test_tcp_jacobian_matches_finite_differences():
    import pinocchio as pin

    for robot in ("panda", "ur5"):
        rb = load_robot(robot)
        q = rb.random_configuration(np.random.default_rng(3))[0]
        jac = rb.tcp_jacobian(q)
        p0, r0 = rb.tcp_pose(q)
        h = 1e-6
        for i in range(rb.dof):
            dq = np.zeros(rb.dof)
            dq[i] = h
            p1, r1 = rb.tcp_pose(q + dq)
            np.testing.assert_allclose((p1 - p0) / h, jac[:3, i], atol=1e-5)
            np.testing.assert_allclose(pin.log3(r1 @ r0.T) / h, jac[3:, i], atol=1e-5)


_PYBULLET_SCRIPT = r"""
import json, sys
import numpy as np
import pybullet as p
out = {}
cid = p.connect(p.DIRECT)
p.setGravity(0, 0, -9.81)
p.setTimeStep(1 / 240)
for path in sys.argv[1:]:
    body = p.loadURDF(path, useFixedBase=True)
    names = {}
    for j in range(p.getNumJoints(body)):
        info = p.getJointInfo(body, j)
        names[info[12].decode()] = j
    for _ in range(240):
        p.stepSimulation()
    states = [p.getJointState(body, j)[0] for j in range(p.getNumJoints(body))]
    out[path] = {"links": names, "finite": bool(np.all(np.isfinite(states)))}
print("RESULT " + json.dumps(out))
"""


def test_every_description_loads_and_steps_in_pybullet_without_a_warning(tmp_path):
    files = [str(p) for p in all_descriptions()]
    script = tmp_path / "load.py"
    script.write_text(_PYBULLET_SCRIPT)
    proc = subprocess.run(
        [sys.executable, str(script), *files], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    lines = (proc.stdout + proc.stderr).splitlines()
    result = json.loads(next(l for l in lines if l.startswith("RESULT "))[7:])
    noise = [
        l
        for l in lines
        if l.strip() and not l.startswith("RESULT ") and not l.startswith("pybullet build time")
    ]
    assert noise == [], noise
    for f in files:
        assert result[f]["finite"]
        assert set(EE_LINKS) - {"ee_base"} <= set(result[f]["links"]) or f.endswith(
            "throwing_ee.urdf"
        )


def test_every_description_loads_in_pinocchio_without_output(tmp_path):
    script = tmp_path / "pin.py"
    script.write_text(
        "import sys, pinocchio as pin\n"
        "for f in sys.argv[1:]:\n"
        "    m = pin.buildModelFromUrdf(f)\n"
        "    assert m.existFrame('ee_tcp'), f\n"
    )
    files = [str(p) for p in all_descriptions()]
    proc = subprocess.run(
        [sys.executable, str(script), *files], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "" and proc.stderr.strip() == ""


@pytest.mark.parametrize("robot", robot_names())
def test_pybullet_and_pinocchio_agree_on_the_grip_centre(robot):
    """Two independent kinematics engines read the same composite URDF."""
    import pybullet as p

    rb = load_robot(robot)
    cid = p.connect(p.DIRECT)
    try:
        body = p.loadURDF(str(rb.urdf), useFixedBase=True, physicsClientId=cid)
        idx = {}
        for j in range(p.getNumJoints(body, physicsClientId=cid)):
            info = p.getJointInfo(body, j, physicsClientId=cid)
            idx[info[1].decode()] = j
            idx["link:" + info[12].decode()] = j
        tcp = idx["link:" + TCP_FRAME]
        rng = np.random.default_rng(7)
        for q in rb.random_configuration(rng, 20):
            for name, v in zip(rb.spec.arm_joints, q, strict=True):
                p.resetJointState(body, idx[name], float(v), physicsClientId=cid)
            st = p.getLinkState(body, tcp, computeForwardKinematics=True, physicsClientId=cid)
            pos_pb = np.array(st[4])
            rot_pb = np.array(p.getMatrixFromQuaternion(st[5])).reshape(3, 3)
            pos, rot = rb.tcp_pose(q)
            np.testing.assert_allclose(pos, pos_pb, atol=1e-6)
            np.testing.assert_allclose(rot, rot_pb, atol=1e-6)
    finally:
        p.disconnect(cid)


def test_panda_tcp_is_0145_m_past_the_flange_along_its_axis():
    import pinocchio as pin

    rb = load_robot("panda")
    q = rb.home
    pin.framesForwardKinematics(rb.model, rb.data, q)
    flange = rb.data.oMf[rb.model.getFrameId("panda_link8")]
    pos, rot = rb.tcp_pose(q)
    np.testing.assert_allclose(pos, flange.translation + 0.145 * flange.rotation[:, 2], atol=1e-9)
    np.testing.assert_allclose(rot[:, 2], flange.rotation[:, 2], atol=1e-9)
    # The fingers open along the Franka hand's finger axis: yaw -45° about the flange z.
    assert math.isclose(float(rot[:, 0] @ flange.rotation[:, 0]), math.cos(math.pi / 4))


def test_missing_example_robot_data_is_a_clear_error(monkeypatch, tmp_path):
    monkeypatch.setenv(paths.ERD_ENV, str(tmp_path))
    paths.example_robot_data_dir.cache_clear()
    try:
        with pytest.raises(MissingDependency, match="example-robot-data"):
            paths.example_robot_data_dir()
    finally:
        monkeypatch.delenv(paths.ERD_ENV)
        paths.example_robot_data_dir.cache_clear()
    assert (paths.example_robot_data_dir() / "panda_description").is_dir()


def test_missing_robots_folder_is_a_clear_error(monkeypatch, tmp_path):
    monkeypatch.setenv(paths.ROBOTS_ENV, str(tmp_path))
    paths.robots_dir.cache_clear()
    try:
        with pytest.raises(MissingDependency, match="robots/"):
            paths.robots_dir()
    finally:
        monkeypatch.delenv(paths.ROBOTS_ENV)
        paths.robots_dir.cache_clear()


def test_unknown_robot_names_the_valid_ones():
    with pytest.raises(InvalidInput, match="panda, ur10, ur3, ur5"):
        load_robot("kuka")
    with pytest.raises(InvalidInput, match="panda, ur10, ur3, ur5"):
        composite_urdf("kuka")


def test_limits_are_the_documented_ones():
    panda = load_robot("panda").limits
    # Franka Emika Panda datasheet (joints 1-7) and URDF velocity limits.
    np.testing.assert_array_equal(panda.acceleration, [15, 7.5, 10, 12.5, 15, 20, 20])
    np.testing.assert_array_equal(panda.jerk, [7500, 3750, 5000, 6250, 7500, 10000, 10000])
    np.testing.assert_array_equal(panda.velocity, [2.175] * 4 + [2.61] * 3)
    ur5 = load_robot("ur5").limits
    np.testing.assert_allclose(ur5.upper, [2 * math.pi] * 2 + [math.pi] + [2 * math.pi] * 3)
    np.testing.assert_array_equal(ur5.velocity, [3.15] * 3 + [3.2] * 3)


def test_a_broken_mount_file_names_the_file_and_field(monkeypatch, tmp_path):
    import shutil

    shutil.copytree(ROBOTS_DIR / "throwing_ee", tmp_path / "throwing_ee")
    (tmp_path / "panda_throwing").mkdir()
    text = (ROBOTS_DIR / "panda_throwing" / "mount.yaml").read_text()
    text = text.replace("jerk_limits: [7500.0,", "jerk_limits: [")
    (tmp_path / "panda_throwing" / "mount.yaml").write_text(text)
    monkeypatch.setenv(paths.ROBOTS_ENV, str(tmp_path))
    paths.robots_dir.cache_clear()
    try:
        with pytest.raises(InvalidParameter, match=r"mount.yaml: field 'jerk_limits' must be 7"):
            load_mount("panda")
    finally:
        monkeypatch.delenv(paths.ROBOTS_ENV)
        paths.robots_dir.cache_clear()
