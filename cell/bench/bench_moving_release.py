"""Release on the move against the static release, in the PyBullet cell (issue 16).

For random throws (an object, a bin, a lift pose over the pick station) it plans the
static release (`plan_facing`) and lets `choose_release` try releases on the move; it
reports the time each saves (to the release, and over the out-and-back cycle) and flies
in the scene, all by the same machinery (`release_in_scene`, the static ones with a
vanishing grip velocity): the moving throw chosen by the time to the release, the same
plan made static, and the static plan. Columns: the plant's release velocity against
the planned one; the moving landing against its prediction (`predict_moving_landing`,
and `predict_landing` with σ's base velocity: "world-frame"); the same plan made static
against the model (an unplanned throw: it may hit a bin's wall); the motion's shift of
the landing against the release formulation applied to the measured static launch
(`motion_shift_error`); the static plan's landing against its prediction; in the bin.

    python -m cell.bench.bench_moving_release [n] [seed]
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

OBJECTS = ("cube40", "cube50", "cyl50", "cuboid_a", "sphere55")
BINS = ("mid", "far")
LIFT_M = 0.15  # [m] the lift over the pick station the move starts from


@dataclass(frozen=True)
class Scenario:
    """A throw to plan: the object (catalogue and model), the goal, the static plan, the
    start configuration (at rest) and what the pads hold the item with."""

    obj: Any
    model_obj: Any
    goal: np.ndarray
    static_plan: Any
    q_start: np.ndarray
    hold: Any


def scenario(
    scene: Any, robot: Any, params: Any, obj_name: str, bin_id: str, offset_xy: np.ndarray
) -> Scenario:
    """The static plan to the bin and the lift pose over the station (+ offset) [m]."""
    from cell.arm.grip_limits import carry_hold
    from cell.catalogue import get_object
    from cell.frames import tcp_for_item_centre
    from cell.optimize.bounds import ThrowBounds
    from cell.optimize.plan import plan_facing
    from cell.robot.ik import solve_release_ik

    obj = get_object(obj_name)
    mo = params.model_object(obj)
    b = next(x for x in scene.bins if x.id == bin_id)
    goal = np.array([*b.center_xy, b.rim_height])
    sp = plan_facing(mo, goal, params.ee, ThrowBounds())
    lift = np.array(
        [
            scene.pick_station_xy[0] + offset_xy[0],
            scene.pick_station_xy[1] + offset_xy[1],
            scene.pick_station_height + obj.size[2] / 2 + LIFT_M,
        ]
    )
    tcp0 = tcp_for_item_centre(lift, -math.pi / 2, 0.0, sp.stroke_m, obj)
    q0 = solve_release_ik(robot, tcp0, -math.pi / 2, 0.0, np.asarray(scene.ready_q)).q
    return Scenario(obj, mo, goal, sp, q0, carry_hold(params, obj, sp.stroke_m))


def fly(scene: Any, ee: Any, sc: Scenario, stroke_m: float, motion: Any) -> tuple[Any, Any]:
    """Grip the item at the start, run the motion (`release_in_scene`) and watch the item
    come to rest: (its Outcome, whose track's times count from the tracker's start, the
    step after the latch; the SceneRelease)."""
    from cell.sim.release import release_in_scene

    scene.set_arm(sc.q_start, teleport=True)
    item = scene.spawn_item(sc.obj)
    try:
        ee.grasp(stroke_m, item)
        rel = release_in_scene(scene, ee, motion)
        return scene.watch_until_rest(item, timeout_s=3.0), rel
    finally:
        scene.remove_item(item)


PLANE_Z_M = 0.3  # [m] a plane over every bin's rim: each flight crosses it in free flight
T_EXIT_S = 0.07  # [s] after the latch: the item has left the end-effector (~40-60 ms)


def track_since_latch(out: Any, scene: Any) -> np.ndarray:
    """A flight's track as rows of (t since the latch [s], x, y, z [m]): the throw starts
    tracking after one launch step."""
    tr = np.asarray(out.track, float).copy()
    tr[:, 0] += scene.launch_dt_s
    return tr


def exit_state(track: np.ndarray, t_exit: float, window: float = 0.01) -> tuple[Any, Any]:
    """Position [m] and velocity [m/s] at t_exit [s since the latch] from a track, fitted
    over `window` with gravity taken out (drag, under 0.1 % of g there, neglected)."""
    from cell.model.params import G

    s = track[(track[:, 0] >= t_exit) & (track[:, 0] <= t_exit + window)]
    tau = s[:, 0] - t_exit
    p = s[:, 1:4].copy()
    p[:, 2] += 0.5 * G * tau**2
    coef = np.linalg.lstsq(np.c_[np.ones_like(tau), tau], p, rcond=None)[0]
    return coef[0], coef[1]


def model_flight(model_obj: Any, p: np.ndarray, v: np.ndarray, land_z: float) -> np.ndarray:
    """The model's flight (drag, planar RK4) from a state to the plane z = land_z: (x, y)."""
    from cell.model.planar import flight_planar_one
    from cell.model.throw import drag_constant

    k = float(
        drag_constant(
            np.array([model_obj.code]), np.array([model_obj.mass]), np.array([model_obj.size])
        )[0]
    )
    vh = math.hypot(v[0], v[1])
    dist = flight_planar_one(float(p[2]), vh, float(v[2]), k, land_z, 0.07)[0]
    return np.asarray(p[:2] + dist * v[:2] / vh, float)


