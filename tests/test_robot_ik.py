"""Inverse kinematics of release poses: accuracy, success rate, nearest solution, failure."""

import math

import numpy as np
import pytest

from cell.errors import IKFailed, InvalidInput
from cell.model import throw_axis
from cell.robot.ik import AXIS_TOL_RAD, POSITION_TOL_M, ReleasePose, pose_error, solve_ik
from cell.robot.model import axis_frame, load_robot

N_POSES = 200


def fk_poses(robot, n, seed, roll=False):
    rng = np.random.default_rng(seed)
    qs = robot.random_configuration(rng, n)
    poses = []
    for q in qs:
        p, r = robot.tcp_pose(q)
        pose = ReleasePose(p, r[:, 2])
        if roll:
            # The roll that reproduces r: angle of r's x axis from axis_frame(e, a, 0)'s.
            r0 = pose.rotation()
            roll_angle = math.atan2(float(r[:, 0] @ r0[:, 1]), float(r[:, 0] @ r0[:, 0]))
            pose = ReleasePose(p, r[:, 2], roll_angle)
        poses.append((q, pose))
    return poses


def independent_errors(robot, q, pose):
    """Position [m] and axis [rad] errors of q, from FK only."""
    p, r = robot.tcp_pose(q)
    z = r[:, 2]
    return float(np.linalg.norm(p - pose.position)), math.acos(min(1.0, float(z @ pose.axis)))


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_fk_of_ik_is_within_1mm_and_half_a_degree_on_99_percent_of_fk_poses(name):
    robot = load_robot(name)
    ok = 0
    for _, pose in fk_poses(robot, N_POSES, seed={"panda": 11, "ur5": 12}[name]):
        try:
            res = solve_ik(robot, pose, robot.home)
        except IKFailed:
            continue
        ep, ea = independent_errors(robot, res.q, pose)
        assert ep <= POSITION_TOL_M and ea <= AXIS_TOL_RAD
        assert ep == pytest.approx(res.position_error_m, abs=1e-12)
        assert np.all(res.q >= robot.limits.lower) and np.all(res.q <= robot.limits.upper)
        ok += 1
    assert ok / N_POSES >= 0.99


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_fixed_roll_reaches_the_full_orientation(name):
    robot = load_robot(name)
    ok = 0
    poses = fk_poses(robot, 40, seed=21, roll=True)
    for _, pose in poses:
        try:
            res = solve_ik(robot, pose, robot.home)
        except IKFailed:
            continue
        _, r = robot.tcp_pose(res.q)
        angle = math.acos(np.clip((np.trace(pose.rotation().T @ r) - 1) / 2, -1, 1))
        assert angle <= AXIS_TOL_RAD
        ok += 1
    assert ok >= 0.95 * len(poses)


def test_the_solution_starts_from_and_stays_near_the_current_configuration():
    robot = load_robot("panda")
    rng = np.random.default_rng(5)
    for q_true, pose in fk_poses(robot, 20, seed=31):
        q_cur = np.clip(
            q_true + rng.normal(0, 0.02, robot.dof), robot.limits.lower, robot.limits.upper
        )
        res = solve_ik(robot, pose, q_cur)
        assert res.seeds_tried == 1
        assert np.linalg.norm(res.q - q_cur) < 0.15


def test_ur5_wide_joints_come_back_within_2pi_of_the_current_configuration():
    robot = load_robot("ur5")
    q_cur = robot.home.copy()
    q_cur[5] = 5.5  # wrist 3 far round: the same pose is reachable 2π lower
    p, r = robot.tcp_pose(q_cur)
    res = solve_ik(robot, ReleasePose(p, r[:, 2]), robot.home)
    assert np.max(np.abs(res.q - robot.home)) < math.pi


def test_unreachable_pose_raises_ikfailed_with_the_residual():
    robot = load_robot("panda")
    pose = ReleasePose.from_angles((2.0, 0.0, 0.5), 0.3, 0.0)
    with pytest.raises(IKFailed, match="best residual") as info:
        solve_ik(robot, pose, random_seeds=4)
    # The Panda reaches ~0.855 m + flange + TCP: at least 0.8 m short of 2 m.
    assert info.value.position_error_m > 0.8
    ep, _, _ = pose_error(robot, info.value.q_best, pose)
    assert ep == pytest.approx(info.value.position_error_m)


