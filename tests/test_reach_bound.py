"""The sound reach test (`cell.robot.reach_bound`) that lets `Kinematics._lift_q` skip a
lift IK cannot solve.

Independent checks: it never refuses a pose a configuration reaches (sampled
configurations of each arm, their own tool poses: IK's answer there is known without
running it), nor one a full IK solves; it is tight on the UR arms (a sampled configuration
comes within a few mm of the bound); where it refuses, IK's whole search (every seed,
the polish) fails too; and the lift it refuses on the UR3 demo is out of reach.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cell.errors import IKFailed
from cell.jobs import parse_job
from cell.orchestrator import Orchestrator
from cell.robot.ik import AXIS_TOL_RAD, POSITION_TOL_M, IKNoSolution, ReleasePose, solve_ik
from cell.robot.model import load_robot
from cell.robot.reach_bound import bound_of, reach_bound

ARMS = ("panda", "ur3", "ur5", "ur10")


@pytest.mark.parametrize("name", ARMS)
def test_never_refuses_a_reached_pose(name: str) -> None:
    robot = load_robot(name)
    bound = reach_bound(robot)
    kept = bound_of(robot)
    assert bound is not None and kept is not None and kept.reach_m == bound.reach_m
    assert bound_of(robot) is kept  # made once
    rng = np.random.default_rng(7)
    closest = math.inf
    for q in robot.random_configuration(rng, 1500):
        p, r = robot.tcp_pose(q)
        assert not bound.refuses(p, r[:, 2], 0.0, 0.0)
        c = p + bound.v[2] * r[:, 2]
        gap = bound.reach_m - (np.linalg.norm(c - bound.origin) - math.hypot(*bound.v[:2]))
        closest = min(closest, float(gap))
    assert closest >= -1e-9
    if name != "panda":  # the UR's parallel joints: a bound within a few mm of the arm's
        assert closest < 0.01


@pytest.mark.parametrize("name", ARMS)
def test_refused_poses_are_out_of_ik_reach(name: str) -> None:
    """Grip-down poses along a ray from the shoulder, from in reach to beyond: a pose
    solved by the full IK is never refused; the first refused ones fail in IK too."""
    robot = load_robot(name)
    bound = reach_bound(robot)
    assert bound is not None
    home = np.asarray(robot.home, float)
    refused = solved = 0
    for k, out in enumerate(np.linspace(0.3, 1.6, 14)):
        d = np.array([math.cos(0.4 * k), math.sin(0.4 * k), 0.0]) * out * bound.reach_m
        tcp = bound.origin + d + np.array([0.0, 0.0, 0.1 * (k % 3)])
        pose = ReleasePose.from_angles(tcp, -math.pi / 2, 0.0)
        no = bound.refuses(tcp, pose.axis, POSITION_TOL_M, AXIS_TOL_RAD)
        try:
            solve_ik(robot, pose, home)
        except IKNoSolution:
            refused += no
            continue
        solved += 1
        assert not no, f"{name}: refused a pose IK solves at {tcp}"
    assert solved >= 2 and refused >= 2


def test_the_ur3_lift_over_the_station_is_refused_and_unsolved() -> None:
    robot = load_robot("ur3")
    bound = reach_bound(robot)
    assert bound is not None
    tcp = np.array([0.32, -0.22, 0.351])  # the demo's lift LIFT_M over a cube50
    pose = ReleasePose.from_angles(tcp, -math.pi / 2, 0.0)
    assert bound.refuses(tcp, pose.axis, POSITION_TOL_M, AXIS_TOL_RAD)
    with pytest.raises(IKNoSolution):
        solve_ik(robot, pose, np.asarray(robot.home, float))
    lower = np.array([0.32, -0.22, 0.283])  # half as high: not refused
    assert not bound.refuses(lower, pose.axis, POSITION_TOL_M, AXIS_TOL_RAD)


def _lift_both_ways(o: Any, p_item: np.ndarray, q_pick: np.ndarray) -> tuple[Any, Any, int]:
    """`_lift_q`'s answer (a configuration or the IKFailed's text) with the bound and
    without (IK run at every height), and how many heights the bound refused."""
    obj, stroke = o.job.items[0].obj, 0.081
    refused = [0]
    real = o._beyond_reach

    def counted(tcp: np.ndarray) -> bool:
        no = bool(real(tcp))
        refused[0] += no
        return no

    answers = []
    for check in (counted, lambda tcp: False):
        o._ik_memo.clear()
        o._beyond_reach = check
        try:
            answers.append(o._lift_q(p_item, stroke, obj, q_pick).tobytes())
        except IKFailed as exc:
            answers.append(str(exc))
        finally:
            del o._beyond_reach
    return answers[0], answers[1], refused[0]


# the UR3 demo's cell (tasks/bins_ur3.yaml: its arm, station and bins) with its first item
# alone: the lift is the arm's and the station's, and the demo's meshes and spheres (the
# duck, the teddy, sphere40, sphere55) need no grip probe here (up to 3.5 CPU-s of the
# test, `Orchestrator._probe_meshes`)
UR3_CELL = (
    (Path(__file__).resolve().parents[1] / "tasks" / "bins_ur3.yaml").read_text().split("items:")[0]
    + """items:
  - {object: cube50, count: 1, bin: chute_1}
policy: auto
seed: 0
limits: {place_reach_m: 0.5, item_time_limit_s: 20}
"""
)


def test_the_lift_is_the_one_ik_at_every_height_gives() -> None:
    """On the UR3 demo's station: the same lift with the bound as without it, where it
    skips the highest lift; and the same error where no lift is found at all."""
    o = Orchestrator(parse_job(UR3_CELL, "ur3_cell.yaml"), session="reach-bound")
    try:
        obj = o.job.items[0].obj
        for roll in (0.0, math.pi):
            o._frame = (0.0, roll)
            p_item = np.array([0.32, -0.22, 0.225])
            tcp = o._tcp_for_item_centre(p_item, -math.pi / 2, 0.0, 0.081, obj)
            q_pick = o.ik_frame(tcp)
            with_bound, without, refused = _lift_both_ways(o, p_item, q_pick)
            assert refused >= 1 and with_bound == without
        far = np.array([0.45, -0.3, 0.5])  # every lift beyond the UR3, the pick too
        with_bound, without, refused = _lift_both_ways(o, far, np.asarray(o.robot.home, float))
        assert refused == 3 and isinstance(without, str) and with_bound == without
    finally:
        o._frame = None
        o.close()
