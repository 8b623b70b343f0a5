"""IK speed and success on reachable release poses; trajectory computation times."""

from __future__ import annotations

import time

import numpy as np

from cell.errors import IKFailed, TrajectoryError
from cell.kinds import ROBOTS


def _ik_figures(name: str, n: int, seed: int) -> tuple[list[float], int]:
    from cell.robot.ik import ReleasePose, solve_ik
    from cell.robot.model import load_robot

    robot = load_robot(name)
    rng = np.random.default_rng(seed)
    times: list[float] = []
    ok = 0
    for q in robot.random_configuration(rng, n):
        p, r = robot.tcp_pose(q)
        pose = ReleasePose(p, r[:, 2])
        t0 = time.perf_counter()
        try:
            solve_ik(robot, pose, robot.home)
            ok += 1
        except IKFailed:
            pass
        times.append(time.perf_counter() - t0)
    return times, ok


def _trajectory_figures(name: str, n: int, seed: int) -> tuple[list[float], list[float]]:
    from cell.robot.model import load_robot
    from cell.robot.motion import plan_move, plan_path

    robot = load_robot(name)
    rng = np.random.default_rng(seed)
    lo = robot.limits.lower + 0.1
    hi = robot.limits.upper - 0.1
    t_path: list[float] = []
    t_move: list[float] = []
    for _ in range(n):
        # pick -> lift -> pre-release: three nearby configurations after home.
        pick = np.clip(robot.home + rng.uniform(-0.5, 0.5, robot.dof), lo, hi)
        lift = np.clip(pick + rng.uniform(-0.2, 0.2, robot.dof), lo, hi)
        pre = np.clip(lift + rng.uniform(-0.5, 0.5, robot.dof), lo, hi)
        t0 = time.perf_counter()
        try:
            plan_path([robot.home, pick, lift, pre], robot)
        except TrajectoryError:
            continue
        t_path.append(time.perf_counter() - t0)
        dq1 = rng.uniform(-0.3, 0.3, robot.dof) * robot.limits.velocity
        release = np.clip(pre + rng.uniform(-0.3, 0.3, robot.dof), lo + 0.3, hi - 0.3)
        t0 = time.perf_counter()
        try:
            plan_move(pre, None, release, dq1, robot)
        except TrajectoryError:
            continue
        t_move.append(time.perf_counter() - t0)
    return t_path, t_move


def run(quick: bool) -> dict[str, float]:
    """IK and trajectory figures for the Panda and the UR5.

    IK: release poses (position + throw axis, roll free) from the forward kinematics of
    uniform random configurations, solved from home. Trajectories: toppra through home →
    pick → lift → pre-release, and a ruckig move to a release state with a joint velocity.

    Returns:
        ik_median_ms, ik_success_rate (both arms pooled), per-arm figures, and
        trajectory_median_ms (toppra), ruckig_median_ms.
    """
    n_ik = 60 if quick else 300
    n_traj = 5 if quick else 30
    out: dict[str, float] = {}
    all_t: list[float] = []
    all_ok = 0
    path_t: list[float] = []
    move_t: list[float] = []
    for i, name in enumerate(ROBOTS):
        times, ok = _ik_figures(name, n_ik, seed=100 + i)
        all_t += times
        all_ok += ok
        out[f"ik_median_ms_{name}"] = float(np.median(times) * 1e3)
        out[f"ik_success_rate_{name}"] = ok / n_ik
        tp, tm = _trajectory_figures(name, n_traj, seed=200 + i)
        path_t += tp
        move_t += tm
    out["ik_median_ms"] = float(np.median(all_t) * 1e3)
    out["ik_p95_ms"] = float(np.percentile(all_t, 95) * 1e3)
    out["ik_success_rate"] = all_ok / (2 * n_ik)
    out["trajectory_median_ms"] = float(np.median(path_t) * 1e3) if path_t else float("nan")
    out["ruckig_median_ms"] = float(np.median(move_t) * 1e3) if move_t else float("nan")
    return out
