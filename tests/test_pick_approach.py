"""The empty arm's approach to a kinematic pick (`Orchestrator._approach`): it does not stop
over the item, and still comes straight down onto it from above, within the joint limits
of the robot description, and the grasp after it holds the item.

Independent checks: the grip centre's path from the arm's forward kinematics over every
commanded configuration (not the planner's own clearance check), the joint limits from the
robot description, and the plant's grip (`holds_item`)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cell.arm.tuning import TUNING
from cell.jobs import parse_job
from cell.orchestrator import Orchestrator

JOB = """\
cell: {robot: %s}
pick_station: {position_m: [0.45, -0.40, 0.20]}
bins:
  - {id: far, position_m: [1.40, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}
items:
  - {object: cube50, count: 1, bin: far}
  - {object: sphere40, count: 1, bin: far}
seed: 0
"""


class Watched(Orchestrator):
    """The arm, keeping the pick configuration of each grip over an item (`over_item`)."""

    picks: list[np.ndarray]

    def over_item(self, item: Any, stroke: float, obj: Any) -> tuple[np.ndarray, np.ndarray]:
        out = super().over_item(item, stroke, obj)
        self.picks.append(out[0])
        return out


@pytest.fixture(params=["panda", "ur5"])
def orch(request: Any, tmp_path: Path) -> Iterator[Watched]:
    job = parse_job(JOB % request.param, str(tmp_path / "job.yaml"))
    o = Watched(job, session="approach")
    o.picks = []
    yield o
    o.close()


def test_the_approach_comes_straight_down_onto_the_item_and_the_grasp_holds_it(
    orch: Watched, monkeypatch: pytest.MonkeyPatch
) -> None:
    commanded: list[np.ndarray] = []
    set_arm = orch.scene.set_arm
    monkeypatch.setattr(
        orch.scene, "set_arm", lambda q: (commanded.append(np.array(q)), set_arm(q))[1]
    )
    taken: list[bool] = []
    approach = orch._approach
    monkeypatch.setattr(orch, "_approach", lambda *a: (taken.append(approach(*a)), taken[-1])[1])
    picks = orch.picks
    lim, dt = orch.robot.limits, orch.scene.dt_s
    for index, spec in enumerate(orch.job.expanded_items()):
        commanded.clear()
        obj, target = spec.obj, orch.job.bin(spec.bin)
        item = orch.present(index, obj)
        d = orch.decide(index, obj, target)
        orch.pick(d, obj, item)
        q_pick = picks[-1]  # where the pick put the grip (in the frame it grips in)
        assert taken == [True] * (index + 1)  # the straight approach, not the fallback
        assert orch.ee.holds_item()
        qs = np.array(commanded)
        np.testing.assert_allclose(qs[-1], q_pick, atol=1e-8)
        assert np.all(qs >= lim.lower - 1e-6) and np.all(qs <= lim.upper + 1e-6)
        assert np.all(np.abs(np.diff(qs, axis=0)) / dt <= lim.velocity * (1 + 1e-6))
        # the grip centre: below the point the pads' length and the clearance over the
        # pick, only straight over the pick and only going down
        p = np.array([orch.robot.tcp_pose(q)[0] for q in qs])
        over = orch.scene.geometry.pad_length_m + TUNING.pick_over_clearance_m
        low = p[:, 2] < p[-1, 2] + over - 1e-3
        assert low[-1] and np.all(low[np.argmax(low) :])  # once below, it stays below
        assert np.max(np.linalg.norm(p[low, :2] - p[-1, :2], axis=1)) < 2e-3
        assert np.all(np.diff(p[low, 2]) <= 1e-6)
        orch.carry(d, obj, item)
        orch.release(d)
        orch.finish(d)
