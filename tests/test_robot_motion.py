"""Trajectories: limits hold on dense samples, the end state is the target, closed forms."""

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from cell.errors import InvalidInput, TrajectoryError
from cell.robot.model import load_robot
from cell.robot.motion import (
    ChainTrajectory,
    check_limits,
    monotone_samples,
    move_time,
    plan_approach,
    plan_move,
    plan_path,
    plan_stop,
    release_joint_velocity,
    spline_path,
)

RTOL = 1e-6  # relative tolerance on a limit


def random_waypoints(robot, rng, k=4, spread=0.6):
    lo = robot.limits.lower + 0.15
    hi = robot.limits.upper - 0.15
    wps = [robot.home]
    for _ in range(k - 1):
        wps.append(np.clip(wps[-1] + rng.uniform(-spread, spread, robot.dof), lo, hi))
    return wps


def dense(traj, n=4001):
    ts = np.linspace(0.0, traj.duration, n)
    q, dq, ddq = traj.sample_many(ts)
    return ts, q, dq, ddq


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_toppra_path_respects_limits_and_passes_the_waypoints(name):
    robot = load_robot(name)
    lim = robot.limits
    rng = np.random.default_rng(1)
    for _ in range(4):
        wps = random_waypoints(robot, rng)
        traj = plan_path(wps, robot)
        ts, q, dq, ddq = dense(traj)
        assert np.all(np.abs(dq) <= lim.velocity * (1 + RTOL))
        assert np.all(np.abs(ddq) <= lim.acceleration * (1 + RTOL))
        assert np.all(q >= lim.lower - 1e-9) and np.all(q <= lim.upper + 1e-9)
        # At rest at both ends, exactly at the first and last waypoints.
        np.testing.assert_allclose(q[0], wps[0], atol=1e-9)
        np.testing.assert_allclose(q[-1], wps[-1], atol=1e-9)
        np.testing.assert_allclose(dq[0], 0.0, atol=1e-9)
        np.testing.assert_allclose(dq[-1], 0.0, atol=1e-9)
        # Through every intermediate waypoint (up to the sampling step).
        step = np.max(np.abs(dq)) * (ts[1] - ts[0])
        for w in wps[1:-1]:
            assert np.min(np.max(np.abs(q - w), axis=1)) <= step + 1e-9
        # Velocities are the derivative of positions (finite differences).
        fd = np.gradient(q, ts, axis=0)
        assert np.max(np.abs(fd[1:-1] - dq[1:-1])) < 0.02 * np.max(lim.velocity)


@pytest.mark.parametrize("d", [0.05, 0.3, 1.5])
def test_toppra_single_joint_move_is_near_the_bang_bang_optimum(d):
    """Closed form: a rest-to-rest move of one joint takes d/v + v/a (or 2√(d/a))."""
    robot = load_robot("panda")
    q0 = robot.home.copy()
    q1 = q0.copy()
    q1[0] += d
    v, a = robot.limits.velocity[0], robot.limits.acceleration[0]
    t_opt = d / v + v / a if d > v * v / a else 2 * np.sqrt(d / a)
    t = plan_path([q0, q1], robot).duration
    # toppra plans on 98 % of the limits: at most 1/0.98 slower.
    assert t_opt * (1 - 1e-6) <= t <= t_opt / 0.98 * 1.001


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_ruckig_arrives_with_the_target_velocity_within_all_limits(name):
    robot = load_robot(name)
    lim = robot.limits
    rng = np.random.default_rng(2)
    for _ in range(8):
        q0, q1 = random_waypoints(robot, rng, k=2, spread=0.8)
        q1 = np.clip(q1, lim.lower + 0.5, lim.upper - 0.5)
        dq1 = rng.uniform(-0.5, 0.5, robot.dof) * lim.velocity
        traj = plan_move(q0, None, q1, dq1, robot)
        ts, q, dq, ddq = dense(traj, 8001)
        np.testing.assert_allclose(q[0], q0, atol=1e-9)
        np.testing.assert_allclose(dq[0], 0.0, atol=1e-9)
        q_end, dq_end, ddq_end = traj.end_state()
        np.testing.assert_allclose(q_end, q1, atol=1e-8)
        np.testing.assert_allclose(dq_end, dq1, atol=1e-8)
        np.testing.assert_allclose(ddq_end, 0.0, atol=1e-6)
        assert np.all(np.abs(dq) <= lim.velocity * (1 + RTOL))
        assert np.all(np.abs(ddq) <= lim.acceleration * (1 + RTOL))
        # Jerk by finite differences of the acceleration (piecewise constant jerk).
        jerk = np.diff(ddq, axis=0) / np.diff(ts)[:, None]
        assert np.all(np.abs(jerk) <= lim.jerk * (1 + 1e-4))
        use = check_limits(traj, robot)
        assert use["position_margin_rad"] >= 0.0


