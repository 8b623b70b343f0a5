"""Release on the move (issue 16): the arm's motion, the planner, and the plant.

The scene tests fly one throw of cube50 to the "mid" bin in the Panda cell, released on
the move as `choose_release` planned it (by the time to the release), and the same
plan made static (the same σ, pose and stroke, the same scene machinery
`release_in_scene`, the grip's velocity 1e-6 m/s), so that what the motion adds can be
told from what the model gets wrong about the band's launch anyway.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from cell.errors import TrajectoryError
from cell.robot import moving_release
from cell.robot.model import load_robot
from cell.robot.moving_release import (
    choose_release,
    plan_moving_release,
    predict_moving_landing,
    throw_axis,
)

ROBOT = "panda"


@pytest.fixture(scope="module")
def robot():
    return load_robot(ROBOT)


def _release_pose(robot):
    """A release configuration of the cell (the throw axis 25° up toward +x) and a lift
    pose over the pick station, both from IK."""
    from cell.robot.ik import solve_release_ik

    q_rel = solve_release_ik(robot, np.array([0.45, 0.1, 0.75]), 0.44, 0.23, robot.home).q
    q0 = solve_release_ik(robot, np.array([0.45, -0.4, 0.5]), -math.pi / 2, 0.0, robot.home).q
    return q0, q_rel


# -- the motion, without the plant -------------------------------------------------
def test_ruckig_arrives_at_the_release_state_and_the_grip_moves_at_v(robot):
    q0, q_rel = _release_pose(robot)
    u = throw_axis(0.44, 0.23)
    v = 0.5 * u
    m = plan_moving_release(robot, q0, q_rel, v)
    # ruckig's end state is its target: the run-in's first state, at zero acceleration
    q_a, dq_a, ddq_a = m.approach.end_state()
    q_i, dq_i, _ = m.run_in.sample(0.0)
    np.testing.assert_allclose(q_a, q_i, atol=1e-9)
    np.testing.assert_allclose(dq_a, dq_i, atol=1e-9)
    np.testing.assert_allclose(ddq_a, 0.0, atol=1e-9)
    # and it got there by its own velocity: ∫ q̇ dt over the approach (Simpson) = q_i − q0
    ts = np.linspace(0.0, m.approach.duration, 4001)
    _, dqs, _ = m.approach.sample_many(ts)
    h = ts[1] - ts[0]
    integral = h / 3 * (dqs[0] + 4 * dqs[1:-1:2].sum(0) + 2 * dqs[2:-1:2].sum(0) + dqs[-1])
    np.testing.assert_allclose(q0 + integral, q_i, atol=1e-6)
    assert np.all(np.abs(dqs) <= robot.limits.velocity * (1 + 1e-9))
    # the release state: the planned configuration, the grip centre at v, the axis still,
    # by finite differences of the forward kinematics (not by the Jacobian)
    q_r, dq_r, _ = m.state(m.t_release_s)
    np.testing.assert_allclose(q_r, q_rel, atol=1e-9)
    np.testing.assert_allclose(dq_r, m.dq_release, atol=1e-9)
    d = 1e-4
    (pa, ra), (pb, rb) = (robot.tcp_pose(m.state(m.t_release_s + s)[0]) for s in (-d, d))
    np.testing.assert_allclose((pb - pa) / (2 * d), v, atol=1e-4)
    assert np.linalg.norm(rb[:, 2] - ra[:, 2]) / (2 * d) < 1e-3  # the axis turns < 1 mrad/s
    # the coast keeps v; the stop ends at rest
    for s in (0.5, 1.0):
        t = m.t_release_s + s * m.coast.duration
        p1, p2 = (robot.tcp_pose(m.state(t + e)[0])[0] for e in (-d, d))
        np.testing.assert_allclose((p2 - p1) / (2 * d), v, atol=1e-4)
    np.testing.assert_allclose(m.stop.end_state()[1], 0.0, atol=1e-9)


def test_a_release_velocity_above_the_joint_limits_is_refused(robot):
    q0, q_rel = _release_pose(robot)
    with pytest.raises(TrajectoryError, match="limit"):
        plan_moving_release(robot, q0, q_rel, 5.0 * throw_axis(0.44, 0.23))


def test_without_a_faster_moving_release_the_static_one_is_kept(robot):
    from cell.catalogue import get_object
    from cell.errors import InvalidInput
    from cell.model.params import DEFAULT_EE
    from cell.optimize.plan import plan_facing

    obj = get_object("cube50")
    sp = plan_facing(obj, (1.3, 0.3, 0.15), DEFAULT_EE)
    q0, _ = _release_pose(robot)
    ch = choose_release(robot, obj, sp, q0, DEFAULT_EE, speeds_mps=())
    assert ch.moving is None and ch.saved_s == 0.0 and ch.saved_to_release_s == 0.0
    assert ch.static_cycle_s > ch.static_to_release_s > 0.0
    with pytest.raises(InvalidInput):
        choose_release(robot, obj, sp, q0, DEFAULT_EE, criterion="fastest")


def test_the_moving_landing_of_a_static_plan_is_the_models(robot):
    """predict_moving_landing with no grip velocity is predict_landing's landing."""
    from cell.catalogue import get_object
    from cell.model.params import DEFAULT_EE
    from cell.optimize.plan import plan_facing

    sp = plan_facing(get_object("cube50"), (1.3, 0.3, 0.15), DEFAULT_EE)
    np.testing.assert_allclose(
        predict_moving_landing(get_object("cube50"), sp, DEFAULT_EE),
        [sp.pred_x_m, sp.pred_y_m],
        atol=1e-9,
    )


