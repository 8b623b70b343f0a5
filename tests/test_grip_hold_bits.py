"""`cell.robot.grip_hold._point_motion` (the grip's frame alone placed, r = R r_local for
all instants at once) against the same kinematics asked of Pinocchio instant by instant
with every frame placed (`updateFramePlacements`) and one product R r_local per instant,
as it was computed before: the same floats, bit for bit, on random states of three arms
(at rest, moving, accelerating) and items off the grip's centre; and the point's
acceleration against a finite difference of its position (an independent check of the
kinematics both read)."""

from __future__ import annotations

import numpy as np
import pytest

from cell.robot.grip_hold import _point_motion
from cell.robot.model import Robot, load_robot


def _instant_by_instant(
    robot: Robot, qs: np.ndarray, dqs: np.ndarray, ddqs: np.ndarray, offset: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    import pinocchio as pin

    m, d, fr = robot.model, robot.data, robot.tcp_frame
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    a_o, alphas, ws, r, rots = [], [], [], [], []
    for q, dq, ddq in zip(qs, dqs, ddqs, strict=True):
        pin.forwardKinematics(m, d, q, dq, ddq)
        pin.updateFramePlacements(m, d)
        a_o.append(pin.getFrameClassicalAcceleration(m, d, fr, lwa).linear.copy())
        alphas.append(pin.getFrameAcceleration(m, d, fr, lwa).angular.copy())
        ws.append(pin.getFrameVelocity(m, d, fr, lwa).angular.copy())
        rots.append(d.oMf[fr].rotation.copy())
        r.append(rots[-1] @ offset)
    w, rr, al = np.array(ws), np.array(r), np.array(alphas)
    acc = np.array(a_o) + np.cross(al, rr) + np.cross(w, np.cross(w, rr))
    return acc, al, np.array(rots)


@pytest.mark.parametrize("name", ["panda", "ur5", "ur3"])
def test_point_motion_is_pinocchios_instant_by_instant(name: str) -> None:
    robot = load_robot(name)
    rng = np.random.default_rng(61)
    for trial, k in enumerate((1, 2, 201, 501)):
        qs = robot.random_configuration(rng, k)
        dqs = rng.normal(0.0, 1.5, qs.shape) * (trial > 0)  # the first at rest
        ddqs = rng.normal(0.0, 8.0, qs.shape) * (trial > 0)
        offset = rng.normal(0.0, 0.05, 3) * (trial != 1)
        got = _point_motion(robot, qs, dqs, ddqs, tuple(offset))
        want = _instant_by_instant(robot, qs, dqs, ddqs, offset)
        for g, w in zip(got, want, strict=True):
            assert g.shape == w.shape
            assert g.tobytes() == w.tobytes(), (name, trial)


def test_point_acceleration_is_the_second_difference_of_its_position() -> None:
    robot = load_robot("panda")
    rng = np.random.default_rng(62)
    q0, dq, ddq = robot.random_configuration(rng, 1)[0], rng.normal(0, 1, 7), rng.normal(0, 3, 7)
    offset = np.array([0.01, -0.02, 0.06])
    h = 1e-4
    ts = np.array([-h, 0.0, h])
    qs = q0 + np.outer(ts, dq) + 0.5 * np.outer(ts**2, ddq)
    pos = []
    for q in qs:
        p, rot = robot.tcp_pose(q)
        pos.append(p + rot @ offset)
    want = (pos[0] - 2 * pos[1] + pos[2]) / h**2
    acc = _point_motion(robot, qs[1:2], dq[None], ddq[None], tuple(offset))[0][0]
    np.testing.assert_allclose(acc, want, atol=1e-4 * max(1.0, float(np.linalg.norm(want))))
