"""IK speed and success on reachable release poses; trajectory computation times."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from cell.errors import IKFailed, TrajectoryError
from cell.robot.carry import GripHold

BENCH_ROBOTS = ("panda", "ur5")
"""The arms `cell bench robot` measures (its published figures are theirs); any mount
under robots/ can be measured with `_ik_figures(name, ...)`."""


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


def _carry_hold() -> GripHold:
    """What the scene's pads hold a 110 g, 50 mm cube with at a 70 mm stroke: on every
    path of the benchmark, the grip bounds the carry below the arm's limits and a time
    scaling keeps it within (`plan_carry`'s bisection and the grip-shaped path both run)."""
    from cell.arm.grip_limits import carry_hold
    from cell.model.objects import ObjectParams
    from cell.params import load_params, scene_params_path

    cube = ObjectParams(shape="cuboid", mass=0.11, size=(0.05, 0.05, 0.05), name="")
    return carry_hold(load_params(scene_params_path()), cube, 0.07)  # type: ignore[no-any-return]


def _carry_path(robot: Any, rng: np.random.Generator) -> list[np.ndarray]:
    """The benchmark's path [rad]: home -> pick -> lift -> pre-release, three nearby
    configurations drawn from `rng` after home, each 0.1 rad inside the joint limits."""
    lo = robot.limits.lower + 0.1
    hi = robot.limits.upper - 0.1
    pick = np.clip(robot.home + rng.uniform(-0.5, 0.5, robot.dof), lo, hi)
    lift = np.clip(pick + rng.uniform(-0.2, 0.2, robot.dof), lo, hi)
    pre = np.clip(lift + rng.uniform(-0.5, 0.5, robot.dof), lo, hi)
    return [robot.home, pick, lift, pre]


def _trajectory_figures(
    name: str, n: int, seed: int
) -> tuple[list[float], list[float], list[float]]:
    from cell.robot.carry import plan_carry
    from cell.robot.model import load_robot
    from cell.robot.motion import plan_move, plan_path

    hold = _carry_hold()
    robot = load_robot(name)
    rng = np.random.default_rng(seed)
    lo = robot.limits.lower + 0.1
    hi = robot.limits.upper - 0.1
    t_path: list[float] = []
    t_move: list[float] = []
    t_carry: list[float] = []
    for _ in range(n):
        way = _carry_path(robot, rng)
        pre = way[-1]
        t0 = time.perf_counter()
        try:
            plan_path(way, robot)
        except TrajectoryError:
            continue
        t_path.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        try:
            plan_carry(way, robot, hold)
            t_carry.append(time.perf_counter() - t0)
        except TrajectoryError:
            pass
        dq1 = rng.uniform(-0.3, 0.3, robot.dof) * robot.limits.velocity
        release = np.clip(pre + rng.uniform(-0.3, 0.3, robot.dof), lo + 0.3, hi - 0.3)
        t0 = time.perf_counter()
        try:
            plan_move(pre, None, release, dq1, robot)
        except TrajectoryError:
            continue
        t_move.append(time.perf_counter() - t0)
    return t_path, t_move, t_carry


def run(quick: bool) -> dict[str, float]:
    """IK and trajectory figures for the Panda and the UR5.

    IK: release poses (position + throw axis, roll free) from the forward kinematics of
    uniform random configurations, solved from home. Trajectories: toppra through home →
    pick → lift → pre-release, the same carrying a cube within the grip (`plan_carry`),
    and a ruckig move to a release state with a joint velocity.

    Returns:
        ik_median_ms, ik_success_rate (both arms pooled), per-arm figures, and
        trajectory_median_ms (toppra), carry_median_ms (`plan_carry`), ruckig_median_ms.
    """
    n_ik = 60 if quick else 300
    n_traj = 5 if quick else 30
    out: dict[str, float] = {}
    all_t: list[float] = []
    all_ok = 0
    path_t: list[float] = []
    move_t: list[float] = []
    carry_t: list[float] = []
    for i, name in enumerate(BENCH_ROBOTS):
        times, ok = _ik_figures(name, n_ik, seed=100 + i)
        all_t += times
        all_ok += ok
        out[f"ik_median_ms_{name}"] = float(np.median(times) * 1e3)
        out[f"ik_success_rate_{name}"] = ok / n_ik
        tp, tm, tc = _trajectory_figures(name, n_traj, seed=200 + i)
        path_t += tp
        move_t += tm
        carry_t += tc
    out["ik_median_ms"] = float(np.median(all_t) * 1e3)
    out["ik_p95_ms"] = float(np.percentile(all_t, 95) * 1e3)
    out["ik_success_rate"] = all_ok / (2 * n_ik)
    out["trajectory_median_ms"] = float(np.median(path_t) * 1e3) if path_t else float("nan")
    out["carry_median_ms"] = float(np.median(carry_t) * 1e3) if carry_t else float("nan")
    out["ruckig_median_ms"] = float(np.median(move_t) * 1e3) if move_t else float("nan")
    return out
