"""With `cycle_search`, what makes the search cheaper must not change what it chooses: the
IK and the approaches remembered through a decision (`Orchestrator._solve_ik`,
`_release_ik`, `_approach_s`), and the candidates left out by a lower bound on their cycle
(`Orchestrator._cycle_bound_s`), timed soonest bound first across both rolls and against
what another release bounds' plan already has (`_release_search`, `_beat`).

Independent checks: the same decision made by the exhaustive search (every candidate
solved afresh and timed), the bound against every cycle the planner times and against
ruckig's jerk-limited move at the full limits (a second solver, which no rest-to-rest move
can beat by more than the bound allows), and the bound's closed form for one joint.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import pytest

from cell.arm.planner import ThrowChoice, soonest_of
from cell.arm.tuning import TUNING
from cell.orchestrator import Orchestrator
from cell.robot.ik import IKNoSolution, ReleasePose, solve_ik
from cell.robot.motion import move_time
from cell.robot.moving_release import COAST_S
from tests.test_release_choice import JOB  # random layout 2's geometry (Panda)


@pytest.fixture(scope="module")
def orchestrator(orchestrator_on: Any) -> Any:
    # the job's bin_0 has a low rim (0.05 m): its throws are planned in the steep bounds
    # first (`ArmTuning.steep_rim_m`, on as by default), whose plans are held to the
    # ordinary bounds' tests (`cell.arm.steep.steep_passes`)
    return orchestrator_on(JOB, "cost", cycle_search=True)


def _decide(
    o: Orchestrator, k: int, exhaustive: bool
) -> tuple[Any, list[tuple[float, float, float]]]:
    """Item k's decision, the arm at rest where it is; and (bound, tighter bound, cycle
    timed) [s] of every candidate the planner timed (`_cycle_bound_s`, `_way_bound_s`).
    `exhaustive`: every IK solved afresh, no candidate left out."""
    spec = o.job.expanded_items()[k]
    o.present(k, spec.obj)
    timed: list[tuple[float, float, float]] = []
    cycle, bound, way_bound = o._static_cycle_s, o._cycle_bound_s, o._way_bound_s

    def watched(obj: Any, plan: Any, stroke: float, q_rel: Any, over: Any = None) -> float:
        t = cycle(obj, plan, stroke, q_rel, over)
        over = over or o.over_item(o._presented, stroke, obj)
        back = o._approach_s(q_rel, over, stroke, obj)
        timed.append((bound(over[0], q_rel), way_bound(over[0], q_rel, back, 0.0), t))
        return t

    o._static_cycle_s = watched  # type: ignore[method-assign]
    kept = o.tuning
    # every candidate under the bound timed: the pruning alone (`release_timed_max`, which
    # may change the choice, is `test_the_search_times_only_the_soonest_bounded`'s; so is
    # `release_timed_max_lower`, in the lower release bounds)
    o.tuning = dataclasses.replace(kept, release_timed_max=0, release_timed_max_lower=None)
    if exhaustive:
        o._release_ik = lambda robot, pose, seed=None: solve_ik(robot, pose, seed)  # type: ignore[method-assign]
        o._cycle_bound_s = lambda q_pick, q_rel: -math.inf  # type: ignore[method-assign]
        o._way_bound_s = lambda *a: -math.inf  # type: ignore[method-assign]
    try:
        d = o.decide(k, spec.obj, o.job.bin(spec.bin))
    finally:
        for name in ("_static_cycle_s", "_release_ik", "_cycle_bound_s", "_way_bound_s"):
            o.__dict__.pop(name, None)
        o.tuning = kept
        o.scene.remove_item(o._presented)
    return d, timed


@pytest.mark.parametrize("k", [0, 1, 2])
def test_the_cheaper_search_chooses_as_the_exhaustive_one(orchestrator: Any, k: int) -> None:
    o = orchestrator
    full, timed_full = _decide(o, k, exhaustive=True)
    fast, timed_fast = _decide(o, k, exhaustive=False)
    assert fast.action == full.action == "throw"
    assert fast.plan == full.plan
    assert fast.stroke_m == full.stroke_m
    np.testing.assert_allclose(fast.state.q_release, full.state.q_release, atol=1e-12)
    # fewer cycles timed, never more
    assert len(timed_fast) <= len(timed_full), (timed_fast, timed_full)
    for b, tight, t in timed_full:
        assert b <= t, timed_full  # a lower bound on every cycle the planner times
        assert b <= tight <= t, timed_full  # and the tighter one between the two


def test_the_bound_is_under_ruckigs_moves_and_is_its_closed_form(orchestrator: Any) -> None:
    o = orchestrator
    lim = o.robot.limits
    rng = np.random.default_rng(3)
    for _ in range(20):
        q0, q1 = o.robot.random_configuration(rng, 2)
        each_way = (o._cycle_bound_s(q0, q1) - TUNING.settle_s - COAST_S) / 2
        # ruckig's rest-to-rest move at the full limits, jerk-limited: no quicker
        assert each_way <= move_time(q0, q1, o.robot) + 1e-9
        assert each_way <= move_time(q1, q0, o.robot) + 1e-9
    # one joint turned: 1 rad on the first, under the distance where it reaches full speed
    # (a triangle, 2√(d/a)) or over it (d/v + v/a)
    for d_rad in (0.05, 3.0):
        q0 = np.asarray(o.robot.home, float)
        q1 = q0.copy()
        q1[0] += d_rad if q0[0] + d_rad <= lim.upper[0] else -d_rad
        v, a = lim.velocity[0] * (1 + 1e-3), lim.acceleration[0] * (1 + 1e-3)
        if d_rad <= v * v / a:
            expected = 2 * math.sqrt(d_rad / a)
        else:
            expected = d_rad / v + v / a
        assert o._cycle_bound_s(q0, q1) == pytest.approx(2 * expected + TUNING.settle_s + COAST_S)


def test_a_release_out_of_reach_is_searched_once_per_decision(orchestrator: Any) -> None:
    o = orchestrator
    # 1.5 m up over the base: out of the Panda's reach (about 1.2 m from its shoulder)
    pose = ReleasePose.from_angles(np.array([0.1, 0.0, 1.5]), 0.3, 0.0, 0.0)
    o._ik_memo.clear()
    with pytest.raises(IKNoSolution) as first:
        o._release_ik(o.robot, pose, np.asarray(o.robot.home, float))
    assert first.value.position_error_m >= TUNING.ik_out_of_reach_m
    # from another seed: the same verdict, not searched again
    with pytest.raises(IKNoSolution) as again:
        o._release_ik(o.robot, pose, np.asarray(o.q, float) + 0.1)
    assert again.value is first.value
    # a pose in reach is solved as solve_ik solves it, and remembered as such
    q_home = np.asarray(o.robot.home, float)
    p, r = o.robot.tcp_pose(q_home)
    near = ReleasePose(p, r[:, 2], None)
    got = o._release_ik(o.robot, near, q_home)
    np.testing.assert_allclose(got.q, solve_ik(o.robot, near, q_home).q, atol=1e-12)
    assert o._release_ik(o.robot, near, q_home) is got


def test_a_release_that_cannot_beat_another_bounds_plan_is_not_timed(orchestrator: Any) -> None:
    """`_release_search` with `beat`: every candidate whose bound is not under it is left
    untimed; where that is all of them, the estimate (False, ∞), which `soonest_of` never
    prefers to a plan that has one; with `beat` just over the soonest cycle, that cycle."""
    o = orchestrator
    spec = o.job.expanded_items()[2]
    o.present(2, spec.obj)
    try:
        d = o.decide(2, spec.obj, o.job.bin(spec.bin))
        plan, stroke = d.plan, d.stroke_m
        centre = np.array([plan.x_m, plan.y_m, plan.z_m])
        tcp = o._tcp_for_item_centre(centre, plan.elevation_rad, plan.azimuth_rad, stroke, spec.obj)
        timed: list[float] = []
        cycle = o._static_cycle_s

        def watched(*a: Any) -> float:
            timed.append(cycle(*a))
            return timed[-1]

        o._static_cycle_s = watched  # type: ignore[method-assign]
        kept = o._frame
        try:
            full = o._release_search(tcp, plan, stroke, spec.obj, None)
            n_full = len(timed)
            timed.clear()
            none = o._release_search(tcp, plan, stroke, spec.obj, 0.0)
            assert timed == []  # nothing timed: no cycle is under 0 s
            assert full is not None and none is not None
            assert none[0] == (False, math.inf)
            assert not full[0][0]  # the soonest asks no more of the grip than it holds
            just = o._release_search(tcp, plan, stroke, spec.obj, full[0][1] + 1e-9)
            assert just is not None and just[0] == full[0]
            np.testing.assert_allclose(just[1], full[1], atol=1e-12)
            assert len(timed) <= n_full
        finally:
            o.__dict__.pop("_static_cycle_s", None)
            o._frame = kept
    finally:
        o.scene.remove_item(o._presented)
    first = ThrowChoice(full[0], plan, 0.0, full[1], None, np.zeros(3), spec.obj)
    pruned = dataclasses.replace(first, cost=none[0])
    assert soonest_of([first, pruned]) is first
    assert o._beat([first, pruned]) == full[0][1]


def test_the_search_times_only_the_soonest_bounded(orchestrator: Any) -> None:
    """`release_timed_max` k: of the candidates the full search times (soonest bound
    first), only the first k are; with k = 1 the release is the soonest-bounded
    candidate's, with its own timed estimate, whatever the others' would be; with k at
    least the number the full search times, the same choice as it."""
    o = orchestrator
    spec = o.job.expanded_items()[1]
    o.present(1, spec.obj)
    kept_tuning, kept_frame = o.tuning, o._frame
    cycle = o._static_cycle_s
    timed: list[tuple[Any, float]] = []

    def watched(obj: Any, plan: Any, stroke: float, q_rel: Any, over: Any = None) -> float:
        timed.append((np.array(q_rel), cycle(obj, plan, stroke, q_rel, over)))
        return timed[-1][1]

    try:
        d = o.decide(1, spec.obj, o.job.bin(spec.bin))
        plan, stroke = d.plan, d.stroke_m
        centre = np.array([plan.x_m, plan.y_m, plan.z_m])
        tcp = o._tcp_for_item_centre(centre, plan.elevation_rad, plan.azimuth_rad, stroke, spec.obj)
        o._static_cycle_s = watched  # type: ignore[method-assign]

        def search(k: int) -> Any:
            timed.clear()
            o.tuning = dataclasses.replace(kept_tuning, release_timed_max=k)
            return o._release_search(tcp, plan, stroke, spec.obj, None)

        full = search(0)
        every = list(timed)
        assert full is not None and len(every) >= 2  # a choice among several
        one = search(1)
        assert len(timed) == 1 and one is not None
        np.testing.assert_array_equal(one[1], every[0][0])  # the soonest-bounded
        approach = one[0][1] - every[0][1]  # the approach's weighted share, the same for both
        assert approach >= 0.0
        assert one[0][1] >= full[0][1]  # never sooner than the full search's choice
        same = search(len(every))
        assert same is not None and same[0] == full[0]
        np.testing.assert_array_equal(same[1], full[1])
        # `release_timed_max_lower`: in the lower release bounds only
        for lower, k in ((True, 1), (False, len(every))):
            timed.clear()
            o.tuning = dataclasses.replace(
                kept_tuning, release_timed_max=0, release_timed_max_lower=1
            )
            got = o._release_search(tcp, plan, stroke, spec.obj, None, lower)
            assert len(timed) == k and got is not None
            np.testing.assert_array_equal(got[1], (one if lower else full)[1])
    finally:
        o.__dict__.pop("_static_cycle_s", None)
        o.tuning, o._frame = kept_tuning, kept_frame
        o.scene.remove_item(o._presented)


def test_the_rank_bound_is_the_way_bound_and_no_looser(orchestrator: Any) -> None:
    """`_rank_bound_s`: with `release_rank_way` the way bound (the way back to the pick
    planned as `_static_cycle_s` plans it), never under the bang-bang rank it replaced,
    never over the cycle `_static_cycle_s` times; without it, the bang-bang rank."""
    o = orchestrator
    spec = o.job.expanded_items()[0]
    o.present(0, spec.obj)
    kept_tuning, kept_frame = o.tuning, o._frame
    try:
        d = o.decide(0, spec.obj, o.job.bin(spec.bin))
        plan, stroke, q_rel = d.plan, d.stroke_m, d.state.q_release
        o._frame = o._pick_frame(plan, q_rel)
        over = o.over_item(o._presented, stroke, spec.obj)
        w = kept_tuning.approach_weight
        o.tuning = dataclasses.replace(kept_tuning, release_rank_way=True)
        way = o._rank_bound_s(q_rel, over, (stroke, spec.obj), 0.4)
        back = o._approach_s(q_rel, over, stroke, spec.obj)
        assert way == o._way_bound_s(over[0], q_rel, back, 0.4)
        o.tuning = dataclasses.replace(kept_tuning, release_rank_way=False)
        bang = o._rank_bound_s(q_rel, over, (stroke, spec.obj), 0.4)
        assert bang == o._cycle_bound_s(over[0], q_rel) + w * 0.4
        assert bang <= way + 1e-12
        timed = o._static_cycle_s(spec.obj, plan, stroke, q_rel, over)
        assert way <= timed + w * 0.4 + 1e-9
    finally:
        o.tuning, o._frame = kept_tuning, kept_frame
        o.scene.remove_item(o._presented)
