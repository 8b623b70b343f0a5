"""The robot layer's kinematics asked again for the same inputs: `grip_hold._point_motion`
and `Robot.tcp_positions` keep their answers by the inputs' bytes, and a move's
positions alone (`Trajectory.positions`) are `sample_many`'s.

Independent checks: each answer against the kinematics asked of Pinocchio instant by
instant with every frame placed (`getFrameAcceleration` for α, `framesForwardKinematics`
for the positions), bit for bit, for a first call, the same call again, and calls that
differ from it in one input alone (the configurations, the rates, the accelerations, the
point, the robot); and the positions against ruckig's and toppra's own states at the same
clipped instants.
"""

from __future__ import annotations

import numpy as np
import pytest

from cell.robot import grip_hold
from cell.robot.grip_hold import _point_motion
from cell.robot.model import Robot, load_robot
from cell.robot.motion import plan_move, plan_path


def _pinocchio(
    robot: Robot, qs: np.ndarray, dqs: np.ndarray, ddqs: np.ndarray, offset: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The point's acceleration, α and the rotations, instant by instant (every frame
    placed, α from `getFrameAcceleration`)."""
    import pinocchio as pin

    m, d, fr = robot.model, robot.data, robot.tcp_frame
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    a_o, alphas, ws, rots = [], [], [], []
    for q, dq, ddq in zip(qs, dqs, ddqs, strict=True):
        pin.forwardKinematics(m, d, q, dq, ddq)
        pin.updateFramePlacements(m, d)
        a_o.append(pin.getFrameClassicalAcceleration(m, d, fr, lwa).linear.copy())
        alphas.append(pin.getFrameAcceleration(m, d, fr, lwa).angular.copy())
        ws.append(pin.getFrameVelocity(m, d, fr, lwa).angular.copy())
        rots.append(d.oMf[fr].rotation.copy())
    w, al, rr = np.array(ws), np.array(alphas), np.array(rots)
    r = np.array([rot @ offset for rot in rr])
    acc = np.array(a_o) + np.cross(al, r) + np.cross(w, np.cross(w, r))
    return acc, al, rr


def _same(got: tuple[np.ndarray, ...], want: tuple[np.ndarray, ...]) -> bool:
    pairs = zip(got, want, strict=True)
    return all(g.shape == w.shape and g.tobytes() == w.tobytes() for g, w in pairs)


def test_point_motion_asked_again_is_pinocchios_for_each_input() -> None:
    panda, ur5 = load_robot("panda"), load_robot("ur5")
    rng = np.random.default_rng(64)
    qs = panda.random_configuration(rng, 31)
    dqs, ddqs = rng.normal(0.0, 1.0, qs.shape), rng.normal(0.0, 5.0, qs.shape)
    offset = np.array([0.01, -0.02, 0.05])
    first = _point_motion(panda, qs, dqs, ddqs, tuple(offset))
    assert _same(first, _pinocchio(panda, qs, dqs, ddqs, offset))
    again = _point_motion(panda, qs.copy(), dqs.copy(), ddqs.copy(), tuple(offset))
    assert _same(again, first)
    assert all(not a.flags.writeable for a in again)  # kept: nobody writes into it
    # one input changed at a time: each answer is its own inputs'
    q2 = qs.copy()
    q2[17, 3] += 1e-9
    d2, a2 = dqs.copy(), ddqs.copy()
    d2[0, 0] = -d2[0, 0]
    a2[30, 6] *= 2.0
    off2 = offset + np.array([0.0, 0.0, 1e-6])
    for args in (
        (q2, dqs, ddqs, offset),
        (qs, d2, ddqs, offset),
        (qs, dqs, a2, offset),
        (qs, dqs, ddqs, off2),
    ):
        got = _point_motion(panda, args[0], args[1], args[2], tuple(args[3]))
        assert _same(got, _pinocchio(panda, *args))
        assert not _same(got, first)
    # the same numbers for another arm (the UR5's six joints: the Panda's first six)
    q6, d6, a6 = qs[:, :6].copy(), dqs[:, :6].copy(), ddqs[:, :6].copy()
    assert _same(_point_motion(ur5, q6, d6, a6, tuple(offset)), _pinocchio(ur5, q6, d6, a6, offset))


def test_point_motion_kept_for_another_robot_is_not_taken() -> None:
    """An entry whose robot is not the one asking (a robot at an id another one had) is
    made again for the asking robot."""
    panda = load_robot("panda")
    rng = np.random.default_rng(65)
    qs = panda.random_configuration(rng, 5)
    zeros = np.zeros_like(qs)
    want = _pinocchio(panda, qs, zeros, zeros, np.zeros(3))
    other = object.__new__(Robot)  # another robot, under the Panda's key
    key = repr((id(panda), qs.shape, qs.shape, qs.shape)).encode()
    key += grip_hold.array_key(qs, zeros, zeros, (0.0, 0.0, 0.0))
    wrong = tuple(np.full_like(a, np.nan) for a in want)
    grip_hold._MOTIONS.put(key, (other, wrong))  # type: ignore[arg-type]
    assert _same(_point_motion(panda, qs, zeros, zeros, (0.0, 0.0, 0.0)), want)
    assert _same(_point_motion(panda, qs, zeros, zeros, (0.0, 0.0, 0.0)), want)


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_tcp_positions_asked_again_are_tcp_poses(name: str) -> None:
    robot = load_robot(name)
    qs = robot.random_configuration(np.random.default_rng(66), 50)
    want = np.array([robot.tcp_pose(q)[0] for q in qs])
    first = robot.tcp_positions(qs)
    assert first.tobytes() == want.tobytes()
    again = robot.tcp_positions(qs.copy())
    assert again.tobytes() == want.tobytes() and not again.flags.writeable
    q2 = qs.copy()
    q2[49, 0] += 1e-3  # one joint of one configuration
    got = robot.tcp_positions(q2)
    assert got.tobytes() == np.array([robot.tcp_pose(q)[0] for q in q2]).tobytes()
    assert got[:49].tobytes() == want[:49].tobytes() and not np.array_equal(got[49], want[49])
    # fewer rows of the same configurations: their own answer, not the longer one's
    assert robot.tcp_positions(qs[:10]).tobytes() == want[:10].tobytes()


def test_a_moves_positions_are_its_samples() -> None:
    robot = load_robot("panda")
    rng = np.random.default_rng(67)
    q0, q1, q2 = robot.home + 0.5 * (robot.random_configuration(rng, 3) - robot.home)
    ruckig = plan_move(q0, None, q1, None, robot)
    toppra = plan_path([q0, q1, q2], robot)
    for tr in (ruckig, toppra):
        ts = np.arange(0.0, tr.duration + 0.01, 1 / 240)  # past the end: clipped
        assert ts[-1] > tr.duration
        got = tr.positions(ts)
        want = tr.sample_many(ts)[0]
        assert got.shape == want.shape and got.tobytes() == want.tobytes(), tr.kind
    at = ruckig.duration * 0.37
    assert ruckig.positions([at])[0].tobytes() == np.array(ruckig._traj.at_time(at)[0]).tobytes()
