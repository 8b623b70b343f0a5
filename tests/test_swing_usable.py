"""`_departure` asks `_swing` for the twist-free swing from each lift with the test its
route must pass (`usable`: it rises from the station and the grip holds it still); where
neither the swing nor the spline between its ends would pass, `_swing` does not weigh the
two against each other (`_direct_is_better`: a sphere's two carries planned).

Independent check: the same decisions, and the same cycle timed for every candidate, as
`_swing` weighing them everywhere (the search before); on the demo's spheres, whose
departures try lifts whose routes do not rise from the station.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

JOB = """\
cell: {robot: panda, ee: pybullet}
pick_station: {position_m: [0.45, -0.40, 0.20]}
bins:
  - {id: chute_2, position_m: [1.90, 0.80],  size_m: [0.30, 0.30], rim_height_m: 0.15}
  - {id: chute_3, position_m: [2.80, -0.70], size_m: [0.30, 0.30], rim_height_m: 0.15}
items:
  - {object: sphere40,  count: 1, bin: chute_3}
  - {object: sphere55,  count: 1, bin: chute_2}
policy: throw
seed: 0
"""


@pytest.fixture(scope="module")
def orchestrator(orchestrator_on: Any) -> Any:
    return orchestrator_on(JOB, "usable", cycle_search=True)


def _decide(o: Any, k: int, weigh_all: bool) -> tuple[Any, list[float], int]:
    """Item k's decision, the cycles timed, and how often the two were weighed."""
    spec = o.job.expanded_items()[k]
    o.present(k, spec.obj)
    cycles: list[float] = []
    weighed = [0]
    cycle, swing, direct = o._static_cycle_s, o._swing, o._direct_is_better

    def timed(*a: Any) -> float:
        cycles.append(cycle(*a))
        return cycles[-1]

    def swung(q_from: Any, q_end: Any, plan: Any, carried: Any = None, usable: Any = None) -> Any:
        return swing(q_from, q_end, plan, carried, None if weigh_all else usable)

    def weigh(*a: Any) -> bool:
        weighed[0] += 1
        return bool(direct(*a))

    o._static_cycle_s, o._swing, o._direct_is_better = timed, swung, weigh
    try:
        d = o.decide(k, spec.obj, o.job.bin(spec.bin))
    finally:
        for name in ("_static_cycle_s", "_swing", "_direct_is_better"):
            o.__dict__.pop(name, None)
        o.scene.remove_item(o._presented)
    return d, cycles, weighed[0]


def test_the_spheres_decide_as_when_every_swing_is_weighed(orchestrator: Any) -> None:
    o = orchestrator
    fewer = 0
    for k in (0, 1):
        before, t_before, n_before = _decide(o, k, weigh_all=True)
        after, t_after, n_after = _decide(o, k, weigh_all=False)
        assert after.action == before.action == "throw"
        assert after.plan == before.plan and after.stroke_m == before.stroke_m
        np.testing.assert_array_equal(after.state.q_release, before.state.q_release)
        assert t_after == t_before and len(t_after) >= 2  # every candidate timed the same
        assert n_after <= n_before
        fewer += n_before - n_after
    assert fewer > 0  # the spheres' departures try lifts neither route of which rises
