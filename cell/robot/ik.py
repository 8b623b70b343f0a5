"""Inverse kinematics of the release pose: damped least squares over several seeds.

A release pose is a grip-centre position p [m, W] and a throw axis u (the +z axis of
`ee_tcp`); the roll about u is free (a 5-D task) or fixed (6-D). Each seed is iterated with
damped least squares, joint limits clamped at every step and a null-space pull towards the
current configuration (redundant arms). The converged solution nearest the current
configuration wins; if none converges the call raises IKFailed with the best residual.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numpy as np

from cell.errors import IKFailed, InvalidInput
from cell.robot.model import Robot, axis_frame

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

POSITION_TOL_M = 1e-3
"""Success tolerance on the grip-centre position [m]."""

AXIS_TOL_RAD = math.radians(0.5)
"""Success tolerance on the throw axis (and the roll, when fixed) [rad]."""


class IKNoSolution(IKFailed):
    """No seed reached the pose; carries the best residual found.

    Attributes:
        position_error_m: best position error [m].
        axis_error_rad: axis error of that attempt [rad].
        q_best: the configuration of that attempt [rad].
    """

    def __init__(
        self, message: str, position_error_m: float, axis_error_rad: float, q_best: np.ndarray
    ) -> None:
        super().__init__(message)
        self.position_error_m = position_error_m
        self.axis_error_rad = axis_error_rad
        self.q_best = q_best


@dataclass(frozen=True)
class ReleasePose:
    """Where the grip centre must be and where the throw axis must point.

    Attributes:
        position: grip centre p in W [m], shape (3,).
        axis: throw axis u in W (unit), shape (3,).
        roll: rotation about u [rad] of ee_tcp relative to `axis_frame(e, a, 0)`, or None
            to leave it free.
    """

    position: np.ndarray
    axis: np.ndarray
    roll: float | None = None

    def __post_init__(self) -> None:
        p = np.asarray(self.position, dtype=float).reshape(-1)
        u = np.asarray(self.axis, dtype=float).reshape(-1)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise InvalidInput(f"release position must be 3 finite numbers [m], got {p!r}")
        n = float(np.linalg.norm(u)) if u.shape == (3,) else 0.0
        if not (math.isfinite(n) and n > 1e-9):
            raise InvalidInput(f"throw axis must be a nonzero 3-vector, got {u!r}")
        if self.roll is not None and not math.isfinite(self.roll):
            raise InvalidInput(f"roll must be finite [rad] or None, got {self.roll!r}")
        object.__setattr__(self, "position", p)
        object.__setattr__(self, "axis", u / n)

    @classmethod
    def from_angles(
        cls,
        position: np.ndarray | tuple[float, float, float],
        elevation: float,
        azimuth: float,
        roll: float | None = None,
    ) -> ReleasePose:
        """The pose from MODEL.md's elevation e and azimuth a [rad]:
        u = (cos e cos a, cos e sin a, sin e)."""
        u = axis_frame(elevation, azimuth)[:, 2]
        return cls(np.asarray(position, dtype=float), u, roll)

    @property
    def elevation(self) -> float:
        """e = asin(u_z) [rad]."""
        return math.asin(max(-1.0, min(1.0, float(self.axis[2]))))

    @property
    def azimuth(self) -> float:
        """a = atan2(u_y, u_x) [rad] (0 for a vertical axis)."""
        if math.hypot(self.axis[0], self.axis[1]) < 1e-12:
            return 0.0
        return math.atan2(float(self.axis[1]), float(self.axis[0]))

    def rotation(self) -> np.ndarray:
        """The full target orientation of ee_tcp (roll 0 when free), shape (3, 3)."""
        return axis_frame(self.elevation, self.azimuth, self.roll or 0.0)


@dataclass(frozen=True)
class IKResult:
    """A converged IK solution.

    Attributes:
        q: arm configuration [rad], shape (n,).
        position_error_m: |p(q) - p| [m].
        axis_error_rad: angle between ee_tcp's z and u [rad].
        roll_error_rad: roll error [rad] (0 when the roll is free).
        iterations: DLS iterations spent over all seeds.
        seeds_tried: seeds started.
    """

    q: np.ndarray
    position_error_m: float
    axis_error_rad: float
    roll_error_rad: float
    iterations: int
    seeds_tried: int


def _log3(r: np.ndarray) -> np.ndarray:
    """Rotation vector of a rotation matrix [rad], shape (3,)."""
    c = max(-1.0, min(1.0, (float(np.trace(r)) - 1.0) / 2.0))
    th = math.acos(c)
    v = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    if th < 1e-8:
        return 0.5 * v
    if math.pi - th < 1e-6:
        # Near π the antisymmetric part vanishes: take the axis from the symmetric part.
        b = (r + np.eye(3)) / 2.0
        k = int(np.argmax(np.diag(b)))
        ax = b[:, k] / math.sqrt(max(b[k, k], 1e-12))
        return th * ax / np.linalg.norm(ax)
    return th / (2.0 * math.sin(th)) * v


def _axis_error(z: np.ndarray, u: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, float]:
    """Rotation vector that turns z onto u (perpendicular to both) and its angle [rad]."""
    c = np.array([z[1] * u[2] - z[2] * u[1], z[2] * u[0] - z[0] * u[2], z[0] * u[1] - z[1] * u[0]])
    s = math.sqrt(float(c @ c))
    th = math.atan2(s, float(z @ u))
    if s > 1e-12:
        return th * c / s, th
    return (th * x if th > 1.0 else np.zeros(3)), th


def pose_error(robot: Robot, q: np.ndarray, pose: ReleasePose) -> tuple[float, float, float]:
    """How far configuration q puts the grip centre from a release pose.

    Args:
        robot: the arm.
        q: configuration [rad], shape (n,).
        pose: the target.

    Returns:
        (position error [m], axis error [rad], roll error [rad]; 0 when the roll is free).
    """
    p, r = robot.tcp_pose(q)
    ep = float(np.linalg.norm(pose.position - p))
    _, th = _axis_error(r[:, 2], pose.axis, r[:, 0])
    roll = 0.0
    if pose.roll is not None:
        roll = float(np.linalg.norm(_log3(pose.rotation() @ r.T)))
    return ep, th, roll


_AXIS_LEVER_M = 0.3  # [m] weighs axis errors against position errors in the bounded solve


def _bounded_solve(robot: Robot, pose: ReleasePose, q0: np.ndarray) -> np.ndarray:
    """Bounded least squares (scipy TRF) on position and axis (and roll) from q0."""
    from scipy.optimize import least_squares

    lim = robot.limits
    six = pose.roll is not None
    r_des = pose.rotation()

    def parts(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        p, r = robot.tcp_pose(q)
        jac = robot.tcp_jacobian(q)
        cols = (2,) if not six else (0, 1, 2)
        res = [p - pose.position]
        jrows = [jac[:3]]
        for c in cols:
            # d(column c)/dq_i = ω_i × column c.
            res.append(_AXIS_LEVER_M * (r[:, c] - r_des[:, c]))
            jrows.append(_AXIS_LEVER_M * np.cross(jac[3:].T, r[:, c]).T)
        return np.concatenate(res), np.concatenate(jrows)

    x0 = np.clip(q0, lim.lower + 1e-9, lim.upper - 1e-9)
    sol = least_squares(
        lambda q: parts(q)[0],
        x0,
        jac=lambda q: parts(q)[1],
        bounds=(lim.lower, lim.upper),
        method="trf",
        xtol=1e-12,
        ftol=1e-12,
        gtol=1e-12,
        max_nfev=60,
    )
    return np.clip(np.asarray(sol.x, dtype=float), lim.lower, lim.upper)


def _wrap_near(q: np.ndarray, ref: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Shift joints by multiples of 2π towards ref while staying within the limits."""
    out = q.copy()
    k = np.round((ref - q) / (2 * math.pi))
    cand = q + 2 * math.pi * k
    ok = (cand >= lo) & (cand <= hi)
    out[ok] = cand[ok]
    return out


