"""A throw into a bin with a low rim comes down steeply (`cell.arm.steep.steep_tiers`,
`ArmTuning.steep_rim_m`, `steep_elevation_rad`).

On tune layout 14 (Panda) three 72 mm, 66 g cylinders (`item4_cylinder`, 53.5 mm tall)
thrown 2.3 m into an empty bin with a 0.05 m rim landed within 0.03 m of its centre,
coming down at 50-57°, and skipped off its floor over the far rim (2.2 of their 2.9 m/s
across kept, their centres rising to 0.11-0.13 m). Thrown with the axis 60° up or more
they come down at about 70° and stay. Independent check: the scene's physics (where the
item comes to rest), with the rule and without it.
"""

from __future__ import annotations

import dataclasses

from cell.arm.steep import steep_tiers
from cell.arm.tuning import TUNING
from cell.jobs import parse_job
from cell.optimize.bounds import ThrowBounds
from cell.orchestrator import Orchestrator

JOB = """\
cell: {robot: panda, ee: pybullet}
bins:
  - {id: bin_5, position_m: [-1.292, -1.942], size_m: [0.322, 0.263], rim_height_m: 0.05}
items:
  - {shape: cylinder, mass_kg: 0.0658, size_m: [0.0723, 0.0723, 0.0535], bin: bin_5}
seed: 14
"""


def _tiers(rim_m: float) -> tuple[tuple[list[ThrowBounds], bool], ...]:
    b = ThrowBounds()
    ordinary = [b] + [
        dataclasses.replace(b, elevation_max=e, release_height=h)
        for e, h in TUNING.release_fallbacks
    ]
    shrunk = [dataclasses.replace(x, release_radius=0.3) for x in ordinary]
    return steep_tiers(TUNING, rim_m, ordinary, shrunk)


def test_a_low_rim_is_thrown_at_steeply_first_and_a_higher_one_as_before() -> None:
    steep = _tiers(0.05)
    assert [first for _, first in steep] == [False, True]
    for tier, _ in steep:
        # the fallbacks (45° and 30° at most) cannot throw so steeply: left out
        assert len(tier) == 1
        assert tier[0].elevation_min == TUNING.steep_elevation_rad
        assert tier[0].elevation_max == ThrowBounds().elevation_max
    assert _tiers(TUNING.steep_rim_m) == ()
    assert _tiers(0.2) == ()


def _thrown(tuning: object) -> tuple[bool, float]:
    orch = Orchestrator(parse_job(JOB, "cylinder.yaml"), tuning=tuning)  # type: ignore[arg-type]
    try:
        (r,) = orch.run().results
    finally:
        orch.close()
    assert r.action == "throw", r
    return bool(r.in_bin), float(r.landing_error_m)


def test_the_cylinder_that_skipped_out_of_a_low_rim_stays_in_thrown_steeply() -> None:
    in_bin, err = _thrown(dataclasses.replace(TUNING, steep_rim_m=0.0))  # the rule off
    assert not in_bin and err < 0.03, err  # landed on the aim and left: the skip
    in_bin, err = _thrown(TUNING)
    assert in_bin, err
