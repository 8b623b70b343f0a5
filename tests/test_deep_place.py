"""Places into a deep bin: the housing is wider than the pads, and where the item is set
down on the floor of a 0.25 m rim bin, it goes down below the rim.

Random layout 17's (UR5) 0.33 x 0.27 m bin with a 0.251 m rim held 18 places; seven
items were knocked out of the grip as the housing met the walls (spots kept only the
pads' reach from the walls, and the arm went down and back up on a joint-space line that
strays sideways). Independent check: the scene's contacts between the housing and the
bin, and the items at rest in it.

Random layout 11's (UR5) 0.39 x 0.32 m bin with a 0.298 m rim, 0.71 m from the base:
the pose over the spot and the pose at it, each solved from where the arm was, came out
3.45 rad apart, and the line between them swept the grip through the bin; all three
items dropped. The pose at the spot is solved from over it, and the next spot is tried
where the arm reaches none over the first."""

from __future__ import annotations

from pathlib import Path

import pytest

from cell.jobs import parse_job
from cell.orchestrator import Orchestrator

JOBS = {
    "layout17": """\
cell: {robot: ur5, ee: pybullet}
bins:
  - {id: bin_0, position_m: [-0.209, -0.449], size_m: [0.334, 0.273], rim_height_m: 0.251}
items:
  - {object: o4_cylinder50, count: 4, bin: bin_0}
  - {object: cube30, count: 4, bin: bin_0}
policy: auto
seed: 17
""",
    "layout11": """\
cell: {robot: ur5, ee: pybullet}
bins:
  - {id: bin_0, position_m: [-0.548, 0.463], size_m: [0.391, 0.322], rim_height_m: 0.298}
items:
  - {shape: cuboid, mass_kg: 0.225, size_m: [0.0821, 0.0712, 0.0325], count: 2, bin: bin_0}
  - {object: cyl60, count: 1, bin: bin_0}
policy: auto
seed: 11
""",
}
PLACES = {"layout17": 8, "layout11": 3}


@pytest.mark.parametrize("layout", sorted(JOBS))
def test_places_into_a_deep_bin_keep_the_housing_off_its_walls(
    layout: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    monkeypatch.chdir(tmp_path)
    o = Orchestrator(parse_job(JOBS[layout], str(tmp_path / "job.yaml")), session="deep")
    sc = o.scene
    touched: list[tuple[float, float, float]] = []
    step = sc.step

    def step_and_look(n: int = 1) -> None:
        step(n)
        for c in sc.client.getContactPoints(sc.ee_body, sc.bin_bodies["bin_0"]):
            if c[3] == -1:  # the housing (the end-effector's base link)
                touched.append(tuple(round(v, 3) for v in c[6]))

    monkeypatch.setattr(sc, "step", step_and_look)
    try:
        summary = o.run()
    finally:
        o.close()
    rows = [(r.action, r.failure, r.in_bin) for r in summary.results]
    assert rows == [("place", "", True)] * PLACES[layout], rows
    assert not touched, f"the housing touched the bin at {touched[:3]} ({len(touched)} contacts)"
