"""An item seated in the pads as it lies (`cell.sim.seat`): the kinematic pick holds it
where the physical pick, gripping it on the station, does (shard_661 lies tipped; the
kinematic pick had set it in its catalogue frame, upright and upside down in the grip)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from cell.frames import axis_frame, rot_z
from cell.jobs import parse_job
from cell.model.objects import ObjectParams
from cell.orchestrator import Orchestrator
from cell.sim.seat import SEAT_GAP_M, _hull_extent_x, lying_seat


def test_a_box_lying_on_its_base_sits_centred_on_the_carriage_upside_down_in_e() -> None:
    box = ObjectParams("cuboid", 0.05, (0.03, 0.05, 0.06))
    rest = rot_z(0.3)  # on its base, turned about the vertical
    grip = axis_frame(-math.pi / 2, 0.3, 0.0)  # pointing down, E's x along the box's -x
    centre, seat, half = lying_seat(box, rest, grip, 0.05, 0.012, 0.03)
    assert centre == pytest.approx([0.0, 0.0, 0.05 + 0.03 + SEAT_GAP_M], abs=1e-9)
    assert seat @ [0.0, 0.0, 1.0] == pytest.approx([0.0, 0.0, -1.0], abs=1e-9)
    assert seat @ [1.0, 0.0, 0.0] == pytest.approx([-1.0, 0.0, 0.0], abs=1e-9)
    assert half == pytest.approx(0.015, abs=1e-7)


def test_the_pads_reach_of_a_wedge_is_its_section_within_their_length() -> None:
    """A prism whose section is the triangle (-a, 0), (-a, h), (a, h) in x z: within
    z <= t its hull spans x from -a to -a + 2 a t / h (closed form)."""
    a, h, w = 0.03, 0.04, 0.02
    tri = [(-a, 0.0), (-a, h), (a, h)]
    pts = np.array([(x, y, z) for x, z in tri for y in (-w, w)])
    for t in (0.01, 0.02, 0.035):
        lo, hi = _hull_extent_x(pts, 0.012, t)
        assert lo == pytest.approx(-a, abs=1e-7)
        assert hi == pytest.approx(-a + 2 * a * t / h, abs=1e-7)


JOB = """
cell: {robot: panda}
pick_station: {position_m: [0.45, -0.40, 0.20]}
bins:
  - {id: far, position_m: [1.40, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}
items:
  - {object: %s, bin: far}
seed: 0
"""


class _Picked(Exception):
    """Raised where the carry would start: the pick is what is compared."""


def _seat_after_pick(name: str, pick: str) -> tuple[np.ndarray, np.ndarray]:
    """The item's centre [m] and rotation in E once picked (before the carry)."""
    orch = Orchestrator(parse_job(JOB % name, "seat.yaml"), pick=pick)
    seat: list[tuple[np.ndarray, np.ndarray]] = []

    def carry(*_: Any) -> None:
        cl = orch.scene.client
        inv = cl.invertTransform(*cl.getBasePositionAndOrientation(orch.scene.ee_body))
        assert orch.ee.item is not None
        p, o = cl.multiplyTransforms(*inv, *cl.getBasePositionAndOrientation(orch.ee.item.body))
        seat.append((np.array(p), np.array(cl.getMatrixFromQuaternion(o)).reshape(3, 3)))
        raise _Picked

    orch.carry = carry  # type: ignore[method-assign]
    try:
        with pytest.raises(_Picked):
            orch.run()
    finally:
        orch.close()
    return seat[0]


def test_the_kinematic_pick_holds_the_shard_as_the_physical_pick_does() -> None:
    """shard_661, gripped across its 66 mm side: the two picks' seats within 5 mm and
    0.12 rad (either end forward: the physical pick takes the one nearer the carry's
    heading from where the item lay turned); the catalogue frame's seat is 0.45 rad and
    12 mm from the physical pick's."""
    p_k, r_k = _seat_after_pick("shard_661", "kinematic")
    p_p, r_p = _seat_after_pick("shard_661", "physical")
    turns = (np.eye(3), np.diag([-1.0, -1.0, 1.0]))  # as held, or a half turn about E's z
    gaps = [
        (
            float(np.linalg.norm(p_k - f @ p_p)),
            math.acos(min(1.0, (np.trace(r_k.T @ f @ r_p) - 1) / 2)),
        )
        for f in turns
    ]
    d_m, d_rad = min(gaps)
    assert d_m < 0.005 and d_rad < 0.12, gaps
