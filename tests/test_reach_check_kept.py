"""The job check's reach search (`cell.jobcheck._reaches`): its answer is the default IK
search's (every seed, three solutions collected) though it stops at the first converged
seed, and a pose asked again within the process is not searched again."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from cell import jobcheck
from cell.errors import IKFailed
from cell.robot.ik import ReleasePose, solve_ik
from cell.robot.model import load_robot

# Panda poses, TCP [m, W], the grip pointing down: reached; missed near the base (the
# joints' limits); missed 0.81 m out, 0.23 m up (its nearest solution 5 mm off), and at
# the same x, y 0.25 m lower, reached; beyond any configuration.
POSES = (
    (0.50, 0.0, 0.30),
    (0.05, 0.05, 0.15),
    (0.05, -0.80, 0.23),
    (0.05, -0.80, -0.02),
    (3.0, 0.0, 0.2),
)


def _default_search(robot: Any, tcp: np.ndarray) -> float:
    """The answer of `solve_ik` with its default settings: 0 or the nearest miss [m]."""
    far = float(np.linalg.norm(tcp)) - jobcheck._farthest_m(robot)
    if far >= 0.0:
        return far
    try:
        solve_ik(robot, ReleasePose(tcp, np.array([0.0, 0.0, -1.0])), robot.home)
        return 0.0
    except IKFailed as exc:
        return float(exc.position_error_m)  # type: ignore[attr-defined]


def test_the_reach_answer_is_the_default_searchs() -> None:
    robot = load_robot("panda")
    jobcheck._REACHED.clear()
    got = [jobcheck._reaches(robot, np.array(p)) for p in POSES]
    want = [_default_search(robot, np.array(p)) for p in POSES]
    assert got == want  # to the bit: the messages print the miss
    assert got[0] == 0.0 and got[3] == 0.0
    assert got[1] > 0.0 and got[2] > 0.0 and got[4] > 0.0
    assert got[2] == pytest.approx(0.005, abs=0.001)
    assert math.isfinite(got[4])


def test_a_pose_asked_again_is_not_searched_again(ik_solve_calls: Any) -> None:
    robot = load_robot("panda")
    tcp = np.array([0.05, 0.06, 0.15])  # missed near the base: every seed, the polish
    first = jobcheck._reaches(robot, tcp)
    ik_solve_calls.reset()
    assert jobcheck._reaches(robot, tcp.copy()) == first > 0.0
    assert ik_solve_calls.n == 0
    other = load_robot("ur5")  # another arm: its own search
    jobcheck._reaches(other, tcp)
    assert ik_solve_calls.n == 1


def test_the_answers_kept_per_arm_are_bounded(monkeypatch: pytest.MonkeyPatch) -> None:
    """A long-lived process checking many jobs keeps at most `_REACHED_MAX` answers an
    arm, and an answer asked again after the store emptied is the same."""
    robot = load_robot("panda")
    jobcheck._REACHED.clear()
    monkeypatch.setattr(jobcheck, "_REACHED_MAX", 2)
    first = [jobcheck._reaches(robot, np.array(p)) for p in POSES[:3]]
    assert len(jobcheck._REACHED[robot]) <= 2
    again = [jobcheck._reaches(robot, np.array(p)) for p in POSES[:3]]
    assert again == first
    assert len(jobcheck._REACHED[robot]) <= 2
