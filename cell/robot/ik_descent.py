"""One damped-least-squares descent of the release IK from one seed, and the bounded polish."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.linalg import _umath_linalg  # type: ignore[attr-defined]

from cell.robot.ik_pose import ReleasePose, _axis_angle, _axis_error, _log3
from cell.robot.model import Robot

_AXIS_LEVER_M = 0.3  # [m] weighs axis errors against position errors in the bounded solve


def _bounded_solve(robot: Robot, pose: ReleasePose, q0: np.ndarray) -> np.ndarray:
    """Bounded least squares (scipy TRF) on position and axis (and roll) from q0."""
    from scipy.optimize import least_squares

    lim = robot.limits
    six = pose.roll is not None
    r_des = pose.rotation()

    last: list[tuple[bytes, tuple[np.ndarray, np.ndarray]]] = []

    def parts(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # the solver asks for the residual and then the Jacobian at the same q: the
        # kinematics once for both (the same arrays: the same numbers)
        key = q.tobytes()
        if not last or last[0][0] != key:
            last[:] = [(key, _parts(q))]
        res, jac = last[0][1]
        return res.copy(), jac.copy()

    def _parts(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        p, r = robot.tcp_pose(q)
        jac = robot.tcp_jacobian(q)
        cols = (2,) if not six else (0, 1, 2)
        res = [p - pose.position]
        jrows = [jac[:3]]
        w0, w1, w2 = jac[3], jac[4], jac[5]
        for c in cols:
            # d(column c)/dq_i = ω_i × column c: np.cross's products and differences, row by
            # row, without its axis moves (a tenth of the polish's time)
            res.append(_AXIS_LEVER_M * (r[:, c] - r_des[:, c]))
            b0, b1, b2 = r[:, c].tolist()
            cross = np.array([w1 * b2 - w2 * b1, w2 * b0 - w0 * b2, w0 * b1 - w1 * b0])
            jrows.append(_AXIS_LEVER_M * cross)
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
        gave_up: the search stopped early, every seed so far far off (`solve_ik`'s
            `give_up`).
    """

    best: _Best
    found: list[_Found] = field(default_factory=list)
    ends: list[tuple[float, np.ndarray]] = field(default_factory=list)
    iterations: int = 0
    tried: int = 0
    gave_up: bool = False


def _orientation_error(d: _Descent, r: np.ndarray) -> tuple[np.ndarray, float, float]:
    """The orientation error at a tool rotation r, shape (3, 3).

    Returns:
        (rotation vector w the descent turns by [rad], axis error th [rad], the angle the
        descent drives to zero [rad]: the full rotation's with a fixed roll, else th).
    """
    if d.six:
        w = _log3(d.r_des @ r.T)
        th = _axis_angle(r[:, 2], d.pose.axis)
        ang = math.sqrt(float(w @ w))
    else:
        w, th = _axis_error(r[:, 2], d.pose.axis, r[:, 0])
        ang = th
    return w, th, ang


def _solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """x with a x = b for the descent's damped a (J Jᵀ + λ² I, λ > 0: symmetric positive
    definite, never singular): LAPACK's gesv, the routine `np.linalg.solve` calls, called
    directly (bitwise the same result without its checks, a quarter of its time; the
    descent makes ~15,000 such solves a throw's planning)."""
    return _umath_linalg.solve1(a, b, signature="dd->d")  # type: ignore[no-any-return]


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
        dq = z0 + jt.T @ _solve(a, err - jt @ z0)
    else:
        dq = jt.T @ _solve(a, err)
    step = max(map(abs, dq.tolist()))  # np.abs(dq).max(), as floats: the same, sooner
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
    lower, upper = robot.limits.lower, robot.limits.upper
    world = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    # the loop's names looked up once (the same calls; lookups were a tenth of a descent)
    jacobians, placement, frame_jacobian = (
        pin.computeJointJacobians,
        pin.updateFramePlacement,
        pin.getFrameJacobian,
    )
    target, tol_p, tol_a = d.pose.position, d.tol_position_m, d.tol_axis_rad
    stop_p, stop_a, half = d.stop_p, d.stop_a, d.half
    maximum, minimum, sqrt = np.maximum, np.minimum, math.sqrt
    q = np.array(seed, dtype=float)
    seed_best = (math.inf, q)
    for k in range(d.max_iterations):
        jacobians(model, data, q)
        oMf = placement(model, data, fid)  # data.oMf[fid], updated
        r = oMf.rotation
        e_p = target - oMf.translation
        w, th, ang = _orientation_error(d, r)
        ep = sqrt(float(e_p @ e_p))
        score = ep / tol_p + ang / tol_a
        if score < seed_best[0]:
            seed_best = (score, q)
        if score < s.best[0]:
            s.best = (score, ep, th, q)
        if ep < stop_p and ang < stop_a:
            break
        if k == half and score > 100.0:
            break  # far off after half the budget: a new seed is a better bet
        s.iterations += 1
        dq = _dls_step(d, frame_jacobian(model, data, fid, world), r, e_p, w, q, k)
        q = q + dq  # a new array: seed_best and s.best keep the old one
        minimum(maximum(q, lower, out=q), upper, out=q)  # np.clip's result, sooner
    return seed_best
