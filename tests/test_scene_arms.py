"""Every arm of robots/ in the PyBullet scene: its TCP where Pinocchio puts it."""

from __future__ import annotations

import numpy as np
import pytest

from cell.robot.model import load_robot
from cell.robot.mount import robot_names
from cell.sim import EE_TO_TCP_M, CellScene


@pytest.mark.parametrize("robot", robot_names())
def test_the_scene_tcp_equals_pinocchios_for_random_configurations(robot):
    rb = load_robot(robot)
    qs = rb.random_configuration(np.random.default_rng(7), 25)
    with CellScene(robot) as sc:
        assert len(sc.ready_q) == rb.dof
        for q in qs:
            sc.set_arm(q, teleport=True)
            p, r = sc.ee_pose()
            tcp_scene = p + r[:, 2] * EE_TO_TCP_M
            tcp_pin, rot_pin = rb.tcp_pose(q)
            assert np.linalg.norm(tcp_scene - tcp_pin) < 1e-4  # 0.1 mm
            # the frames agree: rotation angle of R_pin^T R_scene below 0.1°
            c = (np.trace(rot_pin.T @ r) - 1) / 2
            assert np.degrees(np.arccos(np.clip(c, -1, 1))) < 0.1


def test_an_unknown_arm_is_refused():
    from cell.errors import InvalidParameter

    with pytest.raises(InvalidParameter, match="ur5"):
        CellScene("kuka")
