"""The PyBullet scene (DIRECT): bins, items, drag, settle detection, snapshot."""

import math

import numpy as np
import pytest

from cell.errors import InvalidParameter
from cell.sim import BinSpec, CellScene, which_bin

BIN = BinSpec("b1", (1.0, 0.5), (0.3, 0.4), 0.12)


def test_which_bin_inside_outside_and_above_rim():
    bins = [BIN, BinSpec("b2", (0.0, -1.0), (0.2, 0.2), 0.1, yaw=math.pi / 4)]
    assert which_bin((1.0, 0.5, 0.05), bins) == "b1"
    assert which_bin((1.14, 0.69), bins) == "b1"
    assert which_bin((1.16, 0.5, 0.05), bins) is None  # beyond the inner wall
    assert which_bin((1.0, 0.5, 0.2), bins) is None  # above the rim
    # rotated bin: a corner of the unrotated square lies outside the rotated one
    assert which_bin((0.13, -1.0, 0.02), bins) == "b2"
    assert which_bin((0.09, -0.91, 0.02), bins) is None
    # a tall item standing inside has its centre above the rim
    assert which_bin((1.0, 0.5, 0.15), bins) is None
    assert which_bin((1.0, 0.5, 0.15), bins, above_rim_m=0.05) == "b1"


def test_bin_spec_raises_if_rim_is_lower_than_wall():
    with pytest.raises(InvalidParameter, match="rim_height"):
        BinSpec("x", (0, 0), (0.3, 0.3), 0.005)
    with pytest.raises(InvalidParameter, match="size_xy"):
        BinSpec("x", (0, 0), (0.0, 0.3), 0.1)


@pytest.fixture(scope="module")
def scene():
    sc = CellScene(robot=None, bins=[BIN], pick_station_xy=(-1.0, -1.0))
    yield sc
    sc.close()


def test_item_dropped_into_a_bin_is_reported_in_that_bin(scene):
    item = scene.spawn_item("cube40", position=(1.05, 0.45, 0.5))
    out = scene.watch_until_rest(item)
    scene.remove_item(item)
    assert out.rested
    assert out.bin_id == "b1"
    assert out.touchdown_body == scene.bin_bodies["b1"]
    # resting on the bin's floor plate (wall 0.01 m thick): centre at 0.01 + 0.02
    assert out.rest_xyz[2] == pytest.approx(0.03, abs=2e-3)
    # it fell 0.47 m (centre 0.5 m -> 0.03 m at contact): sqrt(2 g h), drag is small
    assert out.touchdown_speed == pytest.approx(math.sqrt(2 * 9.81 * (0.5 - 0.03)), rel=0.03)


def test_item_dropped_outside_every_bin_is_in_none(scene):
    item = scene.spawn_item("sphere40", position=(0.3, -0.3, 0.3))
    out = scene.watch_until_rest(item, timeout_s=3.0)
    scene.remove_item(item)
    assert out.bin_id is None
    assert out.touchdown_body == scene.floor


def test_drag_slows_a_falling_sphere_as_the_closed_form_says(scene):
    # v(t) = v_t tanh(g t / v_t) for quadratic drag from rest; v_t = sqrt(m g / c)
    item = scene.spawn_item("sphere40", position=(-2.0, 2.0, 20.0))
    o = item.obj
    c = 0.5 * 1.225 * 0.47 * math.pi * (o.size[0] / 2) ** 2
    vt = math.sqrt(o.mass * 9.81 / c)
    scene.run_for(1.0)
    v = scene.client.getBaseVelocity(item.body)[0]
    scene.remove_item(item)
    expected = vt * math.tanh(9.81 * 1.0 / vt)
    assert -v[2] == pytest.approx(expected, rel=3e-3)
    assert -v[2] < 9.81 - 0.25  # clearly slower than without air


@pytest.mark.parametrize("name", ["duck", "rock_000"])
def test_mesh_items_come_to_rest_on_the_floor(scene, name):
    item = scene.spawn_item(name, position=(-1.5, 0.0, 0.2))
    out = scene.watch_until_rest(item, timeout_s=3.0)
    scene.remove_item(item)
    assert out.rested and out.bin_id is None
    half_diag = 0.5 * float(np.linalg.norm(item.obj.size))
    assert 0.0 < out.rest_xyz[2] < half_diag


