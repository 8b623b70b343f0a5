"""The moving-base platform: planning with a base velocity, the ruckig drive, the scene."""

import math
from pathlib import Path

import numpy as np
import pytest

from cell.catalogue import get_object
from cell.endeffector.pybullet_backend import PyBulletEndEffector
from cell.errors import InvalidParameter, TrajectoryError
from cell.model import DEFAULT_EE, reference_landing
from cell.params import load_params
from cell.platforms import BaseLimits, MobilePlatform
from cell.platforms.mobile_scene import MovingBaseScene
from cell.sim import BinSpec

SCENE_PARAMS = Path(__file__).resolve().parents[1] / "robots" / "cell_scene" / "ee_params.yaml"
CUBE = get_object("cube50")
GOAL = (2.0, 0.5, 0.15)


@pytest.fixture(scope="module")
def free_plan():
    return MobilePlatform(0.5).plan(CUBE, GOAL, DEFAULT_EE)


def test_free_velocity_plan_lands_on_target(free_plan):
    p = free_plan
    v = np.array([p.vx_mps, p.vy_mps, p.vz_mps])
    assert np.all(np.abs(v[:2]) <= 0.5 + 1e-9) and v[2] == 0.0
    assert np.linalg.norm(v) > 0.1  # the optimiser uses the base's motion
    # an independent fine-step 3-D integration of the planned σ lands on the goal
    ref = reference_landing(p.to_batch(CUBE), DEFAULT_EE, step=2e-4)
    assert math.hypot(ref.x[0] - GOAL[0], ref.y[0] - GOAL[1]) < 2e-3
    # and the base velocity matters: the same σ from a fixed base misses
    still = p.to_batch(CUBE)
    still = type(still)(**{**still.__dict__, "base_velocity": np.zeros((1, 3))})
    miss = reference_landing(still, DEFAULT_EE)
    assert math.hypot(miss.x[0] - GOAL[0], miss.y[0] - GOAL[1]) > 0.1


def test_fixed_speed_plan_drives_at_the_speed_toward_the_target():
    m = MobilePlatform(0.8)
    p = m.plan(CUBE, GOAL, DEFAULT_EE, free_velocity=False)
    v = np.array([p.vx_mps, p.vy_mps])
    assert np.linalg.norm(v) == pytest.approx(0.8)
    ref = m.bounds().nominal_release(np.asarray(GOAL))
    d = np.asarray(GOAL[:2]) - np.asarray(ref[:2])
    assert v / 0.8 == pytest.approx(d / np.linalg.norm(d))
    land = reference_landing(p.to_batch(CUBE), DEFAULT_EE)
    assert math.hypot(land.x[0] - GOAL[0], land.y[0] - GOAL[1]) < 2e-3


def test_ruckig_drive_arrives_with_the_planned_velocity(free_plan):
    lim = BaseLimits(velocity_mps=1.5, acceleration_mps2=1.0, jerk_mps3=5.0)
    m = MobilePlatform(0.5, limits=lim)
    drive = m.arrival(free_plan, start_xy=(-0.5, -0.3))
    p1, v1, a1 = drive.end_state()
    assert p1 == pytest.approx([free_plan.x_m, free_plan.y_m, free_plan.z_m], abs=1e-6)
    assert v1[:2] == pytest.approx([free_plan.vx_mps, free_plan.vy_mps], abs=1e-6)
    # finite differences of the sampled path give the same arrival velocity
    h = 1e-4
    fd = (drive.sample(drive.duration_s)[0] - drive.sample(drive.duration_s - h)[0]) / h
    assert fd[:2] == pytest.approx(v1[:2], abs=2e-3)
    p0, v0, _ = drive.sample(0.0)
    assert p0[:2] == pytest.approx([-0.5, -0.3]) and not v0.any()
    ts = np.linspace(0.0, drive.duration_s, 400)
    vs = np.array([drive.sample(t)[1] for t in ts])
    acc = np.array([drive.sample(t)[2] for t in ts])
    assert np.max(np.abs(vs)) <= lim.velocity_mps + 1e-6
    assert np.max(np.abs(acc)) <= lim.acceleration_mps2 + 1e-6
    # the velocity is the integral of the acceleration (trapezoid over the samples)
    dv = np.trapezoid(acc[:, :2], ts, axis=0)
    assert dv == pytest.approx(v1[:2] - v0[:2], abs=5e-3)


def test_moving_base_throw_in_the_scene_leaves_with_the_base_velocity_and_lands_in_the_bin():
    params = load_params(SCENE_PARAMS)
    obj = params.objects["cube50"]
    m = MobilePlatform(0.5)
    plan = m.plan(obj, GOAL, params.ee, free_velocity=False)
    sc = MovingBaseScene(
        bins=[BinSpec("target", GOAL[:2], (0.4, 0.4), GOAL[2])], pick_station_xy=(-1.5, -1.5)
    )
    try:
        ee = PyBulletEndEffector(sc)
        drive = m.arrival(plan)
        sc.start_drive(drive, plan.elevation_rad, plan.azimuth_rad, plan.stroke_m, CUBE)
        item = sc.spawn_item("cube50")
        ee.grasp(plan.stroke_m, item)
        sc.drive_to_release()
        pos = np.asarray(sc.client.getBasePositionAndOrientation(item.body)[0])
        vel = np.asarray(sc.client.getBaseVelocity(item.body)[0])
        assert pos == pytest.approx([plan.x_m, plan.y_m, plan.z_m], abs=0.01)
        assert vel[:2] == pytest.approx([plan.vx_mps, plan.vy_mps], abs=0.02)
        ee.throw()
        out = sc.watch_until_rest(item, timeout_s=4.0)
        assert out.bin_id == "target"
    finally:
        sc.close()


def test_bad_mobile_settings_raise(free_plan):
    with pytest.raises(InvalidParameter, match="speed_mps"):
        MobilePlatform(3.0)
    with pytest.raises(InvalidParameter, match="direction"):
        MobilePlatform(0.5).base_velocity([0.0, 0.0, 1.0])
    slow = MobilePlatform(0.1, limits=BaseLimits(velocity_mps=0.2))
    with pytest.raises(TrajectoryError, match="limit"):
        slow.arrival(free_plan)
