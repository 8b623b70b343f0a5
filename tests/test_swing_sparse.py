"""A departure asks `_swing` for the twist-free swing from each lift with the test its route
must pass (`usable`); where the sparsest swing (SWING_WAYPOINTS) does not pass, nor the
spline between its ends, no denser swing is solved: the departure takes neither, and a
bottle's lifts had each solved the swing's IK at 2, 4 and 8 waypoints for nothing.

Independent check: each such call of a bottle's decision is recomputed here (the sparsest
swing solved again and tested), and counted: one swing solved in it.
"""

from __future__ import annotations

from typing import Any

import pytest

JOB = """\
cell: {robot: panda, ee: pybullet}
pick_station: {position_m: [0.45, -0.40, 0.20]}
bins:
  - {id: chute_2, position_m: [1.90, 0.80],  size_m: [0.30, 0.30], rim_height_m: 0.15}
items:
  - {object: o6_bottle,  count: 1, bin: chute_2}
policy: throw
seed: 0
"""


@pytest.fixture(scope="module")
def orchestrator(orchestrator_on: Any) -> Any:
    return orchestrator_on(JOB, "sparse", cycle_search=True)


def test_a_swing_neither_route_of_which_is_usable_is_solved_once(orchestrator: Any) -> None:
    o = orchestrator
    spec = o.job.expanded_items()[0]
    o.present(0, spec.obj)
    swing, chain = o._swing, o._swing_waypoints
    solved = [0]
    seen: list[tuple[bool, int]] = []

    def counted(*a: Any) -> Any:
        solved[0] += 1
        return chain(*a)

    def swung(q_from: Any, q_end: Any, plan: Any, carried: Any = None, usable: Any = None) -> Any:
        before = solved[0]
        out = swing(q_from, q_end, plan, carried, usable)
        n = solved[0] - before
        if usable is not None and out:
            first = chain(q_from, q_end, plan, o.tuning.swing_waypoints)
            neither = not usable(first) and not usable([])
            seen.append((neither, n))
        return out

    o._swing, o._swing_waypoints = swung, counted
    try:
        d = o.decide(0, spec.obj, o.job.bin(spec.bin))
    finally:
        for name in ("_swing", "_swing_waypoints"):
            o.__dict__.pop(name, None)
        o.scene.remove_item(o._presented)
    assert d.action == "throw"
    assert any(neither for neither, _ in seen), "no departure's lift without a usable route"
    assert all(n == 1 for neither, n in seen if neither)
