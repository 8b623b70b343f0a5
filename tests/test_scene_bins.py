"""Bins keep what lands in them: kept items stay, asleep until touched; later items land
on them and are scored where they come to rest; places find a clear spot."""

import math

import numpy as np
import pytest

from cell.arm.spots import place_spots
from cell.catalogue import get_object
from cell.sim import BinSpec, CellScene

BIN = BinSpec("b1", (1.0, 0.5), (0.3, 0.3), 0.12)
FLOOR_TOP = BIN.wall  # the floor plate's top [m]


@pytest.fixture
def scene():
    sc = CellScene(robot=None, bins=[BIN], pick_station_xy=(-1.0, -1.0))
    yield sc
    sc.close()


def drop_and_keep(sc, name, xy, z=0.3):
    item = sc.spawn_item(name, position=(xy[0], xy[1], z))
    out = sc.watch_until_rest(item)
    assert out.bin_id == "b1" and sc.in_bin(item) == "b1"
    sc.keep(item)
    return item, out


def test_a_later_item_lands_on_a_kept_one_and_is_scored_where_it_rests(scene):
    first, out1 = drop_and_keep(scene, "cube50", (1.0, 0.5))
    assert out1.rest_xyz[2] == pytest.approx(FLOOR_TOP + 0.025, abs=2e-3)
    second = scene.spawn_item("cube40", position=(1.0, 0.5, 0.4))
    out2 = scene.watch_until_rest(second)
    # it came to rest on the first cube (not on the floor plate), in the bin
    assert out2.touchdown_body == first.body
    assert out2.rest_xyz[2] > FLOOR_TOP + 0.05 and out2.bin_id == "b1"
    assert first in scene.items and scene.kept_items("b1") == [first]


def test_a_kept_item_stays_put_until_something_hits_it(scene):
    first, out1 = drop_and_keep(scene, "cyl50", (1.05, 0.5))
    scene.run_for(0.5)
    cl = scene.client
    still = cl.getBasePositionAndOrientation(first.body)[0]
    assert np.allclose(still, out1.rest_xyz, atol=1e-4)
    # a heavy item dropped on its edge shoves it: asleep (see CellScene.keep), it wakes
    hit = scene.spawn_item("cyl70", position=(1.05 + 0.03, 0.5, 0.6))
    scene.watch_until_rest(hit)
    moved = cl.getBasePositionAndOrientation(first.body)[0]
    assert np.linalg.norm(np.subtract(moved, still)) > 2e-3


def _footprints(scene, kept, obj):
    """(the kept item's centre [m, W], the radii [m] of the circles that hold the new
    item's footprint however it is turned, half its diagonal, and the kept one's, half
    its bounding box's)."""
    lo, hi = scene.item_aabb(kept)
    r_kept = math.hypot(*(hi - lo)[:2]) / 2
    return (lo + hi) / 2, math.hypot(*obj.size[:2]) / 2, r_kept


def test_place_spot_is_the_centre_of_an_empty_bin_then_clear_of_what_it_holds(scene):
    obj = get_object("cuboid_c")
    assert place_spots(scene, "b1", obj)[0] == (1.0, 0.5, FLOOR_TOP)
    kept, _ = drop_and_keep(scene, "cyl70", (1.0, 0.5))
    x, y, z = place_spots(scene, "b1", obj, margin_m=0.01)[0]
    p, r_new, r_kept = _footprints(scene, kept, obj)
    assert math.hypot(x - p[0], y - p[1]) >= r_new + r_kept + 0.01 - 1e-9
    assert abs(x - 1.0) <= 0.15 - r_new and abs(y - 0.5) <= 0.15 - r_new  # inside the walls
    assert z == FLOOR_TOP


def test_a_full_bin_stacks_on_top_of_what_it_holds(scene):
    obj = get_object("cyl70")
    kept = [drop_and_keep(scene, "cyl70", xy)[0] for xy in ((0.93, 0.43), (1.07, 0.57))]
    kept += [
        drop_and_keep(scene, "cyl70", xy)[0] for xy in ((0.93, 0.57), (1.07, 0.43), (1.0, 0.5))
    ]
    x, y, z = place_spots(scene, "b1", obj, margin_m=0.03)[0]
    tops = [
        scene.client.getBasePositionAndOrientation(it.body)[0][2] + max(it.obj.size) / 2
        for it in kept
    ]
    assert z > FLOOR_TOP and z <= max(tops) + 1e-9


def test_place_spots_are_ranked_clear_ones_nearest_the_centre_first(scene):
    obj = get_object("cuboid_c")
    kept, _ = drop_and_keep(scene, "cyl70", (1.0, 0.5))
    spots = place_spots(scene, "b1", obj, margin_m=0.01)
    assert len(set(spots)) == len(spots) > 8  # distinct grid points, enough to try others
    p, r_new, r_kept = _footprints(scene, kept, obj)
    clear = [
        (x, y, z) for x, y, z in spots if math.hypot(x - p[0], y - p[1]) >= r_new + r_kept + 0.01
    ]
    # the clear spots come first, on the floor, nearest the bin's centre first
    assert spots[: len(clear)] == clear and all(z == FLOOR_TOP for *_, z in clear)
    off = [math.hypot(x - 1.0, y - 0.5) for x, y, _ in clear]
    assert all(a <= b + 1e-9 for a, b in zip(off, off[1:], strict=False))  # ties as equal
    # the others (over the kept cylinder) stand on it
    assert all(z > FLOOR_TOP for *_, z in spots[len(clear) :])