_Best = tuple[float, float, float, np.ndarray]  # (score, position error [m], axis error [rad], q)
_Found = tuple[float, np.ndarray, float, float, float]  # (|q - q_cur|, q, ep [m], th, roll [rad])


@dataclass(frozen=True)
class _Descent:
    """The settings of the damped-least-squares descents of one solve, resolved once.

    Attributes:
        pose: the target.
        r_des: its full orientation (the target when the roll is fixed), shape (3, 3).
        six: the roll is fixed (a 6-D task; else 5-D).
        q_cur: the configuration the null-space pull draws towards [rad], shape (n,).
        tol_position_m: success tolerance on the position [m].
        tol_axis_rad: success tolerance on the axis and roll [rad].
        stop_p: position error at which a descent stops [m].
        stop_a: angle error at which a descent stops [rad].
        max_iterations: iterations per seed.
        half: the iteration after which the null-space pull stops and far-off seeds quit.
        lam2: the DLS damping λ² [-].
        null_gain: null-space pull per iteration.
        eye_m: the identity of the task's size (5 or 6).
    """

    pose: ReleasePose
    r_des: np.ndarray
    six: bool
    q_cur: np.ndarray
    tol_position_m: float
    tol_axis_rad: float
    stop_p: float
    stop_a: float
    max_iterations: int
    half: int
    lam2: float
    null_gain: float
    eye_m: np.ndarray

    @classmethod
    def of(
        cls,
        pose: ReleasePose,
        q_cur: np.ndarray,
        tol_position_m: float,
        tol_axis_rad: float,
        max_iterations: int,
        damping: float,
        null_gain: float,
    ) -> _Descent:
        """The settings from `solve_ik`'s arguments."""
        six = pose.roll is not None
        return cls(
            pose=pose,
            r_des=pose.rotation(),
            six=six,
            q_cur=q_cur,
            tol_position_m=tol_position_m,
            tol_axis_rad=tol_axis_rad,
            # Stop tighter than the tolerance: DLS converges fast near the solution.
            stop_p=0.05 * tol_position_m,
            stop_a=0.05 * tol_axis_rad,
            max_iterations=max_iterations,
            half=max_iterations // 2,
            lam2=damping * damping,
            null_gain=null_gain,
            eye_m=np.eye(6 if six else 5),
        )

    def within(self, ep: float, th: float, roll: float) -> bool:
        """Whether errors (position [m], axis and roll [rad]) meet the tolerances."""
        return ep <= self.tol_position_m and th <= self.tol_axis_rad and roll <= self.tol_axis_rad


