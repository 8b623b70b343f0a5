"""A throw's carry goes to the release configuration the decision costed.

Random layout 0 (Panda): a 70 mm, 60 g cylinder (o2_cylinder35) thrown into a bin 1.26 m
out with a 0.051 m rim. The decision (`Orchestrator._release_costs`) timed the release on
one IK branch; the carry re-solved it from the lift pose onto the other. Whose swing asked
0.97 of the grip at rest, more than the carry's bound (0.741), so the whole carry went at
30 % of the limits (`cell.robot.carry.GENTLE_SCALE`): 5.8 s against the 3.2 s timed.
`_release_branch` kept the costed branch only where the level swing itself was beyond
the bound; the spline between the swing's waypoints is not the level swing.

Checked: where the arm is when the latch opens, against the configuration the decision
timed, and the scene's physics (the cylinder at rest in its bin)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cell.decision import Decision
from cell.orchestrator import Orchestrator
from tests.job_rows import job_rows

JOB = """\
cell: {robot: panda, ee: pybullet}
bins:
  - {id: bin_0, position_m: [2.944, 0.757], size_m: [0.292, 0.314], rim_height_m: 0.133}
  - {id: bin_4, position_m: [0.366, 1.207], size_m: [0.256, 0.273], rim_height_m: 0.051}
items:
  - {object: o2_cylinder35, count: 1, bin: bin_4}
policy: auto
seed: 0
"""


def test_the_carry_goes_to_the_release_branch_the_decision_timed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    at_release: list[float] = []

    class Watched(Orchestrator):
        def release(self, d: Decision) -> np.ndarray | None:
            if d.action == "throw":
                gap = np.abs(np.asarray(self.q) - np.asarray(d.state.q_release))
                at_release.append(float(gap.max()))
            return super().release(d)

    rows = job_rows(JOB, tmp_path, "branch", Watched)
    assert rows == [("throw", "", True)], rows
    assert len(at_release) == 1 and at_release[0] < 1e-3, at_release  # [rad]
