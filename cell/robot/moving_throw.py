"""A throw planned with the grip moving at the release (`plan_moving_throw`): the release
solved with the grip's velocity added to the fling, and the arm's motion for it."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from cell.errors import UnreachableTarget
from cell.frames import tcp_for_item_centre
from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams
from cell.robot.carry import GripHold
from cell.robot.model import Robot
from cell.robot.motion import move_time
from cell.robot.moving_landing import predict_moving_landing
from cell.robot.moving_motion import COAST_S, MovingReleaseMotion, plan_moving_release
from cell.robot.trajectory import as_robot, joint_vector


# -- planning the throw ------------------------------------------------------------
@dataclass(frozen=True)
class MovingThrow:
    """A throw planned with the grip moving at the release, and the arm's motion for it.

    Attributes:
        plan: the release state σ (its base velocity vx/vy/vz_mps = v_release) with the
            model's predicted landing pred_x_m, pred_y_m (`predict_moving_landing`);
            its t_flight_s is `predict_landing`'s.
        motion: the arm's approach, coast and stop.
        cycle_s: from rest at q_start through the release to rest back at q_start [s].
    """

    plan: Any
    motion: MovingReleaseMotion
    cycle_s: float


def _moving_sigma(
    obj: ObjectParams,
    static_plan: Any,
    v_release: np.ndarray,
    ee: EndEffectorParams,
    bounds: Any,
) -> Any:
    """The static plan's release pose with the grip at v_release, its stroke and azimuth
    (its elevation when the stroke is at a bound) polished to land on the goal: first on
    `predict_landing` with σ's base velocity (the moving base's formulation), then on
    `predict_moving_landing`, whose landing the plan's pred_x_m, pred_y_m are. Raises
    UnreachableTarget when the predicted miss stays above MISS_TOL."""
    from cell.optimize.plan import MISS_TOL
    from cell.optimize.verify import polish

    sigma = static_plan.sigma.copy()
    sigma[3:6] = v_release
    lower, upper = bounds.vectors(ee)
    lower[:7] = upper[:7] = sigma[:7]
    for k in (7, 8):  # the azimuth/elevation bounds may not contain a facing plan's angle
        lower[k] = min(lower[k], sigma[k] - 0.5)
        upper[k] = max(upper[k], sigma[k] + 0.5)
    target = np.array([static_plan.target_x_m, static_plan.target_y_m, static_plan.land_z_m])
    sigma, xy, miss, t_flight = polish(obj, sigma, target, ee, lower, upper)
    # then on the moving launch taken in the end-effector's frame (predict_moving_landing)
    sigma, xy, miss = _polish_moving(obj, static_plan, sigma, target, ee, lower, upper)
    if not miss <= MISS_TOL:
        raise UnreachableTarget(
            f"with the grip at {np.round(v_release, 3).tolist()} m/s the model misses the "
            f"goal by {miss:.4f} m"
        )
    from cell.model.band import band_state

    return replace(
        _sigma_plan(static_plan, sigma),
        pred_x_m=float(xy[0]),
        pred_y_m=float(xy[1]),
        miss_m=float(miss),
        energy_j=float(band_state(sigma[9], obj.width, ee).energy),
        t_flight_s=float(t_flight),
        method=f"{static_plan.method}+moving",
    )


def _sigma_plan(plan: Any, sigma: np.ndarray) -> Any:
    return replace(
        plan,
        vx_mps=float(sigma[3]),
        vy_mps=float(sigma[4]),
        vz_mps=float(sigma[5]),
        elevation_rad=float(sigma[7]),
        azimuth_rad=float(sigma[8]),
        stroke_m=float(sigma[9]),
    )


def _polish_moving(
    obj: ObjectParams,
    plan: Any,
    sigma: np.ndarray,
    target: np.ndarray,
    ee: EndEffectorParams,
    lower: np.ndarray,
    upper: np.ndarray,
    iterations: int = 6,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Newton on `predict_moving_landing` over the stroke (the elevation when the stroke
    is at a bound) and the azimuth, as `cell.optimize.verify.polish` does on the model:
    (σ, landing (x, y) [m], miss [m])."""

    def land(sg: np.ndarray) -> np.ndarray:
        return predict_moving_landing(obj, _sigma_plan(plan, sg), ee)

    xy = land(sigma)
    miss = float(np.hypot(*(xy - target[:2])))
    for _ in range(iterations):
        if miss <= 1e-4 or not math.isfinite(miss):
            break
        along = 9 if lower[9] + 1e-7 < sigma[9] < upper[9] - 1e-7 else 7
        steps = {9: 1e-6, 7: 1e-5, 8: 1e-6}
        jac = np.empty((2, 2))
        for j, c in enumerate((along, 8)):
            trial = sigma.copy()
            trial[c] += steps[c]
            jac[:, j] = (land(trial) - xy) / steps[c]
        try:
            delta = np.linalg.solve(jac, target[:2] - xy)
        except np.linalg.LinAlgError:
            break
        new = sigma.copy()
        new[[along, 8]] += delta
        new = np.clip(new, lower, upper)
        nxy = land(new)
        nmiss = float(np.hypot(*(nxy - target[:2])))
        if not nmiss < miss:
            break
        sigma, xy, miss = new, nxy, nmiss
    return sigma, xy, miss