def motion_shift_error(
    scene: Any, model_obj: Any, out_m: Any, out_s: Any, v: np.ndarray
) -> tuple[float, float, float]:
    """What the motion adds, measured against the release formulation (see
    tests/test_moving_release.py): (|shift measured − shift predicted| at PLANE_Z_M [m],
    |shift measured| [m], |(v_exit moving − v_exit static) − v| / |v|)."""
    p_s, v_s = exit_state(track_since_latch(out_s, scene), T_EXIT_S)
    _, v_m = exit_state(track_since_latch(out_m, scene), T_EXIT_S)
    pred = model_flight(model_obj, p_s + v * T_EXIT_S, v_s + v, PLANE_Z_M) - model_flight(
        model_obj, p_s, v_s, PLANE_Z_M
    )
    meas = np.array(out_m.crossing(PLANE_Z_M)[:2]) - np.array(out_s.crossing(PLANE_Z_M)[:2])
    gal = float(np.linalg.norm((v_m - v_s) - v) / np.linalg.norm(v))
    return float(np.linalg.norm(meas - pred)), float(np.linalg.norm(meas)), gal


def _static_as_planned(
    scene: Any, ee: Any, robot: Any, sc: Any, q_release: np.ndarray, v: np.ndarray
) -> float:
    """How far [mm] the scenario's static plan, flown from rest at q_release [rad] at its
    own stroke by the same machinery, lands from its prediction."""
    from cell.robot.moving_release import plan_moving_release

    sp = sc.static_plan
    static = plan_moving_release(
        robot, sc.q_start, q_release, 1e-6 * v / np.linalg.norm(v), hold=sc.hold
    )
    out_p, _ = fly(scene, ee, sc, sp.stroke_m, static)
    xy = np.array(out_p.crossing(float(sc.goal[2]))[:2])
    return 1000 * float(np.linalg.norm(xy - [sp.pred_x_m, sp.pred_y_m]))


def _print_summary(rows: list[Any], wall_s: float) -> None:
    """The summary line over the moving releases' `rows` (see `main`)."""
    a = np.array(rows, float)
    if len(a):
        print(
            f"{len(a)} moving releases: saved to the release mean {1000 * a[:, 0].mean():.0f} ms "
            f"(min {1000 * a[:, 0].min():.0f}, max {1000 * a[:, 0].max():.0f}); cycle saved mean "
            f"{1000 * a[:, 1].mean():.0f} ms; v error max {a[:, 2].max():.3f} %; "
            f"|moving − pred| mean {a[:, 3].mean():.1f} mm, max {a[:, 3].max():.1f} mm "
            f"(world-frame pred mean {a[:, 4].mean():.1f} mm); |static − model| mean "
            f"{a[:, 5].mean():.1f} mm, max {a[:, 5].max():.1f} mm; motion shift error mean "
            f"{a[:, 6].mean():.1f} mm, max {a[:, 6].max():.1f} mm; static plans' |landing − pred| "
            f"mean {a[:, 7].mean():.1f} mm, max {a[:, 7].max():.1f} mm; "
            f"{wall_s:.0f} s"
        )


