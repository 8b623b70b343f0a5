"""A ruckig move's samples (`RuckigTrajectory._eval`, `_positions`) against ruckig asked
instant by instant, bit for bit.

The samples are read from ruckig's lists into one array at once; here each instant's
(position, velocity, acceleration) is asked of ruckig's own trajectory (`at_time`) and
compared float for float, with the arrays' layout (each (k, dof), C-contiguous, as the
rows written one by one were). Moves of the Panda and the UR5 from rest and moving.
"""

from __future__ import annotations

import numpy as np
import pytest

from cell.robot.model import load_robot
from cell.robot.motion import plan_move
from cell.robot.trajectory import RuckigTrajectory


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_ruckig_samples_are_ruckigs_own_instant_by_instant(name: str) -> None:
    robot = load_robot(name)
    rng = np.random.default_rng(60)
    lim = robot.limits
    moves = 0
    for trial in range(40):
        q0, q1 = robot.home + 0.6 * (robot.random_configuration(rng, 2) - robot.home)
        dq0 = None if trial % 2 else rng.uniform(-0.3, 0.3, robot.dof) * lim.velocity
        tr = plan_move(q0, dq0, q1, None, robot)
        assert isinstance(tr, RuckigTrajectory)
        moves += 1
        k = (0, 1, 7, 400)[trial % 4]
        ts = np.sort(rng.uniform(0.0, tr.duration, k))
        q, dq, ddq = tr._eval(ts)
        want = np.array([tr._traj.at_time(float(t)) for t in ts]).reshape(k, 3, robot.dof)
        for i, got in enumerate((q, dq, ddq)):
            assert got.shape == (k, robot.dof) and got.flags["C_CONTIGUOUS"]
            assert got.tobytes() == np.ascontiguousarray(want[:, i]).tobytes(), (trial, i)
        pos = tr._positions(ts)
        assert pos.shape == (k, robot.dof)
        assert pos.tobytes() == np.ascontiguousarray(want[:, 0]).tobytes(), trial
    assert moves == 40
