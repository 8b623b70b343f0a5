"""The end-effector mounted on the Panda in the scene (PyBullet DIRECT)."""

import math

import numpy as np
import pytest

from cell.endeffector.pybullet_backend import PyBulletEndEffector
from cell.sim import FLANGE_TO_EE_M, FLANGE_YAW_RAD, PANDA_READY, CellScene


@pytest.fixture(scope="module")
def scene():
    sc = CellScene()
    yield sc
    sc.close()


def _expected_ee(sc):
    cl = sc.client
    # the Panda's own flange, then the mount file's yaw and the plate face's offset
    links = {cl.getJointInfo(sc.arm, j)[12].decode(): j for j in range(cl.getNumJoints(sc.arm))}
    st = cl.getLinkState(sc.arm, links["panda_link8"], computeForwardKinematics=True)
    yaw = cl.getQuaternionFromEuler([0, 0, FLANGE_YAW_RAD])
    p, o = cl.multiplyTransforms(st[4], st[5], [0, 0, FLANGE_TO_EE_M], yaw)
    return np.asarray(p), np.asarray(cl.getMatrixFromQuaternion(o)).reshape(3, 3)


def test_end_effector_rides_on_the_flange_while_the_arm_moves(scene):
    q0 = np.asarray(PANDA_READY)
    q1 = q0 + np.array([0.6, 0.2, 0.0, 0.3, 0.0, -0.2, 0.0])
    samples = [q0 + (q1 - q0) * (1 - math.cos(math.pi * k / 100)) / 2 for k in range(101)]
    scene.follow(samples, 0.01)
    scene.run_for(0.1)
    p, r = scene.ee_pose()
    pe, re = _expected_ee(scene)
    assert np.linalg.norm(p - pe) < 2e-3
    assert np.degrees(np.arccos(np.clip((np.trace(r.T @ re) - 1) / 2, -1, 1))) < 0.5


def test_item_stays_in_the_grip_while_the_arm_moves_then_is_thrown(scene):
    ee = PyBulletEndEffector(scene)
    scene.set_arm(PANDA_READY, teleport=True)
    item = scene.spawn_item("cube40")
    scene.run_for(0.2)
    ee.grasp(0.05)
    before = ee.held_offset_m()
    q0 = np.asarray(PANDA_READY)
    q1 = q0 + np.array([0.3, 0.2, 0.0, 0.3, 0.0, 1.9, 0.0])  # turns the axis 25° above horizontal
    samples = [q0 + (q1 - q0) * (1 - math.cos(math.pi * k / 100)) / 2 for k in range(101)]
    scene.follow(samples, 0.01)
    scene.run_for(0.2)
    assert np.linalg.norm(ee.held_offset_m() - before) < 5e-3
    assert np.degrees(np.arcsin(scene.ee_pose()[1][2, 2])) == pytest.approx(24.6, abs=1.0)
    p_release = np.asarray(scene.client.getBasePositionAndOrientation(item.body)[0])
    ee.throw()
    out = scene.watch_until_rest(item, timeout_s=4.0)
    assert out.rested
    flew = np.linalg.norm(np.asarray(out.touchdown_xy) - p_release[:2])
    assert flew > 0.5


def test_a_release_with_the_arm_moving_adds_the_end_effector_velocity(scene):
    ee = PyBulletEndEffector(scene)
    q1 = np.asarray(PANDA_READY) + np.array([0.0, 0.2, 0.0, 0.3, 0.0, 1.9, 0.0])
    launch = []
    for omega in (0.0, 1.0):  # base joint speed [rad/s]
        scene.set_arm(PANDA_READY, teleport=True)
        item = scene.spawn_item("cube50")
        scene.run_for(0.2)
        ee.grasp(0.06)
        q0 = np.asarray(PANDA_READY)
        scene.follow(
            [q0 + (q1 - q0) * (1 - math.cos(math.pi * k / 100)) / 2 for k in range(101)], 0.01
        )
        assert np.linalg.norm(ee.held_offset_m() - [0, 0, 0.06 + 0.025]) < 3e-3
        t0 = scene.t
        scene.set_arm_motion(
            lambda t, t0=t0, w=omega: q1 + np.array([w * (t - t0), 0, 0, 0, 0, 0, 0])
        )
        scene.run_for(0.3)  # reach steady motion
        v_ee, w_ee = (np.asarray(v) for v in scene.client.getBaseVelocity(scene.ee_body))
        r_ee = scene.ee_pose()[1]
        ee.throw()
        scene.set_arm_motion(None)
        v_item = np.asarray(scene.client.getBaseVelocity(item.body)[0])
        p_item = np.asarray(scene.client.getBasePositionAndOrientation(item.body)[0])
        # velocity of the end-effector's body at the point where the item left it
        v_ee = v_ee + np.cross(w_ee, p_item - scene.ee_pose()[0])
        launch.append((v_ee, r_ee, v_item))
        scene.watch_until_rest(item, timeout_s=3.0)
        scene.remove_item(item)
    (v_ee0, r0, v0), (v_ee1, r1, v1) = launch
    assert np.linalg.norm(v_ee0) < 0.02
    assert np.linalg.norm(v_ee1) > 0.3
    # Galilean: the moving release = the static one turned with the end-effector, plus the
    # end-effector's own velocity where the item leaves it
    expected = r1 @ r0.T @ v0 + v_ee1
    # (what is left: the Coriolis push while the item travels out on the turning
    # end-effector, ~ ω v t_push ≈ 0.1 m/s here)
    assert np.linalg.norm(v1 - expected) < 0.3 * np.linalg.norm(v_ee1)
    assert np.linalg.norm(v1 - r1 @ r0.T @ v0) > 0.7 * np.linalg.norm(v_ee1)
