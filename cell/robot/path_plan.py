"""`plan_path`: toppra's time-optimal parameterisation of a spline through joint
waypoints, at rest at both ends."""

from __future__ import annotations

import functools
import logging
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from cell.errors import InvalidInput, TrajectoryError
from cell.robot.kept import Kept, array_key
from cell.robot.model import Robot
from cell.robot.spline import spline_path
from cell.robot.toppra_bulk import propose_gridpoints
from cell.robot.trajectory import (
    POSITION_TOL_RAD,
    ToppraTrajectory,
    Trajectory,
    as_robot,
    check_limits,
    joint_vector,
)

log = logging.getLogger(__name__)


def _check_scales(**scales: float) -> None:
    """InvalidInput naming the first limit scale outside (0, 1]."""
    for name, s in scales.items():
        if not (0.0 < s <= 1.0):
            raise InvalidInput(f"{name} must be in (0, 1], got {s}")


def _distinct_waypoints(
    rb: Robot, waypoints_q: Sequence[np.ndarray] | np.ndarray
) -> list[np.ndarray]:
    """The waypoints [rad] checked against the joint limits, repeats dropped (≥ 2 left)."""
    wps = [joint_vector(rb, w, f"waypoint {i}") for i, w in enumerate(waypoints_q)]
    if len(wps) < 2:
        raise InvalidInput(f"plan_path needs at least 2 waypoints, got {len(wps)}")
    for i, w in enumerate(wps):
        rb.limits.check_position(w, name=f"waypoint {i}", tol=POSITION_TOL_RAD)
    # Drop repeated waypoints: a zero-length segment has no path parameter.
    keep = [wps[0]] + [
        w for a, w in zip(wps, wps[1:], strict=False) if np.linalg.norm(w - a) > 1e-9
    ]
    if len(keep) < 2:
        raise InvalidInput("plan_path waypoints are all the same configuration: nothing to do")
    return keep


def _spline_within(rb: Robot, keep: list[np.ndarray]) -> Any:
    """The spline through the distinct waypoints; TrajectoryError if it leaves the limits."""
    path = spline_path(keep, rb.limits.lower, rb.limits.upper)
    # Sample the geometric path itself: where no spline keeps within the limits (a waypoint
    # on a limit, the path turning back there), it leaves them.
    qs = path(np.linspace(0.0, 1.0, 400))
    lo = np.min(qs - rb.limits.lower)
    hi = np.min(rb.limits.upper - qs)
    if min(lo, hi) < -POSITION_TOL_RAD:
        raise TrajectoryError(
            f"the spline through the {len(keep)} waypoints leaves the joint limits by "
            f"{-min(lo, hi):.4f} rad between waypoints; add intermediate waypoints"
        )
    return path


# The spline through distinct waypoints and toppra's gridpoints along it, by the bytes of
# the waypoints and the joint limits (or the TrajectoryError's message where the spline
# leaves them): neither depends on the limit scales, and a carry plans the same waypoints
# at several (`cell.robot.carry_plan.plan_carry`: at full speed, shaped by the grip, at
# the bisection's scale or gently). Nothing reads into them: the gridpoints are read-only.
# Bounded: cleared when full.
_PATHS: Kept[tuple[Any, np.ndarray]] = Kept(64, TrajectoryError)


def _path_and_grid(rb: Robot, keep: list[np.ndarray]) -> tuple[Any, np.ndarray]:
    """(`_spline_within`'s path, toppra's gridpoints along it), each made once for the
    same waypoints [rad] and joint limits; TrajectoryError as `_spline_within`."""
    lower, upper = rb.limits.lower, rb.limits.upper

    def make() -> tuple[Any, np.ndarray]:
        path = _spline_within(rb, keep)
        # toppra's own gridpoints (its TOPPRA's defaults), for every scale and margin
        grid = propose_gridpoints(path, max_err_threshold=1e-3, min_nb_points=100)
        grid.setflags(write=False)
        return path, grid

    return _PATHS.get(array_key(lower, upper, *keep), make)


# toppra's joint-limit constraints by their limits' bytes: building one formats its limits
# into a description string (1.6 ms a pair, more than toppra's own planning of a short
# path's grid takes); nothing in them changes once built. Bounded: cleared when full.
_LIMIT_CONSTRAINTS: Kept[tuple[Any, Any]] = Kept(256)


