"""The envelope's edges in the PyBullet scene: each lands in its bin, or the job is refused
before anything moves, with a message that names the item and the bin and says what the
cell can do instead.

The cases span what a user's job can ask at the edges: near bins (0.8–1.3 m), low and high
rims, the longest throws, light and heavy items, thin, flat, wide and tall ones. Which
side of the line each case falls on is the cell's own model (the grip and the planner),
checked here against the plant: a case the cell accepts must land.
"""

from __future__ import annotations

import pytest

from cell.errors import JobError
from cell.jobs import parse_job
from cell.orchestrator import Orchestrator

JOB = """
bins:
  - {id: edge_bin, position_m: %s, size_m: [0.3, 0.3], rim_height_m: %s}
items:
  - %s
policy: throw
"""

LANDS = {
    "near bin 0.9 m": ("[0.9, 0.3]", 0.15, "{object: cube50, bin: edge_bin}"),
    "near bin 1.2 m": ("[1.1, -0.5]", 0.15, "{object: cyl50, bin: edge_bin}"),
    "high rim 0.30 m": ("[1.8, 0.2]", 0.30, "{object: cube50, bin: edge_bin}"),
    "low rim 0.05 m": ("[2.3, -0.6]", 0.05, "{object: cyl50, bin: edge_bin}"),
    "far bin 3.1 m": ("[3.0, -0.8]", 0.15, "{object: cube50, bin: edge_bin}"),
    "light 20 g": (
        "[1.8, 0.2]",
        0.15,
        "{shape: cube, mass_kg: 0.02, size_m: [0.04, 0.04, 0.04], bin: edge_bin}",
    ),
    "flat 90 x 90 x 25 mm": (
        "[1.8, 0.2]",
        0.15,
        "{shape: cuboid, mass_kg: 0.08, size_m: [0.09, 0.09, 0.025], bin: edge_bin}",
    ),
    "wide sphere 90 mm": (
        "[1.8, 0.2]",
        0.15,
        "{shape: sphere, mass_kg: 0.15, size_m: [0.09, 0.09, 0.09], bin: edge_bin}",
    ),
}

REFUSED = {
    # (bin, rim, item, what the message must say besides the item and the bin)
    "heavy 250 g cube, longest throw": (
        "[3.1, 0.6]",
        0.15,
        "{shape: cube, mass_kg: 0.25, size_m: [0.06, 0.06, 0.06], bin: edge_bin}",
        "sort it by hand",
    ),
    "heavy 250 g cylinder": (
        "[1.6, -0.4]",
        0.15,
        "{shape: cylinder, mass_kg: 0.25, size_m: [0.07, 0.07, 0.09], bin: edge_bin}",
        "place it in a bin within reach",
    ),
    # (a 25 x 80 mm box, refused before across 25 mm, is gripped across 80 mm:
    # tests/test_grip_side.py)
    # held at the pads' edges below its equator, pulled out at the wedge's force
    # (cell.model.grip.grip_friction): 1.4 times its weight at the shortest stroke, under
    # the carry's 1.6. Accepted under the law before, it left the grip on all four carries
    # of random layout 7 (the scene drops it hanging from the pads from a 0.06 m stroke).
    "heavy wide sphere 88 mm": (
        "[-0.23, 1.14]",
        0.23,
        "{shape: sphere, mass_kg: 0.182, size_m: [0.088, 0.088, 0.088], bin: edge_bin}",
        "sort it by hand",
    ),
    "too wide for the pads": (
        "[1.8, 0.2]",
        0.15,
        "{shape: cube, mass_kg: 0.05, size_m: [0.13, 0.13, 0.05], bin: edge_bin}",
        "wider than they open",
    ),
    "beyond the longest throw": (
        "[4.5, 0.0]",
        0.15,
        "{object: cube50, bin: edge_bin}",
        "move bin 'edge_bin' within the reach",
    ),
}


@pytest.mark.parametrize("case", sorted(LANDS))
def test_an_accepted_edge_case_lands_in_its_bin(case):
    bin_xy, rim, item = LANDS[case]
    orch = Orchestrator(parse_job(JOB % (bin_xy, rim, item), f"{case}.yaml"))
    try:
        summary = orch.run()
    finally:
        orch.close()
    r = summary.results[0]
    assert r.action == "throw" and r.in_bin, (case, r.failure, r.reason)
    assert r.landing_error_m < 0.15  # within the bin's half-width at its rim


# A cube thrown 1.8 m into a bin with a 0.05 m rim: thrown as flat as the least-energy throw
# it landed on the bin's centre and slid out over the rim (a strict xfail, throws from 50°
# did not help). Thrown with the axis at 60° or more (`ArmTuning.steep_rim_m`, chosen on
# tune layouts 8, 14 and 16 without this test) it comes down steeply and stays.
def test_a_cube_thrown_into_a_low_rimmed_bin_stays_in():
    orch = Orchestrator(
        parse_job(JOB % ("[1.8, 0.2]", 0.05, "{object: cube50, bin: edge_bin}"), "low.yaml")
    )
    try:
        r = orch.run().results[0]
    finally:
        orch.close()
    assert r.in_bin, r.reason


# Marginal: a 100 g cylinder 200 mm tall (50 mm wide) on the level swing to a release 1.8 m
# out. It left the pads before the faster pick (the straight approach and the grasp that ends
# once the pads stop) and stayed in them since; it flipped with milliseconds of the pick's
# timing in between (the pads' couple on a cylinder's line contact is close to its weight's
# lever when it hangs sideways). It flipped back when the carry's tie over the grip's bound
# (GRIP_USE_TIE) applied to every shape: its swing asks 0.756 of the grip at rest, within
# 0.741 + 0.02, it was carried as fast as that allows, and it left the pads. The tie is
# for boxes only since (Orchestrator._over_bound). As its swing at its 55 mm throw stroke
# asks more than the bound at rest, it is now carried at the shortest stroke
# (Orchestrator._carry_stroke), where the pads hold it hardest.
def test_a_tall_cylinder_is_carried_to_its_release():
    item = "{shape: cylinder, mass_kg: 0.1, size_m: [0.05, 0.05, 0.2], bin: edge_bin}"
    orch = Orchestrator(parse_job(JOB % ("[1.8, 0.2]", 0.15, item), "tall.yaml"))
    try:
        r = orch.run().results[0]
    finally:
        orch.close()
    assert r.in_bin, r.reason


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_a_refused_edge_case_is_refused_before_anything_moves_with_its_reason(case):
    bin_xy, rim, item, instead = REFUSED[case]
    with pytest.raises(JobError) as err:
        Orchestrator(parse_job(JOB % (bin_xy, rim, item), f"{case}.yaml"))
    msg = str(err.value)
    assert f"{case}.yaml, line" in msg  # the file and the item's line
    assert "edge_bin" in msg and "item" in msg  # the bin and the item
    assert instead in msg, msg  # what the cell can do instead
    if "sphere" in item:  # as wide every way: no other side to offer the pads
        assert "side" not in msg, msg
