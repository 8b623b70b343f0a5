"""A throw's spot moved off a bin's centre (`cell.arm.spots.throw_spot`: the bin holds an
item there) can lie beyond the reach the job's check proved, which planned onto the centre
(`cell.arm.launch.check_sortable`). The planner then aims at the centre (`Planner._plan`)
instead of failing the item `unreachable`: test layout 1002 (Panda), whose two
`unseen_cuboid`s to bin_2, 2.97 m out, failed so with the spot moved 21 mm beyond (the bin
and the item are that layout's; `cell run` of it: 26 -> 29 of 33 in their bins)."""

from __future__ import annotations

import numpy as np
import pytest

from cell.arm.grip_side import holding_sides, throw_sides
from cell.arm.spots import throw_spot
from cell.errors import UnreachableTarget
from cell.jobs import parse_job
from cell.model.objects import ObjectParams
from cell.orchestrator import Orchestrator

CENTRE = (-2.541, 1.545)
JOB = """
cell: {robot: panda}
bins:
  - {id: bin_2, position_m: [-2.541, 1.545], size_m: [0.269, 0.306], rim_height_m: 0.246}
items:
  - {object: unseen_cuboid, bin: bin_2}
seed: 0
"""


def test_a_spot_beyond_the_proved_reach_is_given_up_for_the_bins_centre() -> None:
    orch = Orchestrator(parse_job(JOB, "reach.yaml"))
    try:
        sc, target = orch.scene, orch.job.bins[0]
        tile = ObjectParams("cuboid", 0.02, (0.05, 0.05, 0.012))  # resting at the centre
        item = sc.spawn_item(tile, position=(*CENTRE, sc.bin_spec("bin_2").wall + 0.007))
        sc.watch_until_rest(item)
        sc.keep(item)
        obj = orch.job.items[0].obj
        # the side the job's check proved (its first, held at 39 mm at most, reaches short)
        side = throw_sides(holding_sides(orch.params, obj), obj)[-1]
        spot = throw_spot(sc, "bin_2", obj)
        assert np.hypot(*spot) > np.hypot(*CENTRE)  # moved away from the arm
        with pytest.raises(UnreachableTarget):  # the spot itself: out of reach
            orch._plan_to((*spot, 0.246), side.obj, target, 0, side.stroke_max_m, None)
        choice = orch._plan(side.obj, target, 0, side.stroke_max_m)
    finally:
        orch.close()
    assert choice.goal is not None
    assert choice.goal == pytest.approx([*CENTRE, 0.246], abs=1e-9)
