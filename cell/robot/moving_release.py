"""Release on the move: the arm throws while its end-effector moves (issue 16).

The moving base's formulation (cell.platforms.mobile) applied to the arm: the grip
centre moves at a velocity v_rel [m/s, W] at the release, the launch is the band's push
along the throw axis plus v_rel (σ's base velocity vx_mps, vy_mps, vz_mps), and the arm
arrives at the release configuration with the joint velocity that gives v_rel.

The motion, one joint trajectory q(t) (`MovingReleaseMotion`):

1. approach: ruckig from rest at q_start to the run-in's first state, at its velocity
   and zero acceleration (`grip_move`: slowed until the pads hold the item, see
   `cell.robot.carry`; a fast approach slid the item off the carriage). Ruckig's
   non-zero target states: `calculate` returns a trajectory whose state at t = duration
   is the target exactly (tested); past the duration `at_time` goes on with the
   target's acceleration (pantor/ruckig#59), so what follows is planned separately; and
   with a target velocity the move may overshoot the target position on the way
   (moveit/moveit#3376): `plan_move` checks the position extrema against the limits.
2. run-in: RUN_IN_S on the straight line at v_rel, the axis fixed (resolved rate,
   q̇ = J⁺ [v_rel; 0], `CoastTrajectory`), ending at (q_rel, q̇_rel), q̇_rel =
   J(q_rel)⁺ [v_rel; 0] (`release_joint_velocity`: the grip's angular velocity held at
   zero, so the throw axis does not turn and every point of the end-effector, the
   item's centre included, moves at v_rel). The latch opens at its end: the release
   instant `t_release_s`.
3. coast: COAST_S more on the line at v_rel while the band pushes the item out (it
   leaves the carriage ~35 ms after the latch, `leave_time_s`).
4. stop: ruckig's velocity interface brakes from the coast's end to rest (`plan_stop`).

The landing (`predict_moving_landing`): the model's launch for the plan made static,
taken in the end-effector's frame (inertial while it moves at v_rel), then v_rel added
to the velocity and v_rel × `leave_time_s` to the position, and the model's flight.
`predict_landing` with σ's base velocity (the moving base's use) carries the item only
the push's fitted ee.dt (~9 ms) along and lands 10-20 mm short at 0.5-0.75 m/s.

`plan_moving_throw` plans the release for an item and a bin with v_rel given (the
static plan's release point, the stroke and azimuth polished to land on the goal),
`choose_release` tries a few v_rel and keeps the soonest (by the cycle, or by the time
to the release) or the static release when none is sooner, and `cell.sim.release.release_in_scene` runs
a motion in the PyBullet cell and opens the latch at the planned instant while the arm
moves.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from cell.errors import IKFailed, InvalidInput, TrajectoryError, UnreachableTarget
from cell.frames import axis_frame, tcp_for_item_centre
from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams
from cell.robot.carry import GripHold
from cell.robot.model import Robot
from cell.robot.motion import move_time, plan_move, plan_stop, release_joint_velocity
from cell.robot.trajectory import Trajectory, as_robot, joint_vector

__all__ = [
    "COAST_S",
    "RUN_IN_S",
    "CoastTrajectory",
    "MovingReleaseMotion",
    "MovingThrow",
    "ReleaseChoice",
    "choose_release",
    "plan_moving_release",
    "plan_moving_throw",
    "throw_axis",
]

log = logging.getLogger(__name__)

COAST_S = 0.08  # [s] constant grip velocity after the latch opens (the item leaves ~60 ms)
RUN_IN_S = 0.05  # [s] constant grip velocity before it (the plant's mount settles)
_COAST_H = 1e-3  # [s] the coast's integration step (RK4) and sample period
SETTLE_S = 0.0  # [s] the static release's wait at the release pose (as the orchestrator's)
DEFAULT_SPEEDS_MPS = (0.25, 0.5, 0.75, 1.0)  # candidate grip speeds at release [m/s]


def throw_axis(elevation: float, azimuth: float) -> np.ndarray:
    """The throw axis u(e, a) in W, shape (3,): `cell.frames.axis_frame`'s z."""
    return axis_frame(elevation, azimuth)[:, 2]


