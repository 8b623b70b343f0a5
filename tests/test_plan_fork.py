"""Planning on a second process (`cell.arm.fork`): a decision's turned facing, or its last
lower release bounds, searched in a forked child while the parent searches the rest.

Independent checks: the serial path's decisions (`plan_workers=1`, the same orchestrator's
code without a fork) item by item, bit for bit; what the child's process does, seen from
outside it (its error's type and message, its BLAS threads as threadpoolctl reports them,
whether its process id is still in the process table after the join).
"""

from __future__ import annotations

import logging
import os
import signal
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cell.errors import IKFailed, InvalidInput
from cell.robot.ik_pose import ReleasePose

# the demo's cell and its three far bins, with three of its items: no mesh or sphere to
# probe as the job is loaded
DEMO = """\
cell: {robot: panda, ee: pybullet}
pick_station: {position_m: [0.45, -0.40, 0.20]}
bins:
  - {id: chute_1, position_m: [1.40, 0.00],  size_m: [0.30, 0.30], rim_height_m: 0.15}
  - {id: chute_2, position_m: [1.90, 0.80],  size_m: [0.30, 0.30], rim_height_m: 0.15}
  - {id: chute_3, position_m: [2.80, -0.70], size_m: [0.30, 0.30], rim_height_m: 0.15}
items:
  - {object: cube50, count: 1, bin: chute_1}
  - {object: cube30, count: 1, bin: chute_3}
  - {object: cuboid_b, count: 1, bin: chute_1}
seed: 0
"""


@pytest.fixture(scope="module")
def pair(orchestrator_on: Any) -> tuple[Any, Any]:
    """The demo's orchestrators planning serially and on two processes."""
    return (
        orchestrator_on(DEMO, "serial", plan_workers=1),
        orchestrator_on(DEMO, "forked", plan_workers=2),
    )


def _decide(o: Any, k: int, q: np.ndarray) -> Any:
    """The decision of the demo's item k with the arm at q [rad]."""
    spec = o.job.expanded_items()[k]
    o.q = q
    o.present(k, spec.obj)
    try:
        return o.decide(k, spec.obj, o.job.bin(spec.bin))
    finally:
        o.scene.remove_item(o._presented)


def test_the_forked_decisions_are_the_serial_ones(pair: tuple[Any, Any]) -> None:
    """A cube50 to chute_1 (the turned facing forked and kept), a cube30 to chute_3 (no
    turned facing: its last lower bounds forked) and a cuboid_b to chute_1 (the turned facing
    forked and not kept), each planned from the previous one's release as a run would:
    the same plans, releases and estimates, bit for bit."""
    serial, forked = pair
    q = np.asarray(serial.scene.ready_q, float)
    facings = []
    for k in (0, 1, 2):
        used = forked.fork_stats.used
        a, b = _decide(serial, k, q), _decide(forked, k, q.copy())
        assert forked.fork_stats.used == used + 1  # its branch was searched in a child
        assert (a.action, a.stroke_m, a.plan) == (b.action, b.stroke_m, b.plan)
        ca, cb = a.state.choice, b.state.choice
        assert (ca.cost, ca.bounds, ca.held, ca.delta) == (cb.cost, cb.bounds, cb.held, cb.delta)
        np.testing.assert_array_equal(a.state.q_release, b.state.q_release)
        np.testing.assert_array_equal(ca.goal, cb.goal)
        facings.append((ca.bounds.facing_rad is None, ca.bounds.release_height))
        _same_planned_moves(serial, forked)
        q = np.asarray(a.state.q_release, float)
    # what the items stand for: the turned facing kept once, the bin faced twice (the
    # cube30 in the cell's bounds, where the forked lower bounds were not kept)
    assert [f for f, _ in facings] == [False, True, True]
    assert facings[1][1] == serial.bounds.release_height
    assert forked.fork_stats.serial == {} and serial.fork_stats.forked == 0
    # what the child's IK searches left is replayed in the parent: the poses out of reach
    # kept for later decisions are the serial path's
    assert set(forked._out_of_reach) == set(serial._out_of_reach)
    assert len(forked._far_poses) == len(serial._far_poses)


