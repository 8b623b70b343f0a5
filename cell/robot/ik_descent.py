"""One damped-least-squares descent of the release IK from one seed, and the bounded polish."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.linalg import _umath_linalg  # type: ignore[attr-defined]

from cell.robot.ik_pose import ReleasePose, _axis_angle, _log3_floats
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


# x with a x = b for the descent's damped a (J Jᵀ + λ² I, λ > 0: symmetric positive definite,
# never singular): LAPACK's gesv, the gufunc `np.linalg.solve` calls, called directly
# (bitwise the same result without its checks; its float64 loop without naming it, which
# takes longer than the solve); the descent makes ~15,000 such solves a throw's planning
_solve = _umath_linalg.solve1


def _descend(robot: Robot, d: _Descent, seed: np.ndarray, s: _Search) -> tuple[float, np.ndarray]:
    """Damped least squares from one seed, joints clamped to their limits at every step.

    Each iteration: the tool's pose and Jacobian (world-aligned) at q; the errors (position
    e_p [m]; orientation w [rad]: the full rotation's vector with a fixed roll, else the
    turn of the throw axis onto the target's, seen in the tool's x-y plane); the score;
    then one DLS step dq = Jᵀ (J Jᵀ + (λ² + 0.01 |e|²) I)⁻¹ e, with a pull towards the
    current configuration in the null space during the first half (J⁺e + (I - J⁺J) z =
    z + J⁺(e - J z)), no joint moving more than 0.5 rad, and the clamp onto the limits.

    The arithmetic of 3- to 7-vectors is done by numpy's BLAS (dot products, matrix
    products, LAPACK's gesv) where it sums, and entry by entry in floats where numpy's
    elementwise operations would make the same IEEE products and differences: numpy's
    call overhead, not the arithmetic, was most of an iteration's time.

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
    p0, p1, p2 = d.pose.position.tolist()
    six, r_des, axis = d.six, d.r_des, d.pose.axis
    u0, u1, u2 = axis.tolist()
    tol_p, tol_a, stop_p, stop_a = d.tol_position_m, d.tol_axis_rad, d.stop_p, d.stop_a
    half, lam2, gain, q_cur = d.half, d.lam2, d.null_gain, d.q_cur
    maximum, minimum, sqrt, atan2 = np.maximum, np.minimum, math.sqrt, math.atan2
    # J Jᵀ + (λ² + 0.01 |e|²) I in place: the damping added to the diagonal (a view) alone,
    # the sums numpy's J Jᵀ + c I makes there (off it, + 0.0 changes nothing)
    m = 6 if six else 5
    a = np.empty((m, m))
    a_diag = a.reshape(-1)[:: m + 1]
    q = np.array(seed, dtype=float)
    seed_best = (math.inf, q)
    best = s.best[0]
    steps = 0
    for k in range(d.max_iterations):
        jacobians(model, data, q)
        oMf = placement(model, data, fid)  # data.oMf[fid], updated
        r = oMf.rotation
        t0, t1, t2 = oMf.translation.tolist()  # e_p = target - translation, entry by entry
        if six:
            # the task's error err = (e_p, w), w the full rotation's vector
            w0, w1, w2 = _log3_floats(r_des.dot(r.T))
            err = np.array((p0 - t0, p1 - t1, p2 - t2, w0, w1, w2))
            e_p, w = err[:3], err[3:]
            ang = sqrt(w.dot(w))
        else:
            # the throw axis z turned onto u by th about z × u (`_axis_error`); only
            # rotations about axes perpendicular to z move it: err = (e_p, the turn in the
            # tool's x-y plane)
            z = r[:, 2]
            z0, z1, z2 = z.tolist()
            c0, c1, c2 = z1 * u2 - z2 * u1, z2 * u0 - z0 * u2, z0 * u1 - z1 * u0
            c = np.array((c0, c1, c2))
            sn = sqrt(c.dot(c))
            ang = th = atan2(sn, z.dot(axis))
            if sn > 1e-12:
                w = np.array((th * c0 / sn, th * c1 / sn, th * c2 / sn))
            else:
                w = th * r[:, 0] if th > 1.0 else np.zeros(3)
            rxy = r[:, :2].T
            g0, g1 = rxy.dot(w).tolist()
            err = np.array((p0 - t0, p1 - t1, p2 - t2, g0, g1))
            e_p = err[:3]
        ep = sqrt(e_p.dot(e_p))
        score = ep / tol_p + ang / tol_a
        if score < seed_best[0]:
            seed_best = (score, q)
        if score < best:
            if six:
                th = _axis_angle(r[:, 2], axis)  # (only kept with the best attempt)
            best = score
            s.best = (score, ep, th, q)
        if ep < stop_p and ang < stop_a:
            break
        if k == half and score > 100.0:
            break  # far off after half the budget: a new seed is a better bet
        steps += 1
        jt = frame_jacobian(model, data, fid, world)  # a new array, (6, n)
        if not six:
            jt[3:5] = rxy.dot(jt[3:])
            jt = jt[:5]
        jt_t = jt.T
        jt.dot(jt_t, a)  # into a
        a_diag += lam2 + 0.01 * float(err.dot(err))
        if k < half:
            # The pull stops halfway: at a joint limit it can fight the clamp.
            z_pull = gain * (q_cur - q)
            dq = z_pull + jt_t.dot(_solve(a, err - jt.dot(z_pull)))
        else:
            dq = jt_t.dot(_solve(a, err))
        step = max(map(abs, dq.tolist()))  # np.abs(dq).max(), as floats: the same, sooner
        if step > 0.5:
            dq *= 0.5 / step
        q = minimum(maximum(q + dq, lower), upper)  # np.clip's result, sooner; a new array
    s.iterations += steps
    return seed_best