# -- in the scene --------------------------------------------------------------------
# The static release's wait at the pose the moving throw below was chosen against: the
# cell's SETTLE_S was 0.05 s then; with none (the cell's now), no release on the move of
# this scenario is sooner (`test_with_no_settle_the_static_release_is_taken_unless_...`)
SCENARIO_SETTLE_S = 0.05


@pytest.fixture(scope="module")
def flown(robot):
    """One moving throw and the same plan made static, flown in the scene: the moving
    throw the planner chooses with the static release waiting SCENARIO_SETTLE_S."""
    from cell.bench.bench_moving_release import fly, scenario
    from cell.endeffector.pybullet_backend import PyBulletEndEffector
    from cell.params import load_params, scene_params_path
    from cell.sim import CellScene

    params = load_params(scene_params_path())
    scene = CellScene(ROBOT)
    ee = PyBulletEndEffector(scene)
    try:
        sc = scenario(scene, robot, params, "cube50", "mid", np.zeros(2))
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(moving_release, "SETTLE_S", SCENARIO_SETTLE_S)
            choice = choose_release(
                robot,
                sc.model_obj,
                sc.static_plan,
                sc.q_start,
                params.ee,
                hold=sc.hold,
                criterion="release",
            )
        mt = choice.moving
        assert mt is not None
        out_m, rel_m = fly(scene, ee, sc, mt.plan.stroke_m, mt.motion)
        v = mt.motion.v_release
        still = plan_moving_release(
            robot, sc.q_start, mt.motion.q_release, 1e-6 * v / np.linalg.norm(v), hold=sc.hold
        )
        out_s, rel_s = fly(scene, ee, sc, mt.plan.stroke_m, still)
        at_rest = plan_moving_release(
            robot, sc.q_start, choice.static_q, 1e-6 * v / np.linalg.norm(v), hold=sc.hold
        )
        out_p, _ = fly(scene, ee, sc, sc.static_plan.stroke_m, at_rest)
        bin_spec = next(b for b in scene.bins if b.id == "mid")
        yield dict(
            sc=sc,
            params=params,
            choice=choice,
            mt=mt,
            out_m=out_m,
            rel_m=rel_m,
            out_s=out_s,
            rel_s=rel_s,
            out_p=out_p,
            bin=bin_spec,
            dt=scene.launch_dt_s,
            scene=scene,
        )
    finally:
        scene.close()


def test_with_no_settle_the_static_release_is_taken_unless_a_moving_one_is_sooner(robot):
    """The cell's static release waits SETTLE_S (none) at the pose: a release on the move
    (run-in, latch, coast) is then taken only where one is sooner by the criterion, the
    soonest of them; here (cube50 to the mid bin) none is, so the static release is
    taken, and every moving candidate planned is no sooner than it."""
    from cell.bench.bench_moving_release import scenario
    from cell.params import load_params, scene_params_path
    from cell.sim import CellScene

    assert moving_release.SETTLE_S == 0.0
    params = load_params(scene_params_path())
    scene = CellScene(ROBOT)
    try:
        sc = scenario(scene, robot, params, "cube50", "mid", np.zeros(2))
    finally:
        scene.close()
    args = (robot, sc.model_obj, sc.static_plan, sc.q_start, params.ee)
    choice = choose_release(*args, hold=sc.hold, criterion="release")
    planned = [mt for _, mt in choice.candidates if not isinstance(mt, str)]
    assert planned, choice.candidates
    assert choice.moving is None
    assert min(mt.motion.t_release_s for mt in planned) >= choice.static_to_release_s
    # the same candidates against a static release that waits SCENARIO_SETTLE_S: sooner
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(moving_release, "SETTLE_S", SCENARIO_SETTLE_S)
        waiting = choose_release(*args, hold=sc.hold, criterion="release")
    assert waiting.static_to_release_s == pytest.approx(
        choice.static_to_release_s + SCENARIO_SETTLE_S
    )
    assert waiting.moving is not None
    assert waiting.moving.motion.t_release_s < waiting.static_to_release_s