def main(n: int = 8, seed: int = 1) -> None:
    """Print one line per throw and a summary."""
    from cell.endeffector.pybullet_backend import PyBulletEndEffector
    from cell.errors import CellError
    from cell.optimize.verify import fly as model_fly
    from cell.params import load_params, scene_params_path
    from cell.robot.model import load_robot
    from cell.robot.moving_release import choose_release, plan_moving_release
    from cell.sim import CellScene

    params = load_params(scene_params_path())
    robot = load_robot("panda")
    rng = np.random.default_rng(seed)
    scene = CellScene("panda")
    ee = PyBulletEndEffector(scene)
    rows = []
    t_wall = time.perf_counter()
    print(
        "object    bin  saved→release[ms] saved cycle[ms] |v|[m/s] v err[%] "
        "moving−pred[mm] (world-frame pred)[mm] static−model[mm] shift err[mm] "
        "static plan−pred[mm] in bin"
    )
    for _ in range(n):
        name = str(rng.choice(OBJECTS))
        bin_id = str(rng.choice(BINS))
        off = rng.uniform(-0.08, 0.08, 2)
        try:
            sc = scenario(scene, robot, params, name, bin_id, off)
            kw: dict[str, Any] = dict(hold=sc.hold)
            args = (robot, sc.model_obj, sc.static_plan, sc.q_start, params.ee)
            by_cycle = choose_release(*args, **kw)
            by_release = choose_release(*args, criterion="release", **kw)
        except CellError as exc:
            print(f"{name:9s} {bin_id:4s} not planned: {exc}")
            continue
        mt = by_release.moving
        if mt is None:
            print(f"{name:9s} {bin_id:4s} static release chosen (no moving one is sooner)")
            continue
        plan = mt.plan
        out_m, rel = fly(scene, ee, sc, plan.stroke_m, mt.motion)
        xy_m = np.array(out_m.crossing(float(sc.goal[2]))[:2])
        v = mt.motion.v_release
        v_err = 100 * float(np.linalg.norm(rel.v_item_mps - v) / np.linalg.norm(v))
        d_m = 1000 * float(np.linalg.norm(xy_m - [plan.pred_x_m, plan.pred_y_m]))
        d_w = 1000 * float(
            np.linalg.norm(xy_m - model_fly(sc.model_obj, plan.sigma, sc.goal, params.ee)[0][0])
        )
        # the same plan made static: the same σ without the grip velocity, same machinery
        sig = plan.sigma.copy()
        sig[3:6] = 0.0
        still = plan_moving_release(
            robot, sc.q_start, mt.motion.q_release, 1e-6 * v / np.linalg.norm(v), hold=sc.hold
        )
        out_s, _ = fly(scene, ee, sc, plan.stroke_m, still)
        xy_s = np.array(out_s.crossing(float(sc.goal[2]))[:2])
        d_s = 1000 * float(
            np.linalg.norm(xy_s - model_fly(sc.model_obj, sig, sc.goal, params.ee)[0][0])
        )
        shift_err, _, _ = motion_shift_error(scene, sc.model_obj, out_m, out_s, v)
        # the static plan as planned (its own stroke), flown by the same machinery
        d_p = _static_as_planned(scene, ee, robot, sc, by_release.static_q, v)
        saved = (by_release.saved_to_release_s, by_cycle.saved_s)
        rows.append((*saved, v_err, d_m, d_w, d_s, 1000 * shift_err, d_p))
        print(
            f"{name:9s} {bin_id:4s} {1000 * by_release.saved_to_release_s:17.0f} "
            f"{1000 * by_cycle.saved_s:15.0f} {np.linalg.norm(v):8.2f} {v_err:8.3f} "
            f"{d_m:15.1f} {d_w:22.1f} {d_s:16.1f} {1000 * shift_err:14.1f} {d_p:20.1f} "
            f"{out_m.bin_id == bin_id}"
        )
    _print_summary(rows, time.perf_counter() - t_wall)
    scene.close()


if __name__ == "__main__":
    main(*(int(x) for x in sys.argv[1:3]))
