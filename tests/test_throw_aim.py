"""A throw aims at its bin's centre unless the bin holds items there: then at the
nearest point clear of them (cell.arm.spots.throw_spot). Checked in the scene: a cylinder
launched at the centre strikes a bottle lying across it, or lands on a cube resting there
and bounces out; one launched at the throw spot lands on the bin's floor."""

import math

import numpy as np
import pytest

from cell.arm.spots import THROW_CLEARANCE_M, THROW_WALL_MARGIN_M, throw_spot
from cell.catalogue import get_object
from cell.jobs import parse_job
from cell.log.store import ThrowStore
from cell.model.objects import ObjectParams
from cell.orchestrator import Orchestrator
from cell.sim import BinSpec, CellScene

LOW = BinSpec("low", (1.2, 0.0), (0.35, 0.35), 0.055)  # rim 55 mm, under a lying bottle's top
G = 9.81


@pytest.fixture
def scene():
    sc = CellScene(robot=None, bins=[LOW], pick_station_xy=(-1.0, -1.0))
    yield sc
    sc.close()


def keep_lying(sc, name, xy):
    """Set an item down lying on its side (axis along W's x) at xy and keep it there."""
    obj = get_object(name)
    z = LOW.wall + obj.size[0] / 2 + 1e-3
    q = (0.0, math.sin(math.pi / 4), 0.0, math.cos(math.pi / 4))  # 90° about y
    item = sc.spawn_item(name, position=(xy[0], xy[1], z), orientation=q)
    out = sc.watch_until_rest(item)
    assert out.bin_id == "low"
    sc.keep(item)
    return item


def launch_at(sc, name, aim_xy, flight_s=0.45, short_m=1.2, height_m=0.5, rim_m=LOW.rim_height):
    """Launch an item from short_m before the aim, height_m up, on the ballistic arc that
    crosses the rim plane (rim_m) at aim_xy after flight_s (drag moves it by millimetres)."""
    p0 = np.array([aim_xy[0] - short_m, aim_xy[1], height_m])
    goal = np.array([aim_xy[0], aim_xy[1], rim_m])
    v0 = (goal - p0) / flight_s + np.array([0.0, 0.0, 0.5 * G * flight_s])
    item = sc.spawn_item(name, position=tuple(p0))
    sc.client.resetBaseVelocity(item.body, linearVelocity=tuple(v0))
    sc.track(item)
    return item, sc.watch_until_rest(item)


def assert_clear_of(sc, body, xy, obj):
    """xy keeps the thrown obj's footprint THROW_CLEARANCE_M from body's footprint circle."""
    lo, hi = (np.asarray(v) for v in sc.client.getAABB(body))
    room = math.hypot(xy[0] - (lo[0] + hi[0]) / 2, xy[1] - (lo[1] + hi[1]) / 2)
    r_new = max(obj.size[:2]) / 2
    assert room >= math.hypot(*(hi - lo)[:2]) / 2 + r_new + THROW_CLEARANCE_M - 1e-9


def test_an_empty_bin_keeps_the_aim_at_the_centre_and_any_item_at_rest_moves_it(scene):
    obj = get_object("cyl60")
    assert throw_spot(scene, "low", obj) == LOW.center_xy
    # even a 12 mm tile, far under the rim: a throw lands on its edge, not on the floor
    tile = ObjectParams("cuboid", 0.02, (0.05, 0.05, 0.012))
    item = scene.spawn_item(tile, position=(*LOW.center_xy, LOW.wall + 0.007))
    scene.watch_until_rest(item)
    scene.keep(item)
    x, y = throw_spot(scene, "low", obj)
    assert_clear_of(scene, item.body, (x, y), obj)
    # of the points as near the centre, the one beyond the tile, seen from the arm's base
    # at W's origin (the bin is 1.2 m along x); from the other side, the other one
    assert x > LOW.center_xy[0] and abs(y - LOW.center_xy[1]) < 1e-9
    x2, y2 = throw_spot(scene, "low", obj, source_xy=(2.4, 0.0))
    assert x2 == pytest.approx(2 * LOW.center_xy[0] - x) and abs(y2 - LOW.center_xy[1]) < 1e-9


