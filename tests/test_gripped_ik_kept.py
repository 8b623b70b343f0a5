"""The grip pointing down at a free roll (`Kinematics._ik_gripped`'s fallback, through
`_gripped_ik`) remembered until the next decision, as the gripped roll's IK already was.

Independent checks: what it returns is what `solve_release_ik` with `solve_ik` itself
(every seed, the polish) returns from the same seed, bit for bit, in reach and out of it
(the same best residual); the same pose from the same seed is not searched twice in one
decision; after `decide`'s clearing, it is not searched again either (the search kept
whole across decisions, `Kinematics._solved`), and with that cleared too it is searched
afresh, to the same answer.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from cell.jobs import parse_job
from cell.orchestrator import Orchestrator
from cell.robot.ik import IKNoSolution, solve_release_ik
from tests.test_reach_bound import UR3_CELL


@pytest.fixture(scope="module")
def orchestrator() -> Any:
    # the UR3 demo's cell with one box: the IK is the arm's, and the demo's meshes and
    # spheres need no grip probe here (`Orchestrator._probe_meshes`)
    o = Orchestrator(parse_job(UR3_CELL, "ur3_cell.yaml"), session="gripped-ik")
    yield o
    o.close()


def test_in_reach_the_same_solution_searched_once(orchestrator: Any, ik_solve_calls: Any) -> None:
    o = orchestrator
    o._ik_memo.clear()
    o._ik_solved.clear()
    o._frame = None  # no gripped roll: the free roll at once
    seed = np.asarray(o.robot.home, float)
    tcp = o.robot.tcp_pose(seed)[0] + np.array([0.02, -0.03, -0.05])
    fresh = solve_release_ik(o.robot, tcp, -math.pi / 2, 0.0, seed)
    calls = ik_solve_calls
    calls.reset()
    first = o._ik_gripped(tcp, -math.pi / 2, 0.0, seed)
    n = calls.n
    again = o._ik_gripped(tcp, -math.pi / 2, 0.0, seed)
    assert n >= 1 and calls.n == n  # the second time, nothing searched
    assert first.tobytes() == fresh.q.tobytes() and again is first
    o._ik_memo.clear()  # as `decide` does: the search kept across decisions, not run again
    assert o._ik_gripped(tcp, -math.pi / 2, 0.0, seed).tobytes() == fresh.q.tobytes()
    assert calls.n == n
    o._ik_memo.clear()
    o._ik_solved.clear()  # nothing kept: searched afresh, the same answer
    assert o._ik_gripped(tcp, -math.pi / 2, 0.0, seed).tobytes() == fresh.q.tobytes()
    assert calls.n == 2 * n


def test_out_of_reach_the_same_verdict_searched_once(
    orchestrator: Any, ik_solve_calls: Any
) -> None:
    o = orchestrator
    o._ik_memo.clear()
    o._ik_solved.clear()
    o._frame = (0.0, 0.0)  # the gripped roll first, then the free roll: both out of reach
    seed = np.asarray(o.robot.home, float)
    tcp = np.array([0.35, -0.2, 0.95])  # 0.95 m up, the grip down: beyond the UR3
    with pytest.raises(IKNoSolution) as fresh:
        solve_release_ik(o.robot, tcp, -math.pi / 2, 0.0, seed)
    calls = ik_solve_calls
    calls.reset()
    with pytest.raises(IKNoSolution) as first:
        o._ik_gripped(tcp, -math.pi / 2, 0.0, seed)
    n = calls.n
    with pytest.raises(IKNoSolution) as again:
        o._ik_gripped(tcp, -math.pi / 2, 0.0, seed)
    assert n == 2 and calls.n == n  # gripped roll + free roll, then nothing
    assert again.value is first.value
    assert first.value.position_error_m == fresh.value.position_error_m
    assert str(first.value) == str(fresh.value)
    o._frame = None
    o._ik_memo.clear()