def test_release_pose_axis_is_model_md_throw_axis():
    for e, a in [(0.0, 0.0), (0.5, 1.0), (-0.3, -2.5), (1.2, 3.0)]:
        pose = ReleasePose.from_angles((0, 0, 0), e, a)
        np.testing.assert_allclose(pose.axis, np.ravel(throw_axis(e, a)), atol=1e-12)
        assert pose.elevation == pytest.approx(e) and pose.azimuth == pytest.approx(a)
        r = axis_frame(e, a, 0.7)
        np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-12)
        assert np.linalg.det(r) == pytest.approx(1.0)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"position": (0, 0), "axis": (0, 0, 1)},
        {"position": (0, 0, np.nan), "axis": (0, 0, 1)},
        {"position": (0, 0, 0.5), "axis": (0, 0, 0)},
        {"position": (0, 0, 0.5), "axis": (0, 0, 1), "roll": math.inf},
    ],
)
def test_bad_release_pose_is_invalid_input(kwargs):
    with pytest.raises(InvalidInput):
        ReleasePose(
            np.asarray(kwargs.pop("position"), dtype=float),
            np.asarray(kwargs.pop("axis"), dtype=float),
            **kwargs,
        )


def test_current_configuration_outside_the_limits_is_invalid_input():
    robot = load_robot("panda")
    q = robot.home.copy()
    q[3] = 0.5  # joint 4's range ends at -0.0698 rad
    with pytest.raises(InvalidInput, match="joint 4"):
        solve_ik(robot, ReleasePose.from_angles((0.5, 0, 0.5), 0.3, 0.0), q)


def test_a_pose_whose_solution_sits_on_joint_limits_is_still_found():
    """Clamped DLS stalls here; the bounded trust-region polish reaches it."""
    robot = load_robot("panda")
    r, az = 0.36, -0.44
    pose = ReleasePose.from_angles((r * math.cos(az), r * math.sin(az), 0.43), 0.34, -0.77)
    with pytest.raises(IKFailed):
        solve_ik(robot, pose, polish=0)
    res = solve_ik(robot, pose)
    ep, ea = independent_errors(robot, res.q, pose)
    assert ep <= POSITION_TOL_M and ea <= AXIS_TOL_RAD
    lim = robot.limits
    assert np.min(np.minimum(res.q - lim.lower, lim.upper - res.q)) < 1e-3  # on a limit


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_a_release_puts_the_pads_in_the_vertical_plane_of_the_throw(name):
    """solve_release_ik: the pads' axis (ee_tcp's x) in the throw's vertical plane, so a
    pad carries the weight; where neither roll 0 nor π is reachable, the free roll."""
    from cell.robot.ik import solve_release_ik

    robot = load_robot(name)
    fixed = 0
    poses = [(q, p) for q, p in fk_poses(robot, 16, seed=31) if abs(p.axis[2]) < 0.95]
    for _, pose in poses:
        res = solve_release_ik(robot, pose.position, pose.elevation, pose.azimuth, robot.home)
        ep, ea = independent_errors(robot, res.q, pose)
        assert ep <= POSITION_TOL_M and ea <= AXIS_TOL_RAD
        x = robot.tcp_pose(res.q)[1][:, 0]
        normal = np.array([-math.sin(pose.azimuth), math.cos(pose.azimuth), 0.0])
        if abs(float(x @ normal)) <= math.sin(AXIS_TOL_RAD) + 1e-9:
            fixed += 1
        else:  # only when neither pad-under roll has a solution
            for roll in (0.0, math.pi):
                with pytest.raises(IKFailed):
                    solve_ik(robot, ReleasePose(pose.position, pose.axis, roll), robot.home)
    assert fixed >= 0.6 * len(poses) and len(poses) >= 8


def test_a_vertical_release_leaves_the_roll_free():
    from cell.robot.ik import solve_release_ik

    robot = load_robot("ur5")
    p = np.array([0.45, -0.3, 0.35])
    res = solve_release_ik(robot, p, -math.pi / 2, 0.0, robot.home)
    free = solve_ik(robot, ReleasePose.from_angles(p, -math.pi / 2, 0.0), robot.home)
    assert np.allclose(res.q, free.q)


def test_a_search_gives_up_where_its_first_seeds_are_all_far_off():
    """`give_up` (seeds, score): a pose 2 m out is missed by over 0.8 m from every seed, so
    the search stops after that many seeds, unpolished, with the same kind of error; a pose
    in reach (an FK pose) is solved as without it: its first seed converges."""
    robot = load_robot("panda")
    far = ReleasePose.from_angles((2.0, 0.0, 0.5), 0.3, 0.0)
    with pytest.raises(IKFailed, match="after 4 seeds") as info:
        solve_ik(robot, far, give_up=(4, 20.0))
    assert info.value.position_error_m > 0.8  # the Panda is at least 0.8 m short of 2 m
    with pytest.raises(IKFailed, match="after 31 seeds"):
        solve_ik(robot, far)  # without it: home (the current one) and 30 random seeds
    for q, pose in fk_poses(robot, 5, seed=7):
        a = solve_ik(robot, pose, q, give_up=(2, 20.0))
        b = solve_ik(robot, pose, q)
        np.testing.assert_array_equal(a.q, b.q)
        ep, ea = independent_errors(robot, a.q, pose)
        assert ep <= POSITION_TOL_M and ea <= AXIS_TOL_RAD
