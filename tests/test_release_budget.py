"""`ArmTuning.release_budget`: a decision's release search stops timing candidates once it
has timed that many and holds a release the grip holds, keeping the soonest it timed; it
never stops before it has one. None (the default): every search as before.

Independent checks: the number of candidates timed (each counted as `_static_cycle_s` is
called), the estimate each timed candidate has (its cycle timed plus APPROACH_WEIGHT of
the approach from where the arm is, worked out here again), and the unbounded search.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import pytest

from tests.test_release_choice import JOB  # random layout 2's geometry (Panda)


@pytest.fixture(scope="module")
def orchestrator(orchestrator_on: Any) -> Any:
    return orchestrator_on(JOB, "budget", cycle_search=True)


def _watch(o: Any, timed: list[tuple[np.ndarray, float]]) -> None:
    """Record (release, estimate [s]) of every candidate `_release_search` times."""
    cycle, w = o._static_cycle_s, o.tuning.approach_weight

    def watched(obj: Any, plan: Any, stroke: float, q_rel: Any, over: Any) -> float:
        t = cycle(obj, plan, stroke, q_rel, over)
        # the pick in the frame the search set for this candidate (`_frame`)
        timed.append((np.array(q_rel), t + w * o._approach_s(o.q, over, stroke, obj)))
        return t

    o._static_cycle_s = watched


def _decide(o: Any, k: int, **tuning: Any) -> tuple[Any, list[tuple[np.ndarray, float]]]:
    spec = o.job.expanded_items()[k]
    o.present(k, spec.obj)
    kept = o.tuning
    timed: list[tuple[np.ndarray, float]] = []
    _watch(o, timed)
    o.tuning = dataclasses.replace(kept, **tuning)
    try:
        d = o.decide(k, spec.obj, o.job.bin(spec.bin))
    finally:
        o.__dict__.pop("_static_cycle_s", None)
        o.tuning = kept
        o.scene.remove_item(o._presented)
    return d, timed


def test_a_budget_never_spent_decides_as_none(orchestrator: Any) -> None:
    o = orchestrator
    free, timed_free = _decide(o, 1, release_budget=None)
    large, timed_large = _decide(o, 1, release_budget=10**6)
    assert free.plan == large.plan and free.stroke_m == large.stroke_m
    np.testing.assert_array_equal(free.state.q_release, large.state.q_release)
    assert [t for _, t in timed_free] == [t for _, t in timed_large]


def test_a_small_budget_stops_the_decision_early_with_a_throw_that_holds(
    orchestrator: Any,
) -> None:
    o = orchestrator
    free, timed_free = _decide(o, 1, release_budget=None)
    one, timed_one = _decide(o, 1, release_budget=1)
    assert len(timed_free) >= 3  # several candidates timed without a budget
    assert 1 <= len(timed_one) < len(timed_free)  # fewer with it: it is not ignored
    assert one.action == "throw"
    cost = one.state.choice.cost
    assert cost is not None and not cost[0] and math.isfinite(cost[1])  # one that holds
    # its release is one it timed, and no sooner than the unbounded search's choice
    assert any(np.array_equal(one.state.choice.q_release, q) for q, _ in timed_one)
    assert cost[1] >= free.state.choice.cost[1] - 1e-12


def test_the_search_keeps_the_soonest_it_timed(orchestrator: Any) -> None:
    """`_release_search` itself: with every candidate timed, the estimates E; with the
    budget b (the first b of them timed), the soonest of E[:b], at a b where that is not
    the last one timed; with the budget spent before the search, it still times until it
    has a release that holds, and times none where another plan's estimate is in hand."""
    o = orchestrator
    spec = o.job.expanded_items()[1]
    o.present(1, spec.obj)
    kept_tuning, kept_frame = o.tuning, o._frame
    timed: list[tuple[np.ndarray, float]] = []
    try:
        d = o.decide(1, spec.obj, o.job.bin(spec.bin))
        plan, stroke = d.plan, d.stroke_m
        centre = np.array([plan.x_m, plan.y_m, plan.z_m])
        tcp = o._tcp_for_item_centre(centre, plan.elevation_rad, plan.azimuth_rad, stroke, spec.obj)
        _watch(o, timed)

        def search(budget: int | None, spent: int = 0, beat: float | None = None) -> Any:
            timed.clear()
            o._timed_n = spent
            o.tuning = dataclasses.replace(kept_tuning, release_timed_max=0, release_budget=budget)
            return o._release_search(tcp, plan, stroke, spec.obj, beat)

        full = search(None)
        every = [t for _, t in timed]
        assert full is not None and not full[0][0] and len(every) >= 3
        # the least budget whose soonest candidate is not the last it times
        b = next(b for b in range(2, len(every)) if int(np.argmin(every[:b])) != b - 1)
        got = search(b)
        assert len(timed) == b  # stopped there
        assert got is not None and not got[0][0]
        i = int(np.argmin(every[:b]))
        assert got[0][1] == pytest.approx(every[i], abs=1e-9)
        np.testing.assert_array_equal(got[1], timed[i][0])
        # the budget spent already: the first that holds is timed and kept
        first = search(1, spent=10**6)
        assert len(timed) == 1 and first is not None and first[0][1] == pytest.approx(every[0])
        # ... unless a plan that holds is in hand elsewhere (`beat`): none timed
        none = search(1, spent=10**6, beat=1e6)
        assert timed == [] and none is not None and none[0] == (False, math.inf)
    finally:
        o.__dict__.pop("_static_cycle_s", None)
        o.tuning, o._frame = kept_tuning, kept_frame
        o.scene.remove_item(o._presented)
