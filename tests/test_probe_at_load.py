"""The grip of each kind of sphere or mesh a job holds is probed in the scene when the job is
loaded (`Orchestrator._probe_meshes`), not in the first such item's planning: afterwards,
what the planner asks of the probe (`point_hold_use`, `mesh_grip`) is answered without
probing again, with the values a probe made afresh gives."""

from __future__ import annotations

from pathlib import Path

from cell.arm.grip_limits import mesh_grip, point_hold_use
from cell.jobs import parse_job
from cell.model.params import G
from cell.orchestrator import Orchestrator
from cell.sim import grip_probe
from cell.sim.grip_probe import PROBE_STROKES_M

JOB = """\
cell: {robot: panda, ee: pybullet}
bins:
  - {id: bin_0, position_m: [1.2, 0.6], size_m: [0.3, 0.3], rim_height_m: 0.1}
items:
  - {shape: sphere, mass_kg: 0.0485, size_m: [0.0756, 0.0756, 0.0756], count: 2, bin: bin_0}
  - {shape: cube, mass_kg: 0.05, size_m: [0.05, 0.05, 0.05], count: 1, bin: bin_0}
seed: 4
"""


def test_a_sphere_is_probed_when_the_job_is_loaded(tmp_path: Path) -> None:
    grip_probe._probe.cache_clear()
    o = Orchestrator(parse_job(JOB, str(tmp_path / "job.yaml")), session="probe")
    try:
        loaded = grip_probe._probe.cache_info()
        assert loaded.currsize == len(PROBE_STROKES_M)  # the sphere's strokes; no cube's
        sphere = o.job.items[0].obj
        use = point_hold_use(o.params, sphere, 0.08)
        assert grip_probe._probe.cache_info().misses == loaded.misses  # no probe in the plan
        ratio, _ = mesh_grip(o.params, sphere)
        assert 0.0 < ratio <= 1.0
        # the same hold a probe made afresh measures
        grip_probe._probe.cache_clear()
        again = point_hold_use(o.params, sphere, 0.08)
        assert again == use
        assert use > sphere.mass * G / 100.0  # a finite share of a real force
    finally:
        o.close()