def _same_planned_moves(serial: Any, forked: Any) -> None:
    """The moves the serial path's decision planned and keeps for the item's pick and carry
    (`Mover._planned`'s memo, toppra's carries and paths) are kept in the forked parent too,
    those of the child's branch sent back (`PlanFork._memo_merge`), the same trajectories:
    the pick and carry then plan none again. (A ruckig move cannot be pickled: planned
    again where needed, the same move.)"""
    ts = np.linspace(0.0, 5.0, 41)
    kept = 0
    for key, a in serial._plan_memo.items():
        if getattr(a, "kind", "") != "toppra":
            continue
        if key not in forked._plan_memo:
            pytest.fail(f"a {key[0]} move the serial path planned is not kept after the join")
        b = forked._plan_memo[key]
        assert a.duration == b.duration
        for x, y in zip(a.sample_many(ts), b.sample_many(ts), strict=True):
            np.testing.assert_array_equal(x, y)
        kept += 1
    assert kept  # the check checks something


def test_a_childs_error_comes_back_as_the_same_error(pair: tuple[Any, Any]) -> None:
    o = pair[1]

    def fails(exc: Exception) -> Any:
        raise exc

    for exc in (IKFailed("no configuration within tolerance"), ZeroDivisionError("a bug")):
        child = o._fork_branch(lambda exc=exc: fails(exc))
        assert child is not None
        with pytest.raises(type(exc), match=str(exc)):
            o._fork_join(child, lambda: pytest.fail("searched in the parent"))
        with pytest.raises(ChildProcessError):  # reaped: no zombie left
            os.waitpid(child.pid, os.WNOHANG)


def test_the_child_plans_on_one_blas_thread(pair: tuple[Any, Any]) -> None:
    from threadpoolctl import threadpool_info, threadpool_limits

    o = pair[1]
    with threadpool_limits(limits=1):
        child = o._fork_branch(lambda: [p["num_threads"] for p in threadpool_info()])
        assert child is not None
        threads = o._fork_join(child, lambda: pytest.fail("searched in the parent"))
    assert threads and set(threads) == {1}


@pytest.mark.parametrize("how", ["hangs", "is killed"])
def test_a_child_that_hangs_or_dies_is_reaped_and_its_branch_searched_here(
    pair: tuple[Any, Any], monkeypatch: pytest.MonkeyPatch, caplog: Any, how: str
) -> None:
    import cell.arm.fork as fork

    o = pair[1]
    monkeypatch.setattr(fork, "FORK_TIMEOUT_S", 0.5)

    def branch() -> str:
        if how == "hangs":
            time.sleep(60.0)
        else:
            os.kill(os.getpid(), signal.SIGKILL)
        return "the child's"

    before = dict(o.fork_stats.serial)
    child = o._fork_branch(branch)
    assert child is not None
    t0 = time.monotonic()
    with caplog.at_level(logging.INFO, logger="cell.arm.fork"):
        assert o._fork_join(child, lambda: "the parent's") == "the parent's"
    assert time.monotonic() - t0 < 5.0
    why = "timeout" if how == "hangs" else "unreadable"
    assert o.fork_stats.serial.get(why, 0) == before.get(why, 0) + 1
    assert "searched in the parent" in caplog.text
    with pytest.raises(ProcessLookupError):  # killed and reaped: no orphan, no zombie
        os.kill(child.pid, 0)