def _joint_limits(vlim: np.ndarray, alim: np.ndarray) -> tuple[Any, Any]:
    """toppra's joint velocity and acceleration (interpolated) constraints for the limits
    vlim and alim, each shape (dof, 2) [rad/s, rad/s²], built once for those limits."""
    import toppra.constraint as constraint

    return _LIMIT_CONSTRAINTS.get(
        vlim.tobytes() + alim.tobytes(),
        lambda: (
            constraint.JointVelocityConstraint(vlim),
            constraint.JointAccelerationConstraint(
                alim, discretization_scheme=constraint.DiscretizationType.Interpolation
            ),
        ),
    )


@functools.cache
def _toppra_class() -> type:
    """toppra 0.6's TOPPRA with the seidel solver and the constant-acceleration
    parameterisation, its Python steps written leaner: the same solver calls with the same
    numbers in the same order, and the same arithmetic, so the same trajectories bit for
    bit (tests/test_toppra_setup.py compares them with toppra's own):

    - set up as `ReachabilityAlgorithm.__init__` sets it up for a solver named "seidel"
      and linear constraints (`ParameterizationAlgorithm`'s own set-up, then
      `seidelWrapper(constraints, path, gridpoints, solve_lp1d=True)`), without its look
      for the other solvers' packages (`available_solvers`: `importlib.util.find_spec` of
      qpoases and cvxpy, which searches sys.path again on every plan whatever solver is
      named: 1-2 ms a plan);
    - the controllable sets (`compute_controllable_sets`) with its one step inline,
      without two arrays made and checked for NaN a grid point;
    - the forward pass's step (`_forward_step`) with the grid's steps read once, not
      copied out of the solver a grid point;
    - the parameterisation's times and path accelerations (`ParametrizeConstAccel`'s
      `_process_parametrization`) over the whole grid at once: each the same two or
      three operations on the same numbers, the times summed in order
      (`np.add.accumulate`, as its loop adds them)."""
    import toppra.algorithm as algo
    from toppra.parametrizer import ParametrizeConstAccel
    from toppra.solverwrapper.cy_seidel_solverwrapper import seidelWrapper

    toppra_log = logging.getLogger("toppra.algorithm.reachabilitybased.reachability_algorithm")

    class ConstAccel(ParametrizeConstAccel):  # type: ignore[misc]
        def __reduce__(self) -> tuple[Any, ...]:
            # a class made in this function pickles by its state (`cell.arm.fork` sends a
            # forked branch's planned carries): the same object, none of it recomputed
            return (_const_accel, (self.__dict__.copy(),))

        def _process_parametrization(self) -> None:
            ss, vs = self._ss, self._velocities
            ds = ss[1:] - ss[:-1]
            self._us = 0.5 * (self._xs[1:] - self._xs[:-1]) / ds
            self._ts = np.concatenate(([0.0], np.add.accumulate(2 * ds / (vs[:-1] + vs[1:]))))

    class Toppra(algo.TOPPRA):  # type: ignore[misc]
        def __init__(
            self, constraint_list: Sequence[Any], path: Any, gridpoints: np.ndarray
        ) -> None:
            algo.ParameterizationAlgorithm.__init__(
                self,
                constraint_list,
                path,
                gridpoints=gridpoints,
                parametrizer="ParametrizeConstAccel",
            )
            self.parametrizer = ConstAccel
            self.solver_wrapper = seidelWrapper(
                self.constraints, self.path, self.gridpoints, solve_lp1d=True
            )
            self._deltas = self.solver_wrapper.get_deltas()
            self._n_vars = self.solver_wrapper.get_no_vars()

        def compute_controllable_sets(self, sdmin: float, sdmax: float) -> np.ndarray:
            assert sdmin <= sdmax and 0 <= sdmin
            n = self._N
            k = np.zeros((n + 1, 2))
            k[n] = [sdmin**2, sdmax**2]
            sw = self.solver_wrapper
            sw.setup_solver()
            g_upper = np.zeros(self._n_vars)
            g_upper[0] = 1e-9
            g_upper[1] = -1
            g_lower = -g_upper
            solve = sw.solve_stagewise_optim
            nan = np.nan
            for i in range(n - 1, -1, -1):
                lo, hi = k[i + 1, 0], k[i + 1, 1]
                x_upper = solve(i, None, g_upper, nan, nan, lo, hi)[1]
                x_lower = solve(i, None, g_lower, nan, nan, lo, hi)[1]
                k[i, 0] = x_lower
                k[i, 1] = x_upper
                if k[i, 0] < 0:
                    k[i, 0] = 0
                if math.isnan(k[i, 0]) or math.isnan(k[i, 1]):
                    toppra_log.warning(
                        "A numerical error occurs: The controllable set at step "
                        "[%d / %d] can't be computed.",
                        i,
                        n + 1,
                    )
                    return k
            sw.close_solver()
            return k

        def _forward_step(self, i: int, x: float, k_next: np.ndarray) -> np.ndarray:
            if math.isnan(x):
                return np.array([np.nan, np.nan])
            g_upper = np.zeros(self._n_vars)
            g_upper[1] = -1
            g_upper[0] = -2 * self._deltas[i]
            return np.asarray(
                self.solver_wrapper.solve_stagewise_optim(
                    i, None, g_upper, x, x, k_next[0], k_next[1]
                )
            )

    Toppra.const_accel = ConstAccel
    return Toppra