def test_snapshot_writes_a_picture_of_the_cell(tmp_path):
    from PIL import Image

    with CellScene(bins=[BIN]) as sc:
        sc.spawn_item("cube50")
        path = sc.snapshot(tmp_path / "cell.png", width=160, height=120)
    img = np.asarray(Image.open(path))
    assert img.shape == (120, 160, 3)
    assert img.std() > 10  # not a blank frame
    # the arm is drawn (a DIRECT scene loads its meshes only for a picture): the same cell
    # without it differs where the arm stands
    with CellScene(robot=None, bins=[BIN]) as sc:
        sc.spawn_item("cube50")
        bare = sc.render(width=160, height=120)
    differs = np.abs(img.astype(float) - bare.astype(float)).max(axis=2) > 30
    assert differs.sum() > 200, differs.sum()


def test_a_new_item_goes_on_the_station_not_onto_an_item_flying_over_it(scene):
    """An item resting on the station is stacked on; one flying past it (tracked since its
    release) is not: the next item still rests on the station's top."""
    x0, y0 = scene.pick_station_xy
    top = scene.pick_station_height
    flying = scene.spawn_item("cube50", position=(x0, y0, top + 0.25))
    scene.track(flying)  # released: the loop watches it while it flies
    new = scene.spawn_item("cube30")
    z_new = scene.client.getBasePositionAndOrientation(new.body)[0][2]
    assert z_new == pytest.approx(top + new.obj.size[2] / 2 + 1e-3, abs=1e-6)
    scene.remove_item(new)
    scene.remove_item(flying)
    resting = scene.spawn_item("cube50")
    scene.run_for(0.2)
    stacked = scene.spawn_item("cube30")
    z_stacked = scene.client.getBasePositionAndOrientation(stacked.body)[0][2]
    assert z_stacked > top + resting.obj.size[2]  # on top of the resting one


def test_the_arms_meshes_are_loaded_for_a_picture_where_it_stands():
    # a DIRECT scene builds the arm without its visual meshes (they change no physics);
    # show_arm loads them, the arm at the joint positions it had
    with CellScene(bins=[BIN]) as sc:
        cl = sc.client

        def meshes() -> list[str]:
            return [v[4].decode() for v in cl.getVisualShapeData(sc.arm) if v[4]]

        assert not any(m.endswith(".dae") for m in meshes())
        q = [v + 0.2 for v in sc.ready_q]
        sc.set_arm(q, teleport=True)
        flange = cl.getLinkState(sc.arm, sc._flange, computeForwardKinematics=True)[4]
        sc.show_arm()
        assert sum(m.endswith(".dae") for m in meshes()) >= 8  # the Panda's visual meshes
        assert [cl.getJointState(sc.arm, j)[0] for j in sc.arm_joints] == pytest.approx(q)
        again = cl.getLinkState(sc.arm, sc._flange, computeForwardKinematics=True)[4]
        assert again == pytest.approx(flange, abs=1e-9)


def test_each_scene_keeps_its_own_client_and_a_closed_one_is_closed():
    # the client keeps each function it binds to its physics server (cell.sim.scene_build):
    # two scenes at once still each read their own bodies, a closed one reads none
    import pybullet

    a = CellScene(robot=None, bins=[BIN], pick_station_height=0.2)
    b = CellScene(robot=None, bins=[BIN], pick_station_height=0.5)
    try:
        for _ in range(2):  # the bound functions used again
            za = a.client.getBasePositionAndOrientation(a.pick_station)[0][2]
            zb = b.client.getBasePositionAndOrientation(b.pick_station)[0][2]
            assert (za, zb) == pytest.approx((0.1, 0.25))
        n = b.client.getNumBodies()
        a.close()
        with pytest.raises(pybullet.error):
            a.client.getNumBodies()
        assert b.client.getNumBodies() == n
    finally:
        b.close()
