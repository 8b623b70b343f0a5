"""A tall item carried to its release: the 200 mm bottle (o6_bottle, 150 g, its centre of
mass 85 mm above the pads' patch) on random layout 5's UR5 geometry.

Before the grip counted the tilt about y (`cell.robot.carry`: its weight on a pad tips it
out) and the route kept it (`Orchestrator._swing_holds`, `_release_branch`,
`_steep_enough`), two of these three bottles left the pads on the carry: the release
re-solved from the pick came out on the other IK branch, its swing rolled the grip 50°,
and the bottle was released at 25°, where its weight on a pad asks 0.97 of the grip.

Independent check: the scene's physics, the bottles at rest in their bin."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.job_rows import job_rows

JOB = """\
cell: {robot: ur5, ee: pybullet}
bins:
  - {id: bin_0, position_m: [-1.049, -0.046], size_m: [0.303, 0.328], rim_height_m: 0.293}
  - {id: bin_1, position_m: [-1.105, -1.357], size_m: [0.308, 0.324], rim_height_m: 0.272}
  - {id: bin_2, position_m: [-0.079, -2.962], size_m: [0.314, 0.362], rim_height_m: 0.119}
  - {id: bin_3, position_m: [-0.203, 1.36], size_m: [0.287, 0.278], rim_height_m: 0.293}
items:
  - {object: o6_bottle, count: 3, bin: bin_3}
policy: auto
seed: 5
"""


def test_tall_bottles_stay_in_the_grip_and_land(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.chdir(tmp_path)
    rows = job_rows(JOB, tmp_path, "tall")
    assert rows == [("throw", "", True)] * 3, rows
