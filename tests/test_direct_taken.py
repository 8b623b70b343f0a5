"""A sphere's throw carry takes the spline between the level swing's ends wherever it turns
the grip no more off one rotation than the swing (`cell.arm.joints.twist`) and asks no more
of the grip at rest (`_swing_static`), without planning the two carries to weigh which is
sooner (`_direct_is_better`): planning both was the tail of the level items' planning time.

Independent check: each comparison of a sphere's decision is recomputed here from the twist
and the grip's use at rest, and no carry is planned inside it.
"""

from __future__ import annotations

from typing import Any

import pytest

from cell.arm.joints import twist

JOB = """\
cell: {robot: panda, ee: pybullet}
pick_station: {position_m: [0.45, -0.40, 0.20]}
bins:
  - {id: chute_2, position_m: [1.90, 0.80],  size_m: [0.30, 0.30], rim_height_m: 0.15}
items:
  - {object: sphere55,  count: 1, bin: chute_2}
policy: throw
seed: 0
"""


@pytest.fixture(scope="module")
def orchestrator(orchestrator_on: Any) -> Any:
    return orchestrator_on(JOB, "direct", cycle_search=True)


def test_the_direct_carry_is_taken_where_it_turns_and_asks_no_more(orchestrator: Any) -> None:
    o = orchestrator
    spec = o.job.expanded_items()[0]
    o.present(0, spec.obj)
    seen: list[tuple[bool, bool, int]] = []
    direct, carry = o._direct_is_better, o._carry_path
    inside = [False]
    planned = [0]

    def counted(*a: Any, **k: Any) -> Any:
        planned[0] += inside[0]
        return carry(*a, **k)

    def weigh(route: Any, most: float, held: Any, plan: Any) -> bool:
        inside[0], before = True, planned[0]
        try:
            got = bool(direct(route, most, held, plan))
        finally:
            inside[0] = False
        ends = [route[0], route[-1]]
        n = o.tuning.swing_check_samples
        should = twist(o.robot, ends, n) <= twist(o.robot, route, n)
        should = should and o._swing_static(ends, held, plan.elevation_rad)[0] <= most
        seen.append((got, should, planned[0] - before))
        return got

    o._direct_is_better, o._carry_path = weigh, counted
    try:
        d = o.decide(0, spec.obj, o.job.bin(spec.bin))
    finally:
        for name in ("_direct_is_better", "_carry_path"):
            o.__dict__.pop(name, None)
        o.scene.remove_item(o._presented)
    assert d.action == "throw"
    assert seen, "no level swing weighed against the spline between its ends"
    assert all(got == should for got, should, _ in seen)
    assert all(n == 0 for _, _, n in seen)  # no carry planned to weigh them
    assert sum(got for got, _, _ in seen) >= 1
