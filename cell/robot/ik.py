"""Inverse kinematics of the release pose: damped least squares over several seeds.

A release pose is a grip-centre position p [m, W] and a throw axis u (the +z axis of
`ee_tcp`); the roll about u is free (a 5-D task) or fixed (6-D). Each seed is iterated with
damped least squares, joint limits clamped at every step and a null-space pull towards the
current configuration (redundant arms). The converged solution nearest the current
configuration wins; if none converges the call raises IKFailed with the best residual.

The pose, result and tolerances are in `cell.robot.ik_pose`, one seed's descent in
`cell.robot.ik_descent`; this module searches the seeds and re-exports their names.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator

import numpy as np

from cell.errors import IKFailed, InvalidInput
from cell.robot.ik_descent import _bounded_solve, _descend, _Descent, _Search, _wrap_near
from cell.robot.ik_pose import (
    AXIS_TOL_RAD,
    POSITION_TOL_M,
    IKNoSolution,
    IKResult,
    ReleasePose,
    pose_error,
)
from cell.robot.model import Robot

__all__ = [
    "AXIS_TOL_RAD",
    "POSITION_TOL_M",
    "IKNoSolution",
    "IKResult",
    "ReleasePose",
    "pose_error",
    "solve_ik",
    "solve_release_ik",
]


def _check_settings(
    tol_position_m: float,
    tol_axis_rad: float,
    damping: float,
    max_iterations: int,
    random_seeds: int,
    solutions: int,
    null_gain: float,
) -> None:
    """Refuse solver settings out of range (see `solve_ik`).

    Raises:
        InvalidInput: naming the setting and its range.
    """
    for name, v in (
        ("tol_position_m", tol_position_m),
        ("tol_axis_rad", tol_axis_rad),
        ("damping", damping),
    ):
        if not (math.isfinite(v) and v > 0.0):
            raise InvalidInput(f"{name} must be a positive number, got {v!r}")
    if max_iterations < 1 or random_seeds < 0 or solutions < 1 or not (0.0 <= null_gain < 1.0):
        raise InvalidInput(
            "need max_iterations >= 1, random_seeds >= 0, solutions >= 1 and "
            f"0 <= null_gain < 1; got {max_iterations}, {random_seeds}, {solutions}, {null_gain}"
        )


def _current_configuration(robot: Robot, q_current: np.ndarray | None) -> np.ndarray:
    """The current configuration [rad] (home if None), checked against the limits and
    clamped onto them.

    Raises:
        InvalidInput: wrong shape, or outside the limits by more than 1e-6 rad.
    """
    lim = robot.limits
    q_cur = robot.home.copy() if q_current is None else np.asarray(q_current, dtype=float)
    lim.check_position(q_cur, name="q_current", tol=1e-6)
    return np.clip(q_cur, lim.lower, lim.upper)


def _seeds(
    robot: Robot,
    q_cur: np.ndarray,
    p_des: np.ndarray,
    random_seeds: int,
    rng: np.random.Generator | None,
    warm: np.ndarray | None = None,
) -> Iterator[np.ndarray]:
    """The seeds in order: the current configuration, `warm` (if given), home (if
    different), then `random_seeds` random configurations, every other one with its base
    joint turned to face the target. Lazy: the random ones are drawn only when the first
    seeds fail (the same draws with a warm seed or without)."""
    lim = robot.limits
    yield q_cur
    if warm is not None:
        yield warm
    if not np.allclose(robot.home, q_cur):
        yield robot.home
    g = rng if rng is not None else np.random.default_rng(0)
    rand = robot.random_configuration(g, random_seeds)
    # Every other random seed turns the base joint so the arm faces the target: the
    # base yaw is the one joint whose right value is known in advance.
    p_home = robot.tcp_pose(robot.home)[0]
    turn = math.atan2(p_des[1], p_des[0]) - math.atan2(p_home[1], p_home[0])
    q0 = (robot.home[0] + turn + math.pi) % (2 * math.pi) - math.pi
    rand[::2, 0] = np.clip(q0 + g.normal(0.0, 0.2, rand[::2].shape[0]), lim.lower[0], lim.upper[0])
    yield from rand


def _near_current(
    robot: Robot, d: _Descent, q: np.ndarray
) -> tuple[np.ndarray, float, float, float]:
    """q shifted by multiples of 2π towards the current configuration (within the limits),
    with its errors (position [m], axis [rad], roll [rad])."""
    lim = robot.limits
    q = _wrap_near(q, d.q_cur, lim.lower, lim.upper)
    ep, th, roll = pose_error(robot, q, d.pose)
    return q, ep, th, roll


def _search_seeds(
    robot: Robot,
    d: _Descent,
    seeds: Iterator[np.ndarray],
    solutions: int,
    give_up: tuple[int, float] | None = None,
    first: int = 1,
) -> _Search:
    """Descend from each seed in turn; stop at once if one of the `first` seeds converges
    (the current configuration; and a warm start's), else once `solutions` seeds have.
    `give_up` (seeds, score): stop too once that many seeds after the `first` - 1 extra
    ones have been tried, none has converged and none came within that score
    (`_descend`'s: position error / tolerance + angle error / tolerance) of the pose; the
    search is then marked as given up (`_Search.gave_up`)."""
    s = _Search(best=(math.inf, math.inf, math.inf, d.q_cur))
    for seed in seeds:
        if (
            give_up is not None
            and s.tried - (first - 1) >= give_up[0]
            and not s.found
            and min(e[0] for e in s.ends) > give_up[1]
        ):
            s.gave_up = True
            break
        s.tried += 1
        seed_best = _descend(robot, d, seed, s)
        s.ends.append(seed_best)
        if seed_best[0] > 2.0:
            continue
        q, ep, th, roll = _near_current(robot, d, seed_best[1])
        if d.within(ep, th, roll):
            s.found.append((float(np.linalg.norm(q - d.q_cur)), q, ep, th, roll))
            if s.tried <= first or len(s.found) >= solutions:
                break
    return s


def _polish_ends(robot: Robot, d: _Descent, s: _Search, polish: int) -> None:
    """Refine the `polish` closest ends with the bounded solve, adding those that converge.

    DLS with clamping stalls where the solution lies on a joint limit; a bounded
    trust-region solve from the closest ends handles the limits as constraints. Ends far
    off (score > 200: ~0.2 m or ~100°) are not worth it: the pose is out of reach.
    """
    for _, q_end in [e for e in sorted(s.ends, key=lambda e: e[0]) if e[0] < 200.0][:polish]:
        q, ep, th, roll = _near_current(robot, d, _bounded_solve(robot, d.pose, q_end))
        if d.within(ep, th, roll):
            s.found.append((float(np.linalg.norm(q - d.q_cur)), q, ep, th, roll))
        elif ep / d.tol_position_m + max(th, roll) / d.tol_axis_rad < s.best[0]:
            s.best = (ep / d.tol_position_m + max(th, roll) / d.tol_axis_rad, ep, th, q)


def _no_solution(d: _Descent, s: _Search) -> IKNoSolution:
    """The error for a search with no converged seed: the pose, the best residual and
    the tolerances."""
    pose, best = d.pose, s.best
    return IKNoSolution(
        f"IK failed for position {np.round(pose.position, 4).tolist()} m, axis "
        f"{np.round(pose.axis, 4).tolist()}{'' if not d.six else f', roll {pose.roll:.4f} rad'}: "
        f"best residual {best[1] * 1e3:.2f} mm, {math.degrees(best[2]):.2f}° after "
        f"{s.tried} seeds (tolerance {d.tol_position_m * 1e3:.2f} mm, "
        f"{math.degrees(d.tol_axis_rad):.2f}°)",
        position_error_m=best[1],
        axis_error_rad=best[2],
        q_best=best[3],
    )


def solve_ik(
    robot: Robot,
    pose: ReleasePose,
    q_current: np.ndarray | None = None,
    *,
    tol_position_m: float = POSITION_TOL_M,
    tol_axis_rad: float = AXIS_TOL_RAD,
    max_iterations: int = 80,
    random_seeds: int = 30,
    solutions: int = 3,
    damping: float = 3e-3,
    null_gain: float = 0.05,
    polish: int = 3,
    rng: np.random.Generator | None = None,
    give_up: tuple[int, float] | None = None,
    warm: np.ndarray | None = None,
) -> IKResult:
    """Joint configuration that puts the grip centre at a release pose.

    Seeds are tried in order: the current configuration, home, then `random_seeds` random
    configurations. If the current configuration converges, its solution is returned at once
    (it is the one the arm reaches by moving continuously). Otherwise the search stops once
    `solutions` seeds have converged, and the converged configuration nearest the current
    one (after 2π shifts within the limits) is returned.

    Args:
        robot: the arm (see `load_robot`).
        pose: the release pose (position, throw axis, optional roll).
        q_current: the current configuration [rad], shape (n,); home if None.
        tol_position_m: success tolerance on the position [m].
        tol_axis_rad: success tolerance on the axis and roll [rad].
        max_iterations: DLS iterations per seed.
        random_seeds: random seeds after the current and home configurations.
        solutions: converged solutions to collect before choosing the nearest, when the
            current configuration itself does not converge.
        damping: DLS damping λ (λ² added to J Jᵀ, plus a term growing with the error).
        null_gain: null-space pull towards the current configuration per iteration.
        polish: if no seed converges, this many of the closest attempts are refined with a
            bounded trust-region least-squares solve (scipy) before giving up.
        rng: random generator for the random seeds (a fixed seed if None: repeatable).
        give_up: (seeds, score): where that many seeds have been tried, none converged
            and none came within that score of the pose (position error / tol_position_m
            + angle error / tol_axis_rad), the pose is taken as out of reach: no more
            seeds and no polish (None: every seed).
        warm: a warm start [rad], shape (n,) (the solution of a nearby pose): the second
            seed, after the current configuration; if either converges, its solution is
            returned at once, else the usual seeds follow (`give_up` counts them alone).
            Clamped onto the limits.

    Uses `robot.data` as scratch space: one Robot per thread.

    Returns:
        The IKResult of the chosen solution.

    Raises:
        InvalidInput: q_current has the wrong shape or is outside the limits, warm has the
            wrong shape or is not finite, or a solver setting is out of range.
        IKNoSolution (an IKFailed): no seed converged; carries the best residual.
    """
    _check_settings(
        tol_position_m, tol_axis_rad, damping, max_iterations, random_seeds, solutions, null_gain
    )
    q_cur = _current_configuration(robot, q_current)
    d = _Descent.of(pose, q_cur, tol_position_m, tol_axis_rad, max_iterations, damping, null_gain)
    if warm is not None:
        warm = np.asarray(warm, dtype=float)
        if warm.shape != q_cur.shape or not np.all(np.isfinite(warm)):
            raise InvalidInput(
                f"warm must be {q_cur.shape[0]} finite joint angles [rad], got {warm!r}"
            )
        warm = np.clip(warm, robot.limits.lower, robot.limits.upper)
    seeds = _seeds(robot, q_cur, pose.position, random_seeds, rng, warm)
    s = _search_seeds(robot, d, seeds, solutions, give_up, 1 if warm is None else 2)
    if not s.found and polish > 0 and not s.gave_up:
        _polish_ends(robot, d, s, polish)
    if not s.found:
        raise _no_solution(d, s)
    _, q, ep, th, roll = min(s.found, key=lambda f: f[0])
    return IKResult(
        q=q,
        position_error_m=ep,
        axis_error_rad=th,
        roll_error_rad=roll,
        iterations=s.iterations,
        seeds_tried=s.tried,
    )


WEIGHT_ROLLS_RAD = (0.0, math.pi)
"""Rolls that put the pads in the vertical plane of the throw: one pad under the item."""


def solve_release_ik(
    robot: Robot,
    position: np.ndarray,
    elevation: float,
    azimuth: float,
    q_current: np.ndarray | None = None,
    solve: Callable[..., IKResult] | None = None,
) -> IKResult:
    """IK for a release with the item's weight on a pad: the roll fixed at 0 or π.

    With roll 0 (or π) the grip's x axis, across the pads, lies in the vertical plane of
    the throw, so the lower pad carries the item's weight; with the roll free, a 6-DoF
    arm may turn the pads sideways and leave the weight to friction (the UR5 did, and
    dropped the 75 g cyl50 while carrying it). Of the two, the solution nearer
    q_current wins; if neither is reachable the roll is left free. A vertical axis has
    no such plane: there the roll is free at once.

    Args:
        robot: the arm.
        position: grip centre p [m, W], shape (3,).
        elevation: e [rad].
        azimuth: a [rad].
        q_current: the current configuration [rad]; home if None.
        solve: `solve_ik` or a stand-in with its (robot, pose, q_current) arguments (the
            orchestrator's, which remembers what it solved: `Orchestrator._release_ik`).

    Returns:
        The IKResult.

    Raises:
        IKNoSolution: not even the free roll is reachable.
    """
    solve = solve or solve_ik
    q_ref = robot.home if q_current is None else np.asarray(q_current, dtype=float)
    if abs(math.cos(elevation)) > 1e-6:
        found: list[IKResult] = []
        for roll in WEIGHT_ROLLS_RAD:
            try:
                pose = ReleasePose.from_angles(position, elevation, azimuth, roll)
                found.append(solve(robot, pose, q_current))
            except IKFailed:
                continue
        if found:
            return min(found, key=lambda r: float(np.linalg.norm(r.q - q_ref)))
    return solve(robot, ReleasePose.from_angles(position, elevation, azimuth), q_current)