@dataclass
class _Search:
    """What the search over seeds has found so far.

    Attributes:
        best: the attempt of lowest score (for the error when nothing converges).
        found: converged solutions.
        ends: each seed's best (score, q) of its descent.
        iterations: DLS iterations spent.
        tried: seeds started.
    """

    best: _Best
    found: list[_Found] = field(default_factory=list)
    ends: list[tuple[float, np.ndarray]] = field(default_factory=list)
    iterations: int = 0
    tried: int = 0


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
) -> Iterator[np.ndarray]:
    """The seeds in order: the current configuration, home (if different), then
    `random_seeds` random configurations, every other one with its base joint turned to
    face the target. Lazy: the random ones are drawn only when the first seeds fail."""
    lim = robot.limits
    yield q_cur
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


def _orientation_error(d: _Descent, r: np.ndarray) -> tuple[np.ndarray, float, float]:
    """The orientation error at a tool rotation r, shape (3, 3).

    Returns:
        (rotation vector w the descent turns by [rad], axis error th [rad], the angle the
        descent drives to zero [rad]: the full rotation's with a fixed roll, else th).
    """
    if d.six:
        w = _log3(d.r_des @ r.T)
        th = _axis_error(r[:, 2], d.pose.axis, r[:, 0])[1]
        ang = math.sqrt(float(w @ w))
    else:
        w, th = _axis_error(r[:, 2], d.pose.axis, r[:, 0])
        ang = th
    return w, th, ang


