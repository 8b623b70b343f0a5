"""A release pose out of the arm's reach, kept as such across decisions
(`ArmTuning.ik_reach_kept`, `Kinematics._solve_ik`'s `_out_of_reach`).

Independent checks: the verdict kept is the one IK's whole search gives afresh (every
seed, the polish, no give-up) from other seeds too; it is not reused under other search
constants nor with the rule off; the record is bounded; and a decision made with poses
kept from an earlier one is the decision made without them, bit for bit.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from cell.arm import kinematics
from cell.orchestrator import Orchestrator
from cell.robot.ik import IKNoSolution, ReleasePose, solve_ik
from tests.test_release_choice import JOB  # random layout 2's geometry (Panda)

# 1.5 m up over the base: out of the Panda's reach (about 1.2 m from its shoulder)
FAR = ReleasePose.from_angles(np.array([0.1, 0.0, 1.5]), 0.3, 0.0, 0.0)


@pytest.fixture(scope="module")
def orchestrator(orchestrator_on: Any) -> Any:
    # the job's bin_0 has a low rim (0.05 m): its throws are planned in the steep bounds
    # first (`ArmTuning.steep_rim_m`, on as by default), kept only where they pass what an
    # ordinary plan is held to (`cell.arm.steep`)
    return orchestrator_on(JOB, "reach", cycle_search=True)


def test_a_pose_out_of_reach_is_kept_across_decisions(orchestrator: Any) -> None:
    o = orchestrator
    kept = o.tuning
    o._ik_memo.clear()
    o._out_of_reach.clear()
    o._far_poses.clear()
    try:
        with pytest.raises(IKNoSolution) as first:
            o._release_ik(o.robot, FAR, np.asarray(o.robot.home, float))
        o._ik_memo.clear()  # as `decide` does: the next item's plan
        seed = np.asarray(o.q, float) + 0.2
        with pytest.raises(IKNoSolution) as again:
            o._release_ik(o.robot, FAR, seed)
        assert again.value is first.value  # not searched again
        # the verdict is right: the whole search from that seed misses it as far
        with pytest.raises(IKNoSolution) as fresh:
            solve_ik(o.robot, FAR, seed)
        assert fresh.value.position_error_m >= o.tuning.ik_out_of_reach_m
        # other search constants: another verdict, searched afresh
        o._ik_memo.clear()
        o.tuning = dataclasses.replace(kept, ik_give_up=(8, 30.0))
        with pytest.raises(IKNoSolution) as other:
            o._release_ik(o.robot, FAR, seed)
        assert other.value is not first.value
        # another polish: another verdict too (the polish can lower the best residual)
        o._ik_memo.clear()
        o.tuning = dataclasses.replace(kept, ik_polish=kept.ik_polish + 3)
        with pytest.raises(IKNoSolution) as polished:
            o._release_ik(o.robot, FAR, seed)
        assert polished.value is not first.value and polished.value is not other.value
        # the rule off: nothing kept across decisions is used
        o._ik_memo.clear()
        o.tuning = dataclasses.replace(kept, ik_reach_kept=False)
        with pytest.raises(IKNoSolution) as off:
            o._release_ik(o.robot, FAR, seed)
        assert off.value is not first.value and off.value is not other.value
        # a pose in reach is never kept
        q_home = np.asarray(o.robot.home, float)
        p, r = o.robot.tcp_pose(q_home)
        o.tuning = kept
        n = len(o._out_of_reach)
        o._release_ik(o.robot, ReleasePose(p, r[:, 2], None), q_home)
        assert len(o._out_of_reach) == n
    finally:
        o.tuning = kept
        o._ik_memo.clear()


def test_the_record_is_bounded(orchestrator: Any, monkeypatch: pytest.MonkeyPatch) -> None:
    o = orchestrator
    o._out_of_reach.clear()
    o._far_poses.clear()  # the poses near those kept: none (`ik_warm`)
    monkeypatch.setattr(kinematics, "OUT_OF_REACH_KEPT_MAX", 2)
    for k in range(5):
        o._ik_memo.clear()
        pose = ReleasePose.from_angles(np.array([0.1, 0.0, 1.5 + 0.01 * k]), 0.3, 0.0, 0.0)
        with pytest.raises(IKNoSolution):
            o._release_ik(o.robot, pose, np.asarray(o.robot.home, float))
        assert 1 <= len(o._out_of_reach) <= 2
    o._ik_memo.clear()
    o._out_of_reach.clear()
    o._far_poses.clear()


def decide_presented(o: Orchestrator, k: int) -> Any:
    """The job's item k presented on the station, decided, and taken away again."""
    spec = o.job.expanded_items()[k]
    o.present(k, spec.obj)
    try:
        return o.decide(k, spec.obj, o.job.bin(spec.bin))
    finally:
        o.scene.remove_item(o._presented)


def test_a_decision_with_poses_kept_is_the_same(orchestrator: Any, ik_solve_calls: Any) -> None:
    """Items 2 and 3 (the same cube to the same bin): the second decided with what the
    first kept out of reach, and again with nothing kept, the rule off: fewer IK searches,
    the same decision. The steep rule off: into their bin's low rim (0.05 m) their steep
    plans, warm-started (`ArmTuning.ik_warm`), hold and meet no pose out of reach, and
    the rule tested here is the ordinary bounds' search."""
    o = orchestrator
    kept = o.tuning
    calls = ik_solve_calls
    o._out_of_reach.clear()
    o._far_poses.clear()
    try:
        o.tuning = dataclasses.replace(kept, steep_rim_m=0.0)
        decide_presented(o, 2)
        assert o._out_of_reach  # the first decision met a pose out of reach
        o._ik_solved.clear()  # the searches kept whole (`_solved`): not the rule counted here
        calls.reset()
        with_kept = decide_presented(o, 3)
        n_kept = calls.n
        o._out_of_reach.clear()
        o._ik_solved.clear()
        o.tuning = dataclasses.replace(kept, steep_rim_m=0.0, ik_reach_kept=False)
        calls.reset()
        without = decide_presented(o, 3)
        assert n_kept < calls.n  # the poses kept were not searched again
    finally:
        o.tuning = kept
    assert with_kept.plan == without.plan
    np.testing.assert_array_equal(with_kept.state.q_release, without.state.q_release)
    assert with_kept.stroke_m == without.stroke_m
