"""A long throw of a heavy item whose optimised release lies where the arm does not reach
(the release box's far upper corner, the throw axis tilted): the cell plans it again in a
smaller release box (`cell.arm.tuning.TUNING.release_box_shrinks`) instead of failing the item.

Independent checks: the release configuration's forward kinematics (Pinocchio) against
the plan's release pose, and the throw's crossing of the rim plane in the scene."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cell.errors import UnreachableTarget
from cell.frames import tcp_for_item_centre
from cell.jobs import parse_job
from cell.orchestrator import Orchestrator

JOB = """\
cell: {robot: panda}
pick_station: {position_m: [0.45, -0.40, 0.20]}
bins:
  - {id: far, position_m: [2.119, -1.268], size_m: [0.32, 0.26], rim_height_m: 0.08}
items:
  - {shape: cylinder, mass_kg: 0.1735, size_m: [0.0837, 0.0837, 0.0296], count: 1, bin: far}
seed: 0
"""


def _decided(job: Any, session: str) -> tuple[Orchestrator, Any, Any]:
    """(the orchestrator, its decision for the job's one item, the item): the decision
    made as `cell run` makes it, the item presented on the station; the caller closes."""
    orch = Orchestrator(job, session=session)
    spec = job.expanded_items()[0]
    obj = spec.obj
    orch.present(0, obj)
    d = orch.decide(0, obj, job.bin(spec.bin))
    assert d.action == "throw"
    return orch, d, obj


def _released_where_planned(orch: Orchestrator, d: Any, obj: Any) -> None:
    """The release configuration's forward kinematics puts the item's centre where the
    plan has it (within 1 mm)."""
    plan = d.plan
    centre = np.array([plan.x_m, plan.y_m, plan.z_m])
    tcp = tcp_for_item_centre(centre, plan.elevation_rad, plan.azimuth_rad, d.stroke_m, obj)
    p, _ = orch.robot.tcp_pose(d.state.q_release)
    assert np.linalg.norm(p - tcp) < 1e-3


def _thrown_into_reach_of_the_bin(job: Any, session: str) -> None:
    """The whole item, in the scene: thrown, not failed, and it comes down near the bin."""
    orch = Orchestrator(job, session=session)
    try:
        (r,) = orch.run().results
    finally:
        orch.close()
    assert r.action == "throw" and r.failure != "ik"
    assert r.landing_error_m < 0.13  # within the bin's smaller half-width (measured: 0.039 m)


def test_a_heavy_disc_thrown_far_is_planned_in_a_smaller_release_box_and_lands(
    tmp_path: Path,
) -> None:
    job = parse_job(JOB, str(tmp_path / "job.yaml"))
    orch, d, obj = _decided(job, "release-box")
    try:
        # the cell's own release box: the optimiser's release is out of the arm's reach
        assert d.state.choice.bounds.position_max[0] < orch.bounds.position_max[0]  # a smaller box
        _released_where_planned(orch, d, obj)
    finally:
        orch.close()
    _thrown_into_reach_of_the_bin(job, "release-box-run")


def test_a_target_the_smaller_box_puts_out_of_reach_is_planned_in_a_larger_one(
    tmp_path: Path,
) -> None:
    """The same disc aimed 0.1 m farther (random layout 0 aimed it there, at a point of
    its bin clear of what the bin held): the cell's release is out of the arm's reach by
    18 mm, the 0.75 box's nearest release 2.17 m short of the target; the item is planned
    in the 0.9 box and lands, where it had failed with `ik`."""
    from dataclasses import replace

    from cell.arm.tuning import TUNING
    from cell.errors import IKFailed

    job = parse_job(JOB.replace("[2.119, -1.268]", "[2.208, -1.306]"), str(tmp_path / "j.yaml"))
    orch, d, obj = _decided(job, "release-box-far")
    try:
        b = orch.bounds
        lo, hi = np.asarray(b.position_min), np.asarray(b.position_max)
        chosen = d.state.choice.bounds
        half = np.asarray(chosen.position_max) - np.asarray(chosen.position_min)
        assert np.allclose(half, (hi - lo) * 0.9)  # planned in the larger of the two boxes
        # the boxes tried before it: from the cell's own the release is out of the arm's
        # reach, from the smaller one the target
        k = TUNING.release_box_shrinks[0]
        mid = (lo + hi) / 2
        small = replace(
            b,
            position_min=tuple(mid - k * (hi - lo) / 2),
            position_max=tuple(mid + k * (hi - lo) / 2),
        )
        gx, gy, gz = (float(v) for v in d.state.choice.goal)
        with pytest.raises(IKFailed):
            orch._plan_in(obj, (gx, gy, gz), 0, math.inf, b)
        with pytest.raises(UnreachableTarget):
            orch._plan_in(obj, (gx, gy, gz), 0, math.inf, small)
        _released_where_planned(orch, d, obj)
    finally:
        orch.close()
    _thrown_into_reach_of_the_bin(job, "release-box-far-run")
