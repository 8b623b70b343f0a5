"""Release on the move against the static release, in the PyBullet cell (issue 16).

For random throws (an object, a bin, a lift pose over the pick station) it plans the
static release (`plan_facing`) and lets `choose_release` try releases on the move; it
reports the time each saves and flies, in the scene, the moving throw the planner
chose (by the time to the release) and the same plan made static (the same machinery,
`release_in_scene` with a vanishing grip velocity), and prints the plant's release
velocity against the planned one and each landing against the model's prediction.

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
    from cell.catalogue import get_object
    from cell.optimize.bounds import ThrowBounds
    from cell.optimize.plan import plan_facing
    from cell.orchestrator import carry_hold
    from cell.robot.ik import solve_release_ik
    from cell.robot.moving_release import tcp_for_item_centre

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
    tcp0 = tcp_for_item_centre(lift, -math.pi / 2, 0.0, sp.stroke_m, obj.size[2])
    q0 = solve_release_ik(robot, tcp0, -math.pi / 2, 0.0, np.asarray(scene.ready_q)).q
    return Scenario(obj, mo, goal, sp, q0, carry_hold(params, obj, sp.stroke_m))


def fly(scene: Any, ee: Any, sc: Scenario, stroke_m: float, motion: Any) -> tuple[Any, Any]:
    """Grip the item at the start, run the motion (`release_in_scene`) and watch the item
    come to rest: (its Outcome, whose track's times count from the tracker's start, the
    step after the latch; the SceneRelease)."""
    from cell.robot.moving_release import release_in_scene

    scene.set_arm(sc.q_start, teleport=True)
    item = scene.spawn_item(sc.obj)
    try:
        ee.grasp(stroke_m, item)
        rel = release_in_scene(scene, ee, motion)
        return scene.watch_until_rest(item, timeout_s=3.0), rel
    finally:
        scene.remove_item(item)


def main(n: int = 8, seed: int = 1) -> None:
    """Print one line per throw and a summary."""
    from cell.endeffector.pybullet_backend import PyBulletEndEffector
    from cell.errors import CellError
    from cell.orchestrator import scene_params_path
    from cell.params import load_params
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
        "object    bin  saved→rel[ms] saved cycle[ms] |v| [m/s] v err[%] "
        "moving−model[mm] static−model[mm] shift err[mm] bin"
    )
    for _ in range(n):
        name = str(rng.choice(OBJECTS))
        bin_id = str(rng.choice(BINS))
        off = rng.uniform(-0.08, 0.08, 2)
        try:
            sc = scenario(scene, robot, params, name, bin_id, off)
            ch = choose_release(
                robot, sc.model_obj, sc.static_plan, sc.q_start, params.ee, hold=sc.hold
            )
            by_release = choose_release(
                robot,
                sc.model_obj,
                sc.static_plan,
                sc.q_start,
                params.ee,
                hold=sc.hold,
                criterion="release",
            )
        except CellError as exc:
            print(f"{name:9s} {bin_id:4s} not planned: {exc}")
            continue
        mt = by_release.moving
        if mt is None:
            print(f"{name:9s} {bin_id:4s} static release chosen (no moving one is faster)")
            rows.append((0.0, ch.saved_s, math.nan, math.nan, math.nan, math.nan, math.nan))
            continue
        plan = mt.plan
        out_m, rel = fly(scene, ee, sc, plan.stroke_m, mt.motion)
        xy_m, bin_m = np.array(out_m.crossing(float(sc.goal[2]))[:2]), out_m.bin_id
        v = mt.motion.v_release
        v_err = 100 * float(np.linalg.norm(rel.v_item_mps - v) / np.linalg.norm(v))
        pred = np.array([plan.pred_x_m, plan.pred_y_m])
        d_m = 1000 * float(np.linalg.norm(xy_m - pred))
        # the same plan made static: the same σ without the grip velocity, same machinery
        from cell.optimize.verify import fly as model_fly

        sig = plan.sigma.copy()
        sig[3:6] = 0.0
        pred_s = model_fly(sc.model_obj, sig, sc.goal, params.ee)[0][0]
        still = plan_moving_release(
            robot, sc.q_start, mt.motion.q_release, 1e-6 * v / np.linalg.norm(v), hold=sc.hold
        )
        out_s, _ = fly(scene, ee, sc, plan.stroke_m, still)
        xy_s = np.array(out_s.crossing(float(sc.goal[2]))[:2])
        d_s = 1000 * float(np.linalg.norm(xy_s - pred_s))
        shift = 1000 * float(np.linalg.norm((xy_m - xy_s) - (pred - pred_s)))
        from cell.robot.moving_release import predict_moving_landing

        pred_cf = predict_moving_landing(sc.model_obj, plan, params.ee)
        d_cf = 1000 * float(np.linalg.norm(xy_m - pred_cf))
        shift_cf = 1000 * float(np.linalg.norm((xy_m - xy_s) - (pred_cf - pred_s)))
        print(
            f"   carriage-frame model: moving−model {d_cf:.1f} mm, shift err {shift_cf:.1f} mm, "
            f"model diff {1000 * np.linalg.norm(pred_cf - pred):.1f} mm"
        )
        rows.append((by_release.saved_to_release_s, ch.saved_s, v_err, d_m, d_s, shift, 1.0))
        print(
            f"{name:9s} {bin_id:4s} {1000 * by_release.saved_to_release_s:12.0f} "
            f"{1000 * ch.saved_s:15.0f} {np.linalg.norm(v):9.2f} {v_err:8.3f} "
            f"{d_m:16.1f} {d_s:16.1f} {shift:13.1f} {bin_m == bin_id}"
        )
    a = np.array(rows, float)
    if len(a):
        print(
            f"mean saved to release {1000 * np.nanmean(a[:, 0]):.0f} ms, mean cycle saved "
            f"{1000 * np.nanmean(a[:, 1]):.0f} ms; |moving − model| mean "
            f"{np.nanmean(a[:, 3]):.1f} mm max {np.nanmax(a[:, 3]):.1f} mm; |static − model| "
            f"mean {np.nanmean(a[:, 4]):.1f} mm; shift error mean {np.nanmean(a[:, 5]):.1f} mm "
            f"max {np.nanmax(a[:, 5]):.1f} mm; v error max {np.nanmax(a[:, 2]):.3f} %; "
            f"{time.perf_counter() - t_wall:.0f} s"
        )
    scene.close()


if __name__ == "__main__":
    main(*(int(x) for x in sys.argv[1:3]))