def test_ruckig_rest_to_rest_time_is_the_jerk_limited_closed_form():
    """One joint, long move: trapezoid time plus a/j (each ramp lengthened by a/j)."""
    robot = load_robot("panda")
    q0 = robot.home.copy()
    q1 = q0.copy()
    q1[0] += 1.5
    v, a, j = (robot.limits.velocity[0], robot.limits.acceleration[0], robot.limits.jerk[0])
    t_expected = 1.5 / v + v / a + a / j
    assert move_time(q0, q1, robot) == pytest.approx(t_expected, rel=1e-6)


def test_ruckig_move_that_would_overshoot_a_joint_limit_raises():
    robot = load_robot("panda")
    up = robot.limits.upper[0]
    q0 = robot.home.copy()
    q0[0] = up - 0.05
    dq0 = np.zeros(robot.dof)
    dq0[0] = robot.limits.velocity[0]  # heading for the limit at full speed
    q1 = q0.copy()
    q1[0] = up - 0.1
    with pytest.raises(TrajectoryError, match="joint 1's position limit"):
        plan_move(q0, dq0, q1, None, robot)


def test_a_move_too_slow_for_ruckig_to_time_is_a_trajectory_error_not_a_traceback():
    """At a billionth of the UR5's acceleration and jerk limits a one-radian move would
    last about 22,000 s (the time grows as the limits' inverse square root: 7,071 s at
    1e-8, measured); ruckig answers a code its binding cannot name, which surfaced as a
    ValueError from the enum: it is a TrajectoryError like ruckig's other refusals."""
    robot = load_robot("ur5")
    q0 = robot.home.copy()
    q1 = q0.copy()
    q1[0] += 1.0
    slow = plan_move(q0, None, q1, None, robot, acceleration_scale=1e-8, jerk_scale=1e-8)
    assert slow.duration == pytest.approx(7071.0, rel=1e-3)
    with pytest.raises(TrajectoryError, match="ruckig found no trajectory"):
        plan_move(q0, None, q1, None, robot, acceleration_scale=1e-9, jerk_scale=1e-9)


def test_where_the_cubic_spline_leaves_the_limits_the_path_keeps_within_them():
    robot = load_robot("panda")
    up = robot.limits.upper[0]
    a, b, c = (robot.home.copy() for _ in range(3))
    a[0], b[0], c[0] = up - 1.0, up - 0.001, up - 0.3
    c[1] += 1.0
    way = np.array([a, b, c])
    # the cubic spline through them overshoots joint 1's upper limit (scipy's, on its own)
    seg = np.linalg.norm(np.diff(way, axis=0), axis=1)
    ss = np.concatenate([[0.0], np.cumsum(seg)]) / seg.sum()
    assert CubicSpline(ss, way, axis=0)(np.linspace(0.0, 1.0, 2001))[:, 0].max() > up + 0.01
    path = spline_path(way, robot.limits.lower, robot.limits.upper)
    qs = path(np.linspace(0.0, 1.0, 4001))
    assert qs[:, 0].max() <= up
    assert np.allclose(path(ss), way, atol=1e-12)  # through the waypoints
    # the shape-preserving samples: no joint leaves the range of two neighbouring waypoints
    s_dense, q_dense = monotone_samples(ss, way, 8)
    for k in range(len(way) - 1):
        inside = (s_dense >= ss[k]) & (s_dense <= ss[k + 1])
        lo, hi = np.minimum(way[k], way[k + 1]), np.maximum(way[k], way[k + 1])
        assert np.all(q_dense[inside] >= lo - 1e-12) and np.all(q_dense[inside] <= hi + 1e-12)
    # timed at the limits, it stays inside all of them and ends at rest on the last waypoint
    traj = plan_path([a, b, c], robot)
    use = check_limits(traj, robot, n=4001)
    assert use["position_margin_rad"] >= -1e-9 and use["velocity"] <= 1.0 + 1e-6
    assert use["acceleration"] <= 1.0 + 1e-6
    q_end, dq_end, _ = traj.sample(traj.duration)
    assert np.allclose(q_end, c, atol=1e-6) and np.allclose(dq_end, 0.0, atol=1e-6)
    # without limits, the path is the spline through the waypoints, overshoot and all
    assert spline_path(way)(np.linspace(0.0, 1.0, 2001))[:, 0].max() > up + 0.01


def test_a_spline_that_must_leave_the_limits_raises():
    # the middle waypoint on joint 1's limit, the path turning back from it towards a
    # third waypoint off the line: no spline through these stays inside
    robot = load_robot("panda")
    up = robot.limits.upper[0]
    a, b, c = (robot.home.copy() for _ in range(3))
    a[0], b[0], c[0] = up - 1.0, up, up - 0.3
    c[1] += 1.0
    with pytest.raises(TrajectoryError, match="leaves the joint limits"):
        plan_path([a, b, c], robot)


