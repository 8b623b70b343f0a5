"""The release IK's warm start from a nearby pose's solution (`solve_ik`'s `warm`,
`cell.robot.ik_warm.WarmStarts`, `ArmTuning.ik_warm`).

Independent checks: a warm-started search's solution reaches its pose to the IK's
tolerances by forward kinematics alone, within the joint limits; where neither the seed
nor the warm start converges, the search is the cold one (the same solution, bit for bit,
from the same usual seeds); a pose out of reach fails warm or cold, `give_up` counting the
usual seeds alone; the nearest kept solution against a brute-force scan; the record is
bounded; and the orchestrator's release search warm-starts only with `ik_warm` set. Poses
kept as out of reach (`FarPoses`): found by nearness and rule against a scan; a pose within
1 mm of one a whole search missed by 5 mm or more is missed by the whole search too (every
seed and the polish); the release search refuses it unsearched only with `ik_warm` and
`ik_reach_kept`.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import pytest

from cell.errors import IKFailed, InvalidInput
from cell.robot import ik_warm
from cell.robot.ik import AXIS_TOL_RAD, POSITION_TOL_M, IKNoSolution, ReleasePose, solve_ik
from cell.robot.ik_warm import FarPoses, WarmStarts
from cell.robot.model import load_robot
from tests.test_release_choice import JOB  # random layout 2's geometry (Panda)


def _fk_errors(robot: Any, q: np.ndarray, pose: ReleasePose) -> tuple[float, float]:
    """Position [m] and axis [rad] errors of q at `pose`, from forward kinematics only."""
    p, r = robot.tcp_pose(q)
    return float(np.linalg.norm(p - pose.position)), math.acos(min(1.0, float(r[:, 2] @ pose.axis)))


def _pairs(robot: Any, n: int, seed: int) -> list[tuple[ReleasePose, ReleasePose]]:
    """n pairs of poses reached by random configurations (the roll fixed at theirs) and
    the same nudged by up to 1.7 mm and about 0.4°."""
    rng = np.random.default_rng(seed)
    out = []
    for q in robot.random_configuration(rng, n):
        p, r = robot.tcp_pose(q)
        r0 = ReleasePose(p, r[:, 2]).rotation()
        roll = math.atan2(float(r[:, 0] @ r0[:, 1]), float(r[:, 0] @ r0[:, 0]))
        u = r[:, 2] + rng.normal(0.0, 0.004, 3)
        out.append(
            (ReleasePose(p, r[:, 2], roll), ReleasePose(p + rng.uniform(-1e-3, 1e-3, 3), u, roll))
        )
    return out


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_a_warm_search_reaches_its_pose_or_is_the_cold_one(name: str) -> None:
    robot = load_robot(name)
    lim = robot.limits
    rng = np.random.default_rng(5)
    missed = warm_won = 0
    for first, near in _pairs(robot, 40, seed=31):
        try:
            start = solve_ik(robot, first, robot.home).q
        except IKFailed:
            continue
        seed = robot.random_configuration(rng, 1)[0]  # the current configuration
        try:
            cold = solve_ik(robot, near, seed)
        except IKFailed:
            cold = None
        warm = solve_ik(robot, near, seed, warm=start)  # the warm start is a solution 1 mm off
        ep, ea = _fk_errors(robot, warm.q, near)
        assert ep <= POSITION_TOL_M and ea <= AXIS_TOL_RAD
        assert np.all(warm.q >= lim.lower) and np.all(warm.q <= lim.upper)
        missed += warm.seeds_tried > 1
        if warm.seeds_tried <= 2:  # the seed or the warm start converged: stopped at once
            warm_won += warm.seeds_tried == 2
        else:  # neither: the usual seeds' search, the same solution as cold
            assert cold is not None and warm.q.tobytes() == cold.q.tobytes()
    # the warm start converges where the seed misses
    assert missed >= 5 and warm_won >= 0.8 * missed


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_a_warm_start_that_misses_leaves_the_cold_search(name: str) -> None:
    """A warm start on the far side of the joint space (the solution of another pose):
    where it does not converge, the result is the cold search's, bit for bit."""
    robot = load_robot(name)
    lim = robot.limits
    checked = 0
    for pose, _ in _pairs(robot, 12, seed=41):
        far = np.where(np.arange(robot.dof) % 2 == 0, lim.lower, lim.upper) * 0.9
        seed = robot.home
        try:
            cold = solve_ik(robot, pose, seed)
        except IKFailed:
            continue
        warm = solve_ik(robot, pose, seed, warm=far)
        if cold.seeds_tried == 1:  # the seed converged: the warm start is never tried
            assert warm.q.tobytes() == cold.q.tobytes() and warm.seeds_tried == 1
        elif warm.seeds_tried > 2:
            assert warm.q.tobytes() == cold.q.tobytes()
            assert warm.seeds_tried == cold.seeds_tried + 1
        checked += 1
    assert checked >= 6


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_out_of_reach_fails_warm_or_cold(name: str) -> None:
    robot = load_robot(name)
    far = ReleasePose.from_angles(np.array([0.1, 0.0, 1.6]), 0.3, 0.0, 0.0)
    near_home = robot.home + 0.1
    with pytest.raises(IKNoSolution) as cold:
        solve_ik(robot, far, robot.home, give_up=(6, 30.0), polish=0)
    with pytest.raises(IKNoSolution) as warm:
        solve_ik(robot, far, robot.home, give_up=(6, 30.0), polish=0, warm=near_home)
    # the give-up rule counts the usual seeds: the warm start is one more
    assert "after 6 seeds" in str(cold.value) and "after 7 seeds" in str(warm.value)


