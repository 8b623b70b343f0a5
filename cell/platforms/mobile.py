"""The moving-base platform: the end-effector on a mobile base that is moving at release.

A mobile base carries the arm; the arm holds the end-effector still relative
to the base while the base drives, so at release the grip centre moves with
the base velocity v_b [m/s, W] (horizontal: the base drives on the floor).
The thesis' decision variable σ has the base velocity in it (§4.2, eq. 4.2):
the throw optimisation (`cell.optimize.plan_throw`, NLP of eq. 4.1) is given
the box |v_x|, |v_y| ≤ `speed_mps`, v_z = 0 and chooses the velocity with the
rest of σ; with `free_velocity=False` the base drives at exactly `speed_mps`
toward the target and only the rest of σ is optimised.

The base's drive to the release state is a jerk-limited, time-optimal ruckig
trajectory in (x, y) from rest to the planned release point, arriving with
the planned release velocity.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cell.errors import InvalidParameter, TrajectoryError
from cell.jobschema import BASE_SPEED_MAX_MPS
from cell.model.objects import ObjectParams
from cell.model.params import DEFAULT_EE, EndEffectorParams
from cell.optimize import DEFAULT_BOUNDS, ThrowBounds, ThrowPlan, plan_throw

__all__ = ["BaseLimits", "BaseTrajectory", "MobilePlatform"]


@dataclass(frozen=True)
class BaseLimits:
    """Kinematic limits of the mobile base (per horizontal axis).

    Attributes:
        velocity_mps: largest speed along x and along y [m/s].
        acceleration_mps2: largest acceleration [m/s²].
        jerk_mps3: largest jerk [m/s³].
    """

    velocity_mps: float = BASE_SPEED_MAX_MPS
    acceleration_mps2: float = 1.0
    jerk_mps3: float = 5.0

    def __post_init__(self) -> None:
        for name in ("velocity_mps", "acceleration_mps2", "jerk_mps3"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise InvalidParameter(f"base limits: {name}={v!r} must be > 0")


class BaseTrajectory:
    """The base's drive (ruckig), sampled in the horizontal plane of W.

    Attributes:
        duration_s: time from the start to the release [s].
        z_m: height of the grip centre, constant during the drive [m].
    """

    def __init__(self, traj: object, z_m: float) -> None:
        self._traj = traj
        self.duration_s = float(traj.duration)  # type: ignore[attr-defined]
        self.z_m = float(z_m)

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Grip-centre position [m], velocity [m/s] and acceleration [m/s²] at time t, each (3,)."""
        tt = min(max(float(t), 0.0), self.duration_s)
        p, v, a = self._traj.at_time(tt)  # type: ignore[attr-defined]
        return (
            np.array([p[0], p[1], self.z_m]),
            np.array([v[0], v[1], 0.0]),
            np.array([a[0], a[1], 0.0]),
        )

    def end_state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The state at the release (t = duration)."""
        return self.sample(self.duration_s)


class MobilePlatform:
    """A mobile base moving at release.

    Args:
        speed_mps: the base's speed at release [m/s] (the bound of each horizontal
            component when the velocity is free).
        limits: the base's kinematic limits for its drive.
        bounds: the release-state bounds relative to the world (the arm's box, the
            elevation and stroke ranges); their velocity box is replaced.

    Raises:
        InvalidParameter: a negative or too high speed.
    """

    def __init__(
        self,
        speed_mps: float,
        *,
        limits: BaseLimits = BaseLimits(),
        bounds: ThrowBounds = DEFAULT_BOUNDS,
    ) -> None:
        if not (math.isfinite(speed_mps) and 0.0 <= speed_mps <= limits.velocity_mps):
            raise InvalidParameter(
                f"speed_mps={speed_mps}: must be in [0, {limits.velocity_mps}] m/s "
                "(the base's velocity limit)"
            )
        self.speed_mps = float(speed_mps)
        self.limits = limits
        self.base_bounds = bounds

    def base_velocity(self, direction: Sequence[float]) -> np.ndarray:
        """The base velocity at `speed_mps` along a horizontal direction [m/s, W], shape (3,).

        Raises:
            InvalidParameter: a direction with no horizontal part.
        """
        d = np.asarray(direction, float).reshape(-1)[:2]
        norm = float(np.hypot(d[0], d[1])) if d.size == 2 else 0.0
        if not norm > 1e-12:
            raise InvalidParameter(f"direction {direction!r} must have a horizontal part")
        return np.array([*(self.speed_mps * d / norm), 0.0])

    def bounds(self) -> ThrowBounds:
        """The release-state bounds with the base-velocity box |v_x|, |v_y| ≤ speed, v_z = 0."""
        from dataclasses import replace

        s = self.speed_mps
        return replace(
            self.base_bounds, base_velocity_min=(-s, -s, 0.0), base_velocity_max=(s, s, 0.0)
        )

    def plan(
        self,
        obj: ObjectParams,
        target: Sequence[float] | np.ndarray,
        ee: EndEffectorParams = DEFAULT_EE,
        *,
        free_velocity: bool = True,
        current: Sequence[float] | np.ndarray | None = None,
    ) -> ThrowPlan:
        """Plan a throw from the moving base.

        Args:
            obj: the object.
            target: goal (x, y, z) [m, W]; z is the landing plane.
            ee: end-effector parameters.
            free_velocity: let the optimiser choose the base velocity within the
                box; otherwise drive at `speed_mps` toward the target.
            current: the current grip centre [m, W] (the NLP's pose reference).

        Returns:
            The plan (its base velocity in vx_mps, vy_mps, vz_mps).

        Raises:
            UnreachableTarget: no release state within the bounds lands on the target.
        """
        b = self.bounds()
        goal = np.asarray(target, float)
        cur = None if current is None else np.asarray(current, float)
        if free_velocity or self.speed_mps == 0.0:
            return plan_throw(obj, goal, ee, b, current=cur)
        ref = b.nominal_release(goal)
        vb = self.base_velocity(goal[:2] - np.asarray(ref, float)[:2])
        return plan_throw(obj, goal, ee, b, current=cur, base_velocity=vb, method="nlp")

    def arrival(self, plan: ThrowPlan, start_xy: Sequence[float] | None = None) -> BaseTrajectory:
        """The base's drive from rest to the plan's release point and velocity (ruckig).

        Args:
            plan: the throw plan.
            start_xy: where the grip centre starts, at rest [m, W]; default: 1 m
                behind the release point against the release velocity (a run-up).

        Returns:
            The drive; its end state is the plan's release point and base velocity.

        Raises:
            TrajectoryError: ruckig found no trajectory (e.g. a velocity above the limit).
        """
        from ruckig import InputParameter, Result, Ruckig, Trajectory

        p1 = np.array([plan.x_m, plan.y_m])
        v1 = np.array([plan.vx_mps, plan.vy_mps])
        if start_xy is None:
            speed = float(np.linalg.norm(v1))
            back = v1 / speed if speed > 1e-9 else np.zeros(2)
            p0 = p1 - back * 1.0
        else:
            p0 = np.asarray(start_xy, float).reshape(-1)
            if p0.shape != (2,) or not np.all(np.isfinite(p0)):
                raise InvalidParameter(f"start_xy {start_xy!r} must be two finite numbers [m]")
        lim = self.limits
        if np.any(np.abs(v1) > lim.velocity_mps):
            raise TrajectoryError(
                f"release velocity {v1.tolist()} m/s exceeds the base's limit "
                f"{lim.velocity_mps} m/s"
            )
        inp = InputParameter(2)
        inp.current_position = p0.tolist()
        inp.current_velocity = [0.0, 0.0]
        inp.current_acceleration = [0.0, 0.0]
        inp.target_position = p1.tolist()
        inp.target_velocity = v1.tolist()
        inp.target_acceleration = [0.0, 0.0]
        inp.max_velocity = [lim.velocity_mps] * 2
        inp.max_acceleration = [lim.acceleration_mps2] * 2
        inp.max_jerk = [lim.jerk_mps3] * 2
        traj = Trajectory(2)
        try:
            result = Ruckig(2).calculate(inp, traj)
        except RuntimeError as exc:
            raise TrajectoryError(
                f"ruckig: no base trajectory to the release state ({exc})"
            ) from None
        if result != Result.Working:
            raise TrajectoryError(f"ruckig: no base trajectory to the release state ({result})")
        return BaseTrajectory(traj, plan.z_m)
