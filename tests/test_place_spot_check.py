"""The job check places a bin's items over the place's own spot nearest the base
(`cell.jobcheck.place_spot`: the point of `cell.arm.spots.place_spots`' grid nearest the base,
the grid kept the item's footprint and the place's wall margin from the walls), not over a
point 3 cm in from the walls, which no place goes to.

The bin (Panda, `limits.place_reach_m: 1.0`): 0.30 m wide at (0, -0.90) m, its rim 0.12 m up,
a cube50 sent there. The grip pointing down reaches the point 3 cm in from its near wall; the
place's spots keep the cube's footprint (35 mm) and the housing's margin (35 mm: the housing
goes below the rim) from the walls, and the arm reaches none of them: every item sent there
failed `ik` in the run while the job check passed the bin.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from cell.errors import IKFailed, JobError
from cell.jobs import parse_job
from cell.orchestrator import Orchestrator

ROW = "{id: edge, position_m: [0.00, -0.90], size_m: [0.30, 0.30], rim_height_m: 0.12}"
BIN = (0.0, -0.90, 0.30, 0.12)  # centre x, y [m, W], inner side [m], rim height [m]


def _job(policy: str) -> str:
    return (
        f"cell: {{robot: panda}}\nlimits: {{place_reach_m: 1.0}}\nbins:\n  - {ROW}\n"
        f"items:\n  - {{object: cube50, count: 1, bin: edge}}\npolicy: {policy}\nseed: 0\n"
    )


def _spot(message: str) -> tuple[float, float]:
    """The spot the check's message names (x, y) [m, W]."""
    m = re.search(r"spot nearest the base, \((-?[\d.]+), (-?[\d.]+)\) m \(for a cube50: ", message)
    assert m, message
    return float(m.group(1)), float(m.group(2))


def _reached(xy: tuple[float, float]) -> bool:
    """Does the Panda's grip pointing down reach over `xy` with a cube50 held, its lowest
    point 5 cm over the 0.12 m rim (the place's pose over the spot, `cell.arm.place`), at
    the place's stroke (`ArmTuning.pick_stroke_m`)? By the arm's own IK, not the check's."""
    from cell.arm.tuning import ArmTuning
    from cell.jobschema import BIN_WALL_M
    from cell.robot.ik import ReleasePose, solve_ik
    from cell.robot.model import load_robot
    from cell.sim.frames import EE_TO_TCP_M

    t, h = ArmTuning(), 0.05
    centre_z = BIN_WALL_M + h / 2 + t.place_clearance_m + max(t.lift_m, BIN[3] + 0.05)
    tcp_z = centre_z - (EE_TO_TCP_M - t.pick_stroke_m - h / 2)  # cell.frames, the grip down
    robot = load_robot("panda")
    pose = ReleasePose(np.array([xy[0], xy[1], tcp_z]), np.array([0.0, 0.0, -1.0]))
    try:
        solve_ik(robot, pose, robot.home)
    except IKFailed:
        return False
    return True


def test_auto_throws_into_a_bin_whose_near_point_the_arm_reaches_and_no_place_spot() -> None:
    job = parse_job(_job("auto"), "edge.yaml")
    assert job.thrown_bins == frozenset({"edge"})
    (warning,) = job.warnings
    assert "the panda arm cannot place into bin 'edge'" in warning
    assert "under policy auto its items are thrown into it instead" in warning
    x, y = _spot(warning)
    # the spot named lies on the bin's near side, farther in than 3 cm from its near wall
    near_wall = BIN[1] + BIN[2] / 2
    assert x == pytest.approx(0.0, abs=0.005) and near_wall - 0.15 < y < near_wall - 0.03
    # the arm's own IK: the spot named is missed, the point 3 cm in from the wall reached
    assert not _reached((x, y))
    assert _reached((0.0, near_wall - 0.03))
    # the run's witness: the job with the check skipped places, and fails the item's `ik`
    unchecked = parse_job(_job("auto"), "edge.yaml", check_reach=False)
    assert unchecked.thrown_bins == frozenset()
    orch = Orchestrator(unchecked, cycle_search=False, turn_release=False)
    try:
        (r,) = orch.run().results
    finally:
        orch.close()
    assert (r.action, r.failure) == ("failed", "ik"), r


def test_policy_place_refuses_the_bin_naming_the_spot() -> None:
    with pytest.raises(JobError) as err:
        parse_job(_job("place"), "edge.yaml")
    msg = str(err.value)
    assert "edge.yaml, line 4, bins[0].position_m: the panda arm cannot place into bin" in msg
    assert _spot(msg) == _spot(parse_job(_job("auto"), "edge.yaml").warnings[0])