# -- the coast ---------------------------------------------------------------------
class CoastTrajectory(Trajectory):
    """The grip centre on a straight line at a constant velocity, the axis fixed.

    q̇ = J(q)⁺ [v; 0] integrated with RK4 every _COAST_H from q0; between samples the
    state is the cubic Hermite interpolant of (q, q̇), q̈ its derivative.

    Args:
        robot: the arm.
        q0: configuration at the start (with `ending`, at the end) [rad], shape (dof,).
        v: grip-centre velocity [m/s, W], shape (3,).
        duration: the coast's length [s].
        ending: the line ends at q0 (a run-in to the release) instead of starting there.

    Raises:
        TrajectoryError: a joint leaves its position or velocity limit on the way.
    """

    def __init__(
        self, robot: Robot, q0: np.ndarray, v: np.ndarray, duration: float, *, ending: bool = False
    ) -> None:
        self.dof = robot.dof
        self.kind = "coast"
        self.duration = float(duration)
        sign = -1.0 if ending else 1.0  # a run-in is integrated backwards from its end
        twist = np.concatenate([sign * np.asarray(v, float), np.zeros(3)])

        def rate(q: np.ndarray) -> np.ndarray:
            return np.linalg.lstsq(robot.tcp_jacobian(q), twist, rcond=1e-10)[0]

        n = max(1, int(math.ceil(self.duration / _COAST_H)))
        h = self.duration / n
        qs = [np.asarray(q0, float)]
        dqs = [rate(qs[0])]
        for _ in range(n):
            q = qs[-1]
            k1 = dqs[-1]
            k2 = rate(q + h / 2 * k1)
            k3 = rate(q + h / 2 * k2)
            k4 = rate(q + h * k3)
            qn = q + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            qs.append(qn)
            dqs.append(rate(qn))
        self._ts = np.linspace(0.0, self.duration, n + 1)
        self._qs = np.array(qs)
        self._dqs = np.array(dqs)
        if ending:
            self._qs, self._dqs = self._qs[::-1].copy(), -self._dqs[::-1]
        lim = robot.limits
        if np.any(self._qs < lim.lower) or np.any(self._qs > lim.upper):
            raise TrajectoryError("the coast after the release leaves a joint's position range")
        if np.any(np.abs(self._dqs) > lim.velocity):
            raise TrajectoryError("the coast after the release needs a joint above its velocity")

    def _eval(self, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        h = self._ts[1] - self._ts[0]
        i = np.clip(((ts - self._ts[0]) / h).astype(int), 0, len(self._ts) - 2)
        s = ((ts - self._ts[i]) / h)[:, None]
        p0, p1 = self._qs[i], self._qs[i + 1]
        m0, m1 = self._dqs[i] * h, self._dqs[i + 1] * h
        s2, s3 = s * s, s * s * s
        q = (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * p1
        q += (s3 - s2) * m1
        dq = ((6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * m0 + (-6 * s2 + 6 * s) * p1) / h
        dq += (3 * s2 - 2 * s) * m1 / h
        ddq = ((12 * s - 6) * p0 + (6 * s - 4) * m0 + (-12 * s + 6) * p1 + (6 * s - 2) * m1) / (
            h * h
        )
        return q, dq, ddq


def grip_move(
    robot: Robot,
    q0: np.ndarray,
    q1: np.ndarray,
    dq1: np.ndarray | None,
    hold: GripHold | None,
    *,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
    iterations: int = 6,
    gentle: bool = False,
) -> Trajectory:
    """Ruckig from rest at q0 to (q1, dq1), the fastest whose use of the grip stays within
    1/CARRY_MARGIN (`cell.robot.carry.grip_use`): bisection on a factor s that scales the
    acceleration and jerk limits. None for `hold`: the move at the given scales.

    With `gentle`, a move whose path asks too much of the grip at any speed (it turns a
    hanging item) is made at GENTLE_SCALE of the limits instead, as `plan_carry` does.

    Raises:
        TrajectoryError: no move at all (see plan_move), or (without `gentle`) the grip
            cannot hold the item even at the slowest factor tried (2 % of the limits).
    """
    from cell.robot.carry import CARRY_MARGIN, grip_use

    def attempt(s: float) -> tuple[Trajectory, float]:
        tr = plan_move(
            q0,
            None,
            q1,
            dq1,
            robot,
            velocity_scale=velocity_scale,
            acceleration_scale=acceleration_scale * s,
            jerk_scale=s,
        )
        return tr, (0.0 if hold is None else grip_use(tr, robot, hold))

    bound = 1.0 / CARRY_MARGIN
    best = attempt(1.0)
    if best[1] <= bound:
        return best[0]
    lo, hi = 0.0, 1.0
    found: Trajectory | None = None
    for _ in range(iterations):
        mid = max(0.02, 0.5 * (lo + hi))
        tr, use = attempt(mid)
        if use <= bound:
            lo, found = mid, tr
        else:
            hi = mid
    if found is None and gentle:
        from cell.robot.carry import GENTLE_SCALE

        log.info("no speed keeps the move within the grip: moving at %.0f %%", 100 * GENTLE_SCALE)
        return attempt(GENTLE_SCALE)[0]
    if found is None:
        raise TrajectoryError(
            f"no ruckig move to the release keeps the item in the grip (use {best[1]:.2f} "
            f"at full speed, above {bound:.2f} even at {100 * max(0.02, hi):.0f} %)"
        )
    return found


# -- the motion --------------------------------------------------------------------
@dataclass(frozen=True)
class MovingReleaseMotion:
    """The arm's motion for a release on the move: approach, coast, stop (see the module).

    Attributes:
        q_start: where the arm starts, at rest [rad].
        q_release: configuration at the release [rad].
        dq_release: joint velocity at the release [rad/s].
        v_release: the grip centre's (the item's centre's) velocity at the release [m/s, W].
        approach: ruckig from rest at q_start to the run-in's start, at its velocity.
        run_in: the straight line at v_release that ends at (q_release, dq_release).
        coast: the straight line at v_release after the release.
        stop: ruckig from the coast's end to rest.
    """

    q_start: np.ndarray
    q_release: np.ndarray
    dq_release: np.ndarray
    v_release: np.ndarray
    approach: Trajectory
    run_in: Trajectory
    coast: Trajectory
    stop: Trajectory

    @property
    def t_release_s(self) -> float:
        """The release instant, from the start [s]: the latch opens then."""
        return float(self.approach.duration + self.run_in.duration)

    @property
    def duration_s(self) -> float:
        """From the start to rest again [s]."""
        return self.t_release_s + self.coast.duration + self.stop.duration

    @property
    def q_end(self) -> np.ndarray:
        """Where the arm comes to rest [rad]."""
        return self.stop.end_state()[0]

    def state(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q [rad], q̇ [rad/s], q̈ [rad/s²]) at t since the start (clamped to [0, duration])."""
        t1 = self.approach.duration
        t2 = t1 + self.run_in.duration
        t3 = t2 + self.coast.duration
        if t <= t1:
            return self.approach.sample(t)
        if t <= t2:
            return self.run_in.sample(t - t1)
        if t <= t3:
            return self.coast.sample(t - t2)
        return self.stop.sample(t - t3)


def plan_moving_release(
    robot: Robot | str,
    q_start: np.ndarray | Sequence[float],
    q_release: np.ndarray | Sequence[float],
    v_release: np.ndarray | Sequence[float],
    *,
    coast_s: float = COAST_S,
    run_in_s: float = RUN_IN_S,
    hold: GripHold | None = None,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
) -> MovingReleaseMotion:
    """Plan the arm's release on the move: from rest at q_start through q_release with
    the grip centre at v_release, then to rest.

    Args:
        robot: the arm (or its name).
        q_start: the start configuration, at rest [rad].
        q_release: the release configuration [rad].
        v_release: the grip centre's velocity at the release [m/s, W], shape (3,).
        coast_s: how long the grip keeps v_release after the release [s].
        run_in_s: how long it moves at v_release before the release [s] (the plant's
            end-effector, pulled by its mount, settles on the arm's velocity then).
        hold: what the pads hold the item with (`cell.robot.carry.GripHold`): the
            approach is slowed (acceleration and jerk scaled together) until the item's
            use of the grip stays within 1/CARRY_MARGIN (`grip_move`); None: full speed.
            Without it a fast approach slides the item along the pads, off the carriage,
            and the push then hits it from a gap (a harder launch than planned).
        velocity_scale: fraction of the joint velocity limits the approach uses; the
            release's joint velocity must be within them.
        acceleration_scale: fraction of the acceleration limits (approach and stop).

    Returns:
        The motion.

    Raises:
        InvalidInput: bad shapes, configurations outside the limits, a negative coast.
        TrajectoryError: the release velocity needs a joint above its (scaled) limit or is
            singular, or ruckig found no approach or stop within the limits.
    """
    rb = as_robot(robot)
    q0 = joint_vector(rb, q_start, "q_start")
    q1 = joint_vector(rb, q_release, "q_release")
    v = np.asarray(v_release, float).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise InvalidInput(f"v_release {v_release!r} must be three finite numbers [m/s]")
    if not (math.isfinite(coast_s) and coast_s > 0 and math.isfinite(run_in_s) and run_in_s > 0):
        raise InvalidInput(f"coast_s {coast_s!r} and run_in_s {run_in_s!r} must be > 0 s")
    dq1 = release_joint_velocity(q1, v, rb)
    ratio = float(np.max(np.abs(dq1) / (rb.limits.velocity * velocity_scale)))
    if ratio > 1.0:
        raise TrajectoryError(
            f"the release velocity needs {ratio:.2f}x the scaled joint velocity limits"
        )
    run_in = CoastTrajectory(rb, q1, v, run_in_s, ending=True)
    q_in, dq_in, _ = run_in.sample(0.0)
    approach = grip_move(
        rb,
        q0,
        q_in,
        dq_in,
        hold,
        velocity_scale=velocity_scale,
        acceleration_scale=acceleration_scale,
    )
    coast = CoastTrajectory(rb, q1, v, coast_s)
    qc, dqc, ddqc = coast.end_state()
    amax = rb.limits.acceleration * acceleration_scale
    stop = plan_stop(
        qc, dqc, rb, ddq0=np.clip(ddqc, -amax, amax), acceleration_scale=acceleration_scale
    )
    return MovingReleaseMotion(q0, q1, dq1, v, approach, run_in, coast, stop)


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


@dataclass(frozen=True)
class ReleaseChoice:
    """The planner's choice between the static release and the moving ones.

    Attributes:
        moving: the chosen moving throw, or None when the static release is faster.
        static_q: the static release configuration [rad].
        static_to_release_s: the static move's duration to the release [s] (ruckig,
            rest to rest, within the grip as `grip_move`, then SETTLE_S).
        static_cycle_s: that, the push (COAST_S) and the move back to q_start [s].
        candidates: (v_release, MovingThrow or the reason it was refused) tried.
    """

    moving: MovingThrow | None
    static_q: np.ndarray
    static_to_release_s: float
    static_cycle_s: float
    candidates: list[tuple[np.ndarray, MovingThrow | str]]

    @property
    def saved_s(self) -> float:
        """Cycle time the moving release saves over the static one [s] (0 if static)."""
        return 0.0 if self.moving is None else self.static_cycle_s - self.moving.cycle_s

    @property
    def saved_to_release_s(self) -> float:
        """Time to the release the moving release saves over the static one [s]."""
        if self.moving is None:
            return 0.0
        return self.static_to_release_s - self.moving.motion.t_release_s


def release_directions(
    robot: Robot, static_plan: Any, q_start: np.ndarray, q_static: np.ndarray
) -> list[np.ndarray]:
    """Unit directions [W] a release velocity is tried along: the throw axis (all of the
    speed goes into the launch), the straight swing of the grip centre from q_start to
    the release, their bisector, and the grip centre's direction at the end of the
    joint-space straight line from q_start (J(q_rel) (q_rel − q_start): the way a
    synchronised move arrives)."""
    u = throw_axis(static_plan.elevation_rad, static_plan.azimuth_rad)
    swing = robot.tcp_pose(q_static)[0] - robot.tcp_pose(q_start)[0]
    arrive = robot.tcp_jacobian(q_static)[:3] @ (q_static - q_start)
    out = [u]
    for d in (swing, (u + swing / max(np.linalg.norm(swing), 1e-12)), arrive):
        if np.linalg.norm(d) > 1e-6:
            out.append(d / np.linalg.norm(d))
    return out


def choose_release(
    robot: Robot | str,
    obj: ObjectParams,
    static_plan: Any,
    q_start: np.ndarray | Sequence[float],
    ee: EndEffectorParams,
    *,
    bounds: Any = None,
    ik: IK | None = None,
    hold: GripHold | None = None,
    speeds_mps: Sequence[float] = DEFAULT_SPEEDS_MPS,
    directions: Sequence[np.ndarray] | None = None,
    criterion: str = "cycle",
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
) -> ReleaseChoice:
    """Choose between the static release and a moving one by cycle time.

    The cycle is from rest at q_start (the lift pose) through the release to rest back
    at q_start: static = rest-to-rest move to the release + SETTLE_S + the push
    (COAST_S) + the move back; moving = approach + run-in + coast + stop + the move back
    (ruckig for all). Each moving candidate lands on the goal by the model
    (`predict_moving_landing` within MISS_TOL, so within the bin) and is within the
    joint limits all along; the soonest wins if it is sooner than the static release.

    Args:
        robot, obj, static_plan, q_start, ee, bounds, ik, hold: see `plan_moving_throw`
            (both releases' approaches are kept within the grip by `hold`).
        speeds_mps: grip speeds at the release tried [m/s].
        directions: unit directions tried [W]; default `release_directions`.
        criterion: "cycle" (out and back, as above) or "release" (the time from the
            start to the latch: the next pick's move then starts from wherever the arm
            stopped, and is left out).
        velocity_scale, acceleration_scale: fractions of the joint limits used.

    Returns:
        The ReleaseChoice.

    Raises:
        IKFailed: no configuration for the static release pose.
    """
    rb = as_robot(robot)
    q0 = joint_vector(rb, q_start, "q_start")
    solve = ik or _default_ik(rb, q0)
    sp = static_plan
    tcp = tcp_for_item_centre(
        [sp.x_m, sp.y_m, sp.z_m], sp.elevation_rad, sp.azimuth_rad, sp.stroke_m, obj
    )
    q_static = solve(tcp, sp.elevation_rad, sp.azimuth_rad)
    kw: dict[str, Any] = dict(velocity_scale=velocity_scale, acceleration_scale=acceleration_scale)
    t_static = grip_move(rb, q0, q_static, None, hold, gentle=True, **kw).duration + SETTLE_S
    static_cycle = t_static + COAST_S + move_time(q_static, q0, rb)
    dirs = release_directions(rb, sp, q0, q_static) if directions is None else directions
    if criterion not in ("cycle", "release"):
        raise InvalidInput(f"criterion {criterion!r}: give 'cycle' or 'release'")

    def key(mt: MovingThrow) -> float:
        return mt.cycle_s if criterion == "cycle" else mt.motion.t_release_s

    cands: list[tuple[np.ndarray, MovingThrow | str]] = []
    best: MovingThrow | None = None
    bar = static_cycle if criterion == "cycle" else t_static
    for d in dirs:
        # speeds in rising order: a direction is left once a speed is refused or no
        # sooner than the one before it (in the cell's measurements the time rises, or the
        # joint limits refuse, monotonically with the speed along a direction)
        last = math.inf
        for s in sorted(speeds_mps):
            v = s * np.asarray(d, float)
            try:
                mt = plan_moving_throw(
                    rb, obj, sp, v, q0, ee, bounds=bounds, ik=solve, hold=hold, **kw
                )
            except (UnreachableTarget, IKFailed, TrajectoryError) as exc:
                cands.append((v, f"{type(exc).__name__}: {exc}"))
                break
            cands.append((v, mt))
            if best is None or key(mt) < key(best):
                best = mt
            if key(mt) >= min(last, bar):
                break
            last = key(mt)
    if best is not None and key(best) >= bar:
        best = None
    return ReleaseChoice(best, q_static, t_static, static_cycle, cands)


def leave_time_s(
    obj: ObjectParams, stroke_m: float, elevation_rad: float, ee: EndEffectorParams
) -> float:
    """The time [s] from the latch opening until the item leaves the carriage at L_e: the
    band's push (`push_force`, the grip's width) drives the carriage and the item
    (`moving_mass_kg` + the item's mass) from rest at L_s against gravity's component
    along the axis (semi-implicit Euler, 10 µs steps).

    The model's launch state is where and how the item leaves in the end-effector's
    frame; the model's push lasts ee.dt (a fitted constant, ~9 ms) and its ride to L_e
    takes no time, while the plant's item stays in the end-effector for this whole time
    (~35 ms: measured 37 ms in the scene for cube50 at L_s = 85 mm). Released on the
    move, the item is carried v_rel × this time before it flies.
    """
    from cell.model.band import push_force
    from cell.model.params import G
    from cell.sim.mechanism import DEFAULT_GEOMETRY

    end = ee.L_e if ee.L_e > 0 else DEFAULT_GEOMETRY.end_stop_m
    mass = obj.mass + DEFAULT_GEOMETRY.moving_mass_kg
    width = max(float(obj.width), ee.d)
    s, v, t, h = float(stroke_m), 0.0, 0.0, 1e-5
    while s < end and t < 0.5:
        v += (float(push_force(np.float64(s), width, ee)) / mass - G * math.sin(elevation_rad)) * h
        s += v * h
        t += h
    return t


def predict_moving_landing(obj: ObjectParams, plan: Any, ee: EndEffectorParams) -> np.ndarray:
    """The landing (x, y) [m, W] of a plan released with the grip moving at its base
    velocity v_b, the launch taken in the end-effector's frame (inertial, moving at v_b):
    the model's launch state for the plan made static (push and ride), plus v_b to the
    velocity and v_b × `leave_time_s` to the position; then the model's flight.

    `predict_landing` adds v_b before the push instead, so the item is carried only the
    push's fitted ee.dt along: for cube50 at 0.75 m/s that lands 18 mm short of where the
    scene's item lands (whose moving launch is the static one plus v_b within 1 %).
    With v_b = 0 this is `predict_landing`'s landing.
    """
    from cell.model.planar import flight_planar_one
    from cell.model.throw import _FLIGHT_STEP, drag_constant, launch_state
    from cell.optimize.verify import sigma_batch

    vb = np.array([plan.vx_mps, plan.vy_mps, plan.vz_mps])
    sig = plan.sigma.copy()
    sig[3:6] = 0.0
    batch = sigma_batch(obj, sig, plan.land_z_m)
    p1, v1 = (x[0] for x in launch_state(batch, ee))
    if vb.any():
        p1 = p1 + vb * leave_time_s(obj, plan.stroke_m, plan.elevation_rad, ee)
        v1 = v1 + vb
    k = float(drag_constant(batch.shape, batch.mass, batch.size)[0])
    vh = math.hypot(v1[0], v1[1])
    dist = flight_planar_one(float(p1[2]), vh, float(v1[2]), k, float(plan.land_z_m), _FLIGHT_STEP)[
        0
    ]
    return np.asarray(p1[:2] + dist * np.array([v1[0], v1[1]]) / vh, float)