def _const_accel(state: dict[str, Any]) -> Any:
    """`_toppra_class`'s constant-acceleration parameterisation with the state `state` (its
    `__reduce__`: unpickled as it was, nothing recomputed)."""
    toppra: Any = _toppra_class()
    cls = toppra.const_accel
    out = cls.__new__(cls)
    out.__dict__.update(state)
    return out


def plan_path(
    waypoints_q: Sequence[np.ndarray] | np.ndarray,
    robot: Robot | str,
    *,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
    constraints: Sequence[Any] = (),
) -> Trajectory:
    """Time-optimal trajectory along a spline through joint waypoints, at rest at both ends.

    The path is a cubic spline through the waypoints, with the path parameter at each
    waypoint proportional to the cumulative joint-space distance; where that spline
    overshoots a joint limit, the spline that keeps to the shape-preserving cubic through
    them (`spline_path`). Limits are scaled by
    `*_scale`, then tightened by 2 % (toppra's constant-acceleration parameterisation
    overshoots slightly); the result is sampled and, if it still exceeds a limit, planned
    again with tighter margins.

    Args:
        waypoints_q: k ≥ 2 configurations [rad], each shape (dof,).
        robot: the robot (or its name).
        velocity_scale: fraction of the velocity limits to use, in (0, 1].
        acceleration_scale: fraction of the acceleration limits to use, in (0, 1].
        constraints: more toppra path constraints, besides the joint limits (the grip's
            on a carry, `cell.robot.carry.grip_constraint`).

    Returns:
        A Trajectory starting at the first waypoint and stopping at the last.

    Raises:
        InvalidInput: fewer than two waypoints, a bad shape, a waypoint outside the joint
            limits, or a scale outside (0, 1].
        TrajectoryError: toppra found no parameterisation, or the spline leaves the joint
            limits between waypoints.
    """
    rb = as_robot(robot)
    _check_scales(velocity_scale=velocity_scale, acceleration_scale=acceleration_scale)
    keep = _distinct_waypoints(rb, waypoints_q)
    q_start = keep[0]
    path, grid = _path_and_grid(rb, keep)
    vmax = rb.limits.velocity * velocity_scale
    amax = rb.limits.acceleration * acceleration_scale
    for margin in (0.98, 0.95, 0.9, 0.8):
        pc_vel, pc_acc = _joint_limits(
            np.c_[-vmax * margin, vmax * margin], np.c_[-amax * margin, amax * margin]
        )
        # toppra's TOPPRA with the solver it would choose (its first available), seidel,
        # and the constant-acceleration parameterisation
        inst = _toppra_class()([pc_vel, pc_acc, *constraints], path, grid)
        raw = inst.compute_trajectory(0.0, 0.0)
        if raw is None:
            raise TrajectoryError(
                f"toppra found no time parameterisation through {len(keep)} waypoints "
                f"(from {np.round(q_start, 3).tolist()} rad); the path may pass a point where "
                "the limits admit no motion"
            )
        traj = ToppraTrajectory(raw, rb.dof)
        use = check_limits(traj, rb, n=501)
        if use["velocity"] <= velocity_scale * (1 + 1e-6) and use[
            "acceleration"
        ] <= acceleration_scale * (1 + 1e-6):
            return traj
        log.debug("toppra margin %.2f exceeded the limits (%s); retrying", margin, use)
    raise TrajectoryError(f"toppra's trajectory exceeded the limits even at 80 % of them: {use}")