def test_target_velocity_above_the_limit_is_invalid_input():
    robot = load_robot("ur5")
    dq1 = np.zeros(robot.dof)
    dq1[2] = 1.01 * robot.limits.velocity[2]
    with pytest.raises(InvalidInput, match="joint 3's velocity limit"):
        plan_move(robot.home, None, robot.home, dq1, robot)


def test_bad_waypoints_are_invalid_input():
    robot = load_robot("panda")
    with pytest.raises(InvalidInput, match="at least 2"):
        plan_path([robot.home], robot)
    with pytest.raises(InvalidInput, match="7 finite"):
        plan_path([robot.home, robot.home[:6]], robot)
    outside = robot.home.copy()
    outside[3] = 0.2
    with pytest.raises(InvalidInput, match="joint 4"):
        plan_path([robot.home, outside], robot)


def test_sampling_clamps_to_the_interval_and_has_the_right_shapes():
    robot = load_robot("panda")
    q1 = robot.home + 0.2
    traj = plan_move(robot.home, None, q1, None, robot)
    q, dq, ddq = traj.sample_many([-1.0, 0.0, traj.duration, traj.duration + 5.0])
    assert q.shape == dq.shape == ddq.shape == (4, robot.dof)
    np.testing.assert_allclose(q[0], q[1])
    np.testing.assert_allclose(q[2], q[3])
    np.testing.assert_allclose(q[3], q1, atol=1e-9)


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_release_while_moving_reaches_the_grip_centre_velocity(name):
    """Secondary trajectory: arrive at the release pose with the release velocity, then stop."""
    robot = load_robot(name)
    rng = np.random.default_rng(4)
    q_rel = np.clip(
        robot.home + rng.uniform(-0.3, 0.3, robot.dof),
        robot.limits.lower + 0.6,
        robot.limits.upper - 0.6,
    )
    v_tcp = np.array([0.4, 0.0, 0.3])  # [m/s]
    dq_rel = release_joint_velocity(q_rel, v_tcp, robot)
    q_pre = robot.home
    traj = plan_move(q_pre, None, q_rel, dq_rel, robot)
    q_end, dq_end, _ = traj.end_state()
    # Independent check: the TCP velocity from finite differences of FK along the trajectory.
    h = 1e-5
    p_a, r_a = robot.tcp_pose(traj.sample(traj.duration - h)[0])
    p_b, r_b = robot.tcp_pose(q_end)
    np.testing.assert_allclose((p_b - p_a) / h, v_tcp, atol=2e-3)
    np.testing.assert_allclose(r_b[:, 2], r_a[:, 2], atol=1e-6)  # the axis is not turning
    stop = plan_stop(q_end, dq_end, robot)
    q_s, dq_s, ddq_s = dense(stop)[1:]
    np.testing.assert_allclose(dq_s[-1], 0.0, atol=1e-9)
    np.testing.assert_allclose(q_s[0], q_end, atol=1e-9)
    assert np.all(np.abs(ddq_s) <= robot.limits.acceleration * (1 + RTOL))
    assert np.all(q_s >= robot.limits.lower) and np.all(q_s <= robot.limits.upper)


def test_release_velocity_beyond_the_joint_limits_raises():
    robot = load_robot("panda")
    with pytest.raises(TrajectoryError, match="its limit"):
        release_joint_velocity(robot.home, [20.0, 0.0, 0.0], robot)


