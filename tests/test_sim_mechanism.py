"""The end-effector's one description: the scene's body and the code's numbers come from
robots/throwing_ee/throwing_ee.urdf, and a broken file is a clear error."""

import math
import shutil
from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest

from cell.errors import InvalidParameter
from cell.robot.composite import end_effector_urdf
from cell.sim import EE_TO_TCP_M, CellScene
from cell.sim.band import BAND_JOINT, FINGER_LEFT, FINGER_RIGHT
from cell.sim.mechanism import DEFAULT_GEOMETRY, DRIVEN_JOINTS, EEGeometry, load_ee_geometry

# The numbers robots/throwing_ee/README.md documents.
DOCUMENTED = EEGeometry(
    band_mass_kg=0.008,
    finger_mass_kg=0.002,
    base_mass_kg=0.6,
    carriage_half_xy_m=0.02,
    carriage_thickness_m=0.004,
    pad_length_m=0.03,
    pad_thickness_m=0.004,
    pad_half_width_m=0.012,
    finger_open_m=0.06,
    end_stop_m=0.138,
    stroke_lower_m=0.02,
    pad_friction=1.2,
    housing_half_x_m=0.04,
    housing_half_y_m=0.03,
    housing_to_tcp_m=0.130,
)


def test_the_geometry_is_the_documented_one_read_from_the_description():
    assert load_ee_geometry(end_effector_urdf()) == DEFAULT_GEOMETRY
    for f in fields(EEGeometry):
        assert getattr(DEFAULT_GEOMETRY, f.name) == pytest.approx(
            getattr(DOCUMENTED, f.name), abs=1e-15
        ), f.name
    # the pads' torsional friction: μ times the mean distance of a pad's 24 mm x 30 mm face
    # from its centre, in closed form for a rectangle of half sides a, b
    a, b = 0.012, 0.015
    d = math.hypot(a, b)
    mean_r = (2 * a * b * d + a**3 * math.log((b + d) / a) + b**3 * math.log((a + d) / b)) / (
        6 * a * b
    )
    assert DEFAULT_GEOMETRY.pad_spin_friction_m == pytest.approx(1.2 * mean_r, rel=1e-3)
    assert DEFAULT_GEOMETRY.moving_mass_kg == pytest.approx(0.012)


@pytest.fixture(scope="module")
def scene():
    sc = CellScene(robot=None, pick_station_xy=(-1.0, -1.0))
    yield sc
    sc.close()


def test_the_scene_body_is_the_description(scene):
    """What PyBullet built from the file: joints in the order the band drive uses, the
    masses, travel limits, pad boxes and friction of the geometry, E at the held pose."""
    cl, body, geo = scene.client, scene.ee_body, scene.geometry
    assert geo == DEFAULT_GEOMETRY
    names = [cl.getJointInfo(body, j)[1].decode() for j in (BAND_JOINT, FINGER_LEFT, FINGER_RIGHT)]
    assert names == list(DRIVEN_JOINTS)
    assert cl.getDynamicsInfo(body, -1)[0] == geo.base_mass_kg
    assert cl.getDynamicsInfo(body, BAND_JOINT)[0] == geo.band_mass_kg
    band = cl.getJointInfo(body, BAND_JOINT)
    assert (band[8], band[9]) == (geo.stroke_lower_m, geo.end_stop_m)
    for j in (FINGER_LEFT, FINGER_RIGHT):
        info = cl.getDynamicsInfo(body, j)
        assert (info[0], info[1]) == (geo.finger_mass_kg, geo.pad_friction)
        assert cl.getJointInfo(body, j)[9] == geo.finger_open_m
        (shape,) = cl.getCollisionShapeData(body, j)
        np.testing.assert_allclose(
            shape[3],
            [geo.pad_thickness_m, 2 * geo.pad_half_width_m, geo.pad_length_m],
            atol=1e-12,
        )
    # the base frame is E: held where the mount puts it, the TCP EE_TO_TCP_M along its +z
    pos = [0.3, -0.2, 0.9]
    orn = [0.0, 0.3826834323650898, 0.0, 0.9238795325112867]  # 45° about y
    scene.hold_ee(pos, orn, teleport=True)
    p, rot = scene.ee_pose()
    np.testing.assert_allclose(p, pos, atol=1e-12)
    links = {cl.getJointInfo(body, j)[12].decode(): j for j in range(cl.getNumJoints(body))}
    tcp = cl.getLinkState(body, links["ee_tcp"], computeForwardKinematics=True)[4]
    np.testing.assert_allclose(tcp, p + EE_TO_TCP_M * rot[:, 2], atol=1e-12)


def _broken(tmp_path: Path, old: str, new: str, count: int = 1) -> Path:
    folder = tmp_path / "throwing_ee"
    shutil.copytree(end_effector_urdf().parent, folder)
    path = folder / "throwing_ee.urdf"
    text = path.read_text()
    assert text.count(old) >= count, old
    path.write_text(text.replace(old, new, count))
    return path


@pytest.mark.parametrize(
    "old,new,count,message",
    [
        (
            '<contact><lateral_friction value="1.2"/></contact>',
            "",
            1,
            "ee_finger_left.*lateral_friction",
        ),
        (
            '<origin xyz="0 0 0.015" rpy="0 0 0"/>\n      <mass value="0.6"/>',
            '<mass value="0.6"/>',
            1,
            "ee_base's inertial origin",
        ),
        ('<mass value="0.002"/>', '<mass value="0.003"/>', 1, "the two pads"),
        ('name="ee_band_joint"', 'name="ee_stroke_joint"', 1, "no joint 'ee_band_joint'"),
        (
            '<axis xyz="-1 0 0"/>',
            '<axis xyz="0 -1 0"/>',
            1,
            "'ee_finger_left_joint' must be prismatic",
        ),
        (
            '<limit lower="0.02" upper="0.138"',
            '<limit lower="0.138" upper="0.02"',
            1,
            "limits .* are empty",
        ),
        ('<box size="0.04 0.04 0.004"/>', '<box size="0.04 0.05 0.004"/>', 2, "must be square"),
        ('<origin xyz="0.002 0 0.015" rpy="0 0 0"/>', '<origin xyz="0 0 0.015"/>', 2, "inner face"),
        ('<mass value="0.008"/>', '<mass value="heavy"/>', 1, "'ee_band' mass must be 1 finite"),
        ("</robot>", "", 1, "cannot read"),
        (
            '<joint name="ee_tcp_joint" type="fixed">',
            '<joint name="ee_tcp_joint" type="prismatic">',
            1,
            "'ee_tcp_joint' must be fixed",
        ),
        ('<origin xyz="0 0 0.145"', '<origin xyz="0.01 0 0.145"', 1, "on the throw axis"),
    ],
)
def test_a_broken_description_names_the_file_and_the_element(tmp_path, old, new, count, message):
    path = _broken(tmp_path, old, new, count)
    with pytest.raises(InvalidParameter, match=message) as err:
        load_ee_geometry(path)
    assert str(path) in str(err.value)
