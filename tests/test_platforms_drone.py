"""The drone platform in PyBullet (DIRECT): iris hovering, end-effector beneath, downwash field."""

from pathlib import Path

import numpy as np
import pytest

from cell.endeffector.pybullet_backend import PyBulletEndEffector
from cell.errors import InvalidParameter
from cell.model import ThrowBatch
from cell.params import load_params
from cell.platforms import DownwashLaw, predict_drone_landing
from cell.platforms.drone import DroneScene, scene_exit_distance_m
from cell.sim import BinSpec

SCENE_PARAMS = Path(__file__).resolve().parents[1] / "robots" / "cell_scene" / "ee_params.yaml"
LAW = DownwashLaw(induced_mps_per_krpm=0.7)
HOVER_M, STROKE_M, RIM_M = 2.0, 0.05, 0.15


def _model(rpm, scene):
    params = load_params(SCENE_PARAMS)
    obj = params.objects["cube50"]
    b = ThrowBatch.single(
        obj,
        stroke=STROKE_M,
        position=scene.drone.release_point,
        elevation=0.0,
        azimuth=0.0,
        land_z=RIM_M,
    )
    land = predict_drone_landing(
        b,
        params.ee,
        rpm,
        scene.drone.rotor_centre,
        LAW,
        exit_distance_m=scene_exit_distance_m(STROKE_M, scene.geometry),
    )
    return land.xy[0]


def _throw(rpm, bin_xy=None):
    """One horizontal cube throw from under the drone; returns (crossing xy, model xy, outcome)."""
    probe = DroneScene(HOVER_M, rpm, LAW, bins=[BinSpec("x", (9.0, 9.0), (0.3, 0.3), RIM_M)])
    predicted = _model(rpm, probe)
    probe.close()
    centre = tuple(predicted) if bin_xy is None else bin_xy
    sc = DroneScene(
        HOVER_M,
        rpm,
        LAW,
        bins=[BinSpec("target", centre, (0.4, 0.4), RIM_M)],
        pick_station_xy=(-1.5, -1.5),
    )
    try:
        ee = PyBulletEndEffector(sc)
        obj = load_params(SCENE_PARAMS).objects["cube50"]
        sc.hold_at_release(0.0, 0.0, STROKE_M, obj)
        item = sc.spawn_item("cube50")
        ee.grasp(STROKE_M, item)
        held_at = np.asarray(sc.client.getBasePositionAndOrientation(item.body)[0])
        assert np.linalg.norm(held_at - sc.drone.release_point) < 0.01
        ee.throw()
        tr = sc.tracker(item)
        out = sc.watch_until_rest(item, timeout_s=4.0)
        del tr
        cross = np.asarray(out.crossing(RIM_M)[:2])
        return cross, predicted, out
    finally:
        sc.close()


@pytest.fixture(scope="module")
def throws():
    return {rpm: _throw(rpm) for rpm in (0.0, 14860.0)}


def test_drone_throw_lands_in_the_bin_the_downwash_model_predicts(throws):
    cross, predicted, out = throws[14860.0]
    assert out.bin_id == "target"
    reach = float(np.linalg.norm(predicted - [0.0, 0.0]))
    assert reach > 1.5
    # the scene's own launch gap (5 % of reach, as the arm's calibrated model) plus the downwash
    assert np.linalg.norm(cross - predicted) < 0.08 * reach


def test_scene_downwash_shortens_the_throw_as_the_model_says(throws):
    c0, m0, _ = throws[0.0]
    c1, m1, _ = throws[14860.0]
    sim_drop = c0[0] - c1[0]
    model_drop = m0[0] - m1[0]
    assert model_drop > 0.05
    assert sim_drop > 0.05
    assert sim_drop == pytest.approx(model_drop, rel=0.35)
    assert abs(c1[1]) < 0.01  # straight ahead: the column pushes down, not sideways


def test_downwash_force_is_drag_on_the_air_relative_velocity():
    sc = DroneScene(HOVER_M, 12000.0, LAW, bins=[BinSpec("x", (3.0, 3.0), (0.3, 0.3), RIM_M)])
    try:
        d = sc.drone
        p = d.release_point
        w = d.air_velocity(p[None, :])[0]
        assert w[2] < -5.0 and not w[:2].any()
        c = 0.0024
        # at rest: the still-air drag is zero, the downwash drag is c |w| w
        assert d.downwash_force(p, [0, 0, 0], c) == pytest.approx(c * np.linalg.norm(w) * w)
        v = np.array([3.0, 0.0, -1.0])
        rel = v - w
        total = d.downwash_force(p, v, c) - c * np.linalg.norm(v) * v
        assert total == pytest.approx(-c * np.linalg.norm(rel) * rel)
        # far from the column the drone adds nothing
        assert not d.downwash_force([3.0, 3.0, 1.0], v, c).any()
        # the iris body is loaded, fixed, above the release point
        pos, _ = sc.client.getBasePositionAndOrientation(d.body)
        assert pos == pytest.approx((0.0, 0.0, HOVER_M))
        assert sc.client.getNumJoints(d.body) >= 4
    finally:
        sc.close()


def test_bad_drone_settings_raise():
    sc = DroneScene(HOVER_M, 0.0, LAW, bins=[BinSpec("x", (3.0, 3.0), (0.3, 0.3), RIM_M)])
    try:
        from cell.platforms.drone import DronePlatform

        with pytest.raises(InvalidParameter, match="rotor_rpm"):
            DronePlatform(sc.client, 2.0, -1.0, LAW)
        with pytest.raises(InvalidParameter, match="hover_height_m"):
            DronePlatform(sc.client, 20.0, 100.0, LAW)
    finally:
        sc.close()