def _dls_step(
    d: _Descent,
    jac: np.ndarray,
    r: np.ndarray,
    e_p: np.ndarray,
    w: np.ndarray,
    q: np.ndarray,
    k: int,
) -> np.ndarray:
    """One damped-least-squares step dq [rad], no joint moving more than 0.5 rad.

    Args:
        d: the descent's settings.
        jac: the tool's frame Jacobian (world-aligned), shape (6, n).
        r: the tool's rotation, shape (3, 3).
        e_p: position error [m], shape (3,).
        w: orientation error (rotation vector) [rad], shape (3,).
        q: the configuration [rad], shape (n,).
        k: the iteration (the null-space pull acts in the first half).
    """
    if d.six:
        jt = jac
        err = np.concatenate([e_p, w])
    else:
        # Only rotations about axes perpendicular to z move the throw axis.
        jt = np.concatenate([jac[:3], r[:, :2].T @ jac[3:]])
        err = np.concatenate([e_p, r[:, :2].T @ w])
    a = jt @ jt.T + (d.lam2 + 0.01 * float(err @ err)) * d.eye_m
    if k < d.half:
        # J⁺e + (I - J⁺J) z = z + J⁺(e - J z), with J⁺ = Jᵀ (J Jᵀ + λ² I)⁻¹. The
        # pull stops halfway: at a joint limit it can fight the clamp.
        z0 = d.null_gain * (d.q_cur - q)
        dq = z0 + jt.T @ np.linalg.solve(a, err - jt @ z0)
    else:
        dq = jt.T @ np.linalg.solve(a, err)
    step = float(np.max(np.abs(dq)))
    if step > 0.5:
        dq *= 0.5 / step
    return dq


def _descend(robot: Robot, d: _Descent, seed: np.ndarray, s: _Search) -> tuple[float, np.ndarray]:
    """Damped least squares from one seed, joints clamped to their limits at every step.

    Updates the search's best attempt and its iteration count.

    Returns:
        The seed's best (score, q): score = position error / tolerance + angle error /
        tolerance.
    """
    import pinocchio as pin

    model, data, fid = robot.model, robot.data, robot.tcp_frame
    lim = robot.limits
    world = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    q = np.array(seed, dtype=float)
    seed_best = (math.inf, q)
    for k in range(d.max_iterations):
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacement(model, data, fid)
        oMf = data.oMf[fid]
        r = oMf.rotation
        e_p = d.pose.position - oMf.translation
        w, th, ang = _orientation_error(d, r)
        ep = math.sqrt(float(e_p @ e_p))
        score = ep / d.tol_position_m + ang / d.tol_axis_rad
        if score < seed_best[0]:
            seed_best = (score, q)
        if score < s.best[0]:
            s.best = (score, ep, th, q)
        if ep < d.stop_p and ang < d.stop_a:
            break
        if k == d.half and score > 100.0:
            break  # far off after half the budget: a new seed is a better bet
        s.iterations += 1
        jac = pin.getFrameJacobian(model, data, fid, world)
        dq = _dls_step(d, jac, r, e_p, w, q, k)
        q = np.clip(q + dq, lim.lower, lim.upper)
    return seed_best


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
    robot: Robot, d: _Descent, seeds: Iterator[np.ndarray], solutions: int
) -> _Search:
    """Descend from each seed in turn; stop at once if the first converges, else once
    `solutions` seeds have."""
    s = _Search(best=(math.inf, math.inf, math.inf, d.q_cur))
    for seed in seeds:
        s.tried += 1
        seed_best = _descend(robot, d, seed, s)
        s.ends.append(seed_best)
        if seed_best[0] > 2.0:
            continue
        q, ep, th, roll = _near_current(robot, d, seed_best[1])
        if d.within(ep, th, roll):
            s.found.append((float(np.linalg.norm(q - d.q_cur)), q, ep, th, roll))
            if s.tried == 1 or len(s.found) >= solutions:
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

    Uses `robot.data` as scratch space: one Robot per thread.

    Returns:
        The IKResult of the chosen solution.

    Raises:
        InvalidInput: q_current has the wrong shape or is outside the limits, or a solver
            setting is out of range.
        IKNoSolution (an IKFailed): no seed converged; carries the best residual.
    """
    _check_settings(
        tol_position_m, tol_axis_rad, damping, max_iterations, random_seeds, solutions, null_gain
    )
    q_cur = _current_configuration(robot, q_current)
    d = _Descent.of(pose, q_cur, tol_position_m, tol_axis_rad, max_iterations, damping, null_gain)
    s = _search_seeds(robot, d, _seeds(robot, q_cur, pose.position, random_seeds, rng), solutions)
    if not s.found and polish > 0:
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
