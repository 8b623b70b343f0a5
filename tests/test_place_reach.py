"""A place into a bin whose middle the arm does not reach, but its near side it does.

Random layout 3's bin_3 (UR5): 0.87 m from the base, 0.38 x 0.37 m, a 0.089 m rim. Placed
pointing down, a 200 mm bottle's TCP is 0.30 m up: the UR5 misses the bin's centre by 40 mm
there. The eight best place spots (`cell.arm.spots.place_spots`: clear, nearest the centre) are
all beyond its reach; the spots nearest the base, then, are tried as well
(`Orchestrator.spots_to_try`). Checked in the scene: the bottle at rest in its bin, and a
spot nearer the base than the centre by more than the reach it was missed by."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from cell.arm.tuning import TUNING
from cell.orchestrator import Orchestrator
from tests.job_rows import job_rows

JOB = """\
cell: {robot: ur5, ee: pybullet}
bins:
  - {id: bin_3, position_m: [0.843, 0.23], size_m: [0.383, 0.372], rim_height_m: 0.089}
items:
  - {object: o6_bottle, count: 1, bin: bin_3}
policy: place
seed: 3
"""


def test_a_bin_beyond_reach_at_its_middle_is_placed_into_on_its_near_side(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    tried_m: list[float] = []  # the spots tried, from the base [m]

    class Watched(Orchestrator):
        def spots_to_try(self, spots, floor_z):  # type: ignore[no-untyped-def]
            out = super().spots_to_try(spots, floor_z)
            assert len(out) <= 2 * TUNING.place_spots_tried
            assert (
                out[: TUNING.place_spots_tried] == spots[: TUNING.place_spots_tried]
            )  # the best ones first
            tried_m.extend(math.hypot(x, y) for x, y, _ in out)
            return out

    assert job_rows(JOB, tmp_path, "place-reach", Watched) == [("place", "", True)]
    centre = math.hypot(0.843, 0.23)
    assert min(tried_m) < centre - 0.04  # nearer the base than the centre was missed by