def test_a_bad_warm_start_is_refused() -> None:
    robot = load_robot("panda")
    pose = ReleasePose.from_angles(np.array([0.4, 0.0, 0.5]), 0.3, 0.0)
    for bad in (np.zeros(3), np.full(robot.dof, np.nan)):
        with pytest.raises(InvalidInput, match="warm must be"):
            solve_ik(robot, pose, robot.home, warm=bad)


def test_the_nearest_kept_solution_against_a_scan(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(3)
    kept = WarmStarts()
    rows = []
    for _ in range(300):
        p = rng.uniform(-0.01, 0.01, 3)
        u = np.array([1.0, 0.0, 0.0]) + rng.normal(0.0, 0.02, 3)
        roll = [None, 0.0, math.pi][int(rng.integers(3))]
        pose = ReleasePose(p, u, roll)
        q = rng.normal(0.0, 1.0, 7)
        kept.add(pose, q)
        rows.append((pose, q))
    for _ in range(50):
        probe = ReleasePose(rng.uniform(-0.01, 0.01, 3), np.array([1.0, 0.0, 0.0]), 0.0)
        ref = rng.normal(0.0, 1.0, 7)
        near = [
            q
            for pose, q in rows
            if pose.roll == 0.0
            and np.linalg.norm(pose.position - probe.position) <= 4e-3
            and math.acos(min(1.0, float(pose.axis @ probe.axis))) <= math.radians(1.5)
        ]
        got = kept.near(probe, ref, 4e-3, math.radians(1.5))
        if not near:
            assert got is None
        else:
            want = min(near, key=lambda q: float(np.sum((q - ref) ** 2)))
            assert got is not None and got.tobytes() == want.tobytes()
    monkeypatch.setattr(ik_warm, "WARM_KEPT_MAX", 5)
    small = WarmStarts()
    for pose, q in rows[:12]:
        small.add(pose, q)
        assert 1 <= len(small) <= 5


@pytest.fixture(scope="module")
def orchestrator(orchestrator_on: Any) -> Any:
    return orchestrator_on(JOB, "ik-warm", cycle_search=True)


def test_the_release_search_warm_starts_only_when_asked(orchestrator: Any) -> None:
    """A release pose and one 1 mm from it, searched from a seed that misses both: with
    `ik_warm` the second starts from the first's solution (two seeds, not the usual
    search), and reaches its pose; without, nothing is kept as a warm start."""
    o = orchestrator
    robot = o.robot
    q_home = np.asarray(robot.home, float)
    p, r = robot.tcp_pose(q_home)
    pose = ReleasePose(p + np.array([0.06, 0.0, -0.02]), r[:, 2], 0.0)
    near = ReleasePose(pose.position + np.array([0.0, 8e-4, 0.0]), pose.axis, 0.0)
    lim = robot.limits
    seed = np.clip(q_home + np.array([2.0, -1.0, 1.5, -0.5, 2.0, 1.5, -2.0]), lim.lower, lim.upper)
    tuning = o.tuning
    try:
        for warm, expect_kept in ((None, 0), ((2e-3, math.radians(1.0)), 2)):
            o.tuning = dataclasses.replace(tuning, ik_warm=warm)
            o._ik_solved.clear()
            o._ik_memo.clear()
            o._ik_warm.clear()
            first = o._solve_ik(pose, seed, reach=True)
            second = o._solve_ik(near, seed, reach=True)
            assert len(o._ik_warm) == expect_kept
            ep, ea = _fk_errors(robot, second.q, near)
            assert ep <= POSITION_TOL_M and ea <= AXIS_TOL_RAD
            if warm is None:
                assert second.seeds_tried > 2 and first.seeds_tried > 2  # the seed misses
            else:
                assert second.seeds_tried == 2  # the warm start converged
                assert np.linalg.norm(second.q - first.q) < 0.05
    finally:
        o.tuning = tuning
        o._ik_solved.clear()
        o._ik_memo.clear()
        o._ik_warm.clear()


def test_far_poses_against_a_scan() -> None:
    rng = np.random.default_rng(4)
    kept = FarPoses()
    rows = []
    for k in range(200):
        pose = ReleasePose(rng.uniform(-0.01, 0.01, 3), np.array([0.0, 0.0, 1.0]), 0.0)
        rule = ["a", "b"][k % 2]
        kept.add(pose, rule, k)
        rows.append((pose, rule, k))
    copy = kept.copy()
    kept.add(ReleasePose(np.zeros(3), np.array([0.0, 0.0, 1.0]), 0.0), "a", -1)
    assert len(copy) == 200 and len(kept) == 201
    for _ in range(40):
        probe = ReleasePose(rng.uniform(-0.01, 0.01, 3), np.array([0.0, 0.0, 1.0]), 0.0)
        want = [
            k
            for pose, rule, k in rows
            if rule == "b" and np.linalg.norm(pose.position - probe.position) <= 3e-3
        ]
        assert copy.near(probe, "b", 3e-3, 0.01) == (want[0] if want else None)
    other_roll = ReleasePose(rows[0][0].position, rows[0][0].axis, math.pi)
    assert copy.near(other_roll, "a", 1.0, 1.0) is None


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_a_pose_near_one_missed_by_5_mm_is_missed(name: str) -> None:
    """Poses just beyond the arm's reach (a reached pose pushed 3 cm out from the base),
    missed by the release search's rule (`ik_give_up`, no polish) by 5 mm or more: the
    same pose moved by 1 mm and ~0.4° is missed by that search too, and where the whole
    search (every seed and the polish) misses the first, it misses the second."""
    robot = load_robot(name)
    rng = np.random.default_rng(8)
    checked = whole = 0
    for q in robot.random_configuration(rng, 60):
        p, r = robot.tcp_pose(q)
        out = p + 0.03 * p / np.linalg.norm(p)
        pose = ReleasePose(out, r[:, 2], 0.0)
        try:
            solve_ik(robot, pose, robot.home, give_up=(6, 30.0), polish=0)
            continue
        except IKNoSolution as exc:
            if exc.position_error_m < 5e-3:
                continue
        step = rng.normal(0.0, 1.0, 3)
        u = r[:, 2] + rng.normal(0.0, 0.004, 3)
        near = ReleasePose(out + 1e-3 * step / np.linalg.norm(step), u, 0.0)
        with pytest.raises(IKNoSolution):
            solve_ik(robot, near, robot.home, give_up=(6, 30.0), polish=0)
        try:
            solve_ik(robot, pose, robot.home)
        except IKNoSolution:
            with pytest.raises(IKNoSolution):
                solve_ik(robot, near, robot.home)
            whole += 1
        checked += 1
    assert checked >= 6 and whole >= 5


def test_the_release_search_refuses_a_pose_near_one_out_of_reach(
    orchestrator: Any, ik_solve_calls: Any
) -> None:
    o = orchestrator
    tuning = o.tuning
    far = ReleasePose.from_angles(np.array([0.1, 0.0, 1.5]), 0.3, 0.0, 0.0)  # beyond the Panda
    near = ReleasePose(far.position + np.array([6e-4, 0.0, 0.0]), far.axis, 0.0)
    seed = np.asarray(o.robot.home, float)
    try:
        for warm, searched in (((1e-3, math.radians(0.5)), 0), (None, 1)):
            o.tuning = dataclasses.replace(tuning, ik_warm=warm)
            o._ik_memo.clear()
            o._out_of_reach.clear()
            o._far_poses.clear()
            with pytest.raises(IKNoSolution) as first:
                o._release_ik(o.robot, far, seed)
            assert first.value.position_error_m >= tuning.ik_out_of_reach_m
            o._ik_memo.clear()  # the next decision
            ik_solve_calls.reset()
            with pytest.raises(IKNoSolution) as again:
                o._release_ik(o.robot, near, seed)
            assert ik_solve_calls.n == searched
            assert (again.value is first.value) == (searched == 0)
    finally:
        o.tuning = tuning
        o._ik_memo.clear()
        o._out_of_reach.clear()
        o._far_poses.clear()