def test_branches_asking_ik_of_near_poses_are_searched_serially(pair: tuple[Any, Any]) -> None:
    """`_fork_conflict`: a child whose release poses are within `ik_warm` (1 mm, 0.5°) of
    the parent branch's, at the same roll, or the same pose, may have searched otherwise
    than the serial path (warm starts, poses out of reach): its answer is not used."""
    o = pair[1]
    base = ReleasePose.from_angles(np.array([0.5, 0.1, 0.8]), 0.6, 0.3, 0.0)

    def ask(pose: Any, reach: bool = True) -> tuple[Any, ...]:
        where = (pose.position.tobytes(), pose.axis.tobytes(), repr(pose.roll).encode())
        return ("ask", (*where, b""), where, pose if reach else None)

    def moved(dx: float, roll: float = 0.0) -> Any:
        return ReleasePose.from_angles(base.position + [dx, 0.0, 0.0], 0.6, 0.3, roll)

    assert o._fork_conflict([ask(base)], [ask(moved(0.01))], False) == ""
    assert o._fork_conflict([ask(base)], [ask(moved(0.0005))], False).startswith("near")
    assert o._fork_conflict([ask(base)], [ask(moved(0.0005, roll=np.pi))], False) == ""
    assert o._fork_conflict([ask(base, False)], [ask(base)], False).startswith("shared")
    assert o._fork_conflict([ask(base)], [ask(base, False)], False).startswith("shared")
    assert o._fork_conflict([ask(base, False)], [ask(base, False)], False) == ""
    assert o._fork_conflict([], [], True).startswith("stepped")


def test_plan_workers_are_checked(monkeypatch: pytest.MonkeyPatch) -> None:
    from cell.arm.fork import PLAN_WORKERS_ENV, check_plan_workers

    assert check_plan_workers(1) == 1 and check_plan_workers(2) == 2
    with pytest.raises(InvalidInput, match="give 1"):
        check_plan_workers(3)
    monkeypatch.setenv(PLAN_WORKERS_ENV, "2")
    assert check_plan_workers(None) == 2
    monkeypatch.setenv(PLAN_WORKERS_ENV, "many")
    with pytest.raises(InvalidInput, match=r"\$CELL_PLAN_WORKERS='many'"):
        check_plan_workers(None)


@pytest.mark.parametrize("tuning", [{"release_budget": 3}, {"release_lower_room_s": 0.5}])
def test_no_fork_where_a_branch_depends_on_the_other(
    pair: tuple[Any, Any], tuning: dict[str, Any]
) -> None:
    """A work budget counts the candidates of every branch; with `release_lower_room_s`,
    whether a facing's lower bounds are searched depends on its plan in the cell's bounds
    as the other facing's estimate pruned it: the serial path then."""
    import dataclasses

    o = pair[1]
    kept = o.tuning
    o.tuning = dataclasses.replace(kept, **tuning)
    try:
        assert o._fork_branch(lambda: 1) is None
    finally:
        o.tuning = kept
    child = o._fork_branch(lambda: 1)
    assert child is not None and o._fork_join(child, lambda: 0) == 1


def test_a_child_ends_with_its_parent(pair: tuple[Any, Any]) -> None:
    """A parent killed mid-decision leaves no child planning on: the child of a process
    that is killed is killed too (PR_SET_PDEATHSIG)."""
    o = pair[1]
    r, w = os.pipe()
    middle = os.fork()
    if middle == 0:  # a parent that forks a branch and is killed before the join
        os.close(r)
        child = o._fork_branch(lambda: time.sleep(60.0))
        os.write(w, str(child.pid if child else -1).encode())
        os.close(w)
        time.sleep(60.0)
        os._exit(0)
    os.close(w)
    pid = int(os.read(r, 64).decode())
    os.close(r)
    assert pid > 0
    os.kill(middle, signal.SIGKILL)
    os.waitpid(middle, 0)
    deadline = time.monotonic() + 20.0  # at once where it works; a loaded machine's slack
    while time.monotonic() < deadline:
        try:  # the grandchild is not ours to reap: gone, or a zombie of init's
            state = Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0]
        except FileNotFoundError:
            break
        if state == "Z":
            break
        time.sleep(0.05)
    else:
        os.kill(pid, signal.SIGKILL)
        pytest.fail(f"the child {pid} of a killed parent still runs")