def test_the_planner_releases_on_the_move_sooner_than_at_rest(flown):
    ch = flown["choice"]
    assert ch.saved_to_release_s > 0.0
    assert flown["mt"].motion.t_release_s < ch.static_to_release_s
    # the moving plan lands on the goal by the model, within the bin by far
    plan = flown["mt"].plan
    assert plan.miss_m <= 1e-3
    assert np.linalg.norm(flown["mt"].motion.v_release) > 0.1


def test_release_velocity_measured_in_the_plant_matches_the_plan(flown):
    """The item's centre-of-mass velocity at the latch instant (PyBullet's, the item a
    free body held by friction) against the planned v_rel: within 2 %; the latch opened
    at the planned instant (within a physics step)."""
    rel, v = flown["rel_m"], flown["mt"].motion.v_release
    err = np.linalg.norm(rel.v_item_mps - v) / np.linalg.norm(v)
    assert err < 0.02
    assert np.linalg.norm(rel.v_ee_mps - v) / np.linalg.norm(v) < 0.02
    assert abs(rel.t_latch_s - rel.t_planned_s) <= flown["dt"]
    # where: the planned release point, within the mount's drag behind the arm
    plan = flown["mt"].plan
    assert np.linalg.norm(rel.released_at - [plan.x_m, plan.y_m, plan.z_m]) < 2e-3


def test_moving_release_lands_where_the_motion_puts_it(flown):
    """What the motion adds to the landing, measured against predicted, within 5 mm.

    The model's band launch itself is off in this plant by a few mm to 2 cm depending on
    the stroke (the same plan made static lands that far from its prediction, see the
    report). So the landing's shift caused by the motion is compared as well, apart from
    that error: measured, where the moving throw crosses a plane (PLANE_Z_M, over every
    bin's rim) minus where the static one does; predicted, the release formulation
    applied to the static throw's launch measured in the plant — its state once the item
    has left the end-effector (70 ms after the latch), the velocity plus v_rel and the
    position plus v_rel × 70 ms — and both flown by the model's flight. Independently: the moving
    launch measured there is the static one plus v_rel, within 2 % of |v_rel| (Galilean:
    the band pushes in the end-effector's frame).
    """
    from cell.bench.bench_moving_release import (
        PLANE_Z_M,
        T_EXIT_S,
        exit_state,
        model_flight,
        track_since_latch,
    )

    mt, sc, scene = flown["mt"], flown["sc"], flown["scene"]
    v = mt.motion.v_release
    assert T_EXIT_S > flown["rel_m"].throw_done_s  # the item has left the pads by then
    p_s, v_s = exit_state(track_since_latch(flown["out_s"], scene), T_EXIT_S)
    _, v_m = exit_state(track_since_latch(flown["out_m"], scene), T_EXIT_S)
    assert np.linalg.norm((v_m - v_s) - v) < 0.02 * np.linalg.norm(v)
    shift_pred = model_flight(sc.model_obj, p_s + v * T_EXIT_S, v_s + v, PLANE_Z_M) - model_flight(
        sc.model_obj, p_s, v_s, PLANE_Z_M
    )
    xy_m, xy_s = (np.array(flown[k].crossing(PLANE_Z_M)[:2]) for k in ("out_m", "out_s"))
    shift_meas = xy_m - xy_s
    assert np.linalg.norm(shift_meas) > 0.05  # the motion moves the landing by cm
    assert np.linalg.norm(shift_meas - shift_pred) < 5e-3


def test_moving_release_lands_in_the_bin_as_near_the_prediction_as_a_static_one(flown):
    """In the scene: in the bin (where it came to rest, and its rim-plane crossing within
    the bin's half-width of its centre); and as near the plan's predicted landing
    (`predict_moving_landing`) as the static plan lands to its own prediction, within
    5 mm, and within 10 mm outright. (The model's band launch is itself off in this
    plant: static plans land 5-19 mm from their predictions, 12 mm on average over the
    bench's throws; moving ones 2.5-25 mm, 11 mm on average.)"""
    b, plan, out = flown["bin"], flown["mt"].plan, flown["out_m"]
    xy = np.array(out.crossing(b.rim_height)[:2])
    assert out.bin_id == "mid"
    assert np.all(np.abs(xy - np.asarray(b.center_xy)) < np.asarray(b.size_xy) / 2)
    pred = np.array([plan.pred_x_m, plan.pred_y_m])
    np.testing.assert_allclose(
        pred, predict_moving_landing(flown["sc"].model_obj, plan, flown["params"].ee)
    )
    sp = flown["sc"].static_plan
    xy_p = np.array(flown["out_p"].crossing(b.rim_height)[:2])
    d_static = np.linalg.norm(xy_p - [sp.pred_x_m, sp.pred_y_m])
    d_moving = np.linalg.norm(xy - pred)
    print(f"moving {1000 * d_moving:.1f} mm, static {1000 * d_static:.1f} mm")
    assert d_moving < d_static + 5e-3
    assert d_moving < 10e-3
