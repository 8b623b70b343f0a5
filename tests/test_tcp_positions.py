"""`Robot.tcp_positions` (the joints' placements, then the grip's frame alone) against
`Robot.tcp_pose` (every frame placed by `framesForwardKinematics`): the same positions, bit
for bit."""

from __future__ import annotations

import numpy as np
import pytest

from cell.robot.model import load_robot


@pytest.mark.parametrize("name", ["panda", "ur5", "ur3"])
def test_tcp_positions_are_tcp_poses_positions(name: str) -> None:
    robot = load_robot(name)
    qs = robot.random_configuration(np.random.default_rng(6), 300)
    got = robot.tcp_positions(qs)
    want = np.array([robot.tcp_pose(q)[0] for q in qs])
    assert got.shape == (300, 3)
    assert got.tobytes() == want.tobytes()
