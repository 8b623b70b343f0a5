"""The grip-hold model's kinematics (`cell.robot.grip_hold._point_motion`) against the route
it replaced, bit for bit.

The route recomputed here: every frame of the model placed (`updateFramePlacements`) after
each joint state's kinematics, ee_tcp's rotation read from `data.oMf`, each instant's
row written into preallocated arrays, and the item's offset turned into W one instant at a
time (`R @ r_local`). `_point_motion` gathers Pinocchio's answers in lists, places ee_tcp's
frame alone and turns the offsets of all instants in one `np.matmul`: a speed-up that
must give the same floats, so the carries planned with it are the same. Its physics is
checked elsewhere (tests/test_carry_paths.py: a closed form and finite differences).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin
import pytest

from cell.robot.grip_hold import _point_motion
from cell.robot.model import load_robot


def _reference(
    robot: Any, qs: np.ndarray, dqs: np.ndarray, ddqs: np.ndarray, offset: tuple[float, ...]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(a [m/s², W], α [rad/s², W], R) as before the change, on a data of its own."""
    m, fr = robot.model, robot.tcp_frame
    d = m.createData()
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    r_local = np.asarray(offset, float)
    k = len(qs)
    a_o, alphas, ws, r = np.empty((k, 3)), np.empty((k, 3)), np.empty((k, 3)), np.empty((k, 3))
    rots = np.empty((k, 3, 3))
    for i in range(k):
        pin.forwardKinematics(m, d, qs[i], dqs[i], ddqs[i])
        pin.updateFramePlacements(m, d)
        a_o[i] = pin.getFrameClassicalAcceleration(m, d, fr, lwa).linear
        alphas[i] = pin.getFrameAcceleration(m, d, fr, lwa).angular
        ws[i] = pin.getFrameVelocity(m, d, fr, lwa).angular
        rots[i] = d.oMf[fr].rotation
        r[i] = rots[i] @ r_local
    acc = a_o + np.cross(alphas, r) + np.cross(ws, np.cross(ws, r))
    return acc, alphas, rots


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_point_motion_is_the_row_by_row_route_bit_for_bit(name: str) -> None:
    robot = load_robot(name)
    rng = np.random.default_rng(17)
    for trial in range(60):
        k = (0, 1, 2, 201)[trial % 4] if trial < 8 else int(rng.integers(1, 60))
        qs = robot.random_configuration(rng, k)
        dqs = rng.normal(scale=2.0, size=qs.shape)
        ddqs = rng.normal(scale=6.0, size=qs.shape)
        offset = tuple(rng.normal(scale=0.05, size=3)) if trial % 5 else (0.0, 0.0, 0.0)
        got = _point_motion(robot, qs, dqs, ddqs, offset)
        want = _reference(robot, qs, dqs, ddqs, offset)
        for g, w in zip(got, want, strict=True):
            assert g.shape == w.shape and g.dtype == w.dtype
            assert g.tobytes() == w.tobytes(), (name, trial, k)
