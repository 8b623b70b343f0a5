"""The grip limit (cell.model.grip) against the scene's pads: what it says the pads
hold, they hold; well beyond it, the item slips out. And the cell refuses, before a
job starts, an item the pads cannot hold, naming it."""

from __future__ import annotations

import numpy as np
import pytest

from cell.endeffector.pybullet_backend import PyBulletEndEffector
from cell.errors import JobError
from cell.jobs import parse_job
from cell.model.grip import holding_mass_kg
from cell.model.objects import ObjectParams
from cell.model.params import DEFAULT_EE
from cell.orchestrator import Orchestrator
from cell.sim import CellScene

WIDTH_M = 0.03
STROKE_M = 0.06


def _held_after(mass_kg: float, seconds: float = 0.6) -> bool:
    """Grasp a box of this mass at STROKE_M, point the grip down, and wait."""
    obj = ObjectParams(shape="cuboid", mass=mass_kg, size=(WIDTH_M, 0.05, 0.05), name="probe")
    with CellScene() as sc:
        ee = PyBulletEndEffector(sc)
        item = sc.spawn_item(obj)
        sc.run_for(0.05)
        ee.grasp(STROKE_M, item)
        sc.run_for(seconds)
        return ee.holds_item()


def test_the_limit_separates_held_from_dropped_in_the_scene():
    m_hold = holding_mass_kg(DEFAULT_EE, STROKE_M, WIDTH_M)
    assert 0.01 < m_hold < 1.0
    assert _held_after(0.9 * m_hold)
    assert not _held_after(1.15 * m_hold)


def test_the_grip_weakens_as_the_stroke_grows():
    ms = [holding_mass_kg(DEFAULT_EE, s, 0.05) for s in np.linspace(0.03, 0.11, 9)]
    assert all(b < a for a, b in zip(ms, ms[1:], strict=False))


JOB = """
bins:
  - {id: far, position_m: [1.6, 0.0], size_m: [0.3, 0.3], rim_height_m: 0.1}
items:
  - {object: cube50, bin: far}
  - {shape: cuboid, mass_kg: %s, size_m: [%s, %s, 0.06], bin: far}
"""


@pytest.mark.parametrize(
    ("mass", "width", "says"),
    [(0.35, 0.02, "cannot be held"), (0.05, 0.2, "pads")],
)
def test_an_item_the_pads_cannot_hold_is_refused_before_the_job(mass, width, says):
    # square in section: no other side to grip it across (cell.arm.grip_side); 350 g in
    # 20 x 20 x 60 mm is 14,600 kg/m³, a real metal's (a denser mass is refused as such)
    job = parse_job(JOB % (mass, width, width), "job.yaml")
    with pytest.raises(JobError) as err:
        Orchestrator(job)
    msg = str(err.value)
    assert "job.yaml, line 6" in msg and "item1_cuboid" in msg and says in msg
