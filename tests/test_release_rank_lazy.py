"""`_release_search` ranks its candidates by a bound that plans the way back to the pick
(`_rank_bound_s` with `release_rank_way`), worked out only where a candidate might be
ranked before those taken so far (`cell.arm.release._Ranked`, by `_rank_floor_s`).

Independent checks: the lazy order against Python's sort of every candidate's bound
(random candidates, some without a bound); the floor against the planned bound on
sampled releases of a real layout; and the search's choice against the same search
with every bound worked out first (the eager ranking it replaced).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

import cell.arm.release as release_mod
from cell.errors import IKFailed, TrajectoryError
from tests.test_release_choice import JOB  # random layout 2's geometry (Panda)


def _candidates(rng: np.random.Generator, n: int) -> tuple[list[Any], dict[int, float | None]]:
    """n candidates (floor, order, roll, q, over, approach) and their bounds (None:
    raises), each bound at least its floor, ties among bounds and floors included."""
    cands, bounds = [], {}
    for k in range(n):
        floor = float(rng.integers(0, 6)) / 2
        bound = floor + float(rng.integers(0, 4)) / 2
        bounds[k] = None if rng.random() < 0.2 else bound
        cands.append((floor, k, 0.0, np.full(3, k, float), None, 0.0))
    return cands, bounds


def test_the_lazy_ranking_is_the_sort_of_every_bound() -> None:
    rng = np.random.default_rng(7)
    for _ in range(300):
        cands, bounds = _candidates(rng, int(rng.integers(1, 9)))
        worked: list[int] = []

        def exact(
            c: Any, bounds: dict[int, float | None] = bounds, worked: list[int] = worked
        ) -> float:
            worked.append(c[1])
            b = bounds[c[1]]
            if b is None:
                raise (IKFailed if c[1] % 2 else TrajectoryError)("no way back")
            return b

        eager = sorted(
            ((b, *c[1:]) for c in cands if (b := bounds[c[1]]) is not None), key=lambda c: c[:2]
        )
        ranked = release_mod._Ranked(cands, exact)
        got = list(ranked)
        assert [(c[0], c[1]) for c in got] == [(c[0], c[1]) for c in eager]
        assert len(worked) == len(set(worked))  # each bound worked out once
        if eager:  # the first candidate ranked in the search's own order
            first = next(c for c in cands if bounds[c[1]] is not None)
            assert ranked.first()[1] == first[1]
            assert ranked.first()[0] == bounds[first[1]]
        # taking only the first: bounds worked out only where the floor is not above it
        worked.clear()
        ranked = release_mod._Ranked(cands, exact)
        head = next(iter(ranked), None)
        if head is not None:
            for k in worked:
                c = cands[k]
                assert (c[0], c[1]) <= (head[0], head[1])


@pytest.fixture(scope="module")
def orchestrator(orchestrator_on: Any) -> Any:
    return orchestrator_on(JOB, "lazy", cycle_search=True)


def test_the_floor_is_under_the_planned_rank_bound(orchestrator: Any) -> None:
    """On 40 sampled releases (random configurations and the decision's own) of each
    item, with the grip in the chosen frame: `_rank_floor_s` <= `_rank_bound_s`, with
    `release_rank_way` and without (then equal)."""
    o = orchestrator
    kept_tuning, kept_frame = o.tuning, o._frame
    rng = np.random.default_rng(11)
    compared = 0
    for k in (0, 1):
        spec = o.job.expanded_items()[k]
        o.present(k, spec.obj)
        try:
            d = o.decide(k, spec.obj, o.job.bin(spec.bin))
            o._frame = o._pick_frame(d.plan, d.state.q_release)
            over = o.over_item(o._presented, d.stroke_m, spec.obj)
            qs = [d.state.q_release, *o.robot.random_configuration(rng, 39)]
            for q_rel in qs:
                for way in (True, False):
                    o.tuning = dataclasses.replace(kept_tuning, release_rank_way=way)
                    floor = o._rank_floor_s(q_rel, over, 0.3)
                    try:
                        bound = o._rank_bound_s(q_rel, over, (d.stroke_m, spec.obj), 0.3)
                    except (IKFailed, TrajectoryError):
                        continue
                    assert floor <= bound, (way, floor, bound)
                    if not way:
                        assert floor == bound
                    compared += 1
        finally:
            o.tuning, o._frame = kept_tuning, kept_frame
            o.scene.remove_item(o._presented)
    assert compared >= 60


class _Eager(release_mod._Ranked):
    """The ranking before: every candidate's bound worked out as it is found (in the search's
    loop over rolls and seeds, the grip in that roll's frame: `_rank_floor_s` made the
    bound itself, None where there is none), then sorted."""

    def __init__(self, cands: list[Any], exact: Any) -> None:
        self._cands = cands

    def __iter__(self) -> Any:
        ranked = [c for c in self._cands if c[0] is not None]
        yield from sorted(ranked, key=lambda c: c[:2])

    def first(self) -> Any:
        return next(c for c in self._cands if c[0] is not None)


def _bound_as_found(o: Any, stroke_obj: list[Any]) -> Any:
    """A `_rank_floor_s` that works out the rank bound itself (the stroke and object of
    the search under way in `stroke_obj`), None where it raises."""

    def floor(q_rel: Any, over: Any, approach_s: float) -> float | None:
        try:
            return float(o._rank_bound_s(q_rel, over, tuple(stroke_obj), approach_s))
        except (IKFailed, TrajectoryError):
            return None

    return floor


@pytest.mark.parametrize("k", [0, 1, 2])
def test_the_search_chooses_as_with_every_bound_worked_out(
    orchestrator: Any, k: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The decision and every release search in it (each facing's, each release bounds')
    the same with the lazy ranking as with the eager one, and the lazy one plans no more
    ways back."""
    o = orchestrator
    spec = o.job.expanded_items()[k]
    searches: list[Any] = []
    search = o._release_search

    stroke_obj: list[Any] = [0.0, None]

    def watched(*a: Any) -> Any:
        stroke_obj[:] = [a[2], a[3]]  # (tcp, plan, stroke, obj, beat)
        got = search(*a)
        searches.append(None if got is None else (got[0], np.array(got[1]), o._release_room_s))
        return got

    runs, plans = [], []
    for ranking in (release_mod._Ranked, _Eager):
        monkeypatch.setattr(release_mod, "_Ranked", ranking)
        o.present(k, spec.obj)
        searches.clear()
        count = o._approach_s
        calls = [0]

        def counted(*a: Any, count: Any = count, calls: list[int] = calls) -> float:
            calls[0] += 1
            return count(*a)

        o._release_search = watched  # type: ignore[method-assign]
        o._approach_s = counted  # type: ignore[method-assign]
        if ranking is _Eager:
            o._rank_floor_s = _bound_as_found(o, stroke_obj)  # type: ignore[method-assign]
        try:
            d = o.decide(k, spec.obj, o.job.bin(spec.bin))
        finally:
            o.__dict__.pop("_release_search", None)
            o.__dict__.pop("_approach_s", None)
            o.__dict__.pop("_rank_floor_s", None)
            o.scene.remove_item(o._presented)
        runs.append((d, list(searches)))
        plans.append(calls[0])
    (lazy, s_lazy), (eager, s_eager) = runs
    assert lazy.action == eager.action == "throw"
    assert lazy.plan == eager.plan and lazy.stroke_m == eager.stroke_m
    np.testing.assert_array_equal(lazy.state.q_release, eager.state.q_release)
    assert len(s_lazy) == len(s_eager) >= 2
    for a, b in zip(s_lazy, s_eager, strict=True):
        assert (a is None) == (b is None)
        if a is not None:
            assert a[0] == b[0] and a[2] == b[2]
            np.testing.assert_array_equal(a[1], b[1])
    assert plans[0] <= plans[1]
