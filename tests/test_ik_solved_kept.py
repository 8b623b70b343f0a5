"""IK searches kept whole across decisions (`Kinematics._solved`, `_ik_solved`).

Independent checks: what is kept is what `solve_ik` itself returns afresh for the same
pose, seed and give-up rule, bit for bit (a solution, or the same best residual); another
give-up rule is another search; the record is bounded; and a decision made with the
searches an earlier decision kept is the decision made with none kept, bit for bit, with
fewer searches.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from cell.arm import kinematics
from cell.robot.ik import IKNoSolution, ReleasePose, solve_ik
from tests.test_reach_kept import decide_presented
from tests.test_release_choice import JOB  # random layout 2's geometry (Panda)

FAR = ReleasePose.from_angles(np.array([0.1, 0.0, 1.5]), 0.3, 0.0, 0.0)  # beyond the Panda


@pytest.fixture(scope="module")
def orchestrator(orchestrator_on: Any) -> Any:
    return orchestrator_on(JOB, "solved-kept", cycle_search=True)


def _near(o: Any) -> tuple[ReleasePose, np.ndarray]:
    """A pose in reach 6 cm from home's, and a seed 0.3 rad from home."""
    q_home = np.asarray(o.robot.home, float)
    p, r = o.robot.tcp_pose(q_home)
    return ReleasePose(p + np.array([0.06, 0.0, -0.02]), r[:, 2], 0.0), q_home + 0.3


def test_the_kept_search_is_the_fresh_one(orchestrator: Any, ik_solve_calls: Any) -> None:
    o = orchestrator
    o._ik_solved.clear()
    pose, seed = _near(o)
    calls = ik_solve_calls
    for give_up in (None, (6, 30.0)):
        calls.reset()
        key = (pose.position.tobytes(), b"x", seed.tobytes())
        first = o._solved(key, pose, seed, give_up)
        again = o._solved(key, pose, seed, give_up)
        assert calls.n == 1 and again is first  # searched once
        fresh = solve_ik(o.robot, pose, seed, give_up=give_up)
        assert first.q.tobytes() == fresh.q.tobytes()
    assert len(o._ik_solved) == 2  # one search per give-up rule
    key = (FAR.position.tobytes(), b"far", seed.tobytes())
    with pytest.raises(IKNoSolution) as first_far:
        o._solved(key, FAR, seed, None)
    calls.reset()
    with pytest.raises(IKNoSolution) as again_far:
        o._solved(key, FAR, seed, None)
    assert calls.n == 0 and again_far.value is first_far.value
    with pytest.raises(IKNoSolution) as fresh_far:
        solve_ik(o.robot, FAR, seed)
    assert first_far.value.position_error_m == fresh_far.value.position_error_m
    o._ik_solved.clear()


def test_the_record_is_bounded(orchestrator: Any, monkeypatch: pytest.MonkeyPatch) -> None:
    o = orchestrator
    o._ik_solved.clear()
    monkeypatch.setattr(kinematics, "IK_SOLVED_KEPT_MAX", 2)
    pose, seed = _near(o)
    for k in range(5):
        o._solved((bytes([k]),), pose, seed, None)
        assert 1 <= len(o._ik_solved) <= 2
    o._ik_solved.clear()


def test_a_decision_with_searches_kept_is_the_same(orchestrator: Any, ik_solve_calls: Any) -> None:
    """Items 2 and 3 (the same cube to the same bin): item 3 decided after item 2 with the
    searches item 2 kept, and again with none kept."""
    o = orchestrator
    calls = ik_solve_calls
    o._out_of_reach.clear()
    o._far_poses.clear()
    o._ik_solved.clear()
    decide_presented(o, 2)
    out_of_reach = dict(o._out_of_reach)
    far_poses = o._far_poses.copy()
    calls.reset()
    with_kept = decide_presented(o, 3)
    n_kept = calls.n
    o._ik_solved.clear()
    o._out_of_reach.clear()
    o._out_of_reach.update(out_of_reach)  # as item 2 left it: only the searches differ
    o._far_poses = far_poses
    calls.reset()
    without = decide_presented(o, 3)
    assert n_kept < calls.n  # searches item 2 kept were not run again
    assert with_kept.plan == without.plan
    np.testing.assert_array_equal(with_kept.state.q_release, without.state.q_release)
    assert with_kept.stroke_m == without.stroke_m