@pytest.mark.parametrize("short_m", [1.5, 1.9])
def test_a_flat_throw_onto_an_item_at_rest_bounces_out_and_the_aim_beside_it_lands(short_m):
    """A 60 mm cube rests upright at the centre of a 121 mm rim bin (random layout 18's
    bin_1). A 60 mm cylinder launched from short_m before the centre on a flat arc (0.4 s
    of flight) lands on the cube and leaves the bin; launched the same way at the aim
    `throw_spot` gives, it stays in the bin."""
    spec = BinSpec("b", (2.0, 0.0), (0.338, 0.26), 0.121)

    def launch(aim_xy):
        sc = CellScene(robot=None, bins=[spec], pick_station_xy=(-1.0, -1.0))
        try:
            cube = sc.spawn_item("cube60", position=(*spec.center_xy, spec.wall + 0.031))
            sc.watch_until_rest(cube)
            sc.keep(cube)
            aim = throw_spot(sc, "b", get_object("cyl60")) if aim_xy is None else aim_xy
            _, out = launch_at(sc, "cyl60", aim, 0.4, short_m, 0.6, spec.rim_height)
            return out, cube.body
        finally:
            sc.close()

    at_centre, cube = launch(spec.center_xy)
    assert at_centre.touchdown_body == cube
    assert at_centre.bin_id is None
    at_spot, _ = launch(None)
    assert at_spot.bin_id == "b"  # (from 1.5 m it grazes the cube's top edge, and stays)


def test_the_aim_clears_an_item_standing_above_the_rim_and_the_throw_misses_it(scene):
    obj = get_object("cyl60")
    bottle = keep_lying(scene, "o6_bottle", LOW.center_xy)
    lo, hi = (np.asarray(v) for v in scene.client.getAABB(bottle.body))
    assert hi[2] > LOW.rim_height  # it stands above the rim: in the way
    x, y = throw_spot(scene, "low", obj)
    r_new = max(obj.size[:2]) / 2
    # clear of the bottle's footprint circle, and inside the walls by the margin
    assert_clear_of(scene, bottle.body, (x, y), obj)
    for k in range(2):
        assert abs((x, y)[k] - LOW.center_xy[k]) <= LOW.size_xy[k] / 2 - r_new - THROW_WALL_MARGIN_M
    # the scene: at the centre the cylinder strikes the bottle; at the spot, the floor
    _, at_centre = launch_at(scene, "cyl60", LOW.center_xy)
    assert at_centre.touchdown_body == bottle.body
    scene.remove_item(_)
    _, at_spot = launch_at(scene, "cyl60", (x, y))
    assert at_spot.touchdown_body != bottle.body
    assert at_spot.bin_id == "low"


JOB = """\
cell: {robot: panda, ee: pybullet}
bins:
  - {id: bin_5, position_m: [0.023, 1.379], size_m: [0.356, 0.344], rim_height_m: 0.055}
items:
  - {object: cyl60, count: 2, bin: bin_5}
policy: auto
seed: 16
"""


def test_the_cell_throws_clear_of_a_bottle_lying_across_a_low_bin(tmp_path, monkeypatch):
    """Random layout 16's bin_5 (Panda) with a bottle lying across its centre, as one
    thrown there came to rest: the cylinders are thrown at a point clear of it, cross
    the rim plane clear of the bottle's footprint (as the throw log records them),
    within a few centimetres of that point, and stay in the bin."""
    monkeypatch.chdir(tmp_path)
    store = ThrowStore(tmp_path / "aim.sqlite")
    o = Orchestrator(parse_job(JOB, str(tmp_path / "job.yaml")), session="aim", store=store)
    try:
        sc = o.scene
        q = (0.0, math.sin(math.pi / 4), 0.0, math.cos(math.pi / 4))
        bottle = sc.spawn_item("o6_bottle", position=(0.02, 1.40, 0.045), orientation=q)
        sc.watch_until_rest(bottle)
        sc.keep(bottle)
        lo, hi = (np.asarray(v) for v in sc.client.getAABB(bottle.body))
        spot = throw_spot(sc, "bin_5", get_object("cyl60"))
        assert math.dist(spot, (0.023, 1.379)) > 0.05  # moved off the centre
        summary = o.run()
        log = store.table(session="aim")
    finally:
        o.close()
        store.close()
    rows = [(r.action, r.failure, r.in_bin) for r in summary.results]
    assert rows == [("throw", "", True)] * 2, rows
    assert all(r.landing_error_m < 0.05 for r in summary.results)
    # the rim-plane crossings the log holds lie outside the bottle's footprint, widened
    # by the cylinder's radius (aimed at the centre, they would fall on the bottle)
    r_cyl = max(get_object("cyl60").size[:2]) / 2
    assert len(log) == 2
    for x, y in zip(log.num("landed_x_m"), log.num("landed_y_m"), strict=True):
        inside = lo[0] - r_cyl < x < hi[0] + r_cyl and lo[1] - r_cyl < y < hi[1] + r_cyl
        assert not inside, ((x, y), (lo[:2], hi[:2]))