def test_position_bounds_match_dense_sampling_where_ruckigs_own_extrema_do_not():
    """ruckig 0.19.4 reported max 0.666 for joint 2 here; the true maximum is 0.702."""
    from ruckig import InputParameter, Ruckig
    from ruckig import Trajectory as RTrajectory

    from cell.robot.trajectory import RuckigTrajectory

    inp = InputParameter(3)
    inp.current_position = [0.87014485, 0.63170711, -0.994523]
    inp.current_velocity = [-0.64868876, 0.72635784, 0.08292244]
    inp.current_acceleration = [0.0] * 3
    inp.target_position = [0.71480855, -0.93282885, 0.45931089]
    inp.target_velocity = [0.0] * 3
    inp.target_acceleration = [0.0] * 3
    inp.max_velocity = [2.0] * 3
    inp.max_acceleration = [5.0] * 3
    inp.max_jerk = [100.0] * 3
    raw = RTrajectory(3)
    Ruckig(3).calculate(inp, raw)
    ts = np.linspace(0.0, raw.duration, 20001)
    q = np.array([raw.at_time(float(t))[0] for t in ts])
    lo, hi = RuckigTrajectory(raw, 3).position_bounds(np.full(3, 5.0))
    np.testing.assert_allclose(lo, q.min(axis=0), atol=1e-7)
    np.testing.assert_allclose(hi, q.max(axis=0), atol=1e-7)
    assert hi[1] > 0.70

    # With bounds to keep `within`, a joint is refined only where its true extremum could
    # pass them: one bound just under the sampled maximum plus its margin (refined, and
    # found past it as the dense samples are), the rest far out (left as sampled, inside).
    dt = raw.duration / 399
    slack = 5.0 * dt**2 / 8
    t400 = np.linspace(0.0, raw.duration, 400)
    sampled = np.array([raw.at_time(float(t))[0] for t in t400]).max(axis=0)
    upper = np.full(3, 10.0)
    upper[1] = sampled[1] + 0.5 * slack
    lo_w, hi_w = RuckigTrajectory(raw, 3).position_bounds(
        np.full(3, 5.0), within=(np.full(3, -10.0), upper)
    )
    np.testing.assert_allclose(hi_w[1], q.max(axis=0)[1], atol=1e-7)
    assert (hi_w[1] > upper[1]) == (q.max(axis=0)[1] > upper[1])
    np.testing.assert_allclose(hi_w[[0, 2]], sampled[[0, 2]])
    assert np.all(lo_w >= q.min(axis=0) - 1e-7) and np.all(hi_w <= q.max(axis=0) + 1e-7)


def test_a_move_ending_exactly_on_a_joint_limit_is_allowed():
    robot = load_robot("panda")
    q1 = robot.home.copy()
    q1[5] = robot.limits.upper[5]
    traj = plan_move(robot.home, None, q1, None, robot)
    assert traj.end_state()[0][5] == pytest.approx(robot.limits.upper[5], abs=1e-9)


def bang_bang_time(dq, robot):
    """Per-joint rest-to-rest time under the velocity and acceleration limits alone (no
    jerk limit): a lower bound on any move of that joint travel [s]."""
    d, v, a = np.abs(dq), robot.limits.velocity, robot.limits.acceleration
    return float(np.max(np.where(d <= v * v / a, 2 * np.sqrt(d / a), d / v + v / a)))


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_approach_passes_over_the_point_then_runs_down_the_segment_within_all_limits(name):
    """The empty arm's approach: within the description's limits on dense samples, through
    q_over, then on the straight segment to q_to, forward only, ending there at rest; no
    quicker than the per-joint bang-bang bound, and no slower than stopping at q_over."""
    robot = load_robot(name)
    lim = robot.limits
    rng = np.random.default_rng(3)
    lo, hi = lim.lower + 0.2, lim.upper - 0.2
    for _ in range(4):
        q0 = rng.uniform(lo, hi)
        q_to = np.clip(q0 + rng.uniform(-1.2, 1.2, robot.dof), lo, hi)
        q_over = q_to + rng.uniform(-0.1, 0.1, robot.dof)
        traj = plan_approach(q0, q_over, q_to, robot)
        assert isinstance(traj, ChainTrajectory) and len(traj.parts) == 2
        ts, q, dq, ddq = dense(traj)
        assert np.all(np.abs(dq) <= lim.velocity * (1 + RTOL))
        assert np.all(np.abs(ddq) <= lim.acceleration * (1 + RTOL))
        assert np.all(q >= lim.lower - 1e-9) and np.all(q <= lim.upper + 1e-9)
        np.testing.assert_allclose(q[0], q0, atol=1e-9)
        np.testing.assert_allclose(dq[0], 0.0, atol=1e-9)
        np.testing.assert_allclose(q[-1], q_to, atol=1e-8)
        np.testing.assert_allclose(dq[-1], 0.0, atol=1e-8)
        t1 = traj.parts[0].duration
        np.testing.assert_allclose(traj.sample(t1)[0], q_over, atol=1e-8)
        # from q_over on: on the segment, moving forward along it
        seg = q_to - q_over
        u = seg / np.linalg.norm(seg)
        rel = q[ts >= t1] - q_over
        along = rel @ u
        assert np.max(np.linalg.norm(rel - np.outer(along, u), axis=1)) < 1e-6
        assert np.all(np.diff(along) >= -1e-9)
        # continuous in position and velocity where the parts meet (dense samples)
        assert np.max(np.abs(np.diff(q, axis=0))) < np.max(lim.velocity) * (ts[1] - ts[0]) * 1.01
        assert traj.duration >= bang_bang_time(q_to - q0, robot) - 1e-9
        stop = move_time(q0, q_over, robot) + move_time(q_over, q_to, robot)
        assert traj.duration <= stop + 1e-9


def test_approach_without_a_segment_is_invalid_input():
    robot = load_robot("panda")
    with pytest.raises(InvalidInput, match="no segment"):
        plan_approach(robot.home, robot.home + 0.1, robot.home + 0.1, robot)
