"""The release's roll (`Orchestrator._release_q`): of the two rolls that put a thrown
item's weight on a pad (0 and π), the one whose cycle is the shorter.

Independent check: the same item run in the scene three times, from a fresh cell each
time, with the roll left to the cell and with each roll forced; the scene's clock times
the empty approach to the pick and the carry to the release."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import cell.robot.ik as ik
from cell.arm.kinematics import roll_of
from cell.jobs import parse_job
from cell.orchestrator import Orchestrator

JOB = """\
cell: {robot: %s}
pick_station: {position_m: [0.45, -0.40, 0.20]}
bins:
  - {id: back, position_m: [-1.20, 1.00], size_m: [0.30, 0.30], rim_height_m: 0.15}
  - {id: side, position_m: [0.20, 1.60], size_m: [0.30, 0.30], rim_height_m: 0.10}
items:
  - {object: %s, count: 1, bin: %s}
seed: 0
"""


def _cycle(
    text: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, rolls: tuple[float, ...]
) -> tuple[float, float, float]:
    """(the roll taken [rad], the approach [s], the carry [s]) of the job's one item."""
    monkeypatch.setattr(ik, "WEIGHT_ROLLS_RAD", rolls)
    o = Orchestrator(parse_job(text, str(tmp_path / "job.yaml")), session="roll", release="static")
    try:
        spec = o.job.expanded_items()[0]
        obj, target = spec.obj, o.job.bin(spec.bin)
        item = o.present(0, obj)
        d = o.decide(0, obj, target)
        assert d.action == "throw"
        t0 = o.scene.t
        o.pick(d, obj, item)
        t1 = o.scene.t
        o.carry(d, obj, item)
        assert o.ee.holds_item()
        roll = roll_of(o.robot, o.q, d.plan.elevation_rad, d.plan.azimuth_rad)
        return roll, t1 - t0, o.scene.t - t1
    finally:
        o.close()


@pytest.mark.parametrize(
    ("robot", "obj", "bin_id"), [("panda", "cyl50", "back"), ("ur5", "cube50", "side")]
)
def test_the_roll_taken_is_the_one_whose_approach_and_carry_are_shorter(
    robot: str, obj: str, bin_id: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    text = JOB % (robot, obj, bin_id)
    forced = {r: _cycle(text, tmp_path, monkeypatch, (r,)) for r in (0.0, math.pi)}
    roll, approach, carry = _cycle(text, tmp_path, monkeypatch, (0.0, math.pi))
    cost = {r: a + 2.0 * c for r, (_, a, c) in forced.items()}
    # the roll the cell took is a weight-on-a-pad roll, and its cycle is the other's or less
    assert min(abs(roll - r) for r in cost) < 1e-6
    assert approach + 2.0 * carry <= min(cost.values()) + 0.05


def test_a_physical_pick_keeps_the_roll_nearer_where_the_arm_is(tmp_path: Path) -> None:
    """The physical pick grips the item as it lies, headed by the release's roll, not in
    the frame the choice times: there the roll nearer where the arm is stays (on the UR5
    copy of the demo the timed choice cost four grasps)."""
    text = JOB % ("ur5", "cube50", "side")
    o = Orchestrator(
        parse_job(text, str(tmp_path / "job.yaml")),
        session="roll",
        release="static",
        pick="physical",
    )
    try:
        spec = o.job.expanded_items()[0]
        obj, target = spec.obj, o.job.bin(spec.bin)
        o.present(0, obj)
        d = o.decide(0, obj, target)
        plan, q_rel = d.plan, d.state.q_release
        centre = np.array([plan.x_m, plan.y_m, plan.z_m])
        tcp = o._tcp_for_item_centre(centre, plan.elevation_rad, plan.azimuth_rad, d.stroke_m, obj)
        nearer = ik.solve_release_ik(o.robot, tcp, plan.elevation_rad, plan.azimuth_rad, o.q).q
        assert np.allclose(q_rel, nearer, atol=1e-9)
        # and it is the roll the timed choice would not take (the test above: roll 0)
        assert abs(roll_of(o.robot, q_rel, plan.elevation_rad, plan.azimuth_rad) - math.pi) < 1e-6
    finally:
        o.close()