IK = Callable[[np.ndarray, float, float], np.ndarray]


def _default_ik(robot: Robot, seed: np.ndarray) -> IK:
    from cell.robot.ik import solve_release_ik

    def ik(tcp: np.ndarray, elevation: float, azimuth: float) -> np.ndarray:
        return solve_release_ik(robot, tcp, elevation, azimuth, seed).q

    return ik


def plan_moving_throw(
    robot: Robot | str,
    obj: ObjectParams,
    static_plan: Any,
    v_release: np.ndarray | Sequence[float],
    q_start: np.ndarray | Sequence[float],
    ee: EndEffectorParams,
    *,
    bounds: Any = None,
    ik: IK | None = None,
    hold: GripHold | None = None,
    coast_s: float = COAST_S,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
) -> MovingThrow:
    """Plan a throw released with the grip moving at v_release, and the arm's motion.

    The release point (the item's centre) is the static plan's; the launch is the band's
    push along the throw axis plus v_release, the model's (`predict_landing` with σ's base
    velocity), and the stroke and azimuth are polished on it to land on the plan's goal.

    Args:
        robot: the arm (or its name).
        obj: the object as the model knows it (the plan's).
        static_plan: the static plan (`plan_facing`) for the goal.
        v_release: the grip centre's velocity at the release [m/s, W].
        q_start: the configuration the arm starts from, at rest [rad] (the lift pose).
        ee: the end-effector parameters the plan was made with.
        bounds: the ThrowBounds of the elevation and stroke (default: ThrowBounds()).
        ik: (tcp [m, W], elevation, azimuth) → q [rad]; default `solve_release_ik`
            seeded at q_start (the orchestrator passes its `_ik_gripped`).
        hold, coast_s, velocity_scale, acceleration_scale: see `plan_moving_release`
            (the orchestrator's `carry_hold(params, obj, stroke)` for `hold`).

    Returns:
        The MovingThrow.

    Raises:
        UnreachableTarget: no stroke and azimuth land the moving launch on the goal.
        IKFailed: no configuration for the release pose.
        TrajectoryError: the motion is outside the arm's limits.
    """
    from cell.optimize.bounds import ThrowBounds

    rb = as_robot(robot)
    q0 = joint_vector(rb, q_start, "q_start")
    v = np.asarray(v_release, float).reshape(-1)
    plan = _moving_sigma(obj, static_plan, v, ee, bounds or ThrowBounds())
    centre = np.array([plan.x_m, plan.y_m, plan.z_m])
    tcp = tcp_for_item_centre(centre, plan.elevation_rad, plan.azimuth_rad, plan.stroke_m, obj)
    q_rel = (ik or _default_ik(rb, q0))(tcp, plan.elevation_rad, plan.azimuth_rad)
    motion = plan_moving_release(
        rb,
        q0,
        q_rel,
        v,
        coast_s=coast_s,
        hold=hold,
        velocity_scale=velocity_scale,
        acceleration_scale=acceleration_scale,
    )
    back = move_time(motion.q_end, q0, rb)
    return MovingThrow(plan, motion, motion.duration_s + back)
