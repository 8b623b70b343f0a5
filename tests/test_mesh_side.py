"""A mesh's second side (`cell.arm.grip_side.grip_sides`, `cell.catalogue.mesh_turn`):
a rock the pads cannot hold across its first width (narrower than the band's anchor
spacing where the pads meet it) is gripped a quarter turn round, across the width its
vertices give there, thrown into its bin by the kinematic pick and gripped so by the
physical pick (which misses with any flat mesh: the strict xfail below); the grip probe
measures it so turned. It is offered only where the mesh rests on the station as its catalogue frame
has it (`mesh_side_refusal`, `cell.sim.rest`): the shard, which tips over, is refused.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import pytest

from cell.arm.grip_side import grip_sides, holding_sides
from cell.catalogue import catalogue, get_object, mesh_turn, mesh_vertices, pad_width_m
from cell.errors import CannotGrip
from cell.jobs import parse_job
from cell.orchestrator import Orchestrator
from cell.params import load_params, scene_params_path
from cell.sim.mechanism import DEFAULT_GEOMETRY
from tests.job_texts import NEAR_AND_FAR

JOB = NEAR_AND_FAR


def _strip_width(name: str, across: int) -> float:
    """The mesh's extent [m] along catalogue axis `across` within the pads' strip about
    the other horizontal axis, computed here from the vertices on their own."""
    entry = catalogue()[name]
    v = mesh_vertices(entry.params.mesh, entry.mesh_scale)
    along = 1 - across
    strip = v[np.abs(v[:, along]) <= DEFAULT_GEOMETRY.pad_half_width_m]
    return float(strip[:, across].max() - strip[:, across].min())


@pytest.mark.parametrize("name", ["rock_000", "shard_661"])
def test_a_flat_mesh_is_too_narrow_across_its_first_side(name: str) -> None:
    params = load_params(scene_params_path())
    obj = get_object(name)
    assert len(grip_sides(obj)) == 2
    # the first width is under the band's anchor spacing: the pads do not close on it
    assert pad_width_m(obj) == pytest.approx(_strip_width(name, 0))
    assert pad_width_m(obj) <= params.ee.d
    side = grip_sides(obj)[1][1]
    assert side.size == (obj.size[1], obj.size[0], obj.size[2])
    assert mesh_turn(side) == (obj, pytest.approx(math.pi / 2))
    assert mesh_turn(obj) == (obj, 0.0)
    assert pad_width_m(side) == pytest.approx(_strip_width(name, 1))
    assert pad_width_m(side) > 3 * pad_width_m(obj)


def _centre_over_station(name: str) -> tuple[float, float]:
    """(the mesh's centre of mass over the station once it rests, its lowest vertex below
    its centre in its catalogue frame) [m]: equal where it rests as that frame has it."""
    from cell.sim.scene import CellScene

    entry = catalogue()[name]
    v = mesh_vertices(entry.params.mesh, entry.mesh_scale)
    with CellScene(robot=None) as sc:
        item = sc.spawn_item(name)
        sc.run_for(1.0)
        height = float(sc.item_position(item)[2]) - sc.pick_station_height
    return height, -float(v[:, 2].min())


def test_the_rock_rests_as_its_catalogue_frame_has_it_the_shard_tips_over() -> None:
    """`rest_shift` against the item's height on the station: the rock rests on the
    lowest face of its catalogue frame (its centre its lowest vertex's depth over the
    station), the shard, standing on its 40 mm edge in that frame, lower: it tipped."""
    from cell.sim.mechanism import DEFAULT_GEOMETRY
    from cell.sim.rest import rest_shift

    rock, shard = get_object("rock_000"), get_object("shard_661")
    height, depth = _centre_over_station("rock_000")
    assert height == pytest.approx(depth, abs=1e-3)
    assert rest_shift(rock).shift_m < 1e-3
    height, depth = _centre_over_station("shard_661")
    assert height < depth - 2e-3
    rest = rest_shift(shard)
    assert math.radians(15) < rest.tilt_rad < math.radians(30)
    assert rest.shift_m > DEFAULT_GEOMETRY.pad_half_width_m


def test_the_shard_is_refused_naming_both_sides() -> None:
    """The shard's other side is not offered (it does not rest as the throw model and
    the probe seat it); the refusal says what each side was and why."""
    params = load_params(scene_params_path())
    with pytest.raises(CannotGrip) as err:
        holding_sides(params, get_object("shard_661"))
    msg = str(err.value)
    assert "either side" in msg and "14 mm across the pads" in msg
    assert "66 mm across its other side, not offered" in msg and "tipped" in msg


def test_a_round_mesh_offers_one_side() -> None:
    """The egg is as wide both ways where the pads meet it (within its facets): one side,
    as an upright cylinder."""
    egg = get_object("o7_egg")
    assert abs(pad_width_m(egg) - pad_width_m(egg.turned())) < 1e-3
    assert len(grip_sides(egg)) == 1


def test_the_rock_is_held_across_its_second_side_only() -> None:
    params = load_params(scene_params_path())
    name = "rock_000"
    obj = get_object(name)
    sides = holding_sides(params, obj)
    assert [s.yaw_rad for s in sides] == [pytest.approx(math.pi / 2)]
    assert sides[0].obj == obj.turned()


def test_a_mesh_too_heavy_across_both_sides_names_both() -> None:
    params = load_params(scene_params_path())
    heavy = dataclasses.replace(get_object("rock_000"), mass=1.0)
    with pytest.raises(CannotGrip) as err:
        holding_sides(params, heavy)
    msg = str(err.value)
    assert "either side" in msg and "16 mm across" in msg and "64 mm across" in msg


def test_the_duck_keeps_its_first_side() -> None:
    """A mesh the pads hold briskly across its first width is gripped across it, as
    before (`holding_sides`)."""
    params = load_params(scene_params_path())
    duck = get_object("duck")
    assert [s.yaw_rad for s in holding_sides(params, duck)] == [0.0]
    assert duck.turned().turned() == duck


def _run(item: str, **options: Any) -> tuple[Any, list[dict[str, Any]]]:
    rows: list[dict[str, Any]] = []

    class Store:
        def append(self, row: dict[str, Any], **_: Any) -> None:
            rows.append(row)

    # the release search and the turn are not what is checked (the side is the planner's
    # choice before either; the rock lands and the flat mesh misses without them too): off
    options = {"cycle_search": False, "turn_release": False, **options}
    orch = Orchestrator(parse_job(JOB % item, "mesh.yaml"), store=Store(), **options)
    try:
        return orch.run().results[0], rows
    finally:
        orch.close()


def test_a_rock_is_gripped_across_its_second_side_and_thrown_into_its_bin() -> None:
    """rock_000, refused before (16 mm where the pads met it), is gripped across its 64 mm
    side, thrown 1.4 m and lands in its bin; the throw log records it as gripped."""
    result, rows = _run("object: rock_000, bin: far")
    assert result.action == "throw" and result.in_bin, (result.failure, result.reason)
    assert rows and rows[0]["size_x_m"] == pytest.approx(0.064, abs=1e-3)


def test_a_rock_picked_by_contact_is_gripped_across_its_64_mm_side() -> None:
    """The physical pick rolls the grip so the pads close across the rock's second side
    as it lies (`Pick._grip_axes(side_yaw=...)`), level as its catalogue frame has it, and
    throws it (whether it lands: the next test)."""
    result, rows = _run("object: rock_000, bin: far", pick="physical")
    assert result.action == "throw" and result.failure in ("", "missed_bin"), result.reason
    assert rows and rows[0]["size_x_m"] == pytest.approx(0.064, abs=1e-3)


@pytest.mark.xfail(
    strict=True,
    reason="the physical pick holds a flat mesh off the carriage's face (the pads ride on "
    "the carriage and reach 30 mm past it; the rock is 17 mm tall): the carriage strikes it "
    "at the launch, which the throw model does not have; rock_472 across its first side "
    "misses so on main too (docs/grip.md, What is still open)",
)
def test_a_flat_mesh_picked_by_contact_lands() -> None:
    result, _ = _run("object: rock_472, bin: far", pick="physical")
    assert result.in_bin, (result.failure, result.reason)
